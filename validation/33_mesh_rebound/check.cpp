// Validation 33: a sphere and a cube dropped on the floor of a box built from a triangle mesh
// rebound as from the analytic box (plane walls) within 1 %. See README.md.

#include "dynamics/system.hpp"
#include "geometry/polyhedron_contact.hpp"
#include "validation.hpp"

#include <array>
#include <cmath>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <numbers>
#include <string>

namespace kiln::validation {
namespace {

/// Mesh vs analytic rebound ratio: the 1 %.
constexpr double rebound_tolerance = 0.01;

/// Impact and rebound speeds of each particle: the most negative v_z before the first rise, the
/// largest v_z after it (reached when the contact ends; gravity slows it after that).
struct Rebound {
    std::array<double, 2> v_in{0, 0};
    std::array<double, 2> v_out{0, 0};
    long wall_contacts = 0;
};

Rebound run(const std::string& file) {
    io::CaseSpec spec = load_case(file);
    // The cube face-down: its template's first face normal turned to -z.
    const auto& cube = std::get<geometry::ConvexPolyhedron>(spec.scene.shapes.at(0).shape);
    const Vec3 n = geometry::polyhedron_features(cube).face_normals.at(0);
    const Vec3 axis = n.cross(Vec3(0, 0, -1));
    spec.scene.particles.at(1).orientation.fixed =
        axis.norm() < 1e-12
            ? (n.z() < 0 ? Quat::Identity()
                         : Quat(Eigen::AngleAxisd(std::numbers::pi, Vec3::UnitX())))
            : Quat(Eigen::AngleAxisd(std::atan2(axis.norm(), -n.z()), axis.normalized()));
    dynamics::System sys(spec.scene);
    const auto& p = sys.particles();
    Rebound r;
    std::array<bool, 2> rising{false, false};
    const long steps = std::lround(spec.run.end_time / sys.dt());
    for (long s = 0; s < steps; ++s) {
        sys.step();
        r.wall_contacts += sys.counters().wall_contacts;
        for (std::size_t i = 0; i < 2; ++i) {
            const auto k = static_cast<std::size_t>(p.id[i]);
            const double vz = p.v[i].z();
            if (!rising[k]) {
                r.v_in[k] = std::min(r.v_in[k], vz);
                rising[k] = vz > 0.0;
            } else {
                r.v_out[k] = std::max(r.v_out[k], vz);
            }
        }
    }
    return r;
}

TEST(MeshRebound, MeshBoxReboundsAsTheAnalyticBox) {
    reset_results();
    const Rebound plane = run("case_plane.toml");
    const Rebound mesh = run("case_mesh.toml");
    EXPECT_GT(plane.wall_contacts, 0);
    EXPECT_GT(mesh.wall_contacts, 0);
    const std::array<std::string, 2> names{"sphere", "cube"};
    for (std::size_t k = 0; k < 2; ++k) {
        const double e_plane = -plane.v_out[k] / plane.v_in[k];
        const double e_mesh = -mesh.v_out[k] / mesh.v_in[k];
        record(names[k] + " rebound ratio, analytic box", e_plane, 0.5, 0.0, "-");
        record(names[k] + " rebound ratio, mesh box", e_mesh, e_plane, rebound_tolerance, "-");
        EXPECT_GT(e_plane, 0.1) << names[k] << ": no rebound measured";
        EXPECT_NEAR(e_mesh / e_plane, 1.0, rebound_tolerance) << names[k];
    }
}

} // namespace
} // namespace kiln::validation
