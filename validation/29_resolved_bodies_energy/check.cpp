// Validation 29: whole-system energy conservation in a closed, insulated scene with resolved
// clumps (12-sphere cylinders) and resolved polyhedra (cubes, icosahedra) on their body-fixed
// Cartesian cut-cell grids, turned with their orientation, among lumped spheres and resolved
// spheres on the spherical grid. Reference: the first law for an adiabatic system without
// sources, sum_i m_i c_i T_i = const, and the maximum principle (no temperature leaves the
// initial range). Validation 28 covers superquadrics and lumped clumps (superquadrics and
// polyhedra do not meet in one scene yet).

#include "closed_bed.hpp"
#include "common/closed_heat_run.hpp"
#include "dynamics/system.hpp"
#include "thermal/thermal_system.hpp"
#include "validation.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <variant>

namespace kiln::validation {
namespace {

/// Relative drift of sum C T: CG stops at a relative residual of 1e-12 of ||b|| ~ C T / dt per
/// resolved solve; over ~1e5 solves the drift stays well below 1e-9 (as validations 26, 28).
constexpr double energy_tolerance = 1e-9;
/// Maximum principle (K). Cartesian patches split a contact's heat by each cell's distance to the
/// partner's temperature (split_weights in thermal_contacts.cpp), so no cell crosses it within a
/// sub-step and a donor cell at 300 K gives nothing. With the earlier uniform split (per capacity)
/// the lowest cell dipped 3.3e-4 K below 300 K and the bound had been raised to 1e-3 K; measured
/// now: 8.9e-12 K (solver tolerance), so the bound is back at 1e-4 K (README, finding 2). A real
/// violation (the lag limit) is O(10 K).
constexpr double range_tolerance = 1e-4;

TEST(Validation29, ResolvedClumpsAndPolyhedraInAnInsulatedBoxConserveHeat) {
    reset_results();
    const io::CaseSpec spec = load_case();
    dynamics::System sys(spec.scene);
    thermal::ThermalSystem heat(spec.heat, sys);
    for (const std::string& line : heat.describe()) {
        std::printf("  %s\n", line.c_str());
    }
    const long steps = std::lround(spec.run.end_time / sys.dt());
    long clump_contacts = 0; // contact-steps with a resolved clump / polyhedron on either side
    long polyhedron_contacts = 0;
    std::vector<dynamics::ContactRecord> contacts;
    const auto kind = [&](std::uint32_t i) {
        const int s = sys.particles().shape[i];
        if (s < 0) {
            return 0;
        }
        const auto& shape = sys.spec().shapes[static_cast<std::size_t>(s)].shape;
        return std::holds_alternative<geometry::Clump>(shape)              ? 1
               : std::holds_alternative<geometry::ConvexPolyhedron>(shape) ? 2
                                                                           : 0;
    };
    const test::ClosedHeatRun run = test::run_closed_heat(sys, heat, steps, [&] {
        sys.collect_contacts(contacts);
        for (const auto& c : contacts) {
            const int ki = kind(c.i);
            const int kj = c.wall ? 0 : kind(c.j);
            clump_contacts += ki == 1 || kj == 1 ? 1 : 0;
            polyhedron_contacts += ki == 2 || kj == 2 ? 1 : 0;
        }
    });
    const auto& c = heat.counters();
    record("particles", static_cast<double>(sys.particles().size()), 0, 0, "-");
    record("thermal steps", static_cast<double>(c.thermal_steps), 0, 0, "-");
    record("conducting contacts (sum over steps)", static_cast<double>(c.contacts), 0, 0, "-");
    record("contacts with a clump (sum over steps)", static_cast<double>(clump_contacts), 0, 0,
           "-");
    record("contacts with a polyhedron (sum over steps)", static_cast<double>(polyhedron_contacts),
           0, 0, "-");
    record_closed_run(heat, run, energy_tolerance, range_tolerance);
    EXPECT_EQ(static_cast<long>(sys.particles().size()), 118);
    // Both kinds conduct a lot (walls are adiabatic and not counted by the heat module, but
    // counted here), or the test proves nothing.
    EXPECT_GT(clump_contacts, 2000);
    EXPECT_GT(polyhedron_contacts, 2000);
    expect_closed_run(heat, run, energy_tolerance, range_tolerance);
    EXPECT_EQ(sys.narrow_phase_counters().failures, 0);
}

} // namespace
} // namespace kiln::validation
