// Narrow phase on support maps: libccd GJK/EPA and MPR against the independent Newton method.

#include "geometry/convex_contact.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <gtest/gtest.h>
#include <numbers>
#include <random>
#include <vector>

using kiln::Quat;
using kiln::Vec3;
namespace g = kiln::geometry;

namespace {
g::Superquadric make(Vec3 h, double e1, double e2) {
    g::Superquadric q;
    q.half_axes = h;
    q.e1 = e1;
    q.e2 = e2;
    return q;
}

constexpr std::array<g::ConvexMethod, 3> kAll = {g::ConvexMethod::kCcdEpa, g::ConvexMethod::kCcdMpr,
                                                 g::ConvexMethod::kSupportNewton};
} // namespace

TEST(ConvexContact, TwoSpheresAreExactForEveryMethod) {
    const g::Superquadric s = make(Vec3::Constant(1.0), 1.0, 1.0);
    const g::PosedSuperquadric a{&s, Vec3(0.3, -0.2, 0.1),
                                 Quat(Eigen::AngleAxisd(0.3, Vec3::UnitX()))};
    const Vec3 dir = Vec3(1, 2, -2).normalized();
    const g::PosedSuperquadric b{&s, a.x - 1.9 * dir, Quat(Eigen::AngleAxisd(1.1, Vec3::UnitY()))};
    for (const auto m : kAll) {
        const g::ConvexContact c = g::convex_contact(a, b, m);
        // MPR and Newton are exact on spheres up to their 1e-10 tolerances; EPA approximates the
        // sphere by a polytope: depth to its tolerance (about 1e-5 of L = 2), normal to
        // sqrt(2 depth error / radius) ~ 3e-3 rad.
        const bool epa = m == g::ConvexMethod::kCcdEpa;
        const double depth_tol = epa ? 2e-5 * 2.0 : 1e-8;
        const double angle_tol = epa ? 1e-2 : 1e-6;
        EXPECT_TRUE(c.touching);
        EXPECT_TRUE(c.converged) << static_cast<int>(m);
        EXPECT_NEAR(c.depth, 0.1, depth_tol) << static_cast<int>(m);
        EXPECT_LT(std::acos(std::min(1.0, c.normal.dot(dir))), angle_tol) << static_cast<int>(m);
        EXPECT_LT((c.point - (a.x - 0.95 * dir)).norm(), 2.0 * angle_tol) << static_cast<int>(m);
    }
}

TEST(ConvexContact, SeparatedBodiesAreNotTouchingAndNewtonGivesTheGap) {
    const g::Superquadric s = make(Vec3::Constant(1.0), 1.0, 1.0);
    const g::PosedSuperquadric a{&s, Vec3::Zero(), Quat::Identity()};
    const g::PosedSuperquadric b{&s, Vec3(0.0, 2.5, 0.0), Quat::Identity()};
    for (const auto m : kAll) {
        EXPECT_FALSE(g::convex_contact(a, b, m).touching);
    }
    EXPECT_NEAR(g::support_newton_contact(a, b).depth, -0.5, 1e-9);
}

// Agreement of the two MTD methods over 2000 random poses of six shapes (ellipsoid, superball,
// near-cube, cylinder-like, plate, 1:10 needle) at overlaps from 1e-4 to 5e-2 of the length scale.
// Known failure modes are counted, not hidden: libccd's GJK can miss a shallow overlap, libccd's
// EPA can stop at a polytope face through the origin and report a depth near zero, and Newton can
// stop short of its gradient tolerance where f is nearly non-smooth (flat faces meeting).
TEST(ConvexContact, EpaAndNewtonAgreeOverRandomPoses) {
    const std::vector<g::Superquadric> shapes = {
        make(Vec3(1.0, 2.0, 3.0), 1.0, 1.0), // ellipsoid 1:2:3
        make(Vec3(1.0, 1.0, 1.0), 0.5, 0.5), // superball
        make(Vec3(1.0, 1.0, 1.0), 0.3, 0.3), // near-cube
        make(Vec3(1.0, 1.0, 1.5), 0.3, 1.0), // cylinder-like
        make(Vec3(2.0, 2.0, 0.6), 0.4, 0.4), // plate
        make(Vec3(0.5, 0.5, 5.0), 1.0, 1.0), // needle 1:10
    };
    std::mt19937_64 rng(2024);
    std::normal_distribution<double> nd;
    std::uniform_real_distribution<double> ud(0.0, 1.0);
    const auto random_quat = [&] { return Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized(); };
    const int trials = 2000;
    int gjk_missed = 0;
    int epa_early = 0;
    int newton_unconverged = 0;
    int newton_missed = 0;
    int compared = 0;
    double worst_depth = 0.0;
    double worst_angle = 0.0;
    double worst_normal_depth = 0.0;
    std::vector<double> angles;
    double worst_order = -1.0; // largest (EPA - Newton) / L: must stay <= 0 up to round-off
    double worst_mpr_below = -1.0;
    for (int trial = 0; trial < trials; ++trial) {
        const auto& sa = shapes[static_cast<std::size_t>(trial) % shapes.size()];
        const auto& sb = shapes[static_cast<std::size_t>(trial / 6) % shapes.size()];
        g::PosedSuperquadric a{&sa, Vec3::Zero(), random_quat()};
        g::PosedSuperquadric b{&sb, Vec3::Zero(), random_quat()};
        // Put B's support point in direction -u at depth `overlap` below A's support point in
        // direction u (along A's inward normal there): that point is on B and inside A, so the
        // bodies overlap. Overlap log-uniform in [1e-4, 0.05] of the length scale, below the
        // thinnest body's width (shallow to deep contacts).
        const Vec3 u = Vec3(nd(rng), nd(rng), nd(rng)).normalized();
        const double scale = sa.half_axes.maxCoeff() + sb.half_axes.maxCoeff();
        const double overlap = scale * std::pow(10.0, -4.0 + 2.7 * ud(rng));
        b.x = a.support(u) - overlap * u - b.support(-u);
        const g::ConvexContact epa = g::convex_contact(a, b, g::ConvexMethod::kCcdEpa);
        const g::ConvexContact nw = g::convex_contact(a, b, g::ConvexMethod::kSupportNewton);
        const g::ConvexContact mpr = g::convex_contact(a, b, g::ConvexMethod::kCcdMpr);
        EXPECT_TRUE(mpr.touching) << trial;
        if (!nw.touching) {
            ++newton_missed;
            continue;
        }
        if (!epa.touching) {
            ++gjk_missed;
            continue;
        }
        worst_order = std::max(worst_order, (epa.depth - nw.depth) / scale);
        worst_mpr_below = std::max(worst_mpr_below, (nw.depth - mpr.depth) / scale);
        if (epa.depth < 0.5 * nw.depth) {
            ++epa_early;
            continue;
        }
        if (!nw.converged) {
            ++newton_unconverged;
            continue;
        }
        ++compared;
        worst_depth = std::max(worst_depth, std::abs(epa.depth - nw.depth) / scale);
        const double angle = std::acos(std::min(1.0, epa.normal.dot(nw.normal)));
        worst_angle = std::max(worst_angle, angle);
        angles.push_back(angle);
        // Depth along EPA's normal: h_A(n) + h_B(-n) with n = -normal, against the minimum.
        const Vec3 n = -epa.normal;
        worst_normal_depth =
            std::max(worst_normal_depth, (n.dot(a.support(n) - b.support(-n)) - nw.depth) / scale);
    }
    std::sort(angles.begin(), angles.end());
    const double median_angle = angles[angles.size() / 2];
    const double p99_angle = angles[angles.size() * 99 / 100];
    std::printf(
        "%d pairs: compared %d; GJK missed %d, EPA stopped early %d, Newton unconverged %d, "
        "Newton missed %d\n",
        trials, compared, gjk_missed, epa_early, newton_unconverged, newton_missed);
    std::printf("worst |depth difference| / L %.3g; normal angle median %.3g, 99th percentile "
                "%.3g, max %.3g rad; depth along EPA's normal above the minimum %.3g L\n",
                worst_depth, median_angle, p99_angle, worst_angle, worst_normal_depth);
    // The exact MTD is sandwiched: EPA's polytope lies inside A - B (depth from below), Newton
    // evaluates h_A(n) + h_B(-n) at some n (from above); MPR's boundary point is no nearer than
    // the MTD. Round-off only.
    constexpr double kSandwich = 1e-9;
    EXPECT_LT(worst_order, kSandwich);
    EXPECT_LT(worst_mpr_below, kSandwich);
    // EPA tolerance 1e-10 on squared distances, i.e. about 1e-5 of L.
    constexpr double kDepthAgreement = 2e-5;
    EXPECT_LT(worst_depth, kDepthAgreement);
    // EPA's normal is the direction to the nearest polytope face. Where the contact is sharp
    // (small summed curvature radius R) f(n) is flat about its minimum and the normal is only
    // determined to sqrt(2 depth error / R): the meaningful check is that the depth along EPA's
    // normal exceeds the minimum by no more than EPA's depth tolerance; the angle is bounded
    // loosely (99 % of pairs) as a regression guard: sqrt(2 x 1e-5 L / R) = 2e-2 for R = 0.05 L.
    EXPECT_LT(worst_normal_depth, kDepthAgreement);
    constexpr double kAngleP99 = 2e-2;
    EXPECT_LT(p99_angle, kAngleP99);
    // Failure modes: each at most 0.5 % of the pairs (measured: about 0.1 % each); a regression
    // guard, reported above. Newton never misses an overlap.
    constexpr int kMaxFailures = trials / 200;
    EXPECT_EQ(newton_missed, 0);
    EXPECT_LE(gjk_missed, kMaxFailures);
    EXPECT_LE(epa_early, kMaxFailures);
    EXPECT_LE(newton_unconverged, kMaxFailures);
}

TEST(ConvexContact, WarmStartedNewtonFindsTheColdStartResult) {
    // A DEM step moves a pair little: start from the cold-start normal turned by 0.05 rad.
    const g::Superquadric e = make(Vec3(1.0, 2.0, 3.0), 0.6, 0.8);
    std::mt19937_64 rng(9);
    std::normal_distribution<double> nd;
    int fell_back = 0;
    for (int t = 0; t < 200; ++t) {
        g::PosedSuperquadric a{&e, Vec3::Zero(),
                               Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized()};
        g::PosedSuperquadric b{&e, Vec3::Zero(),
                               Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized()};
        const Vec3 u = Vec3(nd(rng), nd(rng), nd(rng)).normalized();
        b.x = a.support(u) - 0.01 * u - b.support(-u);
        const g::ConvexContact cold = g::support_newton_contact(a, b);
        const Vec3 turned =
            (Quat(Eigen::AngleAxisd(0.05, cold.normal.unitOrthogonal())) * cold.normal)
                .normalized();
        const g::ConvexContact warm = g::support_newton_contact(a, b, &turned);
        fell_back += warm.iterations > 60 ? 1 : 0;
        constexpr double kSame = 1e-9; // both converge to the gradient tolerance 1e-11 L
        EXPECT_NEAR(warm.depth, cold.depth, kSame) << t;
        EXPECT_GT(warm.normal.dot(cold.normal), 1.0 - kSame) << t;
        EXPECT_LT(warm.iterations, cold.iterations) << t;
    }
    EXPECT_EQ(fell_back, 0);
}

// The default settings of Newton's method (differences at 1e-8 rad, steps judged by the gradient
// where f is flat to round-off, Broyden updates of the Hessian) against those of 2026-11-24
// (differences at 1e-6 rad, Armijo only, new differences at every iteration) over random poses of
// the six shapes of EpaAndNewtonAgreeOverRandomPoses, cold and warm (previous normal turned by 0.02
// rad) starts. Both stop on the same test, a tangential gradient |g| below kGradTol = 1e-9 L, so
// the two minima agree to what that test pins: the depth to |g|^2 / lambda and the normal to |g| /
// lambda (lambda the smallest eigenvalue of the Hessian of f, the summed curvature radius: at least
// ~1e-2 L for these shapes), i.e. 1e-16 L and 2e-7 rad, plus the round-off of f (1e-16 of the
// coordinates). Both have to converge.
TEST(ConvexContact, DefaultNewtonSettingsAgreeWithTheReferenceSettings) {
    const std::vector<g::Superquadric> shapes = {
        make(Vec3(1.0, 2.0, 3.0), 1.0, 1.0), make(Vec3(1.0, 1.0, 1.0), 0.5, 0.5),
        make(Vec3(1.0, 1.0, 1.0), 0.3, 0.3), make(Vec3(1.0, 1.0, 1.5), 0.3, 1.0),
        make(Vec3(2.0, 2.0, 0.6), 0.4, 0.4), make(Vec3(0.5, 0.5, 5.0), 1.0, 1.0),
        make(Vec3(1.0, 1.0, 1.0), 0.8, 0.8)};
    g::NewtonSettings reference;
    reference.fd_step = 1e-6;
    reference.central_differences = true;
    reference.roundoff_steps = false;
    reference.secant_updates = false;
    reference.analytic_hessian = false;
    std::mt19937_64 rng(611);
    std::normal_distribution<double> nd;
    std::uniform_real_distribution<double> ud(0.0, 1.0);
    const auto random_quat = [&] { return Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized(); };
    const int trials = 1400;
    double worst_depth = 0.0;
    double worst_angle = 0.0;
    long iterations_new = 0;
    long iterations_ref = 0;
    int unconverged_new = 0;
    int unconverged_ref = 0;
    for (int trial = 0; trial < trials; ++trial) {
        const auto& sa = shapes[static_cast<std::size_t>(trial) % shapes.size()];
        const auto& sb = shapes[static_cast<std::size_t>(trial / 7) % shapes.size()];
        g::PosedSuperquadric a{&sa, Vec3::Zero(), random_quat()};
        g::PosedSuperquadric b{&sb, Vec3::Zero(), random_quat()};
        const Vec3 u = Vec3(nd(rng), nd(rng), nd(rng)).normalized();
        const double scale = sa.half_axes.maxCoeff() + sb.half_axes.maxCoeff();
        const double overlap = scale * std::pow(10.0, -4.0 + 2.7 * ud(rng));
        b.x = a.support(u) - overlap * u - b.support(-u);
        const g::ConvexContact cold_new = g::support_newton_contact(a, b, nullptr);
        const g::ConvexContact cold_ref = g::support_newton_contact(a, b, nullptr, reference);
        const Vec3 turned =
            (Quat(Eigen::AngleAxisd(0.02, cold_ref.normal.unitOrthogonal())) * cold_ref.normal)
                .normalized();
        const g::ConvexContact warm_new = g::support_newton_contact(a, b, &turned);
        const g::ConvexContact warm_ref = g::support_newton_contact(a, b, &turned, reference);
        unconverged_new += (cold_new.converged ? 0 : 1) + (warm_new.converged ? 0 : 1);
        unconverged_ref += (cold_ref.converged ? 0 : 1) + (warm_ref.converged ? 0 : 1);
        iterations_new += cold_new.iterations + warm_new.iterations;
        iterations_ref += cold_ref.iterations + warm_ref.iterations;
        for (const auto& [x, y] : {std::pair{&cold_new, &cold_ref}, std::pair{&warm_new, &warm_ref},
                                   std::pair{&warm_new, &cold_ref}}) {
            if (!x->converged || !y->converged) {
                continue;
            }
            worst_depth = std::max(worst_depth, std::abs(x->depth - y->depth) / scale);
            worst_angle = std::max(worst_angle, std::acos(std::min(1.0, x->normal.dot(y->normal))));
        }
    }
    std::printf("defaults against the reference settings: worst depth difference %.3g L, worst "
                "normal angle %.3g rad; unconverged %d (defaults) and %d (reference) of %d; Newton "
                "iterations %ld and %ld\n",
                worst_depth, worst_angle, unconverged_new, unconverged_ref, 2 * trials,
                iterations_new, iterations_ref);
    constexpr double kDepthSame = 1e-14; // round-off of f and |g|^2 / lambda
    constexpr double kAngleSame = 1e-6;  // |g| / lambda with lambda >= 1e-3 L, twice
    EXPECT_LT(worst_depth, kDepthSame);
    EXPECT_LT(worst_angle, kAngleSame);
    EXPECT_LE(unconverged_new, unconverged_ref);
}

TEST(ConvexContact, RelativeCurvatureOfSpheresAndAnEllipsoidTip) {
    // Spheres r1, r2: both relative curvatures 1/r1 + 1/r2, R_e = r1 r2 / (r1 + r2).
    const g::Superquadric s1 = make(Vec3::Constant(1.0), 1.0, 1.0);
    const g::Superquadric s2 = make(Vec3::Constant(0.25), 1.0, 1.0);
    const g::PosedSuperquadric a{&s1, Vec3::Zero(), Quat(Eigen::AngleAxisd(0.7, Vec3::UnitZ()))};
    const g::PosedSuperquadric b{&s2, Vec3(0.3, 1.2, -0.2).normalized() * 1.24, Quat::Identity()};
    const g::ConvexContact c = g::convex_contact(a, b, g::ConvexMethod::kSupportNewton);
    const g::ContactCurvature k = g::contact_curvature(a, b, c);
    constexpr double kTol = 1e-8; // curvature from the analytic Hessian at a converged point
    EXPECT_NEAR(k.k_min, 5.0, kTol);
    EXPECT_NEAR(k.k_max, 5.0, kTol);
    EXPECT_NEAR(k.effective_radius, 0.2, kTol);
    EXPECT_NEAR(k.hertz_area, std::numbers::pi * 0.2 * 0.01, kTol);
    // Tip (a, 0, 0) of an ellipsoid a, b, c (curvatures a/b^2, a/c^2) pressed on a sphere of radius
    // r along x: relative curvatures a/c^2 + 1/r and a/b^2 + 1/r.
    const g::Superquadric e = make(Vec3(1.0, 2.0, 3.0), 1.0, 1.0);
    const g::PosedSuperquadric pe{&e, Vec3::Zero(), Quat::Identity()};
    const g::PosedSuperquadric ps{&s1, Vec3(1.99, 0.0, 0.0), Quat::Identity()};
    const g::ConvexContact ce = g::convex_contact(pe, ps, g::ConvexMethod::kSupportNewton);
    const g::ContactCurvature ke = g::contact_curvature(pe, ps, ce);
    EXPECT_NEAR(ce.depth, 0.01, kTol);
    EXPECT_NEAR(ke.k_min, 1.0 / 9.0 + 1.0, kTol);
    EXPECT_NEAR(ke.k_max, 1.0 / 4.0 + 1.0, kTol);
}

TEST(ConvexContact, ExtremeExponentsAndSizeRatio) {
    // Blockiness at both ends of the supported range, and a size ratio of 1:10.
    const std::vector<g::Superquadric> shapes = {
        make(Vec3(1.0, 1.0, 1.0), 0.1, 0.1), // near-box, sharpest supported edges
        make(Vec3(1.0, 1.0, 1.0), 1.9, 1.9), // near-octahedron
        make(Vec3(1.0, 0.8, 1.2), 0.1, 1.9), // near-double-pyramid sections
        make(Vec3(0.1, 0.1, 0.1), 1.0, 1.0), // sphere ten times smaller
    };
    std::mt19937_64 rng(77);
    std::normal_distribution<double> nd;
    std::uniform_real_distribution<double> ud(0.0, 1.0);
    int unconverged = 0;
    int gjk_missed = 0;
    int epa_early = 0;
    int compared = 0;
    double worst = 0.0;
    double worst_order = -1.0;
    for (int trial = 0; trial < 800; ++trial) {
        const auto& sa = shapes[static_cast<std::size_t>(trial) % 4];
        const auto& sb = shapes[static_cast<std::size_t>(trial / 4) % 4];
        g::PosedSuperquadric a{&sa, Vec3::Zero(),
                               Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized()};
        g::PosedSuperquadric b{&sb, Vec3::Zero(),
                               Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized()};
        const Vec3 u = Vec3(nd(rng), nd(rng), nd(rng)).normalized();
        // Overlap relative to the smaller body: 1e-4 to 5e-2 of its largest half-axis.
        const double small = std::min(sa.half_axes.maxCoeff(), sb.half_axes.maxCoeff());
        const double overlap = small * std::pow(10.0, -4.0 + 2.7 * ud(rng));
        b.x = a.support(u) - overlap * u - b.support(-u);
        const g::ConvexContact nw = g::support_newton_contact(a, b);
        const g::ConvexContact epa = g::convex_contact(a, b, g::ConvexMethod::kCcdEpa);
        EXPECT_TRUE(nw.touching) << trial;
        unconverged += nw.converged ? 0 : 1;
        if (!epa.touching) {
            ++gjk_missed;
            continue;
        }
        const double scale = sa.half_axes.maxCoeff() + sb.half_axes.maxCoeff();
        worst_order = std::max(worst_order, (epa.depth - nw.depth) / scale);
        epa_early += epa.depth < 0.5 * nw.depth ? 1 : 0;
        if (epa.depth > 0.5 * nw.depth && nw.converged) {
            ++compared;
            worst = std::max(worst, std::abs(epa.depth - nw.depth) / scale);
        }
    }
    std::printf("extremes: compared %d of 800, Newton unconverged %d, GJK missed %d, EPA stopped "
                "early %d, worst depth difference %.3g L\n",
                compared, unconverged, gjk_missed, epa_early, worst);
    constexpr double kSandwich = 1e-9; // EPA <= MTD <= Newton, round-off only
    EXPECT_LT(worst_order, kSandwich);
    constexpr double kDepthAgreement = 2e-5; // EPA's precision, as in the random-pose test
    EXPECT_LT(worst, kDepthAgreement);
    // Newton, the default method, must handle the extremes: every pair converges and overlaps.
    EXPECT_EQ(unconverged, 0);
    // libccd is a known weak spot here (measured: 2 % GJK misses, 4.5 % EPA early stops, see
    // docs/theory/shapes.md); a 10 % guard catches a regression of the adapter, not of libccd.
    constexpr int kLibccdGuard = 80;
    EXPECT_LE(gjk_missed, kLibccdGuard);
    EXPECT_LE(epa_early, kLibccdGuard);
}
