// Body contacts at the edges of the supported range (docs/case-format.md, "Non-spherical
// particles"): top blockiness, aspect ratio 1:10, size ratio 1:10, near-zero and near-maximal
// overlap, edge-on and face-on contacts.

#include "dynamics/body_contact.hpp"
#include "dynamics/system.hpp"
#include "geometry/superquadric.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <numbers>

namespace kiln::dynamics {
namespace {

geometry::Superquadric sq(const Vec3& half_axes, double e1, double e2) {
    geometry::Superquadric q;
    q.half_axes = half_axes;
    q.e1 = e1;
    q.e2 = e2;
    return q;
}

Element convex(const geometry::Superquadric& s, const Vec3& x, const Quat& q = Quat::Identity()) {
    return {Element::Kind::superquadric, x, s.bounding_radius(), &s, q, s.half_axes.minCoeff()};
}

Element sphere(const Vec3& x, double r) {
    return {Element::Kind::sphere, x, r, nullptr, Quat::Identity(), r};
}

constexpr double kTop = geometry::Superquadric::kMinExponent; // blockiest supported exponent

TEST(BodyExtremes, FaceOnCubesAtTopBlockinessGiveAxisNormalAndDepth) {
    const auto cube = sq(Vec3::Constant(1e-3), kTop, kTop);
    for (const NarrowPhase m : {NarrowPhase::newton, NarrowPhase::gjk_epa}) {
        const Vec3 up = Vec3::UnitZ();
        const ElementContact c =
            element_contact(convex(cube, Vec3(0, 0, 1.99e-3)), convex(cube, Vec3::Zero()), m, &up);
        ASSERT_TRUE(c.touching);
        constexpr double depth_tol = 2e-8; // m, 0.2 %: EPA stops at its polytope tolerance
        EXPECT_NEAR(c.overlap, 1e-5, depth_tol);
        constexpr double normal_tol = 1e-6; // flat faces: the normal is the axis
        EXPECT_NEAR(c.normal.dot(Vec3::UnitZ()), 1.0, normal_tol);
        // Flat on flat: R* is the larger bounding radius, never infinite.
        constexpr double rounding = 1e-9; // relative; the corners' curvature is not quite zero
        EXPECT_NEAR(c.r_eff / cube.bounding_radius(), 1.0, rounding);
    }
}

TEST(BodyExtremes, StackedThinPlatesDoNotCrossToTheFarFace) {
    // Two of the seed's Inv. IV plates as superquadrics (3.39 x 3.39 x 1 mm, exponents 0.2),
    // stacked almost flat, barely touching: the pose of a lattice pour (bench/lattice_scene.hpp,
    // shape "plate") where Newton on the sphere of directions, started from the right side (the
    // last step's normal, from b down to a) or cold, ended on the far face's minimum, 2.04 mm
    // deep with the normal upwards, and the pile blew up (docs/performance.md, "Session 34"). The
    // depth along any direction bounds the minimum translation distance from above, so the
    // answer may not exceed the smallest overlap of 4000 sampled directions.
    const auto plate = sq(Vec3(1.695e-3, 1.695e-3, 0.5e-3), 0.2, 0.2);
    const Element a =
        convex(plate, Vec3(0.020621543107547696, 0.021059402932523487, 0.00064685252084877227),
               Quat(-0.020369750750663936, -0.34752000808476619, -0.93695345777796502,
                    0.030547261629072914));
    const Element b =
        convex(plate, Vec3(0.020775735893694917, 0.020722329575371387, 0.0016941464452528271),
               Quat(-0.022492736770546987, -0.29666343722750688, -0.9544490972622125,
                    0.022623053292599376));
    const geometry::PosedSuperquadric pa{&plate, a.centre, a.q};
    const geometry::PosedSuperquadric pb{&plate, b.centre, b.q};
    double sampled = 1.0;
    for (int i = 0; i < 4000; ++i) { // a spiral over the sphere of directions (normal from b to a)
        const double z = 1.0 - (2.0 * i + 1.0) / 4000.0;
        const double phi = i * std::numbers::pi * (3.0 - std::sqrt(5.0));
        const Vec3 n(std::sqrt(1.0 - z * z) * std::cos(phi), std::sqrt(1.0 - z * z) * std::sin(phi),
                     z);
        sampled = std::min(sampled, n.dot(pb.support(n)) - n.dot(pa.support(-n)));
    }
    ASSERT_LT(sampled, 1e-4); // the true depth is tiny (the plates are 1 mm thick)
    const Vec3 down = -Vec3::UnitZ();
    for (const Vec3* warm : {&down, static_cast<const Vec3*>(nullptr)}) {
        const ElementContact c = element_contact(a, b, NarrowPhase::newton, warm);
        EXPECT_TRUE(c.converged);
        EXPECT_LE(c.overlap, sampled + 1e-9) << (warm != nullptr ? "warm" : "cold");
        EXPECT_LT(c.normal.z(), -0.99) << (warm != nullptr ? "warm" : "cold");
    }
}

TEST(BodyExtremes, EdgeOnCubesMeetAlongTheEdgeNormal) {
    const auto cube = sq(Vec3::Constant(1e-3), kTop, kTop);
    // Cube a turned 45 degrees about y: its edge points down onto the face of cube b. The edge
    // reaches sqrt(2) mm (minus the small rounding of the e = 0.1 corners) below a's centre.
    const Quat turn(Eigen::AngleAxisd(std::numbers::pi / 4, Vec3::UnitY()));
    const geometry::PosedSuperquadric pa{&cube, Vec3::Zero(), turn};
    const double reach = -pa.support(-Vec3::UnitZ()).z();
    const Vec3 xa(0, 0, 1e-3 + reach - 2e-5);
    const Vec3 up = Vec3::UnitZ();
    const ElementContact newton = element_contact(
        convex(cube, xa, turn), convex(cube, Vec3::Zero()), NarrowPhase::newton, &up);
    const ElementContact epa = element_contact(convex(cube, xa, turn), convex(cube, Vec3::Zero()),
                                               NarrowPhase::gjk_epa, nullptr);
    ASSERT_TRUE(newton.touching);
    ASSERT_TRUE(epa.touching);
    constexpr double depth_tol = 2e-7; // m, 1 % of the overlap: EPA's polytope tolerance
    EXPECT_NEAR(newton.overlap, 2e-5, depth_tol);
    EXPECT_NEAR(epa.overlap, 2e-5, depth_tol);
    constexpr double normal_tol = 1e-3; // the face of b decides the normal
    EXPECT_NEAR(newton.normal.z(), 1.0, normal_tol);
    // An edge on a face: a line contact (one relative curvature is zero); R* = sqrt(L r_edge) is
    // between the floor (5 % of the half-axis) and the bounding radius L of a face contact.
    EXPECT_GE(newton.r_eff, 0.05 * 1e-3 * (1 - 1e-12));
    EXPECT_LT(newton.r_eff, 0.5 * cube.bounding_radius());
}

TEST(BodyExtremes, NearZeroAndNearMaximalOverlapOfEllipsoids) {
    // Aspect ratio 1:10 (the largest supported), against a sphere, along the long axis.
    const auto rod = sq(Vec3(1e-3, 1e-4, 1e-4), 1.0, 1.0);
    for (const double depth : {1e-10, 1e-5, 5e-5}) { // 1e-6 to 0.5 of the rod's half-width
        const Element a = sphere(Vec3(1e-3 + 1e-4 - depth, 0, 0), 1e-4);
        const Vec3 warm = Vec3::UnitX();
        const ElementContact c =
            element_contact(a, convex(rod, Vec3::Zero()), NarrowPhase::newton, &warm);
        ASSERT_TRUE(c.touching) << depth;
        EXPECT_TRUE(c.converged);
        // Along the axis the MTD is the axial overlap as long as it is shallower than the tip's
        // lateral escape (tip radius of curvature b^2/a = 1e-5 m; deeper, a sideways push is
        // shorter).
        if (depth <= 1e-5) {
            EXPECT_NEAR(c.overlap, depth, 1e-3 * depth + 1e-14) << depth;
            EXPECT_NEAR(c.normal.x(), 1.0, 1e-6) << depth;
        } else {
            EXPECT_LT(c.overlap, depth);
            EXPECT_GT(c.overlap, 0.0);
        }
    }
}

SceneSpec scene() {
    SceneSpec s;
    s.materials.push_back({"m", 1e7, 0.3, 2500, 0.5, 0.3, 0.0});
    s.walls.push_back({"floor", PlaneWall{Vec3::Zero(), Vec3::UnitZ()}, 0});
    s.time_step = 1e-6;
    return s;
}

ParticleSpec body(int shape, const Vec3& x, const Quat& q = Quat::Identity()) {
    ParticleSpec p;
    p.shape = shape;
    p.x = x;
    p.orientation.fixed = q;
    return p;
}

TEST(BodyExtremes, RodOfAspectTenSettlesFlatOnTheFloor) {
    SceneSpec s = scene();
    s.shapes.push_back(geometry::make_template("rod", sq(Vec3(2e-3, 2e-4, 2e-4), 0.5, 1.0)));
    // Dropped tilted by 0.2 rad: it lands on one end and falls flat.
    s.particles.push_back(body(0, Vec3(0, 0, 0.6e-3), Quat(Eigen::AngleAxisd(0.2, Vec3::UnitY()))));
    System sys(s);
    for (int k = 0; k < 150000; ++k) {
        sys.step();
    }
    const ParticleStore& p = sys.particles();
    constexpr double flat = 1e-2; // rad
    EXPECT_LT(std::abs((p.q[0] * Vec3::UnitX()).z()), flat);
    constexpr double rest = 1e-6; // m; static overlap of a 0.2 mm rod under its own weight
    EXPECT_NEAR(p.x[0].z(), 2e-4, rest * 10);
    EXPECT_EQ(sys.narrow_phase_counters().failures, 0);
}

TEST(BodyExtremes, SmallSphereRestsOnALargeSuperballAtSizeRatioTen) {
    SceneSpec s = scene();
    s.shapes.push_back(geometry::make_template("ball", sq(Vec3::Constant(1e-3), 0.5, 0.5)));
    s.particles.push_back(body(0, Vec3(0, 0, 1e-3)));
    // On the pole, where the superball's surface is flat (curvature 0 for exponents < 1).
    s.particles.emplace_back(0, 1e-4, Vec3(0, 0, 2.15e-3), Vec3::Zero(), Vec3::Zero());
    System sys(s);
    for (int k = 0; k < 60000; ++k) {
        sys.step();
    }
    const ParticleStore& p = sys.particles();
    const std::size_t small = p.shape[0] < 0 ? 0 : 1;
    // On the flat top of the superball (height 2 mm) plus its own radius.
    constexpr double rest = 2e-6; // m; the two static overlaps are below 1e-6 m
    EXPECT_NEAR(p.x[small].z(), 2.1e-3, rest);
    EXPECT_LT(p.v[small].norm(), 1e-3);
    EXPECT_EQ(sys.narrow_phase_counters().failures, 0);
}

} // namespace
} // namespace kiln::dynamics
