// Resolved and lumped models: energy conservation, solver agreement, thin-body limit, symmetry.

#include "core/error.hpp"
#include "heat/cartesian_grid.hpp"
#include "heat/lumped_model.hpp"
#include "heat/resolved_model.hpp"
#include "heat/spherical_grid.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <memory>
#include <vector>

namespace kiln::heat {
namespace {

const ThermalProperties glass{1.4, 2225.0, 835.0}; // seed Table 1 (Inv. V)

/// Relative: energy balance residual is the solver residual (1e-12) times the condition of C/dt.
constexpr double energy_tolerance = 1e-9;

std::vector<SolverKind> solvers() {
    std::vector<SolverKind> s{SolverKind::cg, SolverKind::bicgstab};
    if (cholmod_available()) {
        s.push_back(SolverKind::cholmod);
    }
    return s;
}

void expect_energy_balance(const std::shared_ptr<const ThermalGrid>& grid, SolverKind kind) {
    const double q = 1e4; // W/m^2
    const double dt = 0.5;
    const std::vector<double> no_h;
    ResolvedOperator op(grid, glass, dt, no_h, {kind, 1e-12, 2000});
    std::vector<double> t(static_cast<std::size_t>(grid->size()), 300.0);
    // A non-uniform flux: only faces with a positive x normal are heated.
    std::vector<double> flux(grid->boundary.size());
    for (std::size_t f = 0; f < flux.size(); ++f) {
        flux[f] = grid->boundary[f].area_normal.x() > 0.0 ? q : 0.0;
    }
    const double e0 = stored_heat(op.cell_capacity(), t);
    double heat_in = 0.0;
    for (int s = 0; s < 10; ++s) {
        const StepReport r = op.step(t, {.ambient = 0.0, .flux_per_face = flux});
        EXPECT_TRUE(r.solve.converged);
        heat_in += r.heat_in;
    }
    const double stored = stored_heat(op.cell_capacity(), t) - e0;
    double expected = 0.0;
    for (std::size_t f = 0; f < flux.size(); ++f) {
        expected += flux[f] * grid->boundary[f].area * dt * 10.0;
    }
    EXPECT_NEAR(heat_in / expected, 1.0, 1e-14);
    EXPECT_NEAR(stored / expected, 1.0, energy_tolerance) << to_string(kind);
}

TEST(ResolvedModel, PrescribedFluxIsStoredExactlyOnBothGrids) {
    const auto sph = std::make_shared<const ThermalGrid>(make_spherical_grid(0.05, {6, 6, 12}));
    const auto cart = std::make_shared<const ThermalGrid>(
        make_cartesian_grid(Superquadric{Vec3(0.05, 0.04, 0.03), 0.5, 0.7}, {.cells_across = 12}));
    for (const SolverKind k : solvers()) {
        expect_energy_balance(sph, k);
        expect_energy_balance(cart, k);
    }
}

TEST(ResolvedModel, ConvectionEnergyBalanceCountsTheRobinHeat) {
    const auto g = std::make_shared<const ThermalGrid>(make_spherical_grid(0.05, {6, 4, 8}));
    const std::vector<double> h{200.0};
    ResolvedOperator op(g, glass, 1.0, h, {SolverKind::cg, 1e-12, 2000});
    std::vector<double> t(static_cast<std::size_t>(g->size()), 300.0);
    const double e0 = stored_heat(op.cell_capacity(), t);
    double heat_in = 0.0;
    for (int s = 0; s < 20; ++s) {
        heat_in += op.step(t, {.ambient = 600.0}).heat_in;
    }
    EXPECT_NEAR((stored_heat(op.cell_capacity(), t) - e0) / heat_in, 1.0, energy_tolerance);
}

TEST(ResolvedModel, SolversAgree) {
    const auto g = std::make_shared<const ThermalGrid>(make_cartesian_grid(
        Superquadric{Vec3(0.01, 0.008, 0.006), 0.4, 1.0}, {.cells_across = 10}));
    // Stagnation-point distribution h = h0 f(theta) (seed, Inv. VI eq. 8-9) about +x.
    std::vector<double> h(g->boundary.size());
    for (std::size_t f = 0; f < h.size(); ++f) {
        const double th =
            std::acos(std::clamp(g->boundary[f].area_normal.normalized().x(), -1.0, 1.0));
        h[f] = 100.0 * (2.1098 + 0.208 * th - 1.018 * th * th + 0.2552 * th * th * th);
    }
    std::vector<std::vector<double>> fields;
    for (const SolverKind k : solvers()) {
        ResolvedOperator op(g, glass, 0.2, h, {k, 1e-12, 2000});
        std::vector<double> t(static_cast<std::size_t>(g->size()), 300.0);
        for (int s = 0; s < 10; ++s) {
            EXPECT_TRUE(op.step(t, {.ambient = 500.0}).solve.converged);
        }
        fields.push_back(t);
    }
    for (std::size_t k = 1; k < fields.size(); ++k) {
        double diff = 0.0;
        for (std::size_t i = 0; i < fields[0].size(); ++i) {
            diff = std::max(diff, std::abs(fields[k][i] - fields[0][i]));
        }
        // K: residual 1e-12 of a right-hand side ~ C T / dt, amplified by the condition number.
        EXPECT_LT(diff, 1e-7) << k;
    }
}

TEST(ResolvedModel, ExtrapolatedGuessGivesTheSameFieldInFewerIterations) {
    const auto g = std::make_shared<const ThermalGrid>(
        make_cartesian_grid(Box{Vec3::Constant(0.002)}, {.cells_across = 9}));
    const std::vector<double> h{500.0};
    const ThermalProperties p{1.0, 2100.0, 1000.0};
    ResolvedOperator plain(g, p, 0.0127, h, {SolverKind::cg, 1e-12, 1000});
    ResolvedOperator extrapolated(g, p, 0.0127, h, {SolverKind::cg, 1e-12, 1000});
    std::vector<double> a(static_cast<std::size_t>(g->size()), 300.0);
    std::vector<double> b = a;
    std::vector<double> previous = a;
    for (int s = 0; s < 100; ++s) {
        const double ambient = 400.0 + 50.0 * std::sin(0.03 * s);
        (void)plain.step(a, {.ambient = ambient});
        (void)extrapolated.step(b, {.ambient = ambient}, previous);
    }
    double diff = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        diff = std::max(diff, std::abs(a[i] - b[i]));
    }
    // K: |error| <= ||r|| / lambda_min(A), lambda_min >= min C_i / dt ~ 1.8e-3 W/K (corner cells),
    // ||r|| <= 1e-12 ||b|| ~ 1e-12 * 180 W: ~1e-7 K per solve for each of the two runs.
    EXPECT_LT(diff, 1e-6);
    EXPECT_LT(extrapolated.total_iterations(), plain.total_iterations());
}

TEST(ResolvedModel, ThermallyThinSphereEqualsLumped) {
    const double r = 0.005;
    const double h = 50.0;
    const ThermalProperties metal{400.0, 2700.0, 900.0}; // Bi = h R / k = 6e-4
    const auto g = std::make_shared<const ThermalGrid>(make_spherical_grid(r, {5, 4, 8}));
    const std::vector<double> hv{h};
    ResolvedOperator op(g, metal, 1.0, hv, {});
    const LumpedModel lumped(metal, g->total_volume(), g->total_area());
    std::vector<double> t(static_cast<std::size_t>(g->size()), 300.0);
    double tl = 300.0;
    for (int s = 0; s < 200; ++s) {
        (void)op.step(t, {.ambient = 400.0});
        tl = lumped.step(tl, 1.0, h, 400.0, 0.0, 0.0);
    }
    // The resolved mean lags the lumped one by the internal resistance, ~ Bi/5 of the driving
    // difference (Bi = 6e-4 here, driving difference <= 100 K): 0.05 K covers it.
    EXPECT_NEAR(mean_temperature(*g, t), tl, 0.05);
    EXPECT_GT(tl - 300.0, 10.0); // the particle did heat up
}

TEST(ResolvedModel, UniformConvectionKeepsSphericalSymmetry) {
    const SphericalResolution res{6, 6, 12};
    const auto g = std::make_shared<const ThermalGrid>(make_spherical_grid(0.02, res));
    const std::vector<double> h{300.0};
    ResolvedOperator op(g, glass, 0.5, h, {SolverKind::bicgstab, 1e-13, 2000});
    std::vector<double> t(static_cast<std::size_t>(g->size()), 300.0);
    for (int s = 0; s < 20; ++s) {
        (void)op.step(t, {.ambient = 400.0});
    }
    for (int i = 1; i <= res.n_r; ++i) {
        const double ref = t[static_cast<std::size_t>(spherical_index(res, i, 0, 0))];
        for (int j = 0; j < res.n_theta; ++j) {
            for (int k = 0; k < res.n_phi; ++k) {
                EXPECT_NEAR(t[static_cast<std::size_t>(spherical_index(res, i, j, k))], ref, 1e-8);
            }
        }
    }
    // Temperatures rise monotonically from the centre out.
    for (int i = 1; i <= res.n_r; ++i) {
        const double inner =
            i == 1 ? t[0] : t[static_cast<std::size_t>(spherical_index(res, i - 1, 0, 0))];
        EXPECT_GT(t[static_cast<std::size_t>(spherical_index(res, i, 0, 0))], inner);
    }
}

TEST(ResolvedModel, RejectsBadInput) {
    const auto g = std::make_shared<const ThermalGrid>(make_spherical_grid(0.02, {2, 2, 2}));
    const std::vector<double> none;
    const std::vector<double> three{1.0, 2.0, 3.0};
    EXPECT_THROW(ResolvedOperator(g, glass, 0.0, none, {}), InputError);
    EXPECT_THROW(ResolvedOperator(g, {0.0, 1.0, 1.0}, 1.0, none, {}), InputError);
    EXPECT_THROW(ResolvedOperator(g, glass, 1.0, three, {}), InputError);
}

TEST(TemperaturePool, FieldsAreContiguousSlices) {
    TemperaturePool pool;
    const int a = pool.add(3, 300.0);
    const int b = pool.add(5, 400.0);
    EXPECT_EQ(pool.field(a).size(), 3U);
    EXPECT_EQ(pool.field(b).size(), 5U);
    EXPECT_EQ(pool.field(b).data(), pool.field(a).data() + 3);
    pool.field(a)[2] = 1.0;
    EXPECT_EQ(pool.values()[2], 1.0);
    EXPECT_EQ(pool.field(b)[0], 400.0);
}

} // namespace
} // namespace kiln::heat
