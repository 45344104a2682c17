// Validation 26: whole-system energy conservation in a closed, insulated scene with many contacts
// (issue 5). Reference: the first law for an adiabatic system without sources: the stored heat
// sum_i C_i T_i is constant. The exchange is conservative by construction (each contact's heat
// rate enters one body and leaves the other as the same number; on resolved grids it is spread
// over patches with the remainder on the last one), so what remains is the linear solver's
// residual.

#include "closed_bed.hpp"
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
    const auto& c = heat.counters();
    record("thermal steps", static_cast<double>(c.thermal_steps), 0, 0, "-");
    record("conducting contacts (sum over steps)", static_cast<double>(c.contacts), 0, 0, "-");
    record_closed_run(heat, run, energy_tolerance, range_tolerance);
    EXPECT_GT(c.contacts, 100000); // many contacts, or the test proves nothing
    expect_closed_run(heat, run, energy_tolerance, range_tolerance);
}

} // namespace
} // namespace kiln::validation
