#pragma once
// Shapes, grids and single-particle deposits shared by the transfer-grid tests.

#include "core/types.hpp"
#include "fluid/deposit_body.hpp"
#include "fluid/exchange.hpp"
#include "fluid/footprints.hpp"
#include "geometry/clump.hpp"
#include "geometry/shape.hpp"
#include "io/shape_reader.hpp"

#include <cmath>
#include <numbers>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace kiln::test {

/// Volume of a sphere of radius r (m^3).
inline double sphere_volume(double r) {
    return 4.0 / 3.0 * std::numbers::pi * r * r * r;
}

/// A template of the shapes/ folder (e.g. "cube").
inline geometry::ShapeTemplate shape_file(const std::string& name) {
    return io::read_shape_file(std::string(KILN_SOURCE_DIR) + "/shapes/" + name + ".toml");
}

/// Sphere template of radius r (m).
inline geometry::ShapeTemplate sphere_template(double r) {
    return geometry::make_template("sphere", geometry::Sphere{r});
}

/// Superquadric with half-axes (1.5, 1.0, 0.75) mm and exponents e1 = 0.5, e2 = 0.8 (blocky).
inline geometry::ShapeTemplate superquadric_template() {
    geometry::Superquadric q;
    q.half_axes = Vec3(1.5e-3, 1.0e-3, 0.75e-3);
    q.e1 = 0.5;
    q.e2 = 0.8;
    return geometry::make_template("superquadric", q);
}

/// Two spheres of radius 1 mm, centres 1 mm apart; exact union volume (two spheres less the lens).
inline geometry::ShapeTemplate clump_template() {
    const std::vector<geometry::ClumpSphere> s = {{Vec3::Zero(), 1e-3}, {Vec3(1e-3, 0, 0), 1e-3}};
    return geometry::make_template("clump", geometry::make_clump(s, "test"));
}
/// Exact volume of clump_template() (m^3).
inline double clump_volume() {
    return 2.0 * sphere_volume(1e-3) - geometry::lens_volume(1e-3, 1e-3, 1e-3);
}

/// Footprints of one particle of template t at x (m, world) with orientation q.
inline fluid::Footprints deposit_one(const fluid::TransferGrid& g, const geometry::ShapeTemplate& t,
                                     const Vec3& x, const Quat& q) {
    const std::vector<fluid::DepositTemplate> templates = {fluid::make_deposit_template(t)};
    const std::vector<int> shape = {0};
    const std::vector<Vec3> pos = {x};
    const std::vector<Quat> rot = {q};
    fluid::Footprints f;
    fluid::compute_footprints(g, templates, {shape, pos, rot}, f);
    return f;
}

/// Total deposited volume of a footprint set (m^3).
inline double deposited_volume(const fluid::Footprints& f) {
    return std::accumulate(f.volume.begin(), f.volume.end(), 0.0);
}

/// Uniform random unit quaternion.
inline Quat random_rotation(std::mt19937_64& rng) {
    std::normal_distribution<double> n;
    return Quat(n(rng), n(rng), n(rng), n(rng)).normalized();
}

} // namespace kiln::test
