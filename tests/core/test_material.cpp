#include "core/material.hpp"

#include "core/error.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <numbers>

namespace kiln {
namespace {

Material glass() {
    return {"glass", 60e9, 0.23, 2540, 0.95, 0.4, 0.0};
}
Material steel() {
    return {"steel", 210e9, 0.3, 7800, 0.8, 0.2, 0.01};
}

TEST(PairTable, EffectiveModuliFollowHertzAndDiRenzo) {
    const PairTable t({glass(), steel()}, {});
    const PairProperties& p = t.at(0, 1);
    const double e_star = 1.0 / ((1 - 0.23 * 0.23) / 60e9 + (1 - 0.09) / 210e9);
    const double g1 = 60e9 / (2 * 1.23);
    const double g2 = 210e9 / (2 * 1.3);
    const double g_star = 1.0 / ((2 - 0.23) / g1 + (2 - 0.3) / g2); // (2 - nu)/G, not (2 - nu^2)/G
    constexpr double rel = 1e-14; // same arithmetic, rounding only
    EXPECT_NEAR(p.effective_modulus / e_star, 1.0, rel);
    EXPECT_NEAR(p.effective_shear / g_star, 1.0, rel);
}

TEST(PairTable, IsSymmetricAndMixesByMean) {
    const PairTable t({glass(), steel()}, {});
    EXPECT_DOUBLE_EQ(t.at(0, 1).restitution, t.at(1, 0).restitution);
    EXPECT_DOUBLE_EQ(t.at(0, 1).restitution, 0.5 * (0.95 + 0.8));
    EXPECT_DOUBLE_EQ(t.at(0, 1).friction, 0.3);
}

TEST(PairTable, OverrideWinsInBothOrders) {
    PairOverride o;
    o.a = 1;
    o.b = 0;
    o.friction = 0.7;
    const PairTable t({glass(), steel()}, {o});
    EXPECT_DOUBLE_EQ(t.at(0, 1).friction, 0.7);
    EXPECT_DOUBLE_EQ(t.at(1, 0).friction, 0.7);
    EXPECT_DOUBLE_EQ(t.at(0, 0).friction, 0.4);
}

TEST(DampingBeta, MatchesDefinitionAndLimits) {
    EXPECT_DOUBLE_EQ(damping_beta(1.0), 0.0);
    const double l = std::log(0.5);
    EXPECT_DOUBLE_EQ(damping_beta(0.5), l / std::sqrt(l * l + std::numbers::pi * std::numbers::pi));
    EXPECT_LT(damping_beta(0.1), damping_beta(0.9));
}

} // namespace
} // namespace kiln

namespace kiln {
namespace {

TEST(ClampedRebound, InversionRoundTrips) {
    constexpr double bisection = 1e-12; // bisection runs to rounding of e'
    for (const double e : {0.15, 0.2, 0.3, 0.5, 0.8, 0.95, 0.999}) {
        const double ep = damping_restitution_for_clamped(e);
        EXPECT_LT(ep, e) << "a clamped contact loses less energy than its dashpot's e'";
        EXPECT_NEAR(clamped_rebound(ep), e, bisection) << e;
    }
    EXPECT_DOUBLE_EQ(damping_restitution_for_clamped(1.0), 1.0);
}

TEST(ClampedRebound, BelowTheLowestIsRefused) {
    const double low = lowest_clamped_rebound();
    EXPECT_GT(low, 0.13);
    EXPECT_LT(low, 0.15);
    EXPECT_TRUE(std::isnan(damping_restitution_for_clamped(0.5 * low)));
    const Material m{"m", 1e7, 0.3, 2500, 0.1, 0.0, 0.0};
    EXPECT_THROW(PairTable({m}, {}, true), InputError);
    EXPECT_NO_THROW(PairTable({m}, {}, false));
}

TEST(ClampedRebound, TableTunesDampingOnlyWhenAsked) {
    const Material m{"m", 1e7, 0.3, 2500, 0.5, 0.0, 0.0};
    EXPECT_DOUBLE_EQ(PairTable({m}, {}, false).at(0, 0).beta, damping_beta(0.5));
    const PairProperties tuned = PairTable({m}, {}, true).at(0, 0);
    EXPECT_DOUBLE_EQ(tuned.restitution, 0.5);
    EXPECT_NEAR(clamped_rebound(tuned.damping_restitution), 0.5, 1e-12);
}

} // namespace
} // namespace kiln
