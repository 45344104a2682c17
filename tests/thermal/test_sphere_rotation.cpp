// Resolved spheres' grids turn with their spin ([heat] sphere_rotation): the orientation follows
// the angular velocity, and wall heat entering at a fixed world point spreads around the band the
// spin sweeps past it instead of piling up on one side of the grid.

#include "dynamics/system.hpp"
#include "thermal/thermal_system.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <gtest/gtest.h>
#include <limits>
#include <numbers>
#include <vector>

namespace kiln::thermal {
namespace {

constexpr double radius = 5e-3;
constexpr double nan = std::numeric_limits<double>::quiet_NaN();

HeatSpec resolved_heat(const dynamics::SceneSpec& s, bool rotation) {
    HeatSpec h;
    h.enabled = true;
    h.step_multiple = 100;
    h.solver.tolerance = 1e-12;
    h.sphere_rotation = rotation;
    MaterialHeat m;
    m.enabled = true;
    m.conductivity = 1.0;
    m.specific_heat = 900;
    m.initial_temperature = 300;
    m.model = heat::HeatModel::resolved;
    m.spherical = {6, 4, 8};
    h.materials.assign(s.materials.size(), m);
    return h;
}

TEST(SphereRotation, GridOrientationFollowsTheSpin) {
    // A free sphere spinning about a tilted axis, no gravity, nothing to touch: after n steps its
    // grid has turned by |w| n dt about w (the integration is exact for a constant w).
    dynamics::SceneSpec s;
    s.materials.push_back({"a", 1e7, 0.3, 2700, 0.5, 0.3, 0.0});
    s.gravity = Vec3::Zero();
    s.time_step = 1e-5;
    const Vec3 w = Vec3(30.0, -20.0, 60.0);
    s.particles.push_back({0, radius, Vec3::Zero(), Vec3::Zero(), w});
    for (const bool rotation : {true, false}) {
        dynamics::System sys(s);
        ThermalSystem heat(resolved_heat(s, rotation), sys);
        const int steps = 3000;
        for (int k = 0; k < steps; ++k) {
            sys.step();
            heat.after_step(sys);
        }
        const std::vector<FieldView> views = heat.fields(sys, {});
        ASSERT_EQ(views.size(), 1U);
        const Quat expected =
            rotation ? Quat(Eigen::AngleAxisd(w.norm() * steps * s.time_step, w.normalized()))
                     : Quat::Identity();
        EXPECT_LT(views[0].q.angularDistance(expected), 1e-10) << rotation;
        EXPECT_TRUE(sys.particles().omega[0].isApprox(w, 1e-14)); // free spin stays
    }
}

/// Spread (max - min) / (max - 300 K) of the temperatures around the ring of outer-shell cells
/// (body frame) that holds the hottest outer cell: the cells at its distance from the centre and
/// its height z, one per azimuthal sector of the spherical grid.
double ring_spread(const FieldView& v) {
    double r_max = 0.0;
    for (const Vec3& x : v.grid->node) {
        r_max = std::max(r_max, x.norm());
    }
    int hottest = -1;
    for (int k = 0; k < v.grid->size(); ++k) {
        const auto c = static_cast<std::size_t>(k);
        if (v.grid->node[c].norm() > 0.99 * r_max &&
            (hottest < 0 || v.field[c] > v.field[static_cast<std::size_t>(hottest)])) {
            hottest = k;
        }
    }
    const double z = v.grid->node[static_cast<std::size_t>(hottest)].z();
    double lo = std::numeric_limits<double>::infinity();
    double hi = -lo;
    int cells = 0;
    for (int k = 0; k < v.grid->size(); ++k) {
        const auto c = static_cast<std::size_t>(k);
        if (v.grid->node[c].norm() > 0.99 * r_max && std::abs(v.grid->node[c].z() - z) < 1e-9) {
            lo = std::min(lo, v.field[c]);
            hi = std::max(hi, v.field[c]);
            ++cells;
        }
    }
    EXPECT_EQ(cells, 8); // the grid's azimuthal sectors
    return (hi - lo) / (hi - 300.0);
}

TEST(SphereRotation, SpinningSphereOnAHotWallHeatsItsWholeEquator) {
    // A frictionless sphere squeezed between a hot plane (x = -l, 600 K) and an adiabatic one
    // (x = +l), spinning about z at 100 rad/s (3.2 turns in 0.2 s): the hot contact at world -x
    // sweeps around the grid's equator. With the grid turning, the outer cells of the heated ring
    // warm nearly alike (measured: spread 0.26); with the world-fixed grid, the heat stays in the
    // one cell facing the wall (spread 1.00). Heat is conserved either way: the stored heat rises
    // by what the wall gave.
    dynamics::SceneSpec s;
    s.materials.push_back({"a", 1e7, 0.3, 2700, 0.2, 0.0, 0.0}); // no friction: the spin stays
    s.gravity = Vec3::Zero();
    s.time_step = 1e-5;
    const double overlap = 2e-5;
    const double l = radius - overlap;
    s.walls.push_back({"hot", dynamics::PlaneWall{Vec3(-l, 0, 0), Vec3::UnitX()}, 0});
    s.walls.push_back({"cold", dynamics::PlaneWall{Vec3(l, 0, 0), -Vec3::UnitX()}, 0});
    s.particles.push_back({0, radius, Vec3::Zero(), Vec3::Zero(), Vec3(0, 0, 100.0)});
    double spread[2] = {0, 0};
    for (const bool rotation : {true, false}) {
        dynamics::System sys(s);
        HeatSpec h = resolved_heat(s, rotation);
        h.wall_temperature = {600.0, nan};
        ThermalSystem heat(h, sys);
        const double e0 = heat.thermal_energy();
        for (int k = 0; k < 20000; ++k) {
            sys.step();
            heat.after_step(sys);
        }
        EXPECT_GT(heat.counters().contacts, 150); // the wall conducted most thermal steps
        EXPECT_NEAR(heat.thermal_energy() - e0, heat.external_heat(), 1e-9 * e0);
        EXPECT_GT(heat.external_heat(), 0.0);
        const std::vector<FieldView> views = heat.fields(sys, {});
        ASSERT_EQ(views.size(), 1U);
        spread[rotation ? 0 : 1] = ring_spread(views[0]);
    }
    std::printf("  ring spread (max - min) / (max - 300 K): turning %.3f, world-fixed %.3f\n",
                spread[0], spread[1]);
    EXPECT_GT(spread[1], 0.9);             // world-fixed grid: the far side stays near 300 K
    EXPECT_LT(spread[0], 0.5 * spread[1]); // turning grid: the band warms around
}

} // namespace
} // namespace kiln::thermal
