// Gas-gap (particle-fluid-particle) conductance after Cheng et al. 1999 (seed Inv. V eqs. 13-16):
// limits, closed forms, an independent brute-force quadrature, symmetry, cut-off and pair search.
#include "core/error.hpp"
#include "heat/gas_conduction.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <numbers>
#include <random>
#include <vector>

namespace kiln::heat {
namespace {

constexpr double r = 1e-3;      // m, the seed's V-7 spheres (d = 2 mm)
constexpr double k_f = 0.02818; // W/(m K), the seed's gas (Table 2)
constexpr double k_s = 10.0;    // W/(m K), validation 27's solid
/// The quadrature's own target is 1e-10; the brute-force reference below carries ~1e-8.
constexpr double quadrature_tolerance = 1e-7;

GasGap gas(double kf = k_f) {
    GasGap g;
    g.conductivity = kf;
    return g;
}

/// The seed's integrand (Inv. V eq. 13) written out again for equal radii, summed with the
/// midpoint rule on n panels: an independent reference for the adaptive quadrature.
double brute_force(double big_r, double half_gap, double ks, double kf, double eps, int n) {
    const double a = big_r + half_gap;
    const double r_ij = 0.560 * big_r / std::cbrt(1.0 - eps);
    const double r_sf = big_r * r_ij / std::hypot(r_ij, a);
    const double r_lo = half_gap < 0.0 ? std::sqrt(big_r * big_r - a * a) : 0.0;
    const double h = (r_sf - r_lo) / n;
    double sum = 0.0;
    for (int k = 0; k < n; ++k) {
        const double x = r_lo + (k + 0.5) * h;
        const double z = std::sqrt(big_r * big_r - x * x);
        const double den = (z - x * a / r_ij) * (2.0 / ks) + 2.0 * (a - z) / kf;
        sum += 2.0 * std::numbers::pi * x / den * h;
    }
    return sum;
}

TEST(GasConduction, MatchesABruteForceQuadratureOfTheLensIntegral) {
    for (const double hr : {-0.002, 0.0, 1e-3, 0.01, 0.1, 0.4}) { // H_g / R (negative: overlap)
        const double s = 2.0 * r + 2.0 * hr * r;
        const double h = gas_gap_conductance(r, r, s, k_s, k_s, gas());
        const double ref = brute_force(r, hr * r, k_s, k_f, 0.4, 2'000'000);
        EXPECT_NEAR(h, ref, quadrature_tolerance * ref) << "H/R = " << hr;
    }
}

TEST(GasConduction, RigidSolidLimitHasAClosedForm) {
    // k_s -> infinity: only the gas resists; with u = sqrt(R^2 - r^2) the integral is
    // pi k_f [a ln((a - u_sf) / (a - R)) - (R - u_sf)] (a = R + H_g > R: a gap, no contact; at
    // contact the rigid limit diverges logarithmically, which the finite k_s keeps finite).
    constexpr double huge_ks = 1e14;               // W/(m K); solid resistance ~1e-13 of the gas
    constexpr double closed_form_tolerance = 1e-8; // relative; the neglected solid part is smaller
    for (const double hr : {0.002, 0.02, 0.3}) {
        const double a = r + hr * r;
        const double r_ij = voronoi_face_radius(r, 0.4);
        const double r_sf = r * r_ij / std::hypot(r_ij, a);
        const double u_sf = std::sqrt(r * r - r_sf * r_sf);
        const double ref =
            std::numbers::pi * k_f * (a * std::log((a - u_sf) / (a - r)) - (r - u_sf));
        const double h = gas_gap_conductance(r, r, 2.0 * a, huge_ks, huge_ks, gas());
        EXPECT_NEAR(h, ref, closed_form_tolerance * ref) << "H/R = " << hr;
    }
}

TEST(GasConduction, VanishesWithTheGasAndIsLinearInASmallGasConductivity) {
    const double s = 2.0 * r + 0.02 * r;
    EXPECT_EQ(gas_gap_conductance(r, r, s, k_s, k_s, gas(0.0)), 0.0);
    // k_f << k_s: the gas dominates every tube, H ~ k_f (to O(k_f / k_s)).
    const double h1 = gas_gap_conductance(r, r, s, k_s, k_s, gas(1e-9));
    const double h2 = gas_gap_conductance(r, r, s, k_s, k_s, gas(2e-9));
    constexpr double linearity_tolerance = 1e-6; // O(k_f / k_s) = 1e-10 and quadrature
    EXPECT_GT(h1, 0.0);
    EXPECT_NEAR(h2 / h1, 2.0, linearity_tolerance);
}

TEST(GasConduction, IsSymmetricInThePair) {
    // Swapping the spheres (radii and conductivities) gives the same conductance: what leaves one
    // enters the other at one H.
    const double s = 1.0e-3 + 2.0e-3 + 1e-4;
    const double hij = gas_gap_conductance(1.0e-3, 2.0e-3, s, 5.0, 50.0, gas());
    const double hji = gas_gap_conductance(2.0e-3, 1.0e-3, s, 50.0, 5.0, gas());
    EXPECT_EQ(hij, hji);
    // Equal radii reduce the equivalent radius to R itself (the seed's form).
    EXPECT_DOUBLE_EQ(gas_gap_reach(r, r, 0.5), 3.0 * r);
}

TEST(GasConduction, CutOffAtHalfTheRadiusAndMonotoneInTheGap) {
    const GasGap g = gas();
    EXPECT_EQ(gas_gap_conductance(r, r, 2.0 * r + 1.0001 * r, k_s, k_s, g), 0.0); // H/R = 0.50005
    EXPECT_GT(gas_gap_conductance(r, r, 2.0 * r + 0.9999 * r, k_s, k_s, g), 0.0);
    double last = 1e300;
    for (const double hr : {-0.01, -0.001, 0.0, 0.001, 0.01, 0.1, 0.3, 0.49}) {
        const double h = gas_gap_conductance(r, r, 2.0 * r + 2.0 * hr * r, k_s, k_s, g);
        EXPECT_LT(h, last) << "H/R = " << hr; // a wider gap conducts less
        last = h;
    }
}

TEST(GasConduction, RefusesBadInput) {
    EXPECT_THROW((void)gas_gap_conductance(0.0, r, 2 * r, k_s, k_s, gas()), InputError);
    EXPECT_THROW((void)gas_gap_conductance(r, r, 2 * r, -1.0, k_s, gas()), InputError);
    EXPECT_THROW((void)gas_gap_conductance(r, r, 2 * r, k_s, k_s, gas(-1.0)), InputError);
    GasGap g = gas();
    g.porosity = 1.0;
    EXPECT_THROW((void)gas_gap_conductance(r, r, 2 * r, k_s, k_s, g), InputError);
    EXPECT_THROW((void)gas_gap_conductance(r, 2 * r, 0.5 * r, k_s, k_s, gas()), InputError);
}

TEST(GasConduction, PairSearchFindsExactlyThePairsWithinReach) {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> pos(0.0, 0.02);
    std::uniform_real_distribution<double> rad(0.5e-3, 1.5e-3);
    std::vector<Vec3> x(600);
    std::vector<double> radius(600);
    for (std::size_t i = 0; i < x.size(); ++i) {
        x[i] = Vec3(pos(rng), pos(rng), pos(rng));
        radius[i] = i % 50 == 7 ? 0.0 : rad(rng); // some entries hidden (bodies, unheated)
    }
    const auto pairs = near_sphere_pairs(x, radius, 0.5);
    std::vector<NearPair> brute;
    for (std::uint32_t i = 0; i < x.size(); ++i) {
        for (std::uint32_t j = i + 1; j < x.size(); ++j) {
            if (radius[i] > 0.0 && radius[j] > 0.0 &&
                (x[j] - x[i]).norm() < gas_gap_reach(radius[i], radius[j], 0.5)) {
                brute.push_back({i, j});
            }
        }
    }
    ASSERT_EQ(pairs.size(), brute.size());
    ASSERT_GT(brute.size(), 100U); // the test exercises many pairs
    for (std::size_t k = 0; k < brute.size(); ++k) {
        EXPECT_EQ(pairs[k].i, brute[k].i);
        EXPECT_EQ(pairs[k].j, brute[k].j);
    }
}

} // namespace
} // namespace kiln::heat
