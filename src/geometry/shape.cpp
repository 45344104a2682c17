// Shape variant helpers and the template registry.

#include "geometry/shape.hpp"

#include "core/error.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <numbers>

namespace kiln::geometry {

namespace {
template <class... Ts> struct Overloaded : Ts... { using Ts::operator()...; };
} // namespace

const char* kind_name(const Shape& s) {
    return std::visit(Overloaded{[](const Sphere&) { return "sphere"; },
                                 [](const Clump&) { return "clump"; },
                                 [](const Superquadric&) { return "superquadric"; },
                                 [](const ConvexPolyhedron&) { return "polyhedron"; }},
                      s);
}

double ReferenceSolid::volume() const {
    if (kind == "sphere") {
        return 4.0 / 3.0 * std::numbers::pi * size.x() * size.x() * size.x();
    }
    if (kind == "cylinder") {
        return std::numbers::pi * size.x() * size.x() * size.y();
    }
    if (kind == "box") {
        return size.prod();
    }
    return 0.0;
}

double ShapeTemplate::density_factor() const {
    if (!density_correction || reference.volume() <= 0.0) {
        return 1.0;
    }
    return reference.volume() / volume;
}

double ShapeTemplate::bounding_radius() const {
    return std::visit(Overloaded{[](const Sphere& s) { return s.radius; },
                                 [](const Clump& c) { return c.bounding_radius(); },
                                 [](const Superquadric& q) { return q.bounding_radius(); },
                                 [](const ConvexPolyhedron& p) { return p.bounding_radius(); }},
                      shape);
}

ShapeTemplate make_template(std::string name, Shape shape) {
    ShapeTemplate t;
    t.name = std::move(name);
    t.reference.kind = "none";
    std::visit(Overloaded{[&](const Sphere& s) {
                              t.volume =
                                  4.0 / 3.0 * std::numbers::pi * s.radius * s.radius * s.radius;
                              t.inertia_unit_density =
                                  Vec3::Constant(0.4 * t.volume * s.radius * s.radius);
                          },
                          [&](const Clump& c) {
                              t.volume = c.volume;
                              t.inertia_unit_density = c.inertia_unit_density;
                          },
                          [&](const Superquadric& q) {
                              t.volume = q.volume();
                              t.inertia_unit_density = q.inertia_unit_density();
                          },
                          [&](const ConvexPolyhedron& p) {
                              t.volume = p.volume;
                              t.inertia_unit_density = p.inertia_unit_density;
                          }},
               shape);
    t.shape = std::move(shape);
    return t;
}

void ShapeRegistry::add(ShapeTemplate t) {
    const std::string key = t.name;
    templates_.insert_or_assign(key, std::move(t));
}

const ShapeTemplate& ShapeRegistry::get(const std::string& name) const {
    const auto it = templates_.find(name);
    if (it == templates_.end()) {
        throw InputError(
            fmt::format("unknown shape '{}'; known shapes: {}", name, fmt::join(names(), ", ")));
    }
    return it->second;
}

std::vector<std::string> ShapeRegistry::names() const {
    std::vector<std::string> out;
    out.reserve(templates_.size());
    for (const auto& [k, v] : templates_) {
        out.push_back(k);
    }
    return out;
}

} // namespace kiln::geometry
