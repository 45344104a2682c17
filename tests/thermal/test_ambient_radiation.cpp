// Radiation to the ambient ([heat] radiation_temperature): a grey particle in a black enclosure
// cools as m c dT/dt = -eps sigma A (T^4 - T_a^4), whose solution is known in closed form as t(T).
// With neighbour radiation the neighbours' view factors are taken from the ambient's.
#include "common/closed_heat_run.hpp"
#include "dynamics/system.hpp"
#include "geometry/shape.hpp"
#include "geometry/shape_metrics.hpp"
#include "heat/radiation.hpp"
#include "thermal/thermal_system.hpp"

#include <cmath>
#include <cstdio>
#include <gtest/gtest.h>
#include <numbers>

namespace kiln::thermal {
namespace {

constexpr double radius = 5e-3;       // m
constexpr double density = 2700;      // kg/m^3
constexpr double specific_heat = 900; // J/(kg K)
constexpr double emissivity = 0.8;    // -
constexpr double t_start = 1000;      // K
constexpr double t_ambient = 300;     // K

/// Time (s) for m c dT/dt = -eps sigma A (T^4 - a^4) to cool from t0 to t (> a):
/// int dT / (T^4 - a^4) = (1 / (4 a^3)) [ln((T - a) / (T + a)) - 2 atan(T / a)], so
/// t = (F(t0) - F(t)) m c / (eps sigma A).
double cooling_time(double t, double t0, double a, double capacity, double area) {
    const auto f = [a](double x) {
        return (std::log((x - a) / (x + a)) - 2.0 * std::atan(x / a)) / (4.0 * a * a * a);
    };
    return (f(t0) - f(t)) * capacity / (emissivity * heat::stefan_boltzmann * area);
}

dynamics::SceneSpec one_particle(int shape) {
    dynamics::SceneSpec s;
    s.materials.push_back({"a", 1e7, 0.3, density, 0.5, 0.3, 0.0});
    s.gravity = Vec3::Zero();
    s.time_step = 1e-5;
    if (shape >= 0) {
        geometry::Superquadric q;
        q.half_axes = Vec3(4e-3, 5e-3, 7e-3);
        q.e1 = 0.6;
        q.e2 = 0.8;
        s.shapes.push_back(geometry::make_template("block", q));
        dynamics::ParticleSpec p;
        p.shape = 0;
        s.particles.push_back(p);
    } else {
        s.particles.push_back({0, radius, Vec3::Zero(), Vec3::Zero(), Vec3::Zero()});
    }
    return s;
}

HeatSpec radiating(const dynamics::SceneSpec& s, heat::HeatModel model, int step_multiple) {
    HeatSpec h;
    h.enabled = true;
    h.step_multiple = step_multiple;
    h.solver.tolerance = 1e-12;
    h.radiation_temperature = t_ambient;
    MaterialHeat m;
    m.enabled = true;
    m.conductivity = 200.0; // Bi = 4 eps sigma T^3 (V/A) / k ~ 3e-3 at 1000 K: thermally thin
    m.specific_heat = specific_heat;
    m.initial_temperature = t_start;
    m.model = model;
    m.emissivity = emissivity;
    m.spherical = {4, 4, 8};
    m.cells_across = 8;
    h.materials.assign(s.materials.size(), m);
    return h;
}

/// Largest |t_analytic(T(t)) - t| / t over a cooling to ~430 K (300 s), and the heat balance.
struct Cooling {
    double error = 0;   // relative error of the time (-)
    double balance = 0; // |stored heat change - external heat| / |external heat| (-)
    double final = 0;   // final mean temperature (K)
};

Cooling cool(heat::HeatModel model, int step_multiple, int shape = -1) {
    const dynamics::SceneSpec s = one_particle(shape);
    dynamics::System sys(s);
    ThermalSystem heat(radiating(s, model, step_multiple), sys);
    double volume = 4.0 / 3.0 * std::numbers::pi * radius * radius * radius;
    double area = 4.0 * std::numbers::pi * radius * radius;
    if (shape >= 0) {
        volume = s.shapes[0].volume;
        area = geometry::surface_area(s.shapes[0].shape).value;
    }
    const double capacity = density * specific_heat * volume;
    const double e0 = heat.thermal_energy();
    Cooling c;
    const double end = 300.0;
    const long steps = std::lround(end / heat.time_step());
    for (long n = 1; n <= steps; ++n) {
        heat.thermal_step(sys); // no mechanics needed: a particle alone at rest
        const double t = static_cast<double>(n) * heat.time_step();
        if (n % (steps / 20) == 0) {
            const double tm = heat.mean_temperature(sys, 0);
            c.error = std::max(
                c.error, std::abs(cooling_time(tm, t_start, t_ambient, capacity, area) - t) / t);
        }
    }
    c.final = heat.mean_temperature(sys, 0);
    c.balance = std::abs(heat.thermal_energy() - e0 - heat.external_heat()) /
                std::abs(heat.external_heat());
    return c;
}

TEST(AmbientRadiation, LumpedSphereFollowsTheAnalyticCoolingCurve) {
    const Cooling coarse = cool(heat::HeatModel::lumped, 5000); // thermal step 0.05 s
    const Cooling fine = cool(heat::HeatModel::lumped, 2500);
    std::printf("lumped: time error %.3g (dt 0.05 s), %.3g (0.025 s), final %.2f K\n", coarse.error,
                fine.error, fine.final);
    EXPECT_LT(coarse.final, 500.0); // a real cooling (1000 K -> 461 K)
    EXPECT_GT(coarse.final, t_ambient);
    // Backward Euler with the linearised T^4: first order in dt (ratio 2 when halved).
    EXPECT_LT(coarse.error, 2e-3);
    EXPECT_NEAR(coarse.error / fine.error, 2.0, 0.2);
    EXPECT_LT(coarse.balance, 1e-12); // what left the particle is booked as external heat
}

TEST(AmbientRadiation, ResolvedSphereAtSmallBiotFollowsTheLumpedCurve) {
    // Bi ~ 3e-3: the resolved mean follows the lumped ODE within the lag of the face rates, the
    // node-to-surface drop (O(Bi)) and the time discretisation (as the lumped test).
    const Cooling r = cool(heat::HeatModel::resolved, 5000);
    std::printf("resolved sphere: time error %.3g, balance %.3g, final %.2f K\n", r.error,
                r.balance, r.final);
    EXPECT_LT(r.error, 2e-3); // measured 5.2e-5
    EXPECT_LT(r.balance, 1e-9);
}

TEST(AmbientRadiation, ResolvedAndLumpedSuperquadricFollowTheCurve) {
    // Any shape: a superquadric block on its Cartesian cut-cell grid (8 across), whose area
    // converges at second order to the template's (1e-3 at this resolution), and lumped.
    const Cooling r = cool(heat::HeatModel::resolved, 5000, 0);
    const Cooling l = cool(heat::HeatModel::lumped, 5000, 0);
    std::printf("superquadric: resolved time error %.3g, lumped %.3g\n", r.error, l.error);
    EXPECT_LT(l.error, 2e-3);
    EXPECT_LT(r.error, 5e-3); // measured 1.2e-3: grid area and time step
    EXPECT_LT(r.balance, 1e-9);
}

// ---- Ambient and neighbour radiation together --------------------------------------------------

/// A sphere at the origin with six neighbours on the axes, centres 2.2 R away (gaps 0.2 R: within
/// the radiation cut-off, no contact), at rest without gravity.
dynamics::SceneSpec star(bool neighbours) {
    dynamics::SceneSpec s = one_particle(-1);
    if (neighbours) {
        for (int a = 0; a < 3; ++a) {
            for (const double sign : {-1.0, 1.0}) {
                s.particles.push_back(
                    {0, radius, sign * 2.2 * radius * Vec3::Unit(a), Vec3::Zero(), Vec3::Zero()});
            }
        }
    }
    return s;
}

TEST(AmbientRadiation, NeighboursTakeTheirViewFactorsFromTheAmbient) {
    // Black spheres (e = 1): a hot sphere whose neighbours are at the ambient temperature sits in
    // an isothermal enclosure (neighbours + ambient) and must lose sigma A (T^4 - T_a^4), as when
    // alone. Counting its whole surface towards the ambient and the neighbours would lose
    // (1 + 6 F) as much (F = 0.055 at 2.2 R: +33 %).
    const auto loss = [](bool neighbours) {
        const dynamics::SceneSpec s = star(neighbours);
        dynamics::System sys(s);
        HeatSpec h = radiating(s, heat::HeatModel::lumped, 100); // one thermal step of 1 ms
        h.materials[0].emissivity = 1.0;
        h.materials[0].initial_temperature = t_ambient;
        h.particle_temperature = {600.0};
        ThermalSystem heat(h, sys);
        for (int k = 0; k < h.step_multiple; ++k) {
            sys.step();
            heat.after_step(sys);
        }
        std::size_t i = 0; // the hot sphere, id 0 (the store may sort particles)
        while (sys.particles().id[i] != 0) {
            ++i;
        }
        return sys.particles().mass[i] * specific_heat * (600.0 - heat.mean_temperature(sys, i));
    };
    const double alone = loss(false);
    const double among = loss(true);
    std::printf("loss in 1 ms: alone %.9g J, among neighbours at T_a %.9g J\n", alone, among);
    // Equal at the start of the step; over it the ambient part is implicit (linearised) and the
    // neighbour part lagged: they differ by ~ dt 4 sigma A T^3 / C ~ 2e-5 of the loss.
    EXPECT_NEAR(among, alone, 1e-4 * alone);
}

TEST(AmbientRadiation, ResolvedSpheresGiveUpTheViewOnTheFacesFacingTheNeighbours) {
    // As above with resolved spheres on both grids: the neighbours' view factors come off the
    // ambient share of the faces that exchange with them (not evenly over the surface), and in
    // total the same: the hot sphere loses what it loses alone.
    for (const GridKind grid : {GridKind::spherical, GridKind::cartesian}) {
        const auto loss = [grid](bool neighbours) {
            const dynamics::SceneSpec s = star(neighbours);
            dynamics::System sys(s);
            HeatSpec h = radiating(s, heat::HeatModel::resolved, 100); // one step of 1 ms
            h.materials[0].grid = grid;
            h.materials[0].emissivity = 1.0;
            h.materials[0].initial_temperature = t_ambient;
            h.particle_temperature = {600.0};
            ThermalSystem heat(h, sys);
            for (int k = 0; k < h.step_multiple; ++k) {
                sys.step();
                heat.after_step(sys);
            }
            std::size_t i = 0; // the hot sphere, id 0
            while (sys.particles().id[i] != 0) {
                ++i;
            }
            return sys.particles().mass[i] * specific_heat *
                   (600.0 - heat.mean_temperature(sys, i));
        };
        const double alone = loss(false);
        const double among = loss(true);
        std::printf("resolved (%s): loss in 1 ms alone %.9g J, among neighbours at T_a %.9g J\n",
                    grid == GridKind::spherical ? "spherical" : "cartesian", alone, among);
        // The neighbour part uses the hemisphere's node temperature, the ambient part each face's
        // surface temperature (Bi ~ 4e-3 below the node): they differ by ~Bi F of the loss.
        EXPECT_NEAR(among, alone, 1e-3 * alone);
    }
}

TEST(AmbientRadiation, IsothermalEnclosureAtTheAmbientExchangesNothing) {
    // Grey spheres, neighbours and ambient all at T_a: no particle's temperature moves.
    const dynamics::SceneSpec s = star(true);
    dynamics::System sys(s);
    HeatSpec h = radiating(s, heat::HeatModel::lumped, 100);
    h.materials[0].initial_temperature = t_ambient;
    ThermalSystem heat(h, sys);
    for (int k = 0; k < 1000; ++k) {
        sys.step();
        heat.after_step(sys);
    }
    // Rounding of the linearised update only (K, J).
    for (std::size_t i = 0; i < sys.particles().size(); ++i) {
        EXPECT_NEAR(heat.mean_temperature(sys, i), t_ambient, 1e-10);
    }
    EXPECT_NEAR(heat.external_heat(), 0.0, 1e-10);
}

TEST(AmbientRadiation, ClosedBedWithNeighbourRadiationConservesHeat) {
    // 27 grey spheres 2.2 R apart (lumped 1000 K and resolved 300 K in turn), no ambient: the
    // pair exchanges are antisymmetric, so sum C T holds to the resolved solves' residual.
    dynamics::SceneSpec s = one_particle(-1);
    s.materials.push_back({"b", 1e7, 0.3, density, 0.5, 0.3, 0.0}); // as "a" (one_particle)
    s.particles.clear();
    for (int k = 0; k < 27; ++k) {
        const Vec3 x = Vec3(k % 3, (k / 3) % 3, k / 9) * 2.2 * radius;
        s.particles.push_back({k % 2, radius, x, Vec3::Zero(), Vec3::Zero()});
    }
    dynamics::System sys(s);
    HeatSpec h = radiating(s, heat::HeatModel::lumped, 100);
    h.radiation_temperature = unset; // closed: neighbours only
    h.materials[1].model = heat::HeatModel::resolved;
    h.materials[1].initial_temperature = t_ambient;
    ThermalSystem heat(h, sys);
    const test::ClosedHeatRun run = test::run_closed_heat(sys, heat, 20000);
    std::printf("radiating bed: drift %.3g, range [%.12g, %.12g] K\n", run.drift, run.lowest,
                run.highest);
    EXPECT_GT(heat.thermal_energy() / heat.heat_capacity(), t_ambient); // heat moved
    EXPECT_LT(run.drift, 1e-9); // the resolved solves' residual 1e-12 per step (validation 26)
    EXPECT_NEAR(heat.external_heat(), 0.0, 1e-15 * run.initial_energy); // solver rounding
    EXPECT_GE(run.lowest, t_ambient - 1e-6); // maximum principle of the lagged exchange (K)
    EXPECT_LE(run.highest, t_start + 1e-6);
}

} // namespace
} // namespace kiln::thermal
