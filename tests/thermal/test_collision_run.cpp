// Collision conduction in the run loop: contact onsets recorded by the sphere kernel, the impact
// heat of collision_conduction.hpp (Sun & Chen 1988 with Zhou et al.'s c') exchanged once per
// impact at the next thermal step, conservatively; nothing changes with the flag off.
#include "common/closed_heat_run.hpp"
#include "common/collision_heat.hpp"
#include "core/error.hpp"
#include "dynamics/system.hpp"
#include "geometry/mesh_wall.hpp"
#include "geometry/shape.hpp"
#include "heat/collision_conduction.hpp"
#include "thermal/thermal_system.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <gtest/gtest.h>
#include <random>

namespace kiln::thermal {
namespace {

using namespace collision_test;

/// The shared collision-heat spec with this file's grid for resolved particles.
HeatSpec heat_of(const dynamics::SceneSpec& s, heat::HeatModel model) {
    HeatSpec h = collision_heat(s, model);
    for (MaterialHeat& m : h.materials) {
        m.spherical = {4, 4, 8};
    }
    return h;
}

TEST(CollisionRun, HeadOnImpactOfLumpedSpheresMovesTheSunChenEnergy) {
    // Two spheres 1 mm apart close at 1 m/s without gravity: the impact (t_c ~ 0.4 ms, 40 steps)
    // is over long before the thermal step at step 1000, so only the impact heat is exchanged.
    dynamics::SceneSpec s = empty_scene();
    const double x = radius + 0.5e-3;
    s.particles.push_back({0, radius, Vec3(-x, 0, 0), Vec3(0.5, 0, 0), Vec3::Zero()});
    s.particles.push_back({0, radius, Vec3(x, 0, 0), Vec3(-0.5, 0, 0), Vec3::Zero()});
    dynamics::System sys(s);
    HeatSpec h = heat_of(s, heat::HeatModel::lumped);
    // The cold sphere starts at 0 K so that its stored heat C T is the heat it received, without
    // cancellation against a large C T_0 (the model is linear in T).
    h.particle_temperature = {0.0, 600.0};
    ThermalSystem heat(h, sys);
    long onsets = 0;
    for (int k = 0; k < h.step_multiple; ++k) {
        sys.step();
        onsets += static_cast<long>(sys.contact_onsets().size());
        heat.after_step(sys);
    }
    ASSERT_EQ(onsets, 1);
    ASSERT_EQ(heat.collisions(), 1);
    std::vector<dynamics::ContactRecord> touching;
    sys.collect_contacts(touching);
    ASSERT_TRUE(touching.empty()); // apart again: no static exchange at the thermal step
    // The energy the library gives for this impact: m* = m/2, R* = R/2, approach speed 1 m/s.
    const double m = sys.particles().mass[0];
    const double tc = heat::hertz_impact_duration(0.5 * m, e_star, 0.5 * radius, 1.0);
    const double rc = heat::hertz_impact_radius(0.5 * m, e_star, 0.5 * radius, 1.0);
    const double e = heat::impact_heat(side, side, tc, rc, 0.0, 600.0);
    ASSERT_GT(e, 0.0);
    const double c = m * specific_heat;
    std::printf("impact: t_c %.4g s, r_c %.4g m, E %.6g J, received %.17g J\n", tc, rc, e,
                c * heat.mean_temperature(sys, 0));
    EXPECT_NEAR(c * heat.mean_temperature(sys, 0), e, formula_tolerance * e);
    EXPECT_NEAR(c * (600.0 - heat.mean_temperature(sys, 1)), e, 1e-9 * e); // 600 K: rounding
    EXPECT_EQ(heat.external_heat(), 0.0);
}

TEST(CollisionRun, ImpactOnAHotWallTakesTheWallImpactHeat) {
    // Seed Inv. VII L2507: against a wall m* = m and R* = R (a plane); the wall is a body of its
    // material at a fixed temperature.
    dynamics::SceneSpec s = empty_scene();
    s.walls.push_back({"floor", dynamics::PlaneWall{Vec3::Zero(), Vec3::UnitZ()}, 0});
    s.particles.push_back({0, radius, Vec3(0, 0, radius + 0.5e-3), Vec3(0, 0, -0.8), Vec3::Zero()});
    dynamics::System sys(s);
    HeatSpec h = heat_of(s, heat::HeatModel::lumped);
    h.wall_temperature = {500.0};
    h.particle_temperature = {0.0};
    ThermalSystem heat(h, sys);
    for (int k = 0; k < h.step_multiple; ++k) {
        sys.step();
        heat.after_step(sys);
    }
    ASSERT_EQ(heat.collisions(), 1);
    std::vector<dynamics::ContactRecord> touching;
    sys.collect_contacts(touching);
    ASSERT_TRUE(touching.empty());
    const double m = sys.particles().mass[0];
    const double tc = heat::hertz_impact_duration(m, e_star, radius, 0.8);
    const double rc = heat::hertz_impact_radius(m, e_star, radius, 0.8);
    const double e = heat::impact_heat(side, side, tc, rc, 0.0, 500.0);
    EXPECT_NEAR(heat.external_heat(), e, formula_tolerance * e);
    EXPECT_NEAR(m * specific_heat * heat.mean_temperature(sys, 0), e, formula_tolerance * e);
}

/// A closed box of 64 spheres with random velocities and no gravity: many impacts among
/// themselves and with the adiabatic walls. Half hot lumped (600 K), half cold resolved (300 K).
dynamics::SceneSpec box(bool record) {
    dynamics::SceneSpec s = empty_scene();
    s.record_contact_onsets = record;
    s.materials.push_back({"b", youngs, poisson, density, 0.9, 0.3, 0.0});
    const double l = 0.05;
    for (int a = 0; a < 3; ++a) {
        const Vec3 n = Vec3::Unit(a);
        s.walls.push_back({"lo", dynamics::PlaneWall{Vec3::Zero(), n}, 0});
        s.walls.push_back({"hi", dynamics::PlaneWall{l * n, -n}, 0});
    }
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int k = 0; k < 64; ++k) {
        const Vec3 x = Vec3(k % 4 + 0.5, (k / 4) % 4 + 0.5, k / 16 + 0.5) * (l / 4.0);
        s.particles.push_back(
            {k % 2, radius, x, Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng))});
    }
    return s;
}

HeatSpec box_heat(const dynamics::SceneSpec& s, bool collisions) {
    HeatSpec h = heat_of(s, heat::HeatModel::lumped);
    h.materials[1].model = heat::HeatModel::resolved;
    h.materials[0].initial_temperature = 600.0;
    h.step_multiple = 100;
    h.collision_conduction = collisions;
    return h;
}

TEST(CollisionRun, ClosedBoxOfCollidingSpheresConservesHeat) {
    const dynamics::SceneSpec s = box(true);
    dynamics::System sys(s);
    ThermalSystem heat(box_heat(s, true), sys);
    const test::ClosedHeatRun run = test::run_closed_heat(sys, heat, 20000);
    const double e0 = run.initial_energy;
    const double drift = run.drift;
    const double lo = run.lowest;
    const double hi = run.highest;
    std::printf("box: %ld impacts, drift %.3g, range [%.12g, %.12g] K, mean %.6g K\n",
                heat.collisions(), drift, lo, hi, heat.thermal_energy() / heat.heat_capacity());
    EXPECT_GT(heat.collisions(), 300); // many impacts, or the test proves nothing
    // Each impact's heat enters one body and leaves the other as the same number; the resolved
    // solves leave a relative residual below 1e-12 (as validation 26).
    EXPECT_LT(drift, 1e-9);
    EXPECT_NEAR(heat.external_heat(), 0.0, 1e-15 * e0); // adiabatic walls take nothing
    EXPECT_GE(lo, 300.0 - 1e-6);
    EXPECT_LE(hi, 600.0 + 1e-6);
    EXPECT_LT(lo, 600.0);
    EXPECT_GT(heat.thermal_energy() / heat.heat_capacity(), 300.0);
}

TEST(CollisionRun, FlagOffChangesNothingAndRecordingLeavesTheMechanicsAlone) {
    // Three runs of the same box: no recording; recording without collision conduction;
    // recording with it. Positions are bit-identical in all three (recording only reads), and
    // temperatures in the first two.
    const dynamics::SceneSpec plain = box(false);
    const dynamics::SceneSpec rec = box(true);
    dynamics::System s0(plain);
    dynamics::System s1(rec);
    dynamics::System s2(rec);
    ThermalSystem h0(box_heat(plain, false), s0);
    ThermalSystem h1(box_heat(rec, false), s1);
    ThermalSystem h2(box_heat(rec, true), s2);
    long onsets = 0;
    for (int k = 0; k < 5000; ++k) {
        s0.step();
        s1.step();
        s2.step();
        EXPECT_TRUE(s0.contact_onsets().empty());
        onsets += static_cast<long>(s1.contact_onsets().size());
        h0.after_step(s0);
        h1.after_step(s1);
        h2.after_step(s2);
    }
    EXPECT_GT(onsets, 50);
    EXPECT_EQ(h1.collisions(), 0);
    EXPECT_GT(h2.collisions(), 50);
    for (std::size_t i = 0; i < s0.particles().size(); ++i) {
        EXPECT_EQ(s0.particles().x[i], s1.particles().x[i]);
        EXPECT_EQ(s0.particles().x[i], s2.particles().x[i]);
        EXPECT_EQ(h0.mean_temperature(s0, i), h1.mean_temperature(s1, i));
    }
    EXPECT_NE(h0.thermal_energy() - h0.heat_capacity() * 300.0, 0.0);
    // Impacts move heat: the hot spheres lose more with collision conduction.
    double hot0 = 0.0;
    double hot2 = 0.0;
    for (std::size_t i = 0; i < s0.particles().size(); ++i) {
        if (s0.particles().material[i] == 0) {
            hot0 += h0.mean_temperature(s0, i);
            hot2 += h2.mean_temperature(s2, i);
        }
    }
    EXPECT_LT(hot2, hot0);
}

TEST(CollisionRun, AMissingRecorderIsRefused) {
    dynamics::SceneSpec s = empty_scene();
    s.particles.push_back({0, radius, Vec3::Zero(), Vec3::Zero(), Vec3::Zero()});
    s.record_contact_onsets = false;
    dynamics::System plain(s);
    try {
        ThermalSystem heat(heat_of(s, heat::HeatModel::lumped), plain);
        FAIL() << "accepted a System that records no onsets";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("record_contact_onsets"), std::string::npos);
    }
}

/// Index of the particle with id `id` (the store may reorder particles) (-).
std::size_t index_of(const dynamics::System& sys, std::int64_t id) {
    const auto& ids = sys.particles().id;
    return static_cast<std::size_t>(std::find(ids.begin(), ids.end(), id) - ids.begin());
}

/// A square mesh floor z = -l of two triangles (shared diagonal through x = y), material 0.
dynamics::MeshWallSpec mesh_floor(double l) {
    return {
        "floor",
        std::make_shared<const geometry::MeshWall>(
            std::vector<Vec3>{Vec3(-l, -l, -l), Vec3(l, -l, -l), Vec3(l, l, -l), Vec3(-l, l, -l)},
            std::vector<std::array<int, 3>>{{0, 1, 2}, {0, 2, 3}}, "test floor"),
        0};
}

TEST(CollisionRun, ImpactOnAHotMeshWallTakesTheWallImpactHeat) {
    // As on the analytic wall: m* = m, R* = R, approach 0.8 m/s, once per impact. Two places:
    // inside one triangle, and on the edge the two triangles share (one impact, not two).
    for (const Vec3& at : {Vec3(0.01, -0.02, 0), Vec3(0.005, 0.005, 0)}) {
        const double l = 0.05;
        dynamics::SceneSpec s = empty_scene();
        s.mesh_walls.push_back(mesh_floor(l));
        s.particles.push_back(
            {0, radius, at + Vec3(0, 0, -l + radius + 0.5e-3), Vec3(0, 0, -0.8), Vec3::Zero()});
        dynamics::System sys(s);
        HeatSpec h = heat_of(s, heat::HeatModel::lumped);
        h.mesh_wall_temperature = {500.0};
        h.particle_temperature = {0.0};
        ThermalSystem heat(h, sys);
        for (int k = 0; k < h.step_multiple; ++k) {
            sys.step();
            for (const dynamics::ContactOnset& e : sys.contact_onsets()) {
                EXPECT_EQ(e.wall, 0); // no analytic walls: mesh wall 0 is wall 0
                EXPECT_NEAR(e.speed, 0.8, 1e-12);
            }
            heat.after_step(sys);
        }
        ASSERT_EQ(heat.collisions(), 1) << "at " << at.transpose();
        std::vector<dynamics::ContactRecord> touching;
        sys.collect_contacts(touching);
        ASSERT_TRUE(touching.empty());
        const double m = sys.particles().mass[0];
        const double tc = heat::hertz_impact_duration(m, e_star, radius, 0.8);
        const double rc = heat::hertz_impact_radius(m, e_star, radius, 0.8);
        const double e = heat::impact_heat(side, side, tc, rc, 0.0, 500.0);
        EXPECT_NEAR(heat.external_heat(), e, formula_tolerance * e);
        EXPECT_NEAR(m * specific_heat * heat.mean_temperature(sys, 0), e, formula_tolerance * e);
    }
}

TEST(CollisionRun, AnalyticAndMeshWallsKeepTheirOwnTemperatures) {
    // An analytic side wall x = -0.04 at 500 K and the mesh floor z = -l at 400 K: a sphere
    // thrown at each takes its own wall's heat (the onset's wall index counts analytic walls
    // first).
    const double l = 0.05;
    dynamics::SceneSpec s = empty_scene();
    s.walls.push_back({"side", dynamics::PlaneWall{Vec3(-0.04, 0, 0), Vec3::UnitX()}, 0});
    s.mesh_walls.push_back(mesh_floor(l));
    s.particles.push_back(
        {0, radius, Vec3(-0.04 + radius + 0.5e-3, 0, 0), Vec3(-0.8, 0, 0), Vec3::Zero()});
    s.particles.push_back(
        {0, radius, Vec3(0.01, 0.02, -l + radius + 0.5e-3), Vec3(0, 0, -0.8), Vec3::Zero()});
    dynamics::System sys(s);
    HeatSpec h = heat_of(s, heat::HeatModel::lumped);
    h.wall_temperature = {500.0};
    h.mesh_wall_temperature = {400.0};
    h.particle_temperature = {0.0, 0.0};
    ThermalSystem heat(h, sys);
    for (int k = 0; k < h.step_multiple; ++k) {
        sys.step();
        heat.after_step(sys);
    }
    ASSERT_EQ(heat.collisions(), 2);
    const double m = sys.particles().mass[0];
    const double tc = heat::hertz_impact_duration(m, e_star, radius, 0.8);
    const double rc = heat::hertz_impact_radius(m, e_star, radius, 0.8);
    const double per_kelvin = heat::impact_heat(side, side, tc, rc, 0.0, 1.0); // J/K
    const double c = m * specific_heat;
    EXPECT_NEAR(c * heat.mean_temperature(sys, index_of(sys, 0)), 500.0 * per_kelvin,
                formula_tolerance * 500.0 * per_kelvin);
    EXPECT_NEAR(c * heat.mean_temperature(sys, index_of(sys, 1)), 400.0 * per_kelvin,
                formula_tolerance * 400.0 * per_kelvin);
}

// ---- Particles added during the run and refresh() ------------------------------------------
// Insertion blocks place their particles at start-up, before the constructor's refresh(); a run
// may add particles later (System::add_particle / add_body, as validation 34's pour), and a caller
// may move particles and call refresh(). A refresh evaluates forces without a step, so it has no
// start-of-step positions: contacts it finds are not impacts (they exchange heat by the static
// law from the next thermal step), and since it keeps the last step's onsets, a refresh between
// step() and after_step() loses none.

TEST(CollisionRun, ASphereAddedDuringTheRunRecordsItsFirstImpact) {
    // A sphere added at rest's partner 5 um away, closing at 1 m/s (dt 1e-5 s: it touches in its
    // first step, the step that also builds its neighbour list): one impact, the library's heat.
    dynamics::SceneSpec s = empty_scene();
    s.particles.push_back({0, radius, Vec3::Zero(), Vec3::Zero(), Vec3::Zero()});
    dynamics::System sys(s);
    HeatSpec h = heat_of(s, heat::HeatModel::lumped);
    h.particle_temperature = {0.0}; // the added sphere gets its material's 300 K
    ThermalSystem heat(h, sys);
    for (int k = 0; k < 10; ++k) {
        sys.step();
        heat.after_step(sys);
    }
    sys.add_particle(0, radius, Vec3(2.0 * radius + 5e-6, 0, 0), Vec3(-1.0, 0, 0), Vec3::Zero());
    long onsets = 0;
    for (int k = 10; k < h.step_multiple; ++k) {
        sys.step();
        onsets += static_cast<long>(sys.contact_onsets().size());
        heat.after_step(sys);
    }
    ASSERT_EQ(onsets, 1);
    ASSERT_EQ(heat.collisions(), 1);
    const double m = sys.particles().mass[0];
    const double tc = heat::hertz_impact_duration(0.5 * m, e_star, 0.5 * radius, 1.0);
    const double rc = heat::hertz_impact_radius(0.5 * m, e_star, 0.5 * radius, 1.0);
    const double e = heat::impact_heat(side, side, tc, rc, 0.0, 300.0);
    EXPECT_NEAR(m * specific_heat * heat.mean_temperature(sys, index_of(sys, 0)), e,
                formula_tolerance * e);
}

TEST(CollisionRun, ContactsFoundByARefreshAreNoImpactsAndARefreshKeepsTheStepsOnsets) {
    // (1) Two spheres placed overlapping and closing: the constructor's refresh finds the contact,
    // the first step sees it touching at its start: no impact. (2) A step whose impact is followed
    // by a refresh before after_step: the impact is still taken.
    {
        dynamics::SceneSpec s = empty_scene();
        s.particles.push_back(
            {0, radius, Vec3(-radius + 1e-6, 0, 0), Vec3(0.5, 0, 0), Vec3::Zero()});
        s.particles.push_back(
            {0, radius, Vec3(radius - 1e-6, 0, 0), Vec3(-0.5, 0, 0), Vec3::Zero()});
        dynamics::System sys(s);
        ThermalSystem heat(heat_of(s, heat::HeatModel::lumped), sys);
        long onsets = 0;
        for (int k = 0; k < 100; ++k) {
            sys.step();
            onsets += static_cast<long>(sys.contact_onsets().size());
            heat.after_step(sys);
        }
        EXPECT_EQ(onsets, 0);
        EXPECT_EQ(heat.collisions(), 0);
    }
    {
        dynamics::SceneSpec s = empty_scene();
        s.particles.push_back(
            {0, radius, Vec3(-radius - 4e-6, 0, 0), Vec3(0.5, 0, 0), Vec3::Zero()});
        s.particles.push_back(
            {0, radius, Vec3(radius + 4e-6, 0, 0), Vec3(-0.5, 0, 0), Vec3::Zero()});
        dynamics::System sys(s);
        HeatSpec h = heat_of(s, heat::HeatModel::lumped);
        h.particle_temperature = {0.0, 600.0};
        ThermalSystem heat(h, sys);
        sys.step(); // closes 10 um: touches
        ASSERT_EQ(sys.contact_onsets().size(), 1U);
        sys.refresh();
        EXPECT_EQ(sys.contact_onsets().size(), 1U); // kept through the refresh
        heat.after_step(sys);
        for (int k = 1; k < h.step_multiple; ++k) {
            sys.step();
            heat.after_step(sys);
        }
        EXPECT_EQ(heat.collisions(), 1);
    }
}

} // namespace
} // namespace kiln::thermal
