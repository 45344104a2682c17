#include "contact/contact_law.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <numbers>

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

} // namespace
} // namespace kiln::contact
