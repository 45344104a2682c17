#include "fluid/deposit_body.hpp"

#include <cmath>
#include <limits>

namespace kiln::fluid {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Distinct face planes of a convex polyhedron: coplanar triangles (a cube's two per face) give
// one plane, so the inside test makes one comparison per face.
PlanesBody planes_of(const geometry::ConvexPolyhedron& p) {
    PlanesBody out;
    out.vertices = p.vertices;
    const double scale = p.bounding_radius();
    for (const auto& f : p.faces) {
        const Vec3& a = p.vertices[f[0]];
        const Vec3 n = (p.vertices[f[1]] - a).cross(p.vertices[f[2]] - a).normalized();
        const double d = n.dot(a);
        bool seen = false;
        for (std::size_t k = 0; k < out.normals.size() && !seen; ++k) {
            seen =
                out.normals[k].dot(n) > 1.0 - 1e-12 && std::abs(out.offsets[k] - d) < 1e-12 * scale;
        }
        if (!seen) {
            out.normals.push_back(n);
            out.offsets.push_back(d);
        }
    }
    return out;
}

struct BodyOf {
    DepositBody operator()(const geometry::Sphere& s) const { return SphereBody{s.radius}; }
    DepositBody operator()(const geometry::ConvexPolyhedron& p) const { return planes_of(p); }
    DepositBody operator()(const geometry::Superquadric& q) const { return SuperquadricBody{q}; }
    DepositBody operator()(const geometry::Clump& c) const { return ClumpBody{c.spheres}; }
};

} // namespace

DepositTemplate make_deposit_template(const geometry::ShapeTemplate& t) {
    return {std::visit(BodyOf{}, t.shape), t.volume, t.bounding_radius()};
}

Aabb world_box(const DepositBody& b, const Vec3& x, const Mat3& r) {
    struct Box {
        const Vec3& x;
        const Mat3& r;
        Aabb operator()(const SphereBody& s) const {
            return {x.array() - s.radius, x.array() + s.radius};
        }
        Aabb operator()(const SuperquadricBody& s) const {
            // The body box [-a, a] turned into the world: half extents |R| a.
            const Vec3 e = r.cwiseAbs() * s.shape.half_axes;
            return {x - e, x + e};
        }
        Aabb operator()(const PlanesBody& p) const {
            Aabb out{Vec3::Constant(kInf), Vec3::Constant(-kInf)};
            for (const Vec3& v : p.vertices) {
                const Vec3 w = r * v;
                out.lo = out.lo.cwiseMin(w);
                out.hi = out.hi.cwiseMax(w);
            }
            return {x + out.lo, x + out.hi};
        }
        Aabb operator()(const ClumpBody& c) const {
            Aabb out{Vec3::Constant(kInf), Vec3::Constant(-kInf)};
            for (const auto& s : c.spheres) {
                const Vec3 w = r * s.centre;
                out.lo = out.lo.cwiseMin(w - Vec3::Constant(s.radius));
                out.hi = out.hi.cwiseMax(w + Vec3::Constant(s.radius));
            }
            return {x + out.lo, x + out.hi};
        }
    };
    return std::visit(Box{x, r}, b);
}

} // namespace kiln::fluid
