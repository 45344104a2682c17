// Orientation convention and the splitting rotation integrator (geometry/rotation.hpp).

#include "geometry/rotation.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <numbers>
#include <random>
#include <vector>

using kiln::Mat3;
using kiln::Quat;
using kiln::Vec3;
namespace g = kiln::geometry;

namespace {
constexpr double kRoundOff = 1e-13; // a few ulps of O(1) values after a handful of products
constexpr double kPi = std::numbers::pi;

/// Maximum deviation between two rotation matrices.
double rot_distance(const Quat& a, const Quat& b) {
    return (g::rotation_matrix(a) - g::rotation_matrix(b)).cwiseAbs().maxCoeff();
}
} // namespace

TEST(Rotation, QuarterTurnAboutZMapsBodyXToWorldY) {
    const Quat q(Eigen::AngleAxisd(0.5 * kPi, Vec3::UnitZ()));
    EXPECT_LT((g::body_to_world(q, Vec3::UnitX()) - Vec3::UnitY()).norm(), kRoundOff);
    EXPECT_LT((g::body_to_world(q, Vec3::UnitY()) + Vec3::UnitX()).norm(), kRoundOff);
    EXPECT_LT((g::world_to_body(q, Vec3::UnitY()) - Vec3::UnitX()).norm(), kRoundOff);
}

TEST(Rotation, MatrixColumnsAreBodyAxesInWorld) {
    // 120 degrees about (1,1,1) cycles the axes: body x -> world y, y -> z, z -> x.
    const Quat q(Eigen::AngleAxisd(2.0 * kPi / 3.0, Vec3(1, 1, 1).normalized()));
    Mat3 expected;
    expected << 0, 0, 1, 1, 0, 0, 0, 1, 0;
    EXPECT_LT((g::rotation_matrix(q) - expected).cwiseAbs().maxCoeff(), kRoundOff);
    // Storage order of Eigen's quaternion: coeffs() = (x, y, z, w).
    EXPECT_DOUBLE_EQ(q.coeffs()[3], q.w());
}

TEST(Rotation, MatrixAgreesWithQuaternionProductForRandomRotations) {
    std::mt19937_64 rng(7);
    std::normal_distribution<double> n;
    for (int i = 0; i < 100; ++i) {
        const Quat q = Quat(n(rng), n(rng), n(rng), n(rng)).normalized();
        const Vec3 v(n(rng), n(rng), n(rng));
        EXPECT_LT((g::rotation_matrix(q) * v - g::body_to_world(q, v)).norm(), kRoundOff * 10);
    }
}

TEST(Rotation, ConstantTorqueAlongAPrincipalAxisIsExact) {
    // Velocity Verlet integrates L(t) = L0 + tau t exactly; with L and tau along a principal axis
    // the body turns about that axis by (L0 t + tau t^2 / 2) / I, reproduced to round-off. (About
    // a general axis the splitting is second order even for a sphere, which is why spheres keep
    // their own fast path.)
    const Vec3 inertia(2.0, 3.0, 5.0);
    const Vec3 axis = Vec3::UnitY();
    Quat q = Quat::Identity();
    Vec3 l = 0.3 * axis;
    const Vec3 tau = 0.7 * axis;
    const double dt = 1e-2;
    const int steps = 300;
    for (int i = 0; i < steps; ++i) {
        g::rotation_step(q, l, inertia, tau, dt);
    }
    const double t = dt * steps;
    const double angle = (0.3 * t + 0.5 * 0.7 * t * t) / inertia.y();
    EXPECT_LT(rot_distance(q, Quat(Eigen::AngleAxisd(angle, axis))), 1e-12);
    EXPECT_LT((l - (0.3 + 0.7 * t) * axis).norm(), 1e-12);
}

TEST(Rotation, SymmetricTopTurnsExactlyAsLandauLifshitz) {
    // Two equal moments i_p about the axes across the symmetry axis s, i_s about it (a cuboid of
    // square section, a regular prism, a square pyramid). Landau & Lifshitz, Sec. 33: in the body
    // frame L turns about e_s at Omega = L_s (1/i_s - 1/i_p), i.e. with (a, b, s) cyclic,
    // L_a(t) = L_a(0) cos(Omega t) + L_b(0) sin(Omega t), L_b(t) = L_b(0) cos - L_a(0) sin; in the
    // world frame the axis R e_s precesses about the fixed L at |L| / i_p. The two fix the
    // orientation (L is not along e_s). free_rotate follows this flow exactly, so after 2000
    // steps (omega dt = 0.05 and 0.3: half angles within the series' range and beyond it, the
    // library's sine) only round-off separates it from the analytic motion, for each axis s and
    // a general start (at most 9e-13 here). The splitting it replaced ended 2e-4 to 7e-3
    // (omega dt = 0.05) and 0.09 to 1.4 (0.3) from it on this run, depending on the axis.
    const Quat q0 = Quat(Eigen::AngleAxisd(0.7, Vec3(1, -2, 0.5).normalized()));
    const Vec3 l(0.3, -0.8, 1.1); // world frame, fixed (no torque)
    for (int s = 0; s < 3; ++s) {
        Vec3 inertia = Vec3::Constant(0.02);
        inertia[s] = 0.05;
        ASSERT_EQ(g::symmetric_axis(inertia), s);
        const int a = (s + 1) % 3;
        const int b = (s + 2) % 3;
        const double ip = g::transverse_moment(inertia, s);
        const Vec3 l0 = g::world_to_body(q0, l);
        const double big_omega = l0[s] * (1.0 / inertia[s] - 1.0 / ip);
        const double rate = l.norm() / ip;
        for (const double dt : {0.05 / rate, 0.3 / rate}) {
            Quat q = q0;
            const int steps = 2000;
            for (int i = 0; i < steps; ++i) {
                Mat3 r = g::unit_rotation_matrix(q);
                g::free_rotate(q, r, l, inertia, dt);
            }
            const double t = dt * steps;
            const Vec3 lb = g::world_to_body(q, l);
            Vec3 expected = l0;
            expected[a] = l0[a] * std::cos(big_omega * t) + l0[b] * std::sin(big_omega * t);
            expected[b] = l0[b] * std::cos(big_omega * t) - l0[a] * std::sin(big_omega * t);
            EXPECT_LT((lb - expected).norm(), 2000 * kRoundOff) << "axis " << s << ", dt " << dt;
            const Vec3 e = g::body_to_world(q, Vec3::Unit(s));
            const Quat turn(Eigen::AngleAxisd(rate * t, l.normalized()));
            EXPECT_LT((e - turn * g::body_to_world(q0, Vec3::Unit(s))).norm(), 2000 * kRoundOff)
                << "axis " << s << ", dt " << dt;
            // omega in its short form against R diag(1/I) R^T L, and the quaternion form.
            const Mat3 r = g::unit_rotation_matrix(q);
            const Vec3 full = r * (r.transpose() * l).cwiseQuotient(inertia);
            const Vec3 omega = g::angular_velocity_world(r, l, inertia);
            EXPECT_LT((omega - full).norm(), kRoundOff * rate);
            EXPECT_LT((g::angular_velocity_world(q, l, inertia) - full).norm(), kRoundOff * rate);
        }
    }
    EXPECT_EQ(g::symmetric_axis(Vec3(0.02, 0.02 * (1 + 1e-9), 0.05)), -1); // not to 1e-12
    EXPECT_EQ(g::symmetric_axis(Vec3(0.02, 0.02 * (1 + 3e-16), 0.05)), 2);
    EXPECT_EQ(g::symmetric_axis(Vec3::Constant(0.02)), -1); // a spherical top
    EXPECT_EQ(g::symmetric_axis(Vec3(1.0, 2.0, 3.0)), -1);
}

TEST(Rotation, SphericalTopTurnsExactlyAboutItsAngularMomentum) {
    // Equal moments (a cube, a regular polyhedron): the body turns uniformly about the fixed L at
    // |L| / I; free_rotate follows that flow exactly, so after many steps (the half angle per step
    // within the series' range and one step beyond it) only round-off separates q from the
    // analytic turn. The splitting is off by O((omega dt)^3) per step instead: with it this run
    // ends 0.011 (omega dt = 0.05) and 1.4 (omega dt = 0.3) from the analytic turn.
    const Quat q0 = Quat(Eigen::AngleAxisd(0.7, Vec3(1, -2, 0.5).normalized()));
    const Vec3 l(0.3, -0.8, 1.1);
    for (const Vec3& inertia : {Vec3(Vec3::Constant(0.02)), Vec3(0.02, 0.02 * (1 + 3e-16), 0.02)}) {
        ASSERT_TRUE(g::spherical_top(inertia));
        const double rate = l.norm() / g::spherical_moment(inertia);
        for (const double dt : {0.05 / rate, 0.3 / rate}) { // half angles 0.025, 0.15 rad
            Quat q = q0;
            const int steps = 2000;
            for (int i = 0; i < steps; ++i) {
                Mat3 r = g::unit_rotation_matrix(q);
                g::free_rotate(q, r, l, inertia, dt);
            }
            const Quat exact = Quat(Eigen::AngleAxisd(rate * dt * steps, l.normalized())) * q0;
            EXPECT_LT(rot_distance(q, exact), 2000 * kRoundOff) << "dt " << dt;
            const Vec3 omega = g::angular_velocity_world(g::unit_rotation_matrix(q), l, inertia);
            EXPECT_LT((omega - l / g::spherical_moment(inertia)).norm(), kRoundOff * rate);
        }
    }
    EXPECT_FALSE(g::spherical_top(Vec3(0.02, 0.02 * (1 + 1e-9), 0.02)));
}

TEST(Rotation, FreeAsymmetricRotorKeepsAngularMomentumAndBoundsEnergy) {
    const Vec3 inertia(1.0, 2.0, 3.0);
    Quat q = Quat(Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized()));
    const Vec3 l0 = g::angular_momentum_world(q, Vec3(0.1, 2.0, 0.05), inertia);
    Vec3 l = l0;
    const double e0 = g::rotational_energy(q, l, inertia);
    const double dt = 0.01;
    double max_err_first = 0.0;
    double max_err_second = 0.0;
    double max_l_body_err = 0.0;
    const int steps = 200000;
    for (int i = 0; i < steps; ++i) {
        g::rotation_step(q, l, inertia, Vec3::Zero(), dt);
        const double err = std::abs(g::rotational_energy(q, l, inertia) - e0) / e0;
        (i < steps / 2 ? max_err_first : max_err_second) =
            std::max(i < steps / 2 ? max_err_first : max_err_second, err);
        max_l_body_err = std::max(max_l_body_err,
                                  std::abs(g::world_to_body(q, l).norm() - l0.norm()) / l0.norm());
    }
    // |L| is exact: L_world is never changed by a free step, and q stays unit.
    EXPECT_EQ(l, l0);
    EXPECT_LT(max_l_body_err, 1e-12);
    // Energy: bounded O(dt^2) error, no drift (second half no worse than first, within 10 %).
    constexpr double kEnergyBound = 1e-5; // measured 3.3e-6 at dt = 0.01 (spin period pi), O(dt^2)
    EXPECT_LT(max_err_first, kEnergyBound);
    EXPECT_LT(max_err_second, 1.1 * max_err_first);
}

TEST(Rotation, ConvergesAtSecondOrder) {
    const Vec3 inertia(1.0, 2.0, 3.0);
    const Quat q0 = Quat(Eigen::AngleAxisd(0.3, Vec3(0, 1, 1).normalized()));
    const Vec3 l0 = g::angular_momentum_world(q0, Vec3(1.0, 0.5, -0.7), inertia);
    const Vec3 tau(0.2, -0.1, 0.05); // constant world torque: exercises the kicks as well
    const double t_end = 2.0;
    const auto run = [&](int steps) {
        Quat q = q0;
        Vec3 l = l0;
        for (int i = 0; i < steps; ++i) {
            g::rotation_step(q, l, inertia, tau, t_end / steps);
        }
        return q;
    };
    const Quat ref = run(20480);
    const double e1 = rot_distance(run(40), ref);
    const double e2 = rot_distance(run(80), ref);
    const double e3 = rot_distance(run(160), ref);
    const double order = std::log2(e1 / e3) / 2.0;
    constexpr double kMinOrder = 1.9; // splitting is second order; 1.9 leaves room for the fit
    EXPECT_GT(order, kMinOrder) << e1 << " " << e2 << " " << e3;
    EXPECT_LT(order, 2.2);
}

TEST(Rotation, EllipticKMatchesTabulatedValues) {
    // Abramowitz & Stegun Table 17.1: K(0) = pi/2, K(m = 0.5) = 1.8540746773013719.
    EXPECT_NEAR(g::elliptic_k(0.0), 0.5 * kPi, 1e-15);
    EXPECT_NEAR(g::elliptic_k(0.5), 1.8540746773013719, 1e-14);
    EXPECT_NEAR(g::elliptic_k(0.99), 3.6956373629898747, 1e-13);
}

TEST(Rotation, FreeRotorHalfPeriodMatchesSymmetricTopLimit) {
    // Far from the separatrix and with I2 -> I1 the motion is the precession of a symmetric top:
    // omega_2 changes sign every pi / Omega with Omega = L3 (1/I3 - 1/I1) (m -> 0, K -> pi/2).
    const Vec3 inertia(1.0, 1.0 + 1e-9, 3.0);
    const Vec3 wb(0.2, 0.0, 1.0);
    const Vec3 lb = wb.cwiseProduct(inertia);
    const double e = 0.5 * wb.dot(lb);
    const double half = g::free_rotor_half_period(inertia, lb.squaredNorm(), e);
    const double omega = lb.z() * (1.0 / inertia.x() - 1.0 / inertia.z());
    EXPECT_NEAR(half, kPi / omega, 1e-6);
}

TEST(Rotation, BodiesInVectorLanesTurnAsOneByOne) {
    // free_rotate_bodies (eight bodies per vector batch, series sine) against free_rotate body by
    // body: 13 bodies (a batch and a padded one), a given index order, one body so fast that its
    // half angle exceeds the series' range and takes the general path, three spherical tops and
    // three symmetric tops (symmetric_axis 0, 1, 2). The two share the same flows, splitting and
    // series, so they agree to round-off (in practice to the bit).
    std::mt19937_64 rng(7);
    std::normal_distribution<double> n01(0.0, 1.0);
    const std::size_t n = 13;
    std::vector<Quat> q(n);
    std::vector<Mat3> rot(n);
    std::vector<Vec3> l(n);
    std::vector<Vec3> inertia(n);
    for (std::size_t i = 0; i < n; ++i) {
        q[i] = Quat(n01(rng), n01(rng), n01(rng), n01(rng)).normalized();
        rot[i] = g::unit_rotation_matrix(q[i]);
        inertia[i] = Vec3(1.0 + 0.1 * static_cast<double>(i), 2.0, 3.0);
        l[i] = Vec3(n01(rng), n01(rng), n01(rng));
    }
    // Spherical tops and symmetric tops (one per axis) among them: batched apart, the others
    // around them.
    inertia[3] = inertia[9] = inertia[11] = Vec3::Constant(2.0);
    inertia[2] = Vec3(3.0, 2.0, 2.0);
    inertia[7] = Vec3(2.0, 1.5, 2.0);
    inertia[10] = Vec3(1.0, 1.0, 0.5);
    constexpr double dt = 1e-3;
    l[5] *= 1e3; // half angle ~ |L| dt / (2 I) ~ 1 rad: beyond the series
    const std::vector<std::uint32_t> index = {12, 0, 3, 5, 1, 2, 4, 6, 7, 8, 9, 10, 11};
    std::vector<Quat> one = q;
    for (std::size_t i = 0; i < n; ++i) {
        Mat3 r = rot[i];
        g::free_rotate(one[i], r, l[i], inertia[i], dt);
    }
    g::free_rotate_bodies(index.data(), index.size(), q.data(), rot.data(), l.data(),
                          inertia.data(), dt);
    for (std::size_t i = 0; i < n; ++i) {
        EXPECT_LT(rot_distance(q[i], one[i]), kRoundOff) << "body " << i;
        EXPECT_NEAR(q[i].norm(), 1.0, kRoundOff);
    }
    EXPECT_GT(rot_distance(q[5], Quat(rot[5])), 0.1); // the fast body did turn by a lot
}
