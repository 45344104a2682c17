// Validation 28: whole-system energy conservation in a closed, insulated scene with every
// particle kind (issue 5: "works for every shape that exists"). Spheres (lumped and resolved on
// the spherical grid), 12-sphere clumps (lumped), superballs and 1:2:3 ellipsoids (resolved on
// their Cartesian cut-cell grids, turned with their orientation; and lumped). Reference: the
// first law for an adiabatic system without sources, sum_i m_i c_i T_i = const, and the maximum
// principle (no temperature leaves the initial range). Clump pairs conduct through every touching
// member pair, so one body pair can carry several contacts. Gas in the gaps and radiation between
// neighbours of every kind exchange too (bodies: gaps from their shapes, equivalent radii).

#include "closed_bed.hpp"
#include "common/closed_heat_run.hpp"
#include "dynamics/system.hpp"
#include "thermal/thermal_system.hpp"
#include "validation.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <string>

namespace kiln::validation {
namespace {

/// Value of a counter `"key": N` in the heat summary (-); -1 when absent.
long summary_count(const thermal::ThermalSystem& heat, const std::string& key) {
    const std::string j = heat.summary_json();
    const std::size_t at = j.find("\"" + key + "\": ");
    return at == std::string::npos ? -1 : std::stol(j.substr(at + key.size() + 4));
}

/// Relative drift of sum C T: CG stops at a relative residual of 1e-12 of ||b|| ~ C T / dt per
/// resolved solve; over ~1e5 solves the drift stays well below 1e-9 (as validation 26).
constexpr double energy_tolerance = 1e-9;
/// Maximum principle under the lagged explicit exchange with dt G / C_patch <= 0.5 (K).
constexpr double range_tolerance = 1e-6;

TEST(Validation28, MixedShapesInAnInsulatedBoxConserveHeat) {
    reset_results();
    const io::CaseSpec spec = load_case();
    dynamics::System sys(spec.scene);
    thermal::ThermalSystem heat(spec.heat, sys);
    for (const std::string& line : heat.describe()) {
        std::printf("  %s\n", line.c_str());
    }
    const long steps = std::lround(spec.run.end_time / sys.dt());
    long body_contacts = 0; // conducting-contact candidates involving a body, over thermal steps
    std::vector<dynamics::ContactRecord> contacts;
    const test::ClosedHeatRun run = test::run_closed_heat(sys, heat, steps, [&] {
        sys.collect_contacts(contacts);
        const ParticleStore& p = sys.particles();
        for (const auto& c : contacts) {
            body_contacts += p.shape[c.i] >= 0 || (!c.wall && p.shape[c.j] >= 0) ? 1 : 0;
        }
    });
    const auto& c = heat.counters();
    record("particles", static_cast<double>(sys.particles().size()), 0, 0, "-");
    record("thermal steps", static_cast<double>(c.thermal_steps), 0, 0, "-");
    record("conducting contacts (sum over steps)", static_cast<double>(c.contacts), 0, 0, "-");
    record("contacts with a body (sum over steps)", static_cast<double>(body_contacts), 0, 0, "-");
    const long gas_pairs = summary_count(heat, "gas_gap_pairs");
    const long radiation_pairs = summary_count(heat, "radiation_pairs");
    record("gas-gap exchanges (sum over steps)", static_cast<double>(gas_pairs), 0, 0, "-");
    record("radiating pairs (sum over steps)", static_cast<double>(radiation_pairs), 0, 0, "-");
    record_closed_run(heat, run, energy_tolerance, range_tolerance);
    EXPECT_EQ(static_cast<long>(sys.particles().size()), 134);
    EXPECT_GT(body_contacts, 10000); // bodies conduct a lot, or the test proves nothing
    EXPECT_GT(gas_pairs, 10000);     // and so do the gaps
    EXPECT_GT(radiation_pairs, 10000);
    expect_closed_run(heat, run, energy_tolerance, range_tolerance);
    EXPECT_EQ(sys.narrow_phase_counters().failures, 0);
}

} // namespace
} // namespace kiln::validation
