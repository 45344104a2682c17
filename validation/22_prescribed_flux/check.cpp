// Validation 22: prescribed surface heat flux (seed V-3, Oschmann et al. 2016 Inv. V: a uniform
// flux q gives a linear rise of the mean temperature, dT/dt = q A / (rho c_p V), for any shape).
// Energy balance: heat stored = heat supplied, to the solver tolerance, for every grid and solver,
// with a uniform flux and with a one-sided (non-uniform) flux plus per-cell heat rates.

#include "heat/cartesian_grid.hpp"
#include "heat/resolved_model.hpp"
#include "heat/spherical_grid.hpp"
#include "validation.hpp"

#include <cmath>
#include <cstdio>
#include <gtest/gtest.h>
#include <memory>
#include <string>
#include <vector>

namespace kiln::validation {
namespace {

const heat::ThermalProperties steel{14.9, 7900.0, 477.0}; // seed Table 1, Inv. V
constexpr double q = 1e4;                                 // W/m^2, seed V-3
constexpr double dt = 1.0;                                // s
constexpr int steps = 50;

/// Relative energy balance error: the solver stops at ||r|| <= 1e-12 ||b||, b ~ C T / dt, so
/// the stored heat is exact to ~1e-12 of C T, i.e. ~1e-10 of the heat supplied here.
constexpr double balance_tolerance = 1e-8;
/// Mean-temperature rise against q A_exact t / (rho c V_exact): exact for the spherical grid and
/// the box (geometry exact); the cut-cell sphere carries its area/volume error (< 2e-4 at 24
/// across, see the unit tests).
constexpr double rise_tolerance_exact_geometry = 1e-8;
constexpr double rise_tolerance_cut_cells = 1e-3;

struct Case {
    std::string name;
    std::shared_ptr<const heat::ThermalGrid> grid;
    double area = 0.0;   // exact surface area (m^2)
    double volume = 0.0; // exact volume (m^3)
    double rise_tolerance = 0.0;
};

std::vector<Case> cases() {
    const double r = 0.05;
    const double pi = 3.14159265358979323846;
    const heat::Shape box = heat::Box{Vec3(0.05, 0.03, 0.02)};
    const heat::Shape sphere = heat::Sphere{r};
    const heat::Shape sq = heat::Superquadric{Vec3(0.05, 0.04, 0.03), 0.4, 0.8};
    return {
        {"sphere, spherical 10x8x16",
         std::make_shared<const heat::ThermalGrid>(heat::make_spherical_grid(r, {10, 8, 16})),
         4.0 * pi * r * r, 4.0 / 3.0 * pi * r * r * r, rise_tolerance_exact_geometry},
        {"sphere, Cartesian 24",
         std::make_shared<const heat::ThermalGrid>(
             heat::make_cartesian_grid(sphere, {.cells_across = 24})),
         heat::reference_area(sphere), heat::exact_volume(sphere), rise_tolerance_cut_cells},
        {"box, Cartesian 20",
         std::make_shared<const heat::ThermalGrid>(
             heat::make_cartesian_grid(box, {.cells_across = 20})),
         heat::reference_area(box), heat::exact_volume(box), rise_tolerance_exact_geometry},
        {"superquadric, Cartesian 20",
         std::make_shared<const heat::ThermalGrid>(
             heat::make_cartesian_grid(sq, {.cells_across = 20})),
         heat::reference_area(sq), heat::exact_volume(sq), rise_tolerance_cut_cells},
    };
}

std::vector<heat::SolverKind> solvers() {
    std::vector<heat::SolverKind> s{heat::SolverKind::cg, heat::SolverKind::bicgstab};
    if (heat::cholmod_available()) {
        s.push_back(heat::SolverKind::cholmod);
    }
    return s;
}

TEST(PrescribedFlux, UniformFluxRaisesTheMeanLinearlyAndConservesEnergy) {
    reset_results();
    const std::vector<double> no_h;
    std::printf("\n  %-28s %-9s %-12s %-12s %-6s\n", "grid", "solver", "balance err", "rise err",
                "iters/step");
    for (const Case& c : cases()) {
        for (const heat::SolverKind k : solvers()) {
            heat::ResolvedOperator op(c.grid, steel, dt, no_h, {k, 1e-12, 5000});
            std::vector<double> t(static_cast<std::size_t>(c.grid->size()), 300.0);
            const double e0 = heat::stored_heat(op.cell_capacity(), t);
            double supplied = 0.0;
            for (int s = 0; s < steps; ++s) {
                supplied += op.step(t, {.flux = q}).heat_in;
            }
            const double stored = heat::stored_heat(op.cell_capacity(), t) - e0;
            const double balance = std::abs(stored / supplied - 1.0);
            const double rise_ref =
                q * c.area * dt * steps / (steel.density * steel.heat_capacity * c.volume);
            const double rise = heat::mean_temperature(*c.grid, t) - 300.0;
            const double rise_err = std::abs(rise / rise_ref - 1.0);
            std::printf("  %-28s %-9s %-12.2e %-12.2e %.1f\n", c.name.c_str(),
                        std::string(heat::to_string(k)).c_str(), balance, rise_err,
                        static_cast<double>(op.total_iterations()) / steps);
            record(c.name + " " + std::string(heat::to_string(k)) + " balance", balance, 0.0,
                   balance_tolerance, "-");
            EXPECT_LT(balance, balance_tolerance) << c.name;
            EXPECT_LT(rise_err, c.rise_tolerance) << c.name;
        }
    }
}

TEST(PrescribedFlux, NonUniformFluxAndHeatRatesBalance) {
    const std::vector<double> h{25.0};
    for (const Case& c : cases()) {
        // Flux on the +x half, an external heat rate (as contact conduction will give) on the -z
        // half, convection everywhere.
        std::vector<double> flux(c.grid->boundary.size(), 0.0);
        std::vector<double> rate(c.grid->boundary.size(), 0.0);
        for (std::size_t f = 0; f < flux.size(); ++f) {
            const Vec3& n = c.grid->boundary[f].area_normal;
            flux[f] = n.x() > 0.0 ? q : 0.0;
            rate[f] = n.z() < 0.0 ? 0.01 : 0.0;
        }
        heat::ResolvedOperator op(c.grid, steel, dt, h, {heat::SolverKind::cg, 1e-12, 5000});
        std::vector<double> t(static_cast<std::size_t>(c.grid->size()), 300.0);
        const double e0 = heat::stored_heat(op.cell_capacity(), t);
        double supplied = 0.0;
        for (int s = 0; s < steps; ++s) {
            supplied +=
                op.step(t, {.ambient = 290.0, .flux_per_face = flux, .heat_rate = rate}).heat_in;
        }
        const double stored = heat::stored_heat(op.cell_capacity(), t) - e0;
        const double balance = std::abs(stored / supplied - 1.0);
        record(c.name + " non-uniform balance", balance, 0.0, balance_tolerance, "-");
        EXPECT_LT(balance, balance_tolerance) << c.name;
    }
}

TEST(PrescribedFlux, SeedCaseV3MeanTemperatures) {
    // Seed Inv. V, §4.2 (L2030-2032): cube of edge 0.1 m at 300 K, q = 1e4 W/m^2, glass and steel;
    // the text reports ~460 K (glass) and ~380 K (steel) "after 50 s". The seed notes (§8) flag
    // these as inconsistent with a heat balance, which gives them at ~500 s. Measured here on the
    // 21^3 grid the seed used (20 cells across: 21 cells per edge), CHOLMOD or CG, dt = 1 s.
    const heat::Shape cube = heat::Box{Vec3::Constant(0.05)};
    const auto g = std::make_shared<const heat::ThermalGrid>(
        heat::make_cartesian_grid(cube, {.cells_across = 20}));
    const heat::ThermalProperties glass{1.4, 2225.0, 835.0};
    const std::vector<double> no_h;
    std::printf("\n  seed V-3 cube: mean temperature (K) at 50 s and 500 s\n");
    for (const auto& [name, props] : std::vector<std::pair<std::string, heat::ThermalProperties>>{
             {"glass", glass}, {"steel", steel}}) {
        heat::ResolvedOperator op(
            g, props, 1.0, no_h,
            {heat::cholmod_available() ? heat::SolverKind::cholmod : heat::SolverKind::cg, 1e-12,
             5000});
        std::vector<double> t(static_cast<std::size_t>(g->size()), 300.0);
        double t50 = 0.0;
        for (int s = 1; s <= 500; ++s) {
            (void)op.step(t, {.flux = q});
            if (s == 50) {
                t50 = heat::mean_temperature(*g, t);
            }
        }
        const double t500 = heat::mean_temperature(*g, t);
        // Heat balance: 300 K + 6 q t / (rho c_p L), L = 0.1 m.
        const double ref50 = 300.0 + 6.0 * q * 50.0 / (props.density * props.heat_capacity * 0.1);
        const double ref500 = 300.0 + 6.0 * q * 500.0 / (props.density * props.heat_capacity * 0.1);
        std::printf("  %-6s 50 s: %.2f K (balance %.2f K)   500 s: %.2f K (balance %.2f K)\n",
                    name.c_str(), t50, ref50, t500, ref500);
        record("seed V-3 " + name + " mean T at 500 s", t500, ref500, balance_tolerance, "K");
        EXPECT_NEAR(t50 / ref50, 1.0, balance_tolerance);
        EXPECT_NEAR(t500 / ref500, 1.0, balance_tolerance);
    }
}

} // namespace
} // namespace kiln::validation
