// Validation 23: thermally thin limit. For Bi = h L / k << 1 the resolved field is uniform and its
// mean follows the lumped model C dT/dt = h A (T_inf - T) (Oschmann et al. 2016, Inv. V eq. 1;
// validity Bi << 1, seed L511). Both discretisations use backward Euler with the same step, so the
// only difference left is the internal resistance: for a sphere the resolved mean lags by about
// Bi/5 of the lumped change (one-term series: lambda_1^2 = 3 Bi (1 - Bi/5 + ...)).

#include "heat/cartesian_grid.hpp"
#include "heat/lumped_model.hpp"
#include "heat/resolved_model.hpp"
#include "heat/spherical_grid.hpp"
#include "validation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <gtest/gtest.h>
#include <memory>
#include <string>
#include <vector>

namespace kiln::validation {
namespace {

/// |theta_resolved - theta_lumped| relative to the driving difference may be at most Bi: the
/// internal resistance contributes ~Bi/5 (sphere) to ~Bi/3 (cube), and a factor >= 3 is kept
/// for the difference between the e-folding times over the run.
constexpr double bi_factor = 1.0;
/// Inside-to-surface spread of the resolved field, relative to the driving difference, may be at
/// most Bi (it is ~Bi/2 for a sphere at quasi-steady state).
constexpr double spread_factor = 1.0;

TEST(ThinLimit, ResolvedMeanFollowsLumpedForSmallBiot) {
    reset_results();
    const double r = 0.005;
    const heat::ThermalProperties aluminium{237.0, 2702.0, 903.0}; // seed Table 1
    std::printf("\n  %-22s %-8s %-14s %-12s\n", "grid", "Bi", "max |dtheta|", "spread");
    for (const double bi : {1e-3, 1e-2, 1e-1}) {
        const double h = bi * aluminium.conductivity / r;
        const double tau = aluminium.density * aluminium.heat_capacity * r / (3.0 * h);
        const double dt = tau / 50.0;
        const std::vector<double> hv{h};
        const std::vector<std::pair<std::string, std::shared_ptr<const heat::ThermalGrid>>> grids{
            {"spherical 8x4x8",
             std::make_shared<const heat::ThermalGrid>(heat::make_spherical_grid(r, {8, 4, 8}))},
            {"Cartesian 12", std::make_shared<const heat::ThermalGrid>(heat::make_cartesian_grid(
                                 heat::Sphere{r}, {.cells_across = 12}))}};
        for (const auto& [name, g] : grids) {
            heat::ResolvedOperator op(g, aluminium, dt, hv, {heat::SolverKind::cg, 1e-12, 5000});
            // The lumped particle gets the grid's own volume and area, so geometry is not tested
            // here (case 20 and the unit tests do that).
            const heat::LumpedModel lumped(aluminium, g->total_volume(), g->total_area());
            std::vector<double> t(static_cast<std::size_t>(g->size()), 1.0);
            double tl = 1.0;
            double worst = 0.0;
            double spread = 0.0;
            for (int s = 0; s < 150; ++s) { // three e-folding times
                (void)op.step(t, {.ambient = 0.0});
                tl = lumped.step(tl, dt, h, 0.0, 0.0, 0.0);
                worst = std::max(worst, std::abs(heat::mean_temperature(*g, t) - tl));
                const auto [lo, hi] = std::minmax_element(t.begin(), t.end());
                spread = std::max(spread, *hi - *lo);
            }
            std::printf("  %-22s %-8g %-14.3e %-12.3e\n", name.c_str(), bi, worst, spread);
            record(name + " Bi=" + std::to_string(bi).substr(0, 5) + " |theta_res - theta_lump|",
                   worst, 0.0, bi_factor * bi, "-");
            if (bi <= 1e-2) {
                EXPECT_LT(worst, bi_factor * bi) << name << " Bi " << bi;
                EXPECT_LT(spread, spread_factor * bi) << name << " Bi " << bi;
            }
        }
    }
}

} // namespace
} // namespace kiln::validation
