// Polyhedron particles and mesh walls in the step loop: pair and sphere contacts keep momentum,
// both narrow phases agree, walls hold a body at rest, mesh walls act like analytic ones, refusals
// and the saved state.

#include "body_scene.hpp"
#include "core/error.hpp"
#include "dynamics/system.hpp"
#include "io/mesh_reader.hpp"
#include "io/shape_reader.hpp"

#include <cmath>
#include <filesystem>
#include <gtest/gtest.h>
#include <memory>

namespace kiln::dynamics {
namespace {

using test::angular_momentum;
using test::body;
using test::momentum;
using test::shape;

/// The shared scene without gravity.
SceneSpec base_scene() {
    SceneSpec s = test::base_scene();
    s.gravity.setZero();
    return s;
}

/// Oblique, off-centre collision of a polyhedron (template `name`) with a second particle (the
/// same template, or a sphere of radius 1.4 mm when `sphere`); returns the system after 0.02 s.
struct Collision {
    Vec3 p0, p1, l0, l1;
    long contacts = 0;
    double speed_after = 0;
};

Collision collide(const std::string& name, bool sphere, NarrowPhase method) {
    SceneSpec s = base_scene();
    s.narrow_phase = method;
    s.shapes.push_back(shape(name));
    const Quat q(Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized()));
    // Bounding spheres just apart at the start, offsets of a tenth of the size off the line.
    const double r = s.shapes[0].bounding_radius();
    const double r1 = sphere ? 1.4e-3 : r;
    const double gap = 0.02 * r;
    s.particles.push_back(
        body(0, Vec3(-r - gap, 0.1 * r, 0.0), Vec3(0.5, 0, 0), Vec3(0, 20, 0), q));
    if (sphere) {
        s.particles.emplace_back(0, r1, Vec3(r1 + gap, -0.1 * r, 0.05 * r), Vec3(-0.5, 0, 0),
                                 Vec3::Zero());
    } else {
        s.particles.push_back(body(0, Vec3(r1 + gap, -0.1 * r, 0.05 * r), Vec3(-0.5, 0, 0),
                                   Vec3(10, 0, -5), q.conjugate()));
    }
    System sys(s);
    Collision c;
    c.p0 = momentum(sys);
    c.l0 = angular_momentum(sys);
    for (int k = 0; k < 15000; ++k) {
        sys.step();
        c.contacts += sys.counters().particle_contacts;
    }
    c.p1 = momentum(sys);
    c.l1 = angular_momentum(sys);
    c.speed_after = (sys.particles().v[0] - sys.particles().v[1]).norm();
    return c;
}

/// Momentum is exchanged pairwise: conserved to round-off relative to |p| ~ 1.5e-5 kg m/s.
constexpr double kMomentumRounding = 1e-10;

TEST(Polyhedra, PairCollisionsKeepMomentumAndAngularMomentum) {
    for (const std::string name : {"cube", "icosahedron", "cylinder_16"}) {
        for (const bool sphere : {false, true}) {
            const Collision c = collide(name, sphere, NarrowPhase::newton);
            EXPECT_GT(c.contacts, 10) << name << ": no collision";
            EXPECT_LT((c.p1 - c.p0).norm(), kMomentumRounding * c.p0.norm() + 1e-18) << name;
            EXPECT_LT((c.l1 - c.l0).norm(), 1e-9 * (c.l0.norm() + 1e-12)) << name;
            // Inelastic (e = 0.5): the particles separate more slowly than they met (1 m/s).
            EXPECT_LT(c.speed_after, 1.0) << name << (sphere ? " with a sphere" : "");
            EXPECT_GT(c.speed_after, 0.05) << name;
        }
    }
}

TEST(Polyhedra, CommonPlaneAndGjkEpaGiveTheSameCollision) {
    // Both find the exact MTD of two convex polyhedra (EPA within its tolerance, the common plane
    // exactly) and the same patch point: the outcomes agree closely (EPA tolerance ~1e-6 of the
    // size, amplified over one collision).
    const Collision cp = collide("cube", false, NarrowPhase::newton);
    const Collision epa = collide("cube", false, NarrowPhase::gjk_epa);
    EXPECT_NEAR(epa.speed_after / cp.speed_after, 1.0, 1e-3);
}

TEST(Polyhedra, CubeRestsFlatOnAPlaneAndOnAMeshFloor) {
    // A cube face-down settles on the floor with its face level: the contact point stays centred
    // (weighted average of the equally deep vertices), so no rocking torque remains.
    for (const bool mesh : {false, true}) {
        SceneSpec s = base_scene();
        s.gravity = Vec3(0, 0, -9.81);
        s.shapes.push_back(shape("cube"));
        if (mesh) {
            io::MeshInput m = io::read_mesh_file(
                std::filesystem::path(KILN_SOURCE_DIR) / "shapes" / "wall_box_20mm.stl", 1e-3);
            s.mesh_walls.push_back(
                {"floor", std::make_shared<const geometry::MeshWall>(m.points, m.triangles, "box"),
                 0});
        } else {
            s.walls.push_back({"floor", PlaneWall{Vec3::Zero(), Vec3::UnitZ()}, 0});
        }
        const auto& cube = std::get<geometry::ConvexPolyhedron>(s.shapes[0].shape);
        const Vec3 n = geometry::polyhedron_features(cube).face_normals[0];
        const Vec3 axis = n.cross(Vec3(0, 0, -1));
        const Quat q =
            axis.norm() < 1e-12
                ? Quat::Identity()
                : Quat(Eigen::AngleAxisd(std::atan2(axis.norm(), -n.z()), axis.normalized()));
        s.particles.push_back(body(0, Vec3(1e-3, 2e-3, 1.2e-3), Vec3::Zero(), Vec3::Zero(), q));
        System sys(s);
        for (int k = 0; k < 50000; ++k) {
            sys.step();
        }
        const auto& p = sys.particles();
        EXPECT_LT(p.v[0].norm(), 1e-4) << (mesh ? "mesh" : "plane");
        EXPECT_LT(p.omega[0].norm(), 1e-2) << (mesh ? "mesh" : "plane");
        // Still face-down: the face normal points along -z within 1e-4 rad.
        EXPECT_GT(-(p.q[0] * n).z(), 1.0 - 1e-8) << (mesh ? "mesh" : "plane");
        // Resting height: half edge minus the static overlap (micrometres).
        EXPECT_NEAR(p.x[0].z(), 1.13e-3, 2e-5) << (mesh ? "mesh" : "plane");
    }
}

TEST(Polyhedra, SphereOnAMeshFloorRestsAsOnAPlane) {
    double z[2] = {0, 0};
    for (const int mesh : {0, 1}) {
        SceneSpec s = base_scene();
        s.gravity = Vec3(0, 0, -9.81);
        if (mesh != 0) {
            io::MeshInput m = io::read_mesh_file(
                std::filesystem::path(KILN_SOURCE_DIR) / "shapes" / "wall_box_20mm.stl", 1e-3);
            s.mesh_walls.push_back(
                {"floor", std::make_shared<const geometry::MeshWall>(m.points, m.triangles, "box"),
                 0});
        } else {
            s.walls.push_back({"floor", PlaneWall{Vec3::Zero(), Vec3::UnitZ()}, 0});
        }
        // On the diagonal shared by the two top triangles: no bump, one contact.
        s.particles.emplace_back(0, 1.4e-3, Vec3(1e-3, 1e-3, 1.5e-3), Vec3(0.01, 0.01, 0),
                                 Vec3::Zero());
        System sys(s);
        for (int k = 0; k < 30000; ++k) {
            sys.step();
        }
        EXPECT_EQ(sys.counters().wall_contacts, 1);
        z[mesh] = sys.particles().x[0].z();
    }
    EXPECT_NEAR(z[1], z[0], 1e-9); // same law, same overlap: equal to round-off of the settling
}

TEST(Polyhedra, SuperquadricsAgainstMeshWallsAreNotYetSupported) {
    SceneSpec s = base_scene();
    io::MeshInput m = io::read_mesh_file(
        std::filesystem::path(KILN_SOURCE_DIR) / "shapes" / "wall_box_20mm.stl", 1e-3);
    s.mesh_walls.push_back(
        {"floor", std::make_shared<const geometry::MeshWall>(m.points, m.triangles, "box"), 0});
    s.shapes.push_back(shape("ellipsoid_123"));
    s.particles.push_back(body(0, Vec3(0, 0, 0.005)));
    EXPECT_THROW(System{s}, InputError);
}

TEST(Polyhedra, SavedStateContinuesBitForBit) {
    SceneSpec s = base_scene();
    s.gravity = Vec3(0, 0, -9.81);
    s.walls.push_back({"floor", PlaneWall{Vec3::Zero(), Vec3::UnitZ()}, 0});
    s.shapes.push_back(shape("cube"));
    s.shapes.push_back(shape("icosahedron"));
    for (int k = 0; k < 4; ++k) {
        const Quat q(Eigen::AngleAxisd(0.3 * k, Vec3(1, 1, 0).normalized()));
        s.particles.push_back(
            body(k % 2, Vec3(0.0042 * k, 0.0, 0.0022), Vec3(-0.05 * k, 0.0, 0.0), Vec3::Zero(), q));
    }
    System a(s);
    // Save during the first landing, so that the state carries contact histories.
    while (a.counters().wall_contacts == 0 && a.step_count() < 20000) {
        a.step();
    }
    for (int k = 0; k < 20; ++k) {
        a.step();
    }
    const SystemState saved = a.save_state();
    EXPECT_GT(saved.body_contacts.size(), 0U); // the state holds contact histories

    for (int k = 0; k < 3000; ++k) {
        a.step();
    }
    System b(s);
    b.restore_state(saved);
    for (int k = 0; k < 3000; ++k) {
        b.step();
    }
    for (std::size_t i = 0; i < a.particles().size(); ++i) {
        EXPECT_EQ(a.particles().x[i], b.particles().x[i]);
        EXPECT_EQ(a.particles().q[i].coeffs(), b.particles().q[i].coeffs());
    }
}

} // namespace
} // namespace kiln::dynamics
