// Validation 25: two spheres in static contact (seed V-5: Oschmann et al. 2016, Inv. V,
// L2059-2071, Figs. 9-10; seed notes §5.1), run through the coupled loop (System + ThermalSystem),
// lumped and resolved, for aluminium, steel and glass (seed Table 1, L1973).
//
// References:
// - lumped: the two-body problem C dT1/dt = H (T2 - T1), C dT2/dt = H (T1 - T2) with the static
//   contact conductance H = 2 k r_c (Batchelor & O'Brien 1977 / Zhou et al. 2010, seed Inv. V
//   eq. 12 with c = 1): dT(t) = dT0 exp(-2 H t / C). The lagged (explicit) exchange makes it
//   dT0 (1 - 2 H dt / C)^n exactly, which is compared to rounding;
// - the seed's findings (no numbers are printed for V-5): only aluminium reaches a common mean
//   temperature within 1000 s; for aluminium the resolved model shows no noticeable deviation from
//   the FVM even on a coarse grid (thermally thin: resolved = lumped); for thermally thick
//   particles heat travels faster through contacts in the lumped model (Inv. V L2098-2110, V-8).

#include "dynamics/system.hpp"
#include "heat/contact_conduction.hpp"
#include "thermal/thermal_system.hpp"
#include "validation.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <numbers>
#include <string>
#include <vector>

namespace kiln::validation {
namespace {

struct Solid {
    const char* name;
    double density; // kg/m^3
    double c_p;     // J/(kg K)
    double k;       // W/(m K)
};
// Seed Table 1 (Inv. V, L1973-1979).
constexpr Solid solids[] = {
    {"aluminium", 2702, 903, 237}, {"steel", 7900, 477, 14.9}, {"glass", 2225, 835, 1.4}};

constexpr double radius = 0.05;    // m
constexpr double overlap = 2.5e-3; // m
constexpr double dt0 = 300.0;      // K, initial difference

/// The pair overlap held by the squeezing walls against the seed's 2.5 mm (m): the wall positions
/// are given to 1e-8 m in case.toml.
constexpr double overlap_tolerance = 1e-8;
/// Lumped run against (1 - 2 H dt / C)^n: a few roundings per step over 1e4 steps (relative).
constexpr double discrete_tolerance = 1e-9;
/// Lumped run against the continuous exponential at 100 s: the explicit step errs by
/// t (2H/C)^2 dt / 2 = 3.4e-4 relative for aluminium (the fastest).
constexpr double exponential_tolerance = 1e-3;
/// Stored heat of the closed pair: lumped exchange is antisymmetric (rounding); resolved solves
/// leave 1e-12 of ||b|| per step (relative to the stored heat).
constexpr double energy_tolerance = 1e-9;
/// Aluminium, resolved mean vs lumped mean, as a fraction of the initial difference: the seed
/// finds no noticeable deviation for this thermally thin material. Bi_contact = H / (k 4 pi R^2
/// / R) is small, so the resolved grid's internal resistance changes the rate by ~1 %.
constexpr double thin_tolerance = 0.02;
/// "Equalised" (seed: aluminium reaches the same mean temperature): below 1 K.
constexpr double equalised = 1.0;

struct PairRun {
    std::vector<double> t, diff;  // time (s), mean T1 - mean T2 (K)
    std::vector<double> discrete; // lumped reference dT0 prod (1 - 2 H dt / C) (K)
    double energy_drift = 0;      // relative
    double h = 0, c = 0;          // conductance (W/K), capacity (J/K)
};

PairRun run(const Solid& s, heat::HeatModel model,
            const heat::SphericalResolution* grid = nullptr) {
    io::CaseSpec spec = load_case();
    if (grid != nullptr) {
        spec.heat.materials[0].spherical = *grid;
    }
    spec.scene.materials[0].density = s.density;
    spec.heat.materials[0].conductivity = s.k;
    spec.heat.materials[0].specific_heat = s.c_p;
    spec.heat.materials[0].model = model;
    if (model == heat::HeatModel::resolved && heat::cholmod_available()) {
        spec.heat.solver.kind = heat::SolverKind::cholmod; // same answer, factor once
    }
    dynamics::System sys(spec.scene);
    thermal::ThermalSystem heat(spec.heat, sys);
    PairRun r;
    const double capacity = s.density * s.c_p * 4.0 / 3.0 * std::numbers::pi * std::pow(radius, 3);
    double discrete = dt0;
    std::vector<dynamics::ContactRecord> contacts;
    const double e0 = heat.thermal_energy();
    const long steps = std::lround(spec.run.end_time / sys.dt());
    const long sample = std::lround(100.0 / sys.dt());
    for (long n = 1; n <= steps; ++n) {
        sys.step();
        if (sys.step_count() % spec.heat.step_multiple == 0) {
            // The exact discrete lumped reference: one factor (1 - 2 H dt / C) per thermal step,
            // H from the overlap the mechanics hold at that step (2.5 mm up to the 1e-9 m rounding
            // of the wall positions in case.toml).
            sys.collect_contacts(contacts);
            for (const auto& c : contacts) {
                if (!c.wall) {
                    EXPECT_NEAR(c.overlap, overlap, overlap_tolerance);
                    const double h = heat::static_contact_conductance(
                        s.k, s.k, heat::lens_contact_radius(c.overlap, radius, radius), 1.0);
                    discrete *= 1.0 - 2.0 * h * heat.time_step() / capacity;
                }
            }
        }
        heat.after_step(sys);
        if (n % sample == 0) {
            r.discrete.push_back(discrete);
            r.t.push_back(sys.time());
            r.diff.push_back(heat.mean_temperature(sys, 0) - heat.mean_temperature(sys, 1));
            if (sys.particles().id[0] != 0) {
                r.diff.back() = -r.diff.back();
            }
            r.energy_drift = std::max(r.energy_drift, std::abs(heat.thermal_energy() - e0) / e0);
        }
    }
    r.h = heat::static_contact_conductance(s.k, s.k,
                                           heat::lens_contact_radius(overlap, radius, radius), 1.0);
    r.c = s.density * s.c_p * 4.0 / 3.0 * std::numbers::pi * std::pow(radius, 3);
    EXPECT_EQ(heat.counters().max_substeps, 1) << "the 0.1 s step is far inside the lag limit";
    EXPECT_EQ(heat.counters().unconverged, 0);
    return r;
}

TEST(Validation25, ContactPairLumpedAndResolved) {
    reset_results();
    double glass_lumped = 0.0;
    double glass_resolved = 0.0;
    for (const Solid& s : solids) {
        const PairRun lumped = run(s, heat::HeatModel::lumped);
        const PairRun resolved = run(s, heat::HeatModel::resolved);
        const std::string m = s.name;
        // Lumped: exact discrete recursion and the exponential.
        for (std::size_t k = 0; k < lumped.t.size(); ++k) {
            const double discrete = lumped.discrete[k];
            EXPECT_NEAR(lumped.diff[k], discrete, discrete_tolerance * dt0)
                << m << " t=" << lumped.t[k];
        }
        const double expo = dt0 * std::exp(-2.0 * lumped.h * 100.0 / lumped.c);
        record(m + " lumped dT(100 s) vs exponential", lumped.diff[0], expo, exponential_tolerance,
               "K (relative tol)");
        EXPECT_NEAR(lumped.diff[0], expo, exponential_tolerance * expo);
        record(m + " lumped energy drift", lumped.energy_drift, 0.0, energy_tolerance, "-");
        record(m + " resolved energy drift", resolved.energy_drift, 0.0, energy_tolerance, "-");
        EXPECT_LT(lumped.energy_drift, energy_tolerance);
        EXPECT_LT(resolved.energy_drift, energy_tolerance);
        for (std::size_t k = 0; k < lumped.t.size(); ++k) {
            record(m + " dT lumped t=" + std::to_string(int(lumped.t[k])), lumped.diff[k],
                   resolved.diff[k], 0.0, "K (reference column: resolved)");
        }
        const double end_lumped = lumped.diff.back();
        const double end_resolved = resolved.diff.back();
        if (m == "aluminium") {
            double worst = 0.0;
            for (std::size_t k = 0; k < lumped.t.size(); ++k) {
                worst = std::max(worst, std::abs(resolved.diff[k] - lumped.diff[k]) / dt0);
            }
            record("aluminium max |resolved - lumped| / dT0", worst, 0.0, thin_tolerance, "-");
            EXPECT_LT(worst, thin_tolerance);
            EXPECT_LT(std::abs(end_lumped), equalised);
            EXPECT_LT(std::abs(end_resolved), equalised);
            // The seed's coarse grid, 1 + 10 x 2 x 4 nodes (L2061: "no noticeable deviations ...
            // even for a resolution of just 2 x 4 x 10 nodes + 1 center node" for aluminium).
            const heat::SphericalResolution coarse{10, 2, 4};
            const PairRun c = run(s, heat::HeatModel::resolved, &coarse);
            double worst_coarse = 0.0;
            for (std::size_t k = 0; k < lumped.t.size(); ++k) {
                worst_coarse = std::max(worst_coarse, std::abs(c.diff[k] - lumped.diff[k]) / dt0);
            }
            record("aluminium coarse grid (81 cells) max |resolved - lumped| / dT0", worst_coarse,
                   0.0, thin_tolerance, "- (seed not matched, README)");
            record("aluminium coarse dT(100 s)", c.diff[0], lumped.diff[0], 0.0,
                   "K (reference column: lumped)");
            record("aluminium coarse dT(300 s)", c.diff[2], lumped.diff[2], 0.0,
                   "K (reference column: lumped)");
            // Not asserted against the seed's "no noticeable deviation": kiln's coarse grid
            // deviates by several % (README). Asserted: it still equalises and conserves heat.
            EXPECT_LT(std::abs(c.diff.back()), equalised);
            EXPECT_LT(c.energy_drift, energy_tolerance);
        } else {
            // Steel and glass do not equalise within 1000 s (seed).
            EXPECT_GT(end_lumped, 50.0) << m;
            EXPECT_GT(end_resolved, 50.0) << m;
        }
        if (m == "glass") {
            glass_lumped = dt0 - end_lumped;
            glass_resolved = dt0 - end_resolved;
        }
    }
    // Glass, resolved against lumped: the seed prints no V-5 number for it. Recorded, not
    // asserted: with T_undist taken from the rows' inner nodes, which stay near the initial
    // temperatures, the exchange stays within 1 % of the lumped one (README).
    record("glass exchanged dT resolved / lumped", glass_resolved / glass_lumped, 1.0, 0.0, "-");
}

} // namespace
} // namespace kiln::validation
