// Stagnation-point distribution of h and its lagged application.

#include "heat/convection.hpp"
#include "heat/heat_model.hpp"
#include "heat/resolved_model.hpp"
#include "heat/spherical_grid.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <memory>
#include <numbers>
#include <vector>

namespace kiln::heat {
namespace {

TEST(Convection, StagnationFactorKeepsTheMeanCoefficient) {
    // Seed notes §2.8: the area-weighted mean of f over a sphere is 1.0001.
    const ThermalGrid g = make_spherical_grid(0.01, {2, 64, 16});
    const std::vector<double> h = stagnation_distribution(g, Vec3(0.0, 0.0, 1.0), 100.0);
    double ha = 0.0;
    for (std::size_t f = 0; f < h.size(); ++f) {
        ha += h[f] * g.boundary[f].area;
    }
    // Midpoint rule over 64 polar bands: error ~ (pi/64)^2 / 24 f'' ~ 1e-4.
    EXPECT_NEAR(ha / g.total_area() / 100.0, 1.0001, 5e-4);
    EXPECT_NEAR(stagnation_factor(0.0), 2.1098, 1e-12);
    EXPECT_NEAR(stagnation_factor(std::numbers::pi), 0.63, 0.01);
}

/// Max |T_lagged - T_implicit| after 20 s for `steps` steps.
double lag_difference(int steps) {
    const auto g = std::make_shared<const ThermalGrid>(make_spherical_grid(0.01, {6, 8, 8}));
    const ThermalProperties p{1.0, 2000.0, 1000.0};
    const std::vector<double> h = stagnation_distribution(*g, Vec3(1.0, 0.0, 0.0), 200.0);
    const std::vector<double> h0{200.0};
    const double dt = 20.0 / steps;
    ResolvedOperator implicit_op(g, p, dt, h, {SolverKind::cg, 1e-13, 2000});
    ResolvedOperator lagged_op(g, p, dt, h0, {SolverKind::cg, 1e-13, 2000});
    std::vector<double> ti(static_cast<std::size_t>(g->size()), 300.0);
    std::vector<double> tl = ti;
    std::vector<double> rate(g->boundary.size());
    const std::vector<double> ambient{400.0};
    for (int s = 0; s < steps; ++s) {
        (void)implicit_op.step(ti, {.ambient = 400.0});
        lagged_convection(*g, p.conductivity, h, h0, ambient, tl, rate);
        (void)lagged_op.step(tl, {.ambient = 400.0, .heat_rate = rate});
    }
    double d = 0.0;
    for (std::size_t i = 0; i < ti.size(); ++i) {
        d = std::max(d, std::abs(ti[i] - tl[i]));
    }
    return d;
}

TEST(Convection, LaggedCoefficientConvergesToTheImplicitOneAtFirstOrder) {
    const double d1 = lag_difference(20);
    const double d2 = lag_difference(40);
    const double d3 = lag_difference(80);
    EXPECT_GT(d1, 0.0);
    // First order in dt: halving dt halves the lag error; band [1.6, 2.4] for the ratio.
    EXPECT_NEAR(d1 / d2, 2.0, 0.4);
    EXPECT_NEAR(d2 / d3, 2.0, 0.4);
}

TEST(Convection, SurfaceTemperatureSitsBetweenNodeAndFluid) {
    const auto g = std::make_shared<const ThermalGrid>(make_spherical_grid(0.01, {4, 4, 8}));
    const std::vector<double> h{500.0};
    ResolvedOperator op(g, {1.0, 2000.0, 1000.0}, 1.0, h, {});
    std::vector<double> t(static_cast<std::size_t>(g->size()), 300.0);
    const BoundaryLoad load{.ambient = 400.0};
    (void)op.step(t, load);
    std::vector<double> ts(g->boundary.size());
    op.surface_temperature(t, load, ts);
    for (std::size_t f = 0; f < ts.size(); ++f) {
        const double node = t[static_cast<std::size_t>(g->boundary[f].cell)];
        EXPECT_GT(ts[f], node);
        EXPECT_LT(ts[f], 400.0);
        // Flux continuity: k (T_s - T_node)/d = h (T_inf - T_s).
        const double d = g->boundary[f].distance;
        EXPECT_NEAR(1.0 * (ts[f] - node) / d, 500.0 * (400.0 - ts[f]), 1e-9 * 500.0 * 100.0);
    }
}

TEST(HeatModelChoice, AutoPicksLumpedBelowTheBiotThreshold) {
    // Sphere: L_c = R/3.
    const double r = 0.003;
    const double v = 4.0 / 3.0 * 3.14159265358979 * r * r * r;
    const double a = 4.0 * 3.14159265358979 * r * r;
    EXPECT_NEAR(biot_number(100.0, v, a, 1.0), 100.0 * r / 3.0, 1e-12);
    EXPECT_EQ(choose_model(HeatModel::automatic, 0.05), HeatModel::lumped);
    EXPECT_EQ(choose_model(HeatModel::automatic, 0.2), HeatModel::resolved);
    EXPECT_EQ(choose_model(HeatModel::resolved, 1e-6), HeatModel::resolved);
    EXPECT_EQ(choose_model(HeatModel::none, 5.0), HeatModel::none);
    EXPECT_EQ(to_string(HeatModel::automatic), "auto");
}

} // namespace
} // namespace kiln::heat
