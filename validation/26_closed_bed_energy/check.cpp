// Validation 26: whole-system energy conservation in a closed, insulated scene with many contacts
// (issue 5). Reference: the first law for an adiabatic system without sources: the stored heat
// sum_i C_i T_i is constant. The exchange is conservative by construction (each contact's heat
// rate enters one body and leaves the other as the same number; on resolved grids it is spread
// over patches with the remainder on the last one), so what remains is the linear solver's
// residual.

#include "common/closed_heat_run.hpp"
#include "dynamics/system.hpp"
#include "thermal/thermal_system.hpp"
#include "validation.hpp"

#include <cmath>
#include <gtest/gtest.h>

namespace kiln::validation {
namespace {

/// Relative drift of sum C T: CG stops at a relative residual of 1e-12 of ||b|| ~ C T / dt per
/// particle and step; over ~1e5 resolved solves the drift stays well below 1e-9.
constexpr double energy_tolerance = 1e-9;
/// Maximum principle: adiabatic exchange between bodies at 300..600 K cannot leave that range;
/// the lagged explicit exchange keeps it while dt G / C <= 0.5 (sub-steps ensure it) (K).
constexpr double range_tolerance = 1e-6;

TEST(Validation26, ClosedInsulatedBedConservesHeat) {
    reset_results();
    const io::CaseSpec spec = load_case();
    dynamics::System sys(spec.scene);
    thermal::ThermalSystem heat(spec.heat, sys);
    const long steps = std::lround(spec.run.end_time / sys.dt());
    const test::ClosedHeatRun run = test::run_closed_heat(sys, heat, steps);
    const double e0 = run.initial_energy;
    const double drift = run.drift;
    const double lo = run.lowest;
    const double hi = run.highest;
    const auto& c = heat.counters();
    record("thermal steps", static_cast<double>(c.thermal_steps), 0, 0, "-");
    record("conducting contacts (sum over steps)", static_cast<double>(c.contacts), 0, 0, "-");
    record("resolved solves", static_cast<double>(c.solves), 0, 0, "-");
    record("most sub-steps in a thermal step", c.max_substeps, 0, 0, "-");
    record("largest lag ratio dt G / C_patch", c.max_lag_ratio, 0, 0, "-");
    record("mean CG iterations", static_cast<double>(c.iterations) / static_cast<double>(c.solves),
           0, 0, "-");
    record("max relative drift of sum C T", drift, 0.0, energy_tolerance, "-");
    record("external heat", heat.external_heat(), 0.0, 0.0, "J");
    record("lowest temperature", lo, 300.0, range_tolerance, "K");
    record("highest temperature", hi, 600.0, range_tolerance, "K");
    record("final mean temperature", heat.thermal_energy() / heat.heat_capacity(), 0, 0, "K");
    EXPECT_GT(c.contacts, 100000); // many contacts, or the test proves nothing
    EXPECT_LT(drift, energy_tolerance);
    // No convection, flux or hot wall: the external account holds only the rounding of the
    // resolved solves' balance (heat_in minus the contact rates), J relative to the stored heat.
    EXPECT_NEAR(heat.external_heat(), 0.0, 1e-15 * e0);
    EXPECT_GE(lo, 300.0 - range_tolerance);
    EXPECT_LE(hi, 600.0 + range_tolerance);
    EXPECT_EQ(c.unconverged, 0);
}

} // namespace
} // namespace kiln::validation
