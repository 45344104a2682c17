#pragma once
// What validations 26, 28 and 29 (closed, insulated scenes) record and require of a closed heat
// run: the first law (sum C T constant up to the solvers' residual, nothing crossing the boundary)
// and the maximum principle (no temperature leaves the initial range 300..600 K).

#include "common/closed_heat_run.hpp"
#include "thermal/thermal_system.hpp"
#include "validation.hpp"

#include <gtest/gtest.h>

namespace kiln::validation {

/// Initial temperature range of the closed scenes (K).
constexpr double closed_lowest = 300.0;
constexpr double closed_highest = 600.0;

/// Records the solver counters, the drift of sum C T against `energy_tolerance` (relative), the
/// external heat (J), the temperature range against `range_tolerance` (K) and the final mean.
inline void record_closed_run(const thermal::ThermalSystem& heat, const test::ClosedHeatRun& run,
                              double energy_tolerance, double range_tolerance) {
    const auto& c = heat.counters();
    record("resolved solves", static_cast<double>(c.solves), 0, 0, "-");
    record("most sub-steps in a thermal step", c.max_substeps, 0, 0, "-");
    record("largest lag ratio dt G / C_patch", c.max_lag_ratio, 0, 0, "-");
    record("mean CG iterations", static_cast<double>(c.iterations) / static_cast<double>(c.solves),
           0, 0, "-");
    record("max relative drift of sum C T", run.drift, 0.0, energy_tolerance, "-");
    record("external heat", heat.external_heat(), 0.0, 0.0, "J");
    record("lowest temperature", run.lowest, closed_lowest, range_tolerance, "K");
    std::printf("  lowest temperature - %g K: %.3e K\n", closed_lowest, run.lowest - closed_lowest);
    record("highest temperature", run.highest, closed_highest, range_tolerance, "K");
    record("final mean temperature", heat.thermal_energy() / heat.heat_capacity(), 0, 0, "K");
}

/// The checks every closed scene must pass: drift below `energy_tolerance`, no external heat
/// beyond the rounding of the resolved solves' balance (1e-15 of the stored heat: there is no
/// convection, flux or hot wall), the range kept to `range_tolerance` (K), every solve converged.
inline void expect_closed_run(const thermal::ThermalSystem& heat, const test::ClosedHeatRun& run,
                              double energy_tolerance, double range_tolerance) {
    EXPECT_LT(run.drift, energy_tolerance);
    EXPECT_NEAR(heat.external_heat(), 0.0, 1e-15 * run.initial_energy);
    EXPECT_GE(run.lowest, closed_lowest - range_tolerance);
    EXPECT_LE(run.highest, closed_highest + range_tolerance);
    EXPECT_EQ(heat.counters().unconverged, 0);
}

} // namespace kiln::validation
