// Series solutions: eigenvalue equations, initial condition and lumped limit.

#include "heat/analytic.hpp"

#include <cmath>
#include <gtest/gtest.h>

namespace kiln::heat::analytic {
namespace {

TEST(Analytic, EigenvaluesSolveTheirEquations) {
    for (const double bi : {0.01, 1.0, 100.0}) {
        for (const double l : sphere_eigenvalues(bi, 20)) {
            EXPECT_NEAR(1.0 - l / std::tan(l), bi, 1e-8 * (1.0 + bi)) << bi;
        }
        for (const double l : slab_eigenvalues(bi, 20)) {
            EXPECT_NEAR(l * std::tan(l), bi, 1e-8 * (1.0 + bi)) << bi;
        }
    }
}

TEST(Analytic, SeriesStartsFromTheInitialTemperatureAndDecays) {
    const auto ls = sphere_eigenvalues(5.0, 400);
    // At Fo -> 0 the interior is still at theta = 1 (Gibbs-free at interior points).
    EXPECT_NEAR(sphere_theta(ls, 0.0, 1e-4), 1.0, 1e-6);
    EXPECT_NEAR(sphere_mean_theta(ls, 1e-9), 1.0, 5e-3);
    EXPECT_LT(sphere_mean_theta(ls, 1.0), 0.1);
    const auto lp = slab_eigenvalues(5.0, 400);
    EXPECT_NEAR(slab_theta(lp, 0.0, 1e-4), 1.0, 1e-6);
    EXPECT_NEAR(slab_mean_theta(lp, 1e-9), 1.0, 5e-3);
}

TEST(Analytic, SmallBiotGivesTheLumpedDecay) {
    // Bi << 1: lambda_1^2 -> 3 Bi (sphere), Bi (slab); theta ~ exp(-3 Bi Fo).
    const double bi = 1e-4;
    const auto ls = sphere_eigenvalues(bi, 50);
    EXPECT_NEAR(ls[0] * ls[0] / (3.0 * bi), 1.0, 1e-4);
    EXPECT_NEAR(sphere_mean_theta(ls, 1000.0), std::exp(-3.0 * bi * 1000.0), 1e-4);
    const auto lp = slab_eigenvalues(bi, 50);
    EXPECT_NEAR(lp[0] * lp[0] / bi, 1.0, 1e-4);
}

} // namespace
} // namespace kiln::heat::analytic
