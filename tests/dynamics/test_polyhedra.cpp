// Polyhedron particles and mesh walls in the step loop: pair and sphere contacts keep momentum,
// both narrow phases agree, walls hold a body at rest, mesh walls act like analytic ones, refusals
// and the saved state.

#include "body_scene.hpp"
#include "core/error.hpp"
#include "dynamics/system.hpp"
#include "geometry/hull.hpp"
#include "io/shape_reader.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <gtest/gtest.h>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <random>

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
        test::add_floor(s, mesh);
        const auto& cube = std::get<geometry::ConvexPolyhedron>(s.shapes[0].shape);
        const Vec3 n = geometry::polyhedron_features(cube).face_normals[0];
        const Quat q = test::face_down(cube);
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
        test::add_floor(s, mesh != 0);
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

TEST(Polyhedra, SuperquadricOnAMeshFloorRestsAsOnAPlane) {
    // A tilted ellipsoid settles on the top face of an STL box (across the diagonal shared by its
    // two triangles) and on an analytic plane: one contact, and the same height and attitude.
    Vec3 x[2];
    Quat q[2];
    for (const int mesh : {0, 1}) {
        SceneSpec s = base_scene();
        s.gravity = Vec3(0, 0, -9.81);
        test::add_floor(s, mesh != 0);
        s.shapes.push_back(shape("ellipsoid_123"));
        const Quat q0(Eigen::AngleAxisd(1.2, Vec3(1, 0.3, 0).normalized()));
        s.particles.push_back(
            body(0, Vec3(0.5e-3, 0.5e-3, 3.2e-3), Vec3(0.01, 0.01, 0), Vec3::Zero(), q0));
        System sys(s);
        for (int k = 0; k < 40000; ++k) {
            sys.step();
        }
        EXPECT_EQ(sys.counters().wall_contacts, 1) << mesh;
        EXPECT_EQ(sys.narrow_phase_counters().failures, 0) << mesh;
        x[mesh] = sys.particles().x[0];
        q[mesh] = sys.particles().q[0];
    }
    // Same law, same overlap and lever arm: the paths agree to the round-off of the settling.
    EXPECT_LT((x[1] - x[0]).norm(), 1e-9);
    EXPECT_LT(q[1].angularDistance(q[0]), 1e-6);
}

TEST(Polyhedra, ClumpOnAMeshFloorRestsAsOnAPlane) {
    // The 12-sphere cylinder clump settles on the top face of an STL box and on an analytic plane:
    // the same contacts at the same height.
    Vec3 x[2];
    long contacts[2] = {0, 0};
    for (const int mesh : {0, 1}) {
        SceneSpec s = base_scene();
        s.gravity = Vec3(0, 0, -9.81);
        test::add_floor(s, mesh != 0);
        s.shapes.push_back(shape("cylinder_12"));
        // The ParticleSpec radius is left unset, as a case file's body particle has it.
        s.particles.push_back(body(0, Vec3(0.3e-3, 0.2e-3, 3.05e-3)));
        System sys(s);
        for (int k = 0; k < 30000; ++k) {
            sys.step();
        }
        contacts[mesh] = sys.counters().wall_contacts;
        x[mesh] = sys.particles().x[0];
    }
    // The template's principal frame lays the cylinder on its side: one sphere of each ring
    // touches, on the plane and on the mesh alike.
    EXPECT_EQ(contacts[0], 2);
    EXPECT_EQ(contacts[1], contacts[0]);
    EXPECT_LT((x[1] - x[0]).norm(), 1e-9); // same law, same overlaps: round-off of the settling
    EXPECT_LT(x[1].z(), 3.0e-3);           // it came down onto its lower spheres (z = 3 mm)
}

namespace {

/// Overlap of two posed convex shapes along unit n (from b to a): h_b(n) + h_a(-n) (m).
template <class A, class B> double overlap_along(const A& a, const B& b, const Vec3& n) {
    return n.dot(b.support(n)) - n.dot(a.support(-n));
}

/// Brute-force MTD of two convex shapes: the smallest overlap over a Fibonacci sphere of
/// directions, refined by shrinking random steps (m); best_n receives the normal (b to a).
template <class A, class B> double brute_mtd(const A& a, const B& b, Vec3& best_n) {
    double best = std::numeric_limits<double>::infinity();
    const int n_dirs = 20000;
    for (int k = 0; k < n_dirs; ++k) {
        const double z = 1.0 - (2.0 * k + 1.0) / n_dirs;
        const double phi = k * std::numbers::pi * (3.0 - std::sqrt(5.0));
        const Vec3 n(std::sqrt(1 - z * z) * std::cos(phi), std::sqrt(1 - z * z) * std::sin(phi), z);
        const double d = overlap_along(a, b, n);
        if (d < best) {
            best = d;
            best_n = n;
        }
    }
    std::mt19937 rng(11);
    std::normal_distribution<double> gauss;
    for (double step = 0.03; step > 1e-8; step *= 0.85) {
        for (int k = 0; k < 200; ++k) {
            const Vec3 n = (best_n + step * Vec3(gauss(rng), gauss(rng), gauss(rng))).normalized();
            const double d = overlap_along(a, b, n);
            if (d < best) {
                best = d;
                best_n = n;
            }
        }
    }
    return best;
}

/// A cube pressed into a superball in a random pose: the ball (element 0) at the origin, the
/// cube (element 1) along a random unit direction `dir` where the two supports along it overlap
/// by 2e-4 m, and both as posed bodies (for brute_mtd). Draws the cube's and the ball's
/// orientations and `dir` from `rng`, in that order.
struct CubeInBall {
    std::vector<Element> e;
    geometry::PosedPolyhedron cube;
    geometry::PosedSuperquadric ball;
    Vec3 dir;
};

CubeInBall cube_pressed_into_ball(const geometry::ShapeTemplate& cube,
                                  const geometry::PolyhedronFeatures& f,
                                  const geometry::ShapeTemplate& ball, std::mt19937& rng) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const Quat qa(Eigen::AngleAxisd(3.0 * u(rng), Vec3(u(rng), u(rng), u(rng)).normalized()));
    const Quat qb(Eigen::AngleAxisd(3.0 * u(rng), Vec3(u(rng), u(rng), u(rng)).normalized()));
    const Vec3 dir = Vec3(u(rng), u(rng), u(rng)).normalized();
    std::vector<Element> e;
    append_elements(&ball, nullptr, Vec3::Zero(), qb, ball.bounding_radius(), e);
    const geometry::PosedSuperquadric pb{e[0].sq, Vec3::Zero(), qb};
    geometry::PosedPolyhedron pa{&f, Vec3::Zero(), qa};
    const double reach = dir.dot(pb.support(dir)) - dir.dot(pa.support(-dir) - pa.x);
    pa.x = (reach - 2e-4) * dir;
    append_elements(&cube, &f, pa.x, qa, cube.bounding_radius(), e);
    return {std::move(e), pa, pb, dir};
}

} // namespace

TEST(Polyhedra, CubeOnAnEllipsoidWhereEpaCyclesFallsBackToMpr) {
    // The pose of tests/geometry's CcdContact.EpaThatWouldCycleStopsAndMprAnswers (a cube and a
    // 1:2:3 ellipsoid of cases/hot_shapes where libccd's EPA cycles): the element contact must be
    // answered by MPR, flagged as a fallback, with the overlap measured along MPR's normal.
    const geometry::ShapeTemplate cube = shape("cube");
    const geometry::ShapeTemplate ell = shape("ellipsoid_123");
    const geometry::PolyhedronFeatures f =
        geometry::polyhedron_features(std::get<geometry::ConvexPolyhedron>(cube.shape));
    std::vector<Element> e;
    append_elements(&cube, &f,
                    Vec3(-0x1.10edbc65958c3p-8, 0x1.9a7a89ba1070cp-7, 0x1.2724b60aecacap-10),
                    Quat(-0x1.f6890899daa41p-1, 0x1.5f2558bf2684fp-24, -0x1.08b91d53681c6p-17,
                         -0x1.87f709e2434bbp-3),
                    cube.bounding_radius(), e);
    append_elements(&ell, nullptr,
                    Vec3(-0x1.fc9e6946e4ec1p-8, 0x1.5589800c84051p-7, 0x1.a1de5b7c483cp-10),
                    Quat(-0x1.ac282ef99da12p-2, 0x1.60b2b25439d6ap-1, -0x1.034529d699981p-3,
                         0x1.282bbe5bec728p-1),
                    ell.bounding_radius(), e);
    ASSERT_EQ(e.size(), 2U);
    const ElementContact c = element_contact(e[0], e[1], NarrowPhase::newton, nullptr);
    EXPECT_TRUE(c.converged);
    EXPECT_TRUE(c.fell_back);
    ASSERT_TRUE(c.touching);
    EXPECT_GT(c.overlap, 0.0);
    EXPECT_LT(c.overlap, 1e-5); // a light touch: 3.0e-6 m measured
}

TEST(Polyhedra, CubeOnASuperballMatchesBruteForce) {
    // Random poses of a cube pressed into a superball (exponent 4): element_contact's overlap and
    // normal (libccd GJK/EPA, the normal refined where EPA's bounds differ by more than 0.1 %, the
    // overlap evaluated along it) against the brute-force minimum of h_b(n) + h_a(-n) over
    // directions.
    const geometry::ShapeTemplate cube = shape("cube");
    const geometry::ShapeTemplate ball = shape("superball");
    const geometry::PolyhedronFeatures f =
        geometry::polyhedron_features(std::get<geometry::ConvexPolyhedron>(cube.shape));
    std::mt19937 rng(5);
    int touching = 0;
    for (int k = 0; k < 60; ++k) {
        const CubeInBall pose = cube_pressed_into_ball(cube, f, ball, rng);
        const std::vector<Element>& e = pose.e;
        Vec3 n_ref = Vec3::UnitX();
        const double mtd = brute_mtd(pose.cube, pose.ball, n_ref);
        for (const bool swap : {false, true}) {
            const ElementContact c =
                swap ? element_contact(e[0], e[1], NarrowPhase::newton, nullptr)
                     : element_contact(e[1], e[0], NarrowPhase::newton, nullptr);
            ASSERT_TRUE(c.converged) << k;
            ASSERT_EQ(c.touching, mtd > 0.0) << k << " " << mtd;
            if (!c.touching) {
                continue;
            }
            const Vec3 n = swap ? Vec3(-c.normal) : c.normal;
            // Both are upper bounds of the MTD (overlaps along a found direction); the brute
            // force's is good to its last step (0.2 %). The contact's is within 0.1 % of the MTD
            // (refined, or EPA's bounds within 0.1 %), so not above the brute force's by more.
            EXPECT_NEAR(c.overlap, mtd, 2e-3 * mtd) << k;
            EXPECT_LT(c.overlap, mtd + 1e-3 * mtd) << k;
            EXPECT_GT(n.dot(n_ref), 1.0 - 1e-3) << k;
            EXPECT_GT(c.r_eff, 0.0);
            touching += swap ? 0 : 1;
        }
    }
    EXPECT_GT(touching, 30);
}

TEST(Polyhedra, PersistentCubeOnASuperballMatchesBruteForce) {
    // As above, but as a pair that touched at the last step: EPA is skipped and the normal refined
    // from the last one (here the best normal turned by about 2e-3 rad, a step's rotation at
    // 400 rad/s and dt 5e-6 s). The same bounds as from EPA.
    const geometry::ShapeTemplate cube = shape("cube");
    const geometry::ShapeTemplate ball = shape("superball");
    const geometry::PolyhedronFeatures f =
        geometry::polyhedron_features(std::get<geometry::ConvexPolyhedron>(cube.shape));
    std::mt19937 rng(7);
    int touching = 0;
    for (int k = 0; k < 60; ++k) {
        const CubeInBall pose = cube_pressed_into_ball(cube, f, ball, rng);
        const std::vector<Element>& e = pose.e;
        Vec3 n_ref = Vec3::UnitX();
        const double mtd = brute_mtd(pose.cube, pose.ball, n_ref);
        if (!(mtd > 0.0)) {
            continue;
        }
        const Vec3 tilt = n_ref.unitOrthogonal();
        const Vec3 last = (n_ref + 2e-3 * tilt).normalized(); // from the ball to the cube
        for (const bool swap : {false, true}) {
            const Vec3 warm = swap ? Vec3(-last) : last;
            const ElementContact c =
                swap ? element_contact(e[0], e[1], NarrowPhase::newton, &warm, nullptr, true)
                     : element_contact(e[1], e[0], NarrowPhase::newton, &warm, nullptr, true);
            ASSERT_TRUE(c.converged) << k;
            ASSERT_TRUE(c.touching) << k << " " << mtd;
            const Vec3 n = swap ? Vec3(-c.normal) : c.normal;
            EXPECT_NEAR(c.overlap, mtd, 2e-3 * mtd) << k;
            EXPECT_LT(c.overlap, mtd + 1e-3 * mtd) << k;
            EXPECT_GT(n.dot(n_ref), 1.0 - 1e-3) << k;
            touching += swap ? 0 : 1;
        }
    }
    EXPECT_GT(touching, 30);
}

TEST(Polyhedra, CubeFaceOnAnEllipsoidActsAboveTheEllipsoidsDeepestPoint) {
    // A cube lies face down on an ellipsoid's top, off-centre. The overlap is the MTD along the
    // face normal, and its gradient with respect to the cube's rotation is that of a force through
    // the ellipsoid's deepest point (the cube's support along the normal is the whole face, the
    // ellipsoid's a single point; Danskin), so the contact point lies on the normal through that
    // point, half way into the overlap. The midpoint of a face vertex and that point, used before,
    // was off by half the face's extent and made the torque non-conservative (validation 14).
    const geometry::ShapeTemplate cube = shape("cube");
    const geometry::ShapeTemplate ell = shape("ellipsoid_123");
    const geometry::PolyhedronFeatures f =
        geometry::polyhedron_features(std::get<geometry::ConvexPolyhedron>(cube.shape));
    std::vector<Element> e;
    append_elements(&ell, nullptr, Vec3::Zero(), Quat::Identity(), ell.bounding_radius(), e);
    const geometry::PosedSuperquadric pe{e[0].sq, Vec3::Zero(), Quat::Identity()};
    const Vec3 top = pe.support(Vec3::UnitZ()); // (0, 0, 3 mm)
    geometry::PosedPolyhedron pc{&f, Vec3::Zero(), Quat::Identity()};
    const double half = -pc.support(-Vec3::UnitZ()).z(); // the cube's half edge
    const double overlap = 2e-5;
    const Vec3 x(0.5e-3, 0.3e-3, top.z() + half - overlap);
    append_elements(&cube, &f, x, Quat::Identity(), cube.bounding_radius(), e);
    for (const bool persistent : {false, true}) {
        const Vec3 warm(0.0, 1e-3, 1.0);
        const Vec3 w = warm.normalized();
        const ElementContact c = element_contact(e[1], e[0], NarrowPhase::newton,
                                                 persistent ? &w : nullptr, nullptr, persistent);
        ASSERT_TRUE(c.touching) << persistent;
        EXPECT_NEAR(c.overlap, overlap, 1e-12) << persistent;
        EXPECT_GT(c.normal.z(), 1.0 - 1e-12) << persistent;
        EXPECT_NEAR(c.point.x(), top.x(), 1e-9) << persistent;
        EXPECT_NEAR(c.point.y(), top.y(), 1e-9) << persistent;
        EXPECT_NEAR(c.point.z(), top.z() - 0.5 * overlap, 1e-9) << persistent;
    }
}

TEST(Polyhedra, ContactsWithoutTheRadiusChangeNothingElse) {
    // element_contact and element_wall_contact with `radius` false (a contact whose R* of its
    // first step is kept): r_eff 0, every other field the same bits, for superquadric pairs,
    // polyhedron-superquadric pairs (from EPA and from a last normal) and a superquadric on a
    // plane.
    const geometry::ShapeTemplate cube = shape("cube");
    const geometry::ShapeTemplate ball = shape("superball");
    const geometry::ShapeTemplate ell = shape("ellipsoid_123");
    const geometry::PolyhedronFeatures f =
        geometry::polyhedron_features(std::get<geometry::ConvexPolyhedron>(cube.shape));
    std::mt19937 rng(11);
    const auto same = [](const ElementContact& x, const ElementContact& y) {
        EXPECT_EQ(x.touching, y.touching);
        EXPECT_EQ(x.overlap, y.overlap);
        EXPECT_EQ(x.normal, y.normal);
        EXPECT_EQ(x.point, y.point);
        EXPECT_EQ(y.r_eff, 0.0);
    };
    int touching = 0;
    for (int k = 0; k < 40; ++k) {
        CubeInBall pose = cube_pressed_into_ball(cube, f, ball, rng);
        std::vector<Element>& e = pose.e;
        append_elements(&ell, nullptr, Vec3::Zero(), pose.cube.q, ell.bounding_radius(), e);
        e[2].centre = pose.cube.x; // an ellipsoid where the cube is
        const Vec3 warm = pose.dir;
        for (const auto& [i, j] : {std::pair{1, 0}, std::pair{0, 1}, std::pair{2, 0}}) {
            for (const bool last : {false, true}) {
                const Vec3 w = i == 0 ? Vec3(-warm) : warm;
                const ElementContact with =
                    element_contact(e[static_cast<std::size_t>(i)], e[static_cast<std::size_t>(j)],
                                    NarrowPhase::newton, &w, nullptr, last);
                const ElementContact without =
                    element_contact(e[static_cast<std::size_t>(i)], e[static_cast<std::size_t>(j)],
                                    NarrowPhase::newton, &w, nullptr, last, nullptr, false);
                same(with, without);
                touching += with.touching && with.r_eff > 0.0 ? 1 : 0;
            }
        }
        const WallShape floor = PlaneWall{Vec3(0.0, 0.0, -1.2e-3), Vec3::UnitZ()};
        const ElementContact with = element_wall_contact(e[0], floor);
        same(with, element_wall_contact(e[0], floor, false));
        touching += with.touching && with.r_eff > 0.0 ? 1 : 0;
    }
    EXPECT_GT(touching, 60);
}

TEST(Polyhedra, CubeAndSuperballCollideKeepingMomentum) {
    // The pair runs in the step loop: a cube and a superball in one scene collide off-centre;
    // momentum and angular momentum are exchanged pairwise and no query fails.
    SceneSpec s = base_scene();
    s.shapes.push_back(shape("cube"));
    s.shapes.push_back(shape("superball"));
    const double ra = s.shapes[0].bounding_radius();
    const double rb = s.shapes[1].bounding_radius();
    const Quat q(Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized()));
    s.particles.push_back(body(0, Vec3(-ra - 1e-5, 0.2e-3, 0), Vec3(0.5, 0, 0), Vec3(0, 20, 0), q));
    s.particles.push_back(
        body(1, Vec3(rb + 1e-5, -0.2e-3, 0.1e-3), Vec3(-0.5, 0, 0), Vec3(5, 0, 0), q.conjugate()));
    System sys(s);
    const Vec3 p0 = momentum(sys);
    const Vec3 l0 = angular_momentum(sys);
    long contacts = 0;
    for (int k = 0; k < 15000; ++k) {
        sys.step();
        contacts += sys.counters().particle_contacts;
    }
    EXPECT_GT(contacts, 10);
    EXPECT_EQ(sys.narrow_phase_counters().failures, 0);
    EXPECT_LT((momentum(sys) - p0).norm(), kMomentumRounding);
    EXPECT_LT((angular_momentum(sys) - l0).norm(), 1e-9 * l0.norm()); // pairwise: round-off
    // They separated after one collision (coefficient of restitution 0.5 in the material).
    EXPECT_GT((sys.particles().x[0] - sys.particles().x[1]).norm(), ra + rb);
}

/// A pour of cubes, icosahedra, blocky (e = 0.3) and smooth (e = 0.8) superquadrics and a few
/// spheres into a tube: every kind of convex pair meets, with many near misses.
SceneSpec convex_pour() {
    SceneSpec s = base_scene();
    s.gravity = Vec3(0, 0, -9.81);
    s.shapes.push_back(shape("cube"));
    s.shapes.push_back(shape("icosahedron"));
    s.shapes.push_back(test::superquadric(Vec3(1.5e-3, 1e-3, 1e-3), 0.3, 0.3));
    s.shapes.push_back(test::superquadric(Vec3(1.2e-3, 1.2e-3, 1e-3), 0.8, 0.8));
    s.walls.push_back({"floor", PlaneWall{Vec3::Zero(), Vec3::UnitZ()}, 0});
    s.walls.push_back({"tube", CylinderWall{Vec3::Zero(), Vec3::UnitZ(), 0.012}, 0});
    for (int k = 0; k < 5; ++k) {
        InsertSpec ins;
        ins.region = {Vec3(-0.008, -0.008, 0.001 + 0.01 * k), Vec3(0.008, 0.008, 0.01 * (k + 1))};
        ins.count = k < 4 ? 10 : 6;
        ins.shape = k < 4 ? k : -1;
        ins.size.radius = k < 4 ? s.shapes[static_cast<std::size_t>(k)].bounding_radius() : 1e-3;
        ins.orientation.random = true;
        ins.velocity = Vec3(0, 0, -0.3 - 0.2 * k);
        s.inserts.push_back(ins);
    }
    return s;
}

/// Steps two systems `steps` times side by side, asserting the same particle contact count at
/// every step; `contacts` sums `with`'s counts.
void step_both(System& with, System& without, int steps, long& contacts) {
    for (int k = 0; k < steps; ++k) {
        with.step();
        without.step();
        contacts += with.counters().particle_contacts;
        ASSERT_EQ(with.counters().particle_contacts, without.counters().particle_contacts) << k;
    }
}

TEST(Polyhedra, SeparationCacheChangesNoBit) {
    // The separating direction kept per list entry (and the portal search of superquadric near
    // misses) only skips queries whose answer is "apart": a pour with it and one without give the
    // same bits, and it did skip queries.
    System with(convex_pour());
    System without(convex_pour());
    without.use_separation_cache(false);
    long contacts = 0;
    ASSERT_NO_FATAL_FAILURE(step_both(with, without, 30000, contacts));
    EXPECT_GT(contacts, 20000);
    EXPECT_GT(with.separation_skips(), 100000);
    EXPECT_EQ(without.separation_skips(), 0);
    test::expect_same_bits(with.particles(), without.particles());
    std::printf("%ld contacts, %ld of %ld convex queries answered by a separating direction\n",
                contacts, with.separation_skips(), with.narrow_phase_counters().calls);
}

TEST(Polyhedra, OneAndTwoThreadsGiveTheSameBits) {
    // With two threads the narrow phase of pairs of single convex bodies (polyhedra,
    // superquadrics, and either against a sphere) runs ahead of the serial pass, in parallel;
    // each query keeps its entry's cached direction, proof and plane memory. The convex pour gives
    // the same contacts at every step, the same counts and the same bits as with one thread.
    // Clumps (12-sphere cylinders) on top, falling fastest, so that their members meet the
    // polyhedra and superquadrics (the general route, planned ahead with two threads).
    SceneSpec one_spec = convex_pour();
    one_spec.shapes.push_back(shape("cylinder_12"));
    InsertSpec clumps;
    clumps.region = {Vec3(-0.008, -0.008, 0.051), Vec3(0.008, 0.008, 0.085)};
    clumps.count = 5;
    clumps.shape = static_cast<int>(one_spec.shapes.size()) - 1;
    clumps.size.radius = one_spec.shapes.back().bounding_radius();
    clumps.orientation.random = true;
    clumps.velocity = Vec3(0, 0, -1.5);
    one_spec.inserts.push_back(clumps);
    one_spec.threads = 1;
    SceneSpec two_spec = one_spec;
    two_spec.threads = 2;
    System one(one_spec);
    System two(two_spec);
    ASSERT_EQ(two.threads(), 2);
    long contacts = 0;
    ASSERT_NO_FATAL_FAILURE(step_both(two, one, 18000, contacts));
    EXPECT_GT(contacts, 20000);
    test::expect_same_bits(one.particles(), two.particles());
    EXPECT_EQ(one.counters().wall_contacts, two.counters().wall_contacts);
    EXPECT_EQ(one.narrow_phase_counters().calls, two.narrow_phase_counters().calls);
    EXPECT_EQ(one.narrow_phase_counters().fallbacks, two.narrow_phase_counters().fallbacks);
    EXPECT_EQ(one.narrow_phase_counters().failures, 0);
    EXPECT_EQ(two.narrow_phase_counters().failures, 0);
    EXPECT_EQ(one.separation_skips(), two.separation_skips());
    EXPECT_GT(one.separation_skips(), 100000);
    // The records of the contacts (read by heat and the output) are the same too.
    const std::size_t records = test::expect_same_records(one, two);
    std::printf("%ld contacts, %ld narrow-phase queries, %zu contacts at the end\n", contacts,
                two.narrow_phase_counters().calls, records);
}

TEST(Polyhedra, PlaneMemoChangesNoBit) {
    // The memory of a touching polyhedron pair's last common-plane search (geometry::PlaneMemo)
    // only skips candidates that cannot win: the convex pour with it and without it gives the
    // same bits, and the memory answered queries.
    System with(convex_pour());
    System without(convex_pour());
    without.use_plane_memo(false);
    const long answered0 = kiln::geometry::plane_memo_counters().answered;
    long contacts = 0;
    ASSERT_NO_FATAL_FAILURE(step_both(with, without, 30000, contacts));
    const long answered = kiln::geometry::plane_memo_counters().answered - answered0;
    EXPECT_GT(contacts, 20000);
    EXPECT_GT(answered, 1000);
    test::expect_same_bits(with.particles(), without.particles());
    std::printf("%ld contacts, %ld polyhedron queries answered by the memory\n", contacts,
                answered);
}

TEST(Polyhedra, ConvexBlocksAgreeWithTheOneContactRoute) {
    // Contacts of convex elements (pairs and walls) go through the law in blocks of vector lanes;
    // the route before (one contact at a time) is kept behind a switch. From the same state, one
    // step of each finds the same contacts in the same order with the same geometry, and forces,
    // histories, velocities and angular momenta that agree to round-off. Not bit for bit: GCC
    // contracts a * b + c into fused multiply-adds (-ffp-contract=fast) differently in the two
    // routes (e.g. in v_rel = v_a + w_a x r_a - v_b - w_b x r_b), one rounding of ~1e-16 relative
    // per operation. Tolerance: 1e-12 of the step's largest contact force (or history), four
    // decades above such round-off after the law's square roots and Coulomb cap, and ten below
    // any error of physics (a wrong lever arm, sign or mass is of the order of the force).
    const SceneSpec spec = convex_pour();
    System sys(spec);
    const double dt = sys.spec().time_step;
    long compared = 0;
    double worst = 0.0; // largest force difference seen, relative to the step's largest force
    for (int round = 0; round < 120; ++round) { // 30 000 steps of the pour
        for (int k = 0; k < 249; ++k) {
            sys.step();
        }
        System same = sys; // the copy is faithful: the same route gives the same bits
        System single = sys;
        single.use_convex_blocks(false);
        sys.step();
        same.step();
        single.step();
        const std::vector<BodyContactEntry>& cb = sys.body_contacts();
        const std::vector<BodyContactEntry>& cs = single.body_contacts();
        ASSERT_EQ(cb.size(), cs.size()) << round;
        double f_max = 0.0;
        double s_max = 0.0;
        for (const BodyContactEntry& e : cb) {
            f_max = std::max(f_max, e.contact.force.norm());
            s_max = std::max(s_max, e.contact.shear.norm());
        }
        for (std::size_t i = 0; i < cb.size(); ++i) {
            const BodyContact& b = cb[i].contact;
            const BodyContact& s = cs[i].contact;
            ASSERT_TRUE(cb[i].key == cs[i].key) << round << " " << i;
            EXPECT_EQ(b.normal, s.normal); // the narrow phase is the same in both
            EXPECT_EQ(b.point, s.point);
            EXPECT_EQ(b.overlap, s.overlap);
            EXPECT_EQ(b.r_eff, s.r_eff);
            EXPECT_LE((b.force - s.force).norm(), 1e-12 * f_max) << round << " " << i;
            worst = std::max(worst, (b.force - s.force).norm() / f_max);
            EXPECT_LE((b.shear - s.shear).norm(), 1e-12 * s_max) << round << " " << i;
        }
        compared += static_cast<long>(cb.size());
        const ParticleStore& p = sys.particles();
        const ParticleStore& q = single.particles();
        const ParticleStore& r = same.particles();
        ASSERT_EQ(p.size(), q.size());
        for (std::size_t i = 0; i < p.size(); ++i) {
            EXPECT_EQ(p.x[i], r.x[i]);
            EXPECT_EQ(p.v[i], r.v[i]);
            EXPECT_EQ(p.ang_mom[i], r.ang_mom[i]);
            // Positions of this step are drifted before the forces: the same bits.
            EXPECT_EQ(p.x[i], q.x[i]);
            // A half kick of the step's force: its round-off scaled by dt / m (lever arm r).
            EXPECT_LE((p.v[i] - q.v[i]).norm(), 1e-12 * f_max * dt / p.mass[i]) << i;
            EXPECT_LE((p.ang_mom[i] - q.ang_mom[i]).norm(), 1e-12 * f_max * dt * p.radius[i]) << i;
        }
    }
    EXPECT_GT(compared, 500);
    std::printf("%ld element contacts compared, largest force difference %.2g of the step's "
                "largest force\n",
                compared, worst);
}

/// Boxes poured into a tube: cubes, cuboids and plates (three boxes along their body axes).
SceneSpec box_pour() {
    SceneSpec s = base_scene();
    s.gravity = Vec3(0, 0, -9.81);
    s.shapes.push_back(shape("cube"));
    s.shapes.push_back(shape("cuboid_6x6x5"));
    s.shapes.push_back(shape("plate_10x9x2"));
    s.walls.push_back({"floor", PlaneWall{Vec3::Zero(), Vec3::UnitZ()}, 0});
    s.walls.push_back({"tube", CylinderWall{Vec3::Zero(), Vec3::UnitZ(), 0.012}, 0});
    // (bottom, top, half width) of each layer's region (m), and its count.
    const std::array<std::array<double, 3>, 3> region{
        {{0.002, 0.03, 0.0075}, {0.032, 0.062, 0.006}, {0.064, 0.08, 0.0075}}};
    const std::array<int, 3> count{48, 2, 1};
    for (std::size_t k = 0; k < 3; ++k) {
        InsertSpec ins;
        const double w = region[k][2];
        ins.region = {Vec3(-w, -w, region[k][0]), Vec3(w, w, region[k][1])};
        ins.count = count[k];
        ins.shape = static_cast<int>(k);
        ins.size.radius = s.shapes[k].bounding_radius();
        ins.orientation.random = true;
        ins.velocity = Vec3(0, 0, k == 0 ? -0.5 : -1.0);
        s.inserts.push_back(ins);
    }
    return s;
}

TEST(Polyhedra, BoxLanesAgreeWithElementContact) {
    // Resting pairs of two boxes take their narrow phase eight at a time in vector lanes
    // (box_pair_contacts: the relative pose from rotation matrices, the closed-form plane, the
    // depth and the near corners from the half extents), the others element_contact. From the
    // same state, one step of each route finds the same contacts, with the same geometry and
    // forces to round-off. Tolerances, from the two routes' arithmetic: the normal to 1e-12 (both
    // from the same closed form, the relative pose rounded differently, ~1e-16); the overlap to
    // 1e-12 of the boxes' size s (heights of size ~1 mm differenced: ~1e-19 m); the point to
    // 1e-12 s + 2 R x 1e-15 R / (0.02 overlap), R the pair's reach (the sum of the bodies'
    // bounding radii): the band weights 1 - below / band carry a round-off of the corners'
    // heights, which both routes compute from coordinates of up to R in A's frame (a few
    // roundings: <= 1e-15 R), divided by the band (2 % of the overlap), and move the point by
    // that times the spread of the near corners (a body's diameter, <= 2 R); forces and histories
    // to 1e-9 of the step's largest (through the point and the overlap). Far below any error of
    // geometry (a wrong corner or sign moves the point by the size and the overlap by itself).
    const SceneSpec spec = box_pour();
    System sys(spec);
    const double size = 1e-3; // the smallest half extent of the three boxes is about 1 mm
    long compared = 0;
    long lanes = 0;
    double worst_point = 0.0;
    double worst_overlap = 0.0;
    double worst_point_tol = 0.0; // the largest point difference as a fraction of its tolerance
    for (int round = 0; round < 100; ++round) { // 50 000 steps: the pour lands and rests
        for (int k = 0; k < 499; ++k) {
            sys.step();
        }
        System off = sys;
        off.use_box_lanes(false);
        const long lanes0 = sys.box_lane_pairs();
        sys.step();
        off.step();
        lanes += sys.box_lane_pairs() - lanes0;
        EXPECT_EQ(off.box_lane_pairs(), lanes0); // off: none in lanes
        const std::vector<BodyContactEntry>& cl = sys.body_contacts();
        const std::vector<BodyContactEntry>& co = off.body_contacts();
        ASSERT_EQ(cl.size(), co.size()) << round;
        double f_max = 0.0;
        double s_max = 0.0;
        for (const BodyContactEntry& e : co) {
            f_max = std::max(f_max, e.contact.force.norm());
            s_max = std::max(s_max, e.contact.shear.norm());
        }
        const ParticleStore& p = sys.particles();
        std::map<std::int64_t, double> radius; // by id
        for (std::size_t i = 0; i < p.size(); ++i) {
            radius[p.id[i]] = p.radius[i];
        }
        for (std::size_t i = 0; i < cl.size(); ++i) {
            const BodyContact& l = cl[i].contact;
            const BodyContact& o = co[i].contact;
            ASSERT_TRUE(cl[i].key == co[i].key) << round << " " << i;
            const BodyContactKey& key = cl[i].key;
            const double reach = radius.at(key.a) + (key.b >= 0 ? radius.at(key.b) : 0.0);
            EXPECT_LE((l.normal - o.normal).norm(), 1e-12) << round << " " << i;
            EXPECT_LE(std::abs(l.overlap - o.overlap), 1e-12 * size) << round << " " << i;
            const double point_tol =
                1e-12 * size + 2.0 * reach * 1e-15 * reach / (0.02 * o.overlap);
            EXPECT_LE((l.point - o.point).norm(), point_tol) << round << " " << i;
            worst_point_tol = std::max(worst_point_tol, (l.point - o.point).norm() / point_tol);
            EXPECT_EQ(l.r_eff, o.r_eff);
            EXPECT_LE((l.force - o.force).norm(), 1e-9 * f_max) << round << " " << i;
            EXPECT_LE((l.shear - o.shear).norm(), 1e-9 * s_max) << round << " " << i;
            worst_point = std::max(worst_point, (l.point - o.point).norm() / size);
            worst_overlap = std::max(worst_overlap, std::abs(l.overlap - o.overlap) / size);
        }
        compared += static_cast<long>(cl.size());
    }
    EXPECT_GT(lanes, 500); // the route ran (the resting box pairs)
    EXPECT_GT(compared, 2000);
    std::printf("%ld element contacts compared, %ld box pairs in lanes; largest differences: "
                "point %.2g of 1 mm (%.2g of its tolerance), overlap %.2g of 1 mm\n",
                compared, lanes, worst_point, worst_point_tol, worst_overlap);
}

TEST(Polyhedra, BoxFilterChangesNoBit) {
    // The member build leaves out entries of two polyhedra whose boxes along their body axes are
    // more than a skin apart, and builds again when a body of one has moved half a skin (turns
    // included). Pours of boxes (cubes, cuboids, plates: a plate's box is a seventh of its
    // bounding sphere) and of cubes and icosahedra among superquadrics and spheres, with the
    // filter and without: the same contacts at every step, the same bits; entries were left out,
    // and the bodies' turns and motion called member builds between list builds.
    for (const bool boxes : {true, false}) {
        const SceneSpec spec = boxes ? box_pour() : convex_pour();
        System with(spec);
        System without(spec);
        without.use_box_filter(false);
        const long drops_at_start = without.box_filter_drops(); // the constructor's forces
        long contacts = 0;
        ASSERT_NO_FATAL_FAILURE(step_both(with, without, boxes ? 20000 : 15000, contacts));
        EXPECT_GT(contacts, 10000);
        EXPECT_GT(with.box_filter_drops(), boxes ? 2000 : 500);
        EXPECT_EQ(without.box_filter_drops(), drops_at_start);
        if (boxes) { // (the pour of mixed shapes rebuilds its list often enough)
            EXPECT_GT(with.member_builds(), with.neighbour_builds());
        }
        EXPECT_EQ(with.neighbour_builds(), without.neighbour_builds());
        test::expect_same_bits(with.particles(), without.particles());
        std::printf("%s: %ld contacts; %ld member builds (%ld without the filter), %ld entries "
                    "left out\n",
                    boxes ? "boxes" : "convex pour", contacts, with.member_builds(),
                    without.member_builds(), with.box_filter_drops());
    }
}

TEST(Polyhedra, SpinningPlateMeetsItsNeighbourBetweenListBuilds) {
    // Two plates (10 x 9 x 2 mm) side by side, 1.5 mm between their faces: more than the skin
    // (1.36 mm), so the box test leaves their entry out, though their bounding spheres overlap.
    // The first spins about its short axis at 200 rad/s with its centre at rest, so the list is
    // never rebuilt before they meet: only the member build called by its turn (travel_) can
    // bring the pair back in time. They must meet at the same step as without the filter.
    SceneSpec s = base_scene();
    s.shapes.push_back(shape("plate_10x9x2"));
    s.particles.push_back(body(0, Vec3::Zero(), Vec3::Zero(), Vec3(0, 0, 200)));
    s.particles.push_back(body(0, Vec3(0.0115, 0, 0)));
    System with(s);
    System without(s);
    without.use_box_filter(false);
    long first = -1;
    for (long k = 0; k < 4000; ++k) {
        with.step();
        without.step();
        ASSERT_EQ(with.counters().particle_contacts, without.counters().particle_contacts) << k;
        if (first < 0 && with.counters().particle_contacts > 0) {
            first = k;
            EXPECT_EQ(with.neighbour_builds(), 1); // the list was built once, at the start
        }
    }
    EXPECT_GT(first, 0); // they met
    EXPECT_GT(with.box_filter_drops(), 0);
    EXPECT_GT(with.member_builds(), 1);
    test::expect_same_bits(with.particles(), without.particles());
    std::printf("first contact at step %ld; %ld member builds, %ld list builds\n", first,
                with.member_builds(), with.neighbour_builds());
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

namespace kiln::dynamics {
namespace {

/// Penetration depth (m) of two convex polyhedron elements by the separating-axis theorem: the
/// smallest overlap (overlap_along, either sense) over every face normal of either body and every
/// cross product of an edge of one with an edge of the other. Brute force, for tests only.
double separating_axis_depth(const Element& a, const Element& b) {
    const geometry::PosedPolyhedron pa{a.poly, a.centre, a.q};
    const geometry::PosedPolyhedron pb{b.poly, b.centre, b.q};
    std::vector<Vec3> axes;
    for (const geometry::PosedPolyhedron* p : {&pa, &pb}) {
        for (const Vec3& n : p->shape->face_normals) {
            axes.push_back(p->q * n);
        }
    }
    const auto edge = [](const geometry::PosedPolyhedron& p, const std::array<int, 4>& e) {
        const std::vector<Vec3>& v = p.shape->vertices;
        return Vec3(p.q * (v[static_cast<std::size_t>(e[1])] - v[static_cast<std::size_t>(e[0])]));
    };
    for (const auto& ea : pa.shape->edges) {
        for (const auto& eb : pb.shape->edges) {
            const Vec3 ta = edge(pa, ea);
            const Vec3 tb = edge(pb, eb);
            const Vec3 c = ta.cross(tb);
            // Every direction bounds the depth from above, so even the noisy cross product of
            // nearly parallel edges is a valid candidate (and here the deciding one).
            if (c.norm() > 1e-14 * ta.norm() * tb.norm()) {
                axes.push_back(c.normalized());
            }
        }
    }
    double depth = std::numeric_limits<double>::infinity();
    for (const Vec3& n : axes) {
        depth = std::min({depth, overlap_along(pa, pb, n), overlap_along(pa, pb, -n)});
    }
    return depth;
}

TEST(Polyhedra, GjkEpaOverlapOfAShallowCubePairIsTheSeparatingAxisDepth) {
    // Two 2.26 mm cubes of the bed below, touching by 66 nm (3e-5 of the edge), as the bed of an
    // ASan build left them. With libccd's EPA tolerance of curved shapes (1e-10) EPA stopped on a
    // face whose normal was 1.1e-4 rad off, and the overlap along that normal was 179 nm: 2.7
    // times the true depth (kPolytopeEpaTolerance). Both narrow phases must give the
    // separating-axis depth to 1e-3 of it.
    const geometry::ShapeTemplate cube = shape("cube");
    const geometry::PolyhedronFeatures f =
        geometry::polyhedron_features(std::get<geometry::ConvexPolyhedron>(cube.shape));
    std::vector<Element> e;
    append_elements(&cube, &f,
                    Vec3(0x1.4e7e4581a0b82p-8, 0x1.14155c928e1e9p-6, 0x1.ff2e40f216807p-8),
                    Quat(-0x1.ddcdf1e8653bp-2, 0x1.2353860aaea78p-1, -0x1.793e06e621ab2p-2,
                         -0x1.22e58324a37a8p-1),
                    cube.bounding_radius(), e);
    append_elements(&cube, &f,
                    Vec3(0x1.728dd14467a2ep-8, 0x1.237bd5b6e2214p-6, 0x1.738aa9a722892p-8),
                    Quat(-0x1.08b20be8447d9p-4, 0x1.ed3ff4fea4bb1p-1, -0x1.092dfa115073ep-2,
                         0x1.a5debf48f00f5p-6),
                    cube.bounding_radius(), e);
    ASSERT_EQ(e.size(), 2U);
    const double depth = separating_axis_depth(e[0], e[1]);
    ASSERT_GT(depth, 5e-8);
    ASSERT_LT(depth, 8e-8);
    for (const NarrowPhase m : {NarrowPhase::newton, NarrowPhase::gjk_epa}) {
        const ElementContact c = element_contact(e[0], e[1], m, nullptr);
        ASSERT_TRUE(c.converged);
        ASSERT_TRUE(c.touching);
        EXPECT_NEAR(c.overlap, depth, 1e-3 * depth)
            << (m == NarrowPhase::newton ? "common plane" : "GJK/EPA");
    }
}

} // namespace
} // namespace kiln::dynamics

namespace kiln::dynamics {
namespace {

TEST(Polyhedra, GjkEpaWithItsNormalReversedFallsBackToTheCommonPlane) {
    // Eight pairs of 16-edged prisms from the GJK/EPA level of the shape atlas
    // (cases/pour_cylinders/tradeoff.toml), poses as recorded in that run (hex floats). Each pair
    // touches or is apart to within about 1e-6 m. libccd's GJK found every one intersecting and
    // its EPA returned a normal pointing the wrong way. Along that normal the overlap is the size
    // of the bodies (12-16 mm), and that force set the bed spinning. libccd's answer must now come
    // repaired (ccd_adapter.cpp), and the GJK/EPA route answer as the common plane does: the same
    // contact or none.
    const geometry::ShapeTemplate prism = shape("cylinder_16");
    const geometry::PolyhedronFeatures f =
        geometry::polyhedron_features(std::get<geometry::ConvexPolyhedron>(prism.shape));
    struct Pose {
        Vec3 x;
        Quat q;
    };
    const std::array<std::array<Pose, 2>, 8> pairs{{
        {{{Vec3(-0x1.3974485b5f15bp-11, 0x1.b10ee3a9e65f5p-10, 0x1.0a6fd64bd15e4p-7),
           Quat(0x1.66df5ae9949a7p-1, -0x1.3ba40a9c89ae3p-6, -0x1.8484d82be86a4p-4,
                0x1.69cc9c178cb1p-1)},
          {Vec3(-0x1.4570c3b4a2c77p-8, 0x1.d84be40d3cc8cp-8, 0x1.8a7cc63d3170cp-8),
           Quat(0x1.847be1c3c48f6p-1, 0x1.74e4b94cda307p-2, 0x1.12999e7e7a74bp-1,
                -0x1.040d1bf3abf04p-4)}}},
        {{{Vec3(0x1.c0f32749aa6c4p-10, 0x1.ea92f1108a0c2p-8, 0x1.e2dace610389ep-7),
           Quat(0x1.27f822182d3f4p-2, 0x1.074299e148606p-1, -0x1.0bd461a8a782bp-1,
                -0x1.3af840710edacp-1)},
          {Vec3(0x1.64bc1c2fb2304p-9, 0x1.c277a6f395261p-10, 0x1.2756ed9c52f46p-7),
           Quat(0x1.b0e1b4384a216p-1, -0x1.7998c7a38d7a4p-2, 0x1.43678b270d3a7p-3,
                -0x1.68f9981931bbfp-2)}}},
        {{{Vec3(0x1.02d3cb521f17dp-7, -0x1.410ab1e96ade4p-10, 0x1.0a620b969d96dp-5),
           Quat(-0x1.8cce218c7ee66p-3, 0x1.2d99a18921305p-6, -0x1.e4c04ab6b91edp-1,
                0x1.0687e1b60c95ap-2)},
          {Vec3(0x1.4da590d763e93p-9, -0x1.359817642c305p-11, 0x1.344cba41da6aap-5),
           Quat(-0x1.20b83799d79f8p-2, -0x1.02829b3de300bp-1, -0x1.2a2d7829e58bep-1,
                -0x1.2484a2d84360dp-1)}}},
        {{{Vec3(0x1.6a7457635616cp-9, -0x1.e2207e14687dap-15, 0x1.7f6e09c0539fbp-9),
           Quat(-0x1.7d847e3361252p-1, 0x1.346d15851fe59p-1, 0x1.722ca91abe344p-3,
                -0x1.c644332e8e9dfp-3)},
          {Vec3(0x1.99efd64ffbd18p-9, 0x1.e732bc1367d86p-10, 0x1.24fb39c81655p-7),
           Quat(0x1.2676a0c3ba9efp-4, -0x1.6546e2a73e539p-1, -0x1.f1abfdaf0f706p-5,
                -0x1.6b8f050b88bcfp-1)}}},
        {{{Vec3(-0x1.550e125738638p-8, -0x1.7be17abc5bf6ep-8, 0x1.80bf07bf020f4p-9),
           Quat(-0x1.0a5e1b52fafe8p-1, 0x1.b910c61959621p-2, 0x1.e18b60b0147dp-2,
                -0x1.22d65992bf271p-1)},
          {Vec3(0x1.fb834d67efc8cp-11, -0x1.182dfaab29817p-7, 0x1.8106f203b88b4p-9),
           Quat(0x1.78c860f90ec6bp-1, 0x1.2845b851c6228p-4, -0x1.0dc1063b6e1fdp-4,
                -0x1.5707ef90e72f2p-1)}}},
        {{{Vec3(0x1.010e491789aa3p-10, 0x1.e346de9d09b3cp-9, 0x1.34cd226fffadap-6),
           Quat(-0x1.f6222948b3685p-2, -0x1.4f7375f637284p-5, -0x1.99520989c4cf8p-1,
                0x1.60daf09be3d14p-2)},
          {Vec3(-0x1.85f9bcd0c95ccp-9, -0x1.1dd467545cb9bp-10, 0x1.cdab67f721402p-7),
           Quat(-0x1.4591048272356p-3, -0x1.8e2979dc8ed74p-1, 0x1.22563c70c7d29p-2,
                0x1.1385b5c9815cep-1)}}},
        {{{Vec3(-0x1.af3884bad499bp-8, 0x1.35584180e3b88p-8, 0x1.e76165378b9a2p-7),
           Quat(-0x1.6a06f5e3a539fp-1, 0x1.1b6670522613ep-3, 0x1.601bba37a4a38p-1,
                0x1.6ce2729770b0dp-4)},
          {Vec3(-0x1.dbd22f0065759p-8, 0x1.34b8a442e0d61p-8, 0x1.563fe80f04046p-6),
           Quat(0x1.1ffc2df4f05dap-1, -0x1.58ca5ad70bec8p-1, -0x1.5c63a38607ec6p-2,
                0x1.5a51e9e5dd8fap-2)}}},
        {{{Vec3(-0x1.2263f1fda82cep-8, -0x1.013ae82fb8eap-7, 0x1.e95236b64e885p-7),
           Quat(0x1.3266405d366e5p-3, -0x1.6434cff0f0f07p-1, -0x1.220c77b43028ap-3,
                -0x1.605426586f0f2p-1)},
          {Vec3(-0x1.082536b0678b5p-8, -0x1.017de512d59a1p-7, 0x1.574fb14fe84f7p-6),
           Quat(0x1.95bd199021561p-2, -0x1.2d3b12c303a01p-1, -0x1.914272a6b51cp-2,
                -0x1.2bfe306be5e96p-1)}}},
    }};
    int reversed = 0;
    for (std::size_t k = 0; k < pairs.size(); ++k) {
        SCOPED_TRACE(k);
        std::vector<Element> e;
        for (const Pose& p : pairs[k]) {
            append_elements(&prism, &f, p.x, p.q, prism.bounding_radius(), e);
        }
        ASSERT_EQ(e.size(), 2U);
        const geometry::PosedPolyhedron pa{&f, e[0].centre, e[0].q};
        const geometry::PosedPolyhedron pb{&f, e[1].centre, e[1].q};
        const geometry::ConvexContact epa = geometry::ccd_contact(pa, pb, false);
        ASSERT_TRUE(epa.converged);
        reversed += epa.repaired ? 1 : 0;
        if (epa.touching) { // the repaired answer: the smaller overlap along its normal
            EXPECT_LE(geometry::polyhedron_overlap_along(pa, pb, epa.normal),
                      geometry::polyhedron_overlap_along(pa, pb, -epa.normal));
        }
        const ElementContact c = element_contact(e[0], e[1], NarrowPhase::newton, nullptr);
        const ElementContact g = element_contact(e[0], e[1], NarrowPhase::gjk_epa, nullptr);
        ASSERT_TRUE(c.converged);
        ASSERT_TRUE(g.converged);
        ASSERT_EQ(g.touching, c.touching);
        if (c.touching) {
            EXPECT_NEAR(g.overlap, c.overlap, 1e-9 * prism.bounding_radius());
            EXPECT_GT(g.normal.dot(c.normal), 1.0 - 1e-9);
        }
    }
    // The poses still meet libccd's reversed normal (otherwise this test no longer tests it).
    EXPECT_GT(reversed, 0);
    std::printf("EPA normal reversed (and repaired) in %d of %zu pairs\n", reversed, pairs.size());
}

TEST(Polyhedra, GjkEpaFindsTheContactsOfACommonPlaneBed) {
    // Item of issue 4: a GJK/EPA bed of cubes had a third of the contacts of a common-plane bed
    // (docs/performance.md). Here both narrow phases look at the same poses: a lattice of 125
    // randomly turned cubes collapsing into a box, run with the common plane; then every pair of
    // cubes whose bounding spheres overlap is queried by both methods.
    SceneSpec s = base_scene();
    s.materials[0] = {"pom", 5e7, 0.35, 1380, 0.5, 0.3, 0.0};
    s.gravity = Vec3(0, 0, -9.81);
    s.time_step = 5e-6;
    s.shapes.push_back(shape("cube"));
    InsertSpec ins;
    ins.kind = InsertSpec::Kind::lattice;
    ins.count = 125;
    ins.velocity = Vec3(0, 0, -0.2);
    ins.orientation.random = true;
    ins.shape = 0;
    ins.size.radius = s.shapes[0].bounding_radius();
    const double a = 2.0 * ins.size.radius * 1.02;
    ins.spacing = a;
    const Vec3 hi = Vec3::Constant(5 * a + 1e-4);
    ins.region = {Vec3::Zero(), hi};
    for (int k = 0; k < 3; ++k) {
        s.walls.push_back({"lo", PlaneWall{Vec3::Zero(), Vec3::Unit(k)}, 0});
        s.walls.push_back(
            {"hi", PlaneWall{hi + Vec3(0, 0, k == 2 ? 0.05 : 0.0), -Vec3::Unit(k)}, 0});
    }
    s.inserts.push_back(ins);
    System sys(s);
    for (int k = 0; k < 12000; ++k) { // 0.06 s: the lattice has landed and is settling
        sys.step();
    }
    const ParticleStore& p = sys.particles();
    const geometry::PolyhedronFeatures f =
        geometry::polyhedron_features(std::get<geometry::ConvexPolyhedron>(s.shapes[0].shape));
    std::vector<Element> e;
    for (std::size_t i = 0; i < p.size(); ++i) {
        append_elements(&s.shapes[0], &f, p.x[i], p.q[i], p.radius[i], e);
    }
    int cp = 0;
    int epa = 0;
    int both = 0;
    int off = 0;
    int shallow = 0;
    double worst = 0.0;
    double lowest = 1.0;
    double excess = 0.0;
    double shallowest = 1.0;
    for (std::size_t i = 0; i < e.size(); ++i) {
        for (std::size_t j = i + 1; j < e.size(); ++j) {
            const ElementContact c = element_contact(e[i], e[j], NarrowPhase::newton, nullptr);
            const ElementContact g = element_contact(e[i], e[j], NarrowPhase::gjk_epa, nullptr);
            ASSERT_TRUE(g.converged);
            cp += c.touching ? 1 : 0;
            epa += g.touching ? 1 : 0;
            // libccd resolves overlaps down to about 1e-5 of the query's length scale (its EPA
            // tolerance acts on squared distances, ccd_adapter.cpp); a shallower contact may be
            // found by one method only. Counted apart, with its depth printed.
            const double resolution = 1e-4 * (e[i].radius + e[j].radius);
            if (c.touching != g.touching && std::max(c.overlap, g.overlap) < resolution) {
                ++shallow;
                std::printf("below libccd's resolution: common plane %.3g m, GJK/EPA %.3g m\n",
                            c.touching ? c.overlap : 0.0, g.touching ? g.overlap : 0.0);
            }
            if (c.touching && g.touching) {
                ++both;
                const double rel = (g.overlap - c.overlap) / c.overlap;
                worst = std::max(worst, rel);
                lowest = std::min(lowest, rel);
                off += rel > 1e-3 ? 1 : 0;
                excess = std::max(excess, (g.overlap - c.overlap) / (e[i].radius + e[j].radius));
                shallowest = std::min(shallowest, c.overlap / (e[i].radius + e[j].radius));
            }
        }
    }
    std::printf("pairs touching: common plane %d, GJK/EPA %d, both %d; EPA overlap above the "
                "common plane's by more than 0.1 %% in %d, at most %.3g\n",
                cp, epa, both, off, worst);
    std::printf("EPA overlap above the common plane's by at most %.3g of the bodies' summed radii; "
                "shallowest contact %.3g of them\n",
                excess, shallowest);
    // Enough touching pairs for the comparison to mean something. The bed's count moves with
    // every change of rounding in the contact code (125 cubes: 108 pairs when this test was
    // written, 100 after the rotation changes, 89 after the common plane's edge prune), so the
    // guard is 80: it only checks that the bed is a bed.
    EXPECT_GE(cp, 80);
    // Detection: the same pairs touch (so the bench's third of the contacts was not detection),
    // apart from contacts shallower than libccd resolves.
    EXPECT_EQ(both + shallow, std::max(cp, epa));
    EXPECT_LE(shallow, 2);
    // The common plane is the exact MTD (tests above check it against the separating-axis
    // depth); EPA's overlap along its own normal is an upper bound (to round-off) that exceeds it
    // by at most max(sqrt(tol), tol / depth) in lengths scaled by the summed radii
    // (kPolytopeEpaTolerance, polyhedron_contact.hpp): 1e-7 unless a contact is shallower than
    // 1e-7 of them. Before the polytope tolerance (1e-10 for every pair) EPA lay 4.5-6 % above in
    // typical pairs and 30 % to 170 % above in the worst shallow pair of a bed.
    EXPECT_GT(lowest, -1e-9);
    const double tol = geometry::kPolytopeEpaTolerance;
    EXPECT_LE(excess, std::max(std::sqrt(tol), tol / shallowest) * (1.0 + 1e-6));
}

} // namespace
} // namespace kiln::dynamics

namespace kiln::dynamics {
namespace {

/// Contacts of one physical pair from templates whose input lists the same points in another
/// order agree to round-off of the 1 mm size (positions 1e-12 relative, normals 1e-12): the
/// common plane's search and the pair point depend on the geometry only.
constexpr double kOrderRoundOff = 1e-12;
/// The same for libccd's EPA, which converges to ~1e-10 of the size (see below).
constexpr double kEpaOrder = 1e-9;

TEST(Polyhedra, PolyhedronOnAPlaneAveragesEveryVertexInTheBand) {
    // The contact point of a polyhedron on a plane wall (docs/theory/contact.md, "Polyhedra"):
    // the average of its vertices weighted by w = 1 - (overlap - depth) / (0.02 overlap) where
    // w > 0, moved half the overlap out. Every vertex is evaluated here by that rule, for faces
    // and edges lying almost flat (tilts that put vertices at every weight in the band) and for
    // random poses, on a floor and on a tilted plane far from the origin: a route that drops or
    // misweighs a vertex of the band (as a filter of the vertices might) moves the point.
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const std::vector<WallShape> walls{
        PlaneWall{Vec3(0.0, 0.0, -1e-3), Vec3::UnitZ()},
        PlaneWall{Vec3(3.0, -2.0, 5.0), Vec3(0.3, -0.5, 0.8).normalized()}};
    int weighted = 0; // contacts with a vertex of weight in (0, 0.5): near the band's edge
    int cases = 0;
    for (const char* name : {"cube", "cuboid_6x6x5", "plate_10x9x2", "plate_inv4", "icosahedron",
                             "cylinder_16", "pyramid"}) {
        const geometry::ShapeTemplate t = shape(name);
        const auto& hull = std::get<geometry::ConvexPolyhedron>(t.shape);
        const geometry::PolyhedronFeatures f = geometry::polyhedron_features(hull);
        const double r = t.bounding_radius();
        for (const WallShape& ws : walls) {
            const auto& plane = std::get<PlaneWall>(ws);
            for (int k = 0; k < 60; ++k) {
                // The deepest vertex 1e-4 .. 1e-2 of r below the plane; a face (k even) or an
                // edge (k odd) of the body turned towards the wall, then tilted so that the
                // heights of its vertices differ by up to about two bands, or (every fifth) a
                // random pose.
                const double overlap = r * std::pow(10.0, -4.0 + std::abs(u(rng)) * 2.0);
                Quat q;
                if (k % 5 == 4) {
                    q = Quat(
                        Eigen::AngleAxisd(3.0 * u(rng), Vec3(u(rng), u(rng), u(rng)).normalized()));
                } else {
                    const std::size_t fi = static_cast<std::size_t>(k) % f.face_normals.size();
                    Vec3 down = f.face_normals[fi];
                    if (k % 2 == 1) { // between two faces' normals: an edge's
                        const std::size_t e = static_cast<std::size_t>(k) % f.edges.size();
                        down = (f.face_normals[static_cast<std::size_t>(f.edges[e][2])] +
                                f.face_normals[static_cast<std::size_t>(f.edges[e][3])])
                                   .normalized();
                    }
                    // Body-frame `down` onto the world's -n, then a small tilt.
                    const Vec3 to = -plane.normal;
                    const Vec3 axis = down.cross(to);
                    const double angle = std::atan2(axis.norm(), down.dot(to));
                    const Quat onto(Eigen::AngleAxisd(angle, axis.norm() > 1e-9
                                                                 ? Vec3(axis.normalized())
                                                                 : Vec3(down.unitOrthogonal())));
                    const Quat tilt(Eigen::AngleAxisd(0.04 * overlap / r * std::abs(u(rng)),
                                                      Vec3(u(rng), u(rng), u(rng)).normalized()));
                    q = tilt * onto;
                }
                const geometry::PosedPolyhedron at_origin{&f, Vec3::Zero(), q};
                const Vec3 deepest = at_origin.support(-plane.normal);
                const Vec3 x = plane.point - deepest - overlap * plane.normal;
                std::vector<Element> e;
                append_elements(&t, &f, x, q, r, e);
                const ElementContact c = element_wall_contact(e[0], ws);
                ASSERT_TRUE(c.touching) << name << " " << k;
                // Every vertex by the rule.
                const Mat3 rot = q.toRotationMatrix();
                const double band = 0.02 * c.overlap;
                Vec3 sum = Vec3::Zero();
                double wsum = 0.0;
                bool edge_weight = false;
                for (const Vec3& v : f.vertices) {
                    const Vec3 xv = x + rot * v;
                    const double w =
                        1.0 - (c.overlap + (xv - plane.point).dot(plane.normal)) / band;
                    if (w > 0.0) {
                        sum += w * xv;
                        wsum += w;
                        edge_weight = edge_weight || w < 0.5;
                    }
                }
                const Vec3 expected = sum / wsum + 0.5 * c.overlap * plane.normal;
                // Boxes take the rule in closed form (box_plane_wall), in other arithmetic: a
                // height's round-off (1e-15 of the lengths L) moves a weight by that over the band,
                // and the point by that times L.
                const double size = r + x.norm();
                EXPECT_LT((c.point - expected).norm(), 1e-12 * size + 1e-15 * size * size / band)
                    << name << " pose " << k << " overlap " << c.overlap;
                EXPECT_NEAR(c.overlap, overlap, 1e-12 * (r + x.norm())) << name << " " << k;
                weighted += edge_weight ? 1 : 0;
                ++cases;
            }
        }
    }
    // The poses put vertices near the band's edge in many of the cases (where a vertex dropped
    // wrongly would show).
    EXPECT_GT(weighted, cases / 4);
}

TEST(Polyhedra, CubeContactDoesNotDependOnTheVertexOrder) {
    // The cube's inertia is isotropic, so its principal frame was whatever the eigen-solver made
    // of the round-off, which follows the order of the hull's vertices and faces (validation 31
    // changed its scenario when the hull's start changed). Now: the same body frame, and the same
    // contact (overlap, normal, point) from every order, for edge-on and face-on pairs, exactly
    // aligned (ties between vertices and candidate planes) and tilted.
    std::vector<Vec3> corners;
    for (int i = 0; i < 8; ++i) {
        corners.emplace_back((i & 4) != 0 ? 1e-3 : -1e-3, (i & 2) != 0 ? 1e-3 : -1e-3,
                             (i & 1) != 0 ? 1e-3 : -1e-3);
    }
    std::mt19937 rng(11);
    std::vector<geometry::ShapeTemplate> shapes;
    for (int k = 0; k < 6; ++k) {
        std::shuffle(corners.begin(), corners.end(), rng);
        const geometry::Hull h = geometry::convex_hull(corners, "cube");
        shapes.push_back(geometry::make_template(
            "cube", geometry::make_polyhedron(h.vertices, h.faces, "cube")));
    }
    std::vector<geometry::PolyhedronFeatures> features;
    for (const auto& s : shapes) {
        features.push_back(
            geometry::polyhedron_features(std::get<geometry::ConvexPolyhedron>(s.shape)));
    }
    // Body frame: the input frame, so the corners are the same points in every order.
    for (const auto& f : features) {
        for (const Vec3& v : f.vertices) {
            EXPECT_LT((v.cwiseAbs() - Vec3::Constant(1e-3)).norm(), kOrderRoundOff * 1e-3);
        }
    }
    const Quat edge_x(Eigen::AngleAxisd(0.25 * std::numbers::pi, Vec3::UnitZ()));
    const Quat tilt(Eigen::AngleAxisd(0.1, Vec3(0.2, 1.0, 0.4).normalized()));
    struct Pose {
        const char* label;
        Quat qa, qb;
    };
    const std::vector<Pose> poses{
        {"edge-on", edge_x, Quat::Identity()},
        {"face-on", Quat::Identity(), Quat::Identity()},
        {"edge-on tilted", tilt * edge_x, tilt.conjugate()},
        {"face-on tilted", tilt, tilt.conjugate()},
    };
    for (const auto& pose : poses) {
        for (const auto method : {NarrowPhase::newton, NarrowPhase::gjk_epa}) {
            std::vector<ElementContact> out;
            for (std::size_t k = 0; k < shapes.size(); ++k) {
                const auto& cube = std::get<geometry::ConvexPolyhedron>(shapes[k].shape);
                // b's face that looks most towards -x (world normal nb, offset 1 mm) is placed
                // 20 um deep into a's support along -nb, the tip 0.2 mm off the face centre so
                // that the patch is not centred.
                Vec3 nb = Vec3::UnitX();
                for (const Vec3& n : features[k].face_normals) {
                    if ((pose.qb * n).x() < nb.x()) {
                        nb = pose.qb * n;
                    }
                }
                // a's tip along -nb: the mean of its tied support vertices (the support map
                // alone returns the first of them, which follows the order).
                const double h = (-nb).dot(pose.qa * cube.support(pose.qa.conjugate() * -nb));
                Vec3 tip = Vec3::Zero();
                int tied = 0;
                for (const Vec3& v : cube.vertices) {
                    if ((-nb).dot(pose.qa * v) >= h - kOrderRoundOff * 1e-3) {
                        tip += pose.qa * v;
                        ++tied;
                    }
                }
                tip /= tied;
                const Vec3 xb = tip - (1e-3 - 2e-5) * nb + 0.2e-3 * nb.unitOrthogonal();
                std::vector<Element> e;
                append_elements(&shapes[k], &features[k], xb, pose.qb, shapes[k].bounding_radius(),
                                e);
                append_elements(&shapes[k], &features[k], Vec3::Zero(), pose.qa,
                                shapes[k].bounding_radius(), e);
                out.push_back(element_contact(e[0], e[1], method, nullptr));
            }
            // The common plane is exact: the same bits in every order here. EPA stops at its
            // tolerance and follows the tied support vertices it is given (the first of equal
            // ones), and the tie band turns a normal change of 1e-14 into a point shift of
            // ~5e-14 m: its bound is wider.
            const double tol = method == NarrowPhase::newton ? kOrderRoundOff : kEpaOrder;
            for (std::size_t k = 0; k < out.size(); ++k) {
                ASSERT_TRUE(out[k].touching) << pose.label << " order " << k;
                EXPECT_NEAR(out[k].overlap, out[0].overlap, tol * 1e-3)
                    << pose.label << " order " << k;
                EXPECT_LT((out[k].normal - out[0].normal).norm(), tol)
                    << pose.label << " order " << k;
                EXPECT_LT((out[k].point - out[0].point).norm(), tol * 1e-3)
                    << pose.label << " order " << k;
            }
        }
    }
}

} // namespace
} // namespace kiln::dynamics
