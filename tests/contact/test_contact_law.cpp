#include "contact/contact_law.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <numbers>
#include <random>

namespace kiln::contact {
namespace {

PairProperties pair(double e, double mu) {
    const Material m{"m", 1e8, 0.3, 2500, e, mu, 0.1};
    return PairTable({m}, {}).at(0, 0);
}

ContactInput head_on(double overlap, double vn) {
    ContactInput c;
    c.n = Vec3::UnitZ();
    c.overlap = overlap;
    c.r_eff = 0.005;
    c.m_eff = 1e-3;
    c.lever_i = 0.01;
    c.lever_j = 0.01;
    c.v_rel = Vec3(0, 0, vn);
    c.omega_i = Vec3::Zero();
    c.omega_j = Vec3::Zero();
    return c;
}

constexpr double rounding = 1e-12; // relative: same formula evaluated two ways

TEST(HertzMindlin, StaticNormalForceIsHertz) {
    const PairProperties p = pair(0.5, 0.0);
    Vec3 shear = Vec3::Zero();
    const ContactInput c = head_on(1e-5, 0.0);
    const ContactOutput o = evaluate(HertzMindlin{}, ContactModel{}, p, c, shear, 1e-6);
    const double hertz =
        4.0 / 3.0 * p.effective_modulus * std::sqrt(c.r_eff) * std::pow(c.overlap, 1.5);
    EXPECT_NEAR(o.normal_force / hertz, 1.0, rounding);
    EXPECT_NEAR(o.elastic_energy / (0.4 * hertz * c.overlap), 1.0, rounding);
    EXPECT_NEAR(o.force.z(), o.normal_force, rounding * hertz);
}

TEST(HertzMindlin, DampingOpposesApproachAndClampForbidsPull) {
    const PairProperties p = pair(0.3, 0.0);
    Vec3 shear = Vec3::Zero();
    ContactModel model;
    const double approach =
        evaluate(HertzMindlin{}, model, p, head_on(1e-6, -1.0), shear, 1e-6).normal_force;
    const double elastic =
        evaluate(HertzMindlin{}, model, p, head_on(1e-6, 0.0), shear, 1e-6).normal_force;
    const double leave =
        evaluate(HertzMindlin{}, model, p, head_on(1e-6, 50.0), shear, 1e-6).normal_force;
    EXPECT_GT(approach, elastic);
    EXPECT_EQ(leave, 0.0);
    model.clamp_normal_force = false;
    EXPECT_LT(evaluate(HertzMindlin{}, model, p, head_on(1e-6, 50.0), shear, 1e-6).normal_force,
              0.0);
}

TEST(LinearSpringDashpot, DampingGivesExactRestitutionRatio) {
    // gamma = -2 beta sqrt(m k) is critical damping times -beta; e = exp(-zeta pi / sqrt(1 -
    // zeta^2)).
    const PairProperties p = pair(0.4, 0.0);
    const LinearSpringDashpot law{1e5, 2.0 / 7.0};
    Vec3 shear = Vec3::Zero();
    const ContactInput c = head_on(1e-5, -1.0);
    const ContactOutput o = evaluate(law, ContactModel{}, p, c, shear, 1e-6);
    const double gamma = (o.normal_force - law.stiffness * c.overlap) / 1.0;
    const double zeta = gamma / (2.0 * std::sqrt(c.m_eff * law.stiffness));
    EXPECT_NEAR(std::exp(-zeta * std::numbers::pi / std::sqrt(1.0 - zeta * zeta)), 0.4, 1e-12);
}

TEST(Tangential, CoulombCapHoldsWhileSliding) {
    const PairProperties p = pair(0.5, 0.3);
    ContactInput c = head_on(1e-5, 0.0);
    c.v_rel = Vec3(2.0, 0.0, 0.0);
    Vec3 shear = Vec3::Zero();
    ContactOutput o;
    for (int k = 0; k < 200; ++k) {
        o = evaluate(HertzMindlin{}, ContactModel{}, p, c, shear, 1e-6);
    }
    const Vec3 ft = o.force - o.force.dot(c.n) * c.n;
    EXPECT_NEAR(ft.norm(), 0.3 * o.normal_force, 1e-9 * o.normal_force);
    EXPECT_LT(ft.x(), 0.0); // opposes the slip of i relative to j
    EXPECT_NEAR(shear.dot(c.n), 0.0, 1e-20);
}

TEST(Tangential, TorqueSpinsBodiesToReduceSlip) {
    const PairProperties p = pair(0.5, 0.3);
    ContactInput c = head_on(1e-5, 0.0);
    c.v_rel = Vec3(1.0, 0.0, 0.0); // i above j (n = +z) moves in +x
    Vec3 shear = Vec3::Zero();
    const ContactOutput o = evaluate(HertzMindlin{}, ContactModel{}, p, c, shear, 1e-6);
    // Friction on i acts at r = -l z with F = -f x: torque_i = l f (z x x) = +l f y, which turns
    // the bottom of i towards -x. On j, F = +f x at +l z: torque_j = +l f y as well.
    EXPECT_GT(o.torque_i.y(), 0.0);
    EXPECT_GT(o.torque_j.y(), 0.0);
}

TEST(Rolling, ConstantTorqueOpposesRelativeRotation) {
    const PairProperties p = pair(0.5, 0.0);
    ContactModel model;
    model.rolling = RollingModel::constant_torque;
    ContactInput c = head_on(1e-5, 0.0);
    c.omega_i = Vec3(0, 3.0, 0);
    Vec3 shear = Vec3::Zero();
    const ContactOutput o = evaluate(HertzMindlin{}, model, p, c, shear, 1e-6);
    EXPECT_NEAR(o.torque_i.y(), -0.1 * c.r_eff * o.normal_force, 1e-12);
    EXPECT_NEAR(o.torque_j.y(), 0.1 * c.r_eff * o.normal_force, 1e-12);
}

#ifdef __AVX__
// The pair loop evaluates contacts several at a time on the lanes of a vector register
// (dynamics/pair_simd.hpp); the law must give each lane what it gives one contact alone. Random
// contacts cover sticking and sliding, zero history, no friction, rolling with and without
// relative spin, the clamp and no clamp, for both laws.
template <class V, class Law> void lanes_match_one_contact(const Law& law) {
    constexpr int w = sizeof(V) / sizeof(double);
    // Relative, per vector: the compiler may fuse different multiply-adds in vector and scalar
    // code (round-off only).
    constexpr double fused = 1e-11;
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int sliding = 0;
    int sticking_groups = 0;
    for (int it = 0; it < 500; ++it) {
        const double fn_floor = it % 2 == 0 ? 0.0 : -std::numeric_limits<double>::infinity();
        const double rolling = it % 3 == 0 ? 0.0 : 1.0;
        ContactLanes<V> lanes{};
        ContactLanes<double> one[w];
        for (int l = 0; l < w; ++l) {
            ContactLanes<double>& c = one[l];
            Vec3 n(u(rng), u(rng), u(rng));
            n.normalize();
            for (int q = 0; q < 3; ++q) {
                c.n[q] = n[q];
                c.v[q] = 0.5 * u(rng);
                c.wi[q] = it % 5 == 0 ? 0.0 : 20.0 * u(rng);
                c.wj[q] = it % 5 == 0 ? 0.0 : 20.0 * u(rng);
                c.s[q] = it % 7 == 0 ? 0.0 : 2e-5 * u(rng);
            }
            c.overlap = 1e-5 * (1.0 + u(rng));
            c.r_eff = 1e-3 * (1.5 + u(rng));
            c.m_eff = 1e-4 * (1.5 + u(rng));
            c.lever_i = 2e-3;
            c.lever_j = 1.5e-3;
            c.e_star = 3e6 * (1.5 + u(rng));
            c.g_star = 1e6 * (1.5 + u(rng));
            c.beta = -0.3 + 0.1 * u(rng);
            c.mu = it % 11 == 0 ? 0.0 : 0.4 + 0.3 * u(rng);
            c.mu_roll = 0.05 * (1.0 + u(rng));
            c.damping_ratio = 0.0; // read only by the shared_damping_root variant
            for (int q = 0; q < 3; ++q) {
                lanes.n[q][l] = c.n[q];
                lanes.v[q][l] = c.v[q];
                lanes.wi[q][l] = c.wi[q];
                lanes.wj[q][l] = c.wj[q];
                lanes.s[q][l] = c.s[q];
            }
            lanes.overlap[l] = c.overlap;
            lanes.r_eff[l] = c.r_eff;
            lanes.m_eff[l] = c.m_eff;
            lanes.lever_i[l] = c.lever_i;
            lanes.lever_j[l] = c.lever_j;
            lanes.e_star[l] = c.e_star;
            lanes.g_star[l] = c.g_star;
            lanes.beta[l] = c.beta;
            lanes.mu[l] = c.mu;
            lanes.mu_roll[l] = c.mu_roll;
        }
        // The register path's variant (cap only when a lane slides, no rolling term when rolling is
        // off) claims the same bits as the branch-free law: compared exactly.
        ContactLanes<V> fast = lanes;
        // With one material pair the register path also takes the tangential damping from the
        // normal one (other round-off): compared with one contact at a time as the others.
        ContactLanes<V> shared = lanes;
        for (int l = 0; l < w; ++l) {
            shared.damping_ratio[l] = std::sqrt(4.0 * one[l].g_star / one[l].e_star);
        }
        evaluate_lanes<cap_when_sliding | shared_damping_root>(law, fn_floor, rolling, shared,
                                                               1e-5);
        // The register path projects the history with the centre difference d and 1/|d|^2
        // (other round-off): d is n times a distance of a few millimetres.
        ContactLanes<V> projected = shared;
        projected.s[0] = lanes.s[0];
        projected.s[1] = lanes.s[1];
        projected.s[2] = lanes.s[2];
        for (int l = 0; l < w; ++l) {
            const double dist = 3e-3 * (1.0 + 0.5 * u(rng));
            double d2 = 0.0;
            for (int q = 0; q < 3; ++q) {
                projected.d[q][l] = dist * one[l].n[q];
                d2 += projected.d[q][l] * projected.d[q][l];
            }
            projected.inv_d2[l] = 1.0 / d2;
        }
        evaluate_lanes<cap_when_sliding | shared_damping_root | project_by_distance>(
            law, fn_floor, rolling, projected, 1e-5);
        // With friction in every lane, the variant without the friction switch claims the same
        // bits too (compared below when no lane is frictionless).
        ContactLanes<V> friction = lanes;
        bool all_friction = true;
        for (int l = 0; l < w; ++l) {
            all_friction = all_friction && one[l].mu > 0.0;
        }
        if (rolling == 0.0) {
            evaluate_lanes<cap_when_sliding | without_rolling>(law, fn_floor, rolling, fast, 1e-5);
            evaluate_lanes<cap_when_sliding | without_rolling | with_friction>(
                law, fn_floor, rolling, friction, 1e-5);
        } else {
            evaluate_lanes<cap_when_sliding>(law, fn_floor, rolling, fast, 1e-5);
            evaluate_lanes<cap_when_sliding | with_friction>(law, fn_floor, rolling, friction,
                                                             1e-5);
        }
        evaluate_lanes(law, fn_floor, rolling, lanes, 1e-5);
        for (int l = 0; l < w && all_friction; ++l) {
            for (int q = 0; q < 3; ++q) {
                EXPECT_EQ(friction.f[q][l], fast.f[q][l]) << "contact " << it << " lane " << l;
                EXPECT_EQ(friction.ti[q][l], fast.ti[q][l]) << "contact " << it << " lane " << l;
                EXPECT_EQ(friction.tj[q][l], fast.tj[q][l]) << "contact " << it << " lane " << l;
                EXPECT_EQ(friction.s[q][l], fast.s[q][l]) << "contact " << it << " lane " << l;
            }
        }
        for (int l = 0; l < w; ++l) {
            for (int q = 0; q < 3; ++q) {
                EXPECT_EQ(fast.f[q][l], lanes.f[q][l]) << "contact " << it << " lane " << l;
                EXPECT_EQ(fast.ti[q][l], lanes.ti[q][l]) << "contact " << it << " lane " << l;
                EXPECT_EQ(fast.tj[q][l], lanes.tj[q][l]) << "contact " << it << " lane " << l;
                EXPECT_EQ(fast.s[q][l], lanes.s[q][l]) << "contact " << it << " lane " << l;
            }
            EXPECT_EQ(fast.fn[l], lanes.fn[l]);
            EXPECT_EQ(fast.energy[l], lanes.energy[l]);
        }
        bool group_slides = false;
        for (int l = 0; l < w; ++l) {
            ContactLanes<double>& c = one[l];
            const Vec3 s_in(c.s[0], c.s[1], c.s[2]);
            evaluate_lanes(law, fn_floor, rolling, c, 1e-5);
            const auto near = [&](const double(&a)[3], const V(&b)[3]) {
                const Vec3 x(a[0], a[1], a[2]);
                const Vec3 y(b[0][l], b[1][l], b[2][l]);
                EXPECT_LE((x - y).norm(), fused * x.norm()) << "contact " << it << " lane " << l;
            };
            for (const ContactLanes<V>* r : {&lanes, &shared, &projected}) {
                near(c.f, r->f);
                near(c.ti, r->ti);
                near(c.tj, r->tj);
                near(c.s, r->s);
                EXPECT_NEAR(c.fn, r->fn[l], fused * std::abs(c.fn));
                EXPECT_NEAR(c.energy, r->energy[l], fused * c.energy);
            }
            const Vec3 s_out(c.s[0], c.s[1], c.s[2]);
            const bool slides =
                c.mu > 0.0 && (s_out - s_in).norm() > 0.0 &&
                std::abs(Vec3(c.f[0], c.f[1], c.f[2]).cross(Vec3(c.n[0], c.n[1], c.n[2])).norm() -
                         c.mu * std::abs(c.fn)) < 1e-9 * std::abs(c.fn);
            sliding += slides ? 1 : 0;
            group_slides = group_slides || slides;
        }
        sticking_groups += group_slides ? 0 : 1;
    }
    EXPECT_GT(sliding, 50);         // both regimes are exercised (the rest stick)
    EXPECT_GT(sticking_groups, 20); // and the variant's branch for groups where no lane slides
}

TEST(VectorLanes, FourLanesMatchOneContactAtATime) {
    lanes_match_one_contact<lanes::V4>(HertzMindlin{});
    lanes_match_one_contact<lanes::V4>(LinearSpringDashpot{1e5, 2.0 / 7.0});
}
#endif

} // namespace
} // namespace kiln::contact
