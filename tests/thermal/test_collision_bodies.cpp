// Collision conduction of bodies (clumps, superquadrics, polyhedra): contact onsets recorded where
// body_forces() creates a new element contact, with the contact point in world frame, turned into
// each body's frame at that step; the impact heat of collision_conduction.hpp with the element
// contact's R* (a clump member's radius, a superquadric's local radius, a polyhedron's equivalent
// sphere) exchanged once, conservatively; nothing changes with the flag off.
#include "common/closed_heat_run.hpp"
#include "common/collision_heat.hpp"
#include "common/cube_template.hpp"
#include "dynamics/system.hpp"
#include "geometry/clump.hpp"
#include "geometry/mesh_wall.hpp"
#include "geometry/polyhedron.hpp"
#include "geometry/shape.hpp"
#include "heat/collision_conduction.hpp"
#include "thermal/thermal_system.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <gtest/gtest.h>
#include <memory>
#include <random>

namespace kiln::thermal {
namespace {

using namespace collision_test;

/// The shared collision-heat spec with this file's grid for resolved particles.
HeatSpec heat_of(const dynamics::SceneSpec& s, heat::HeatModel model) {
    HeatSpec h = collision_heat(s, model);
    for (MaterialHeat& m : h.materials) {
        m.cells_across = 6;
    }
    return h;
}

/// A clump of one sphere of radius `r`: a body whose element contacts are sphere-sphere.
geometry::ShapeTemplate ball_clump(double r) {
    return geometry::make_template("ball", geometry::make_clump({{Vec3::Zero(), r}}, "test"));
}

/// Dumbbell of two overlapping spheres of radius `r` along body z.
geometry::ShapeTemplate dumbbell(double r) {
    return geometry::make_template(
        "dumbbell",
        geometry::make_clump({{Vec3(0, 0, -0.8 * r), r}, {Vec3(0, 0, 0.8 * r), r}}, "test"));
}

/// A superquadric with half axes `h` (ellipsoid exponents).
geometry::ShapeTemplate ellipsoid(const Vec3& h) {
    geometry::Superquadric q;
    q.half_axes = h;
    return geometry::make_template("ellipsoid", q);
}

/// Cube of edge 2 a (tests/common/cube_template.hpp).
geometry::ShapeTemplate cube(double a) {
    return test::cube_template(a);
}

dynamics::ParticleSpec body_at(int shape, int material, const Vec3& x, const Vec3& v) {
    dynamics::ParticleSpec p;
    p.shape = shape;
    p.material = material;
    p.x = x;
    p.v = v;
    return p;
}

TEST(CollisionBodies, HeadOnImpactOfLumpedClumpsMovesTheSunChenEnergy) {
    // Two one-sphere clumps 1 mm apart close at 1 m/s: one element contact (sphere-sphere, R* =
    // R/2, m* = m/2), over long before the thermal step at step 1000.
    dynamics::SceneSpec s = empty_scene();
    s.shapes.push_back(ball_clump(radius));
    const double x = radius + 0.5e-3;
    s.particles.push_back(body_at(0, 0, Vec3(-x, 0, 0), Vec3(0.5, 0, 0)));
    s.particles.push_back(body_at(0, 0, Vec3(x, 0, 0), Vec3(-0.5, 0, 0)));
    dynamics::System sys(s);
    HeatSpec h = heat_of(s, heat::HeatModel::lumped);
    h.particle_temperature = {0.0, 600.0}; // C T of the cold body is the heat it received
    ThermalSystem heat(h, sys);
    long onsets = 0;
    for (int k = 0; k < h.step_multiple; ++k) {
        sys.step();
        for (const dynamics::ContactOnset& e : sys.contact_onsets()) {
            ++onsets;
            EXPECT_NEAR(e.speed, 1.0, 1e-12);     // before the contact force acts
            EXPECT_NEAR(e.normal[0], 1.0, 1e-12); // from the smaller id (left) to the right
            EXPECT_NEAR(e.point[0], 0.0, 1e-6);   // the contact point between them (world)
        }
        heat.after_step(sys);
    }
    ASSERT_EQ(onsets, 1);
    ASSERT_EQ(heat.collisions(), 1);
    std::vector<dynamics::ContactRecord> touching;
    sys.collect_contacts(touching);
    ASSERT_TRUE(touching.empty()); // apart again: no static exchange at the thermal step
    const double m = sys.particles().mass[0];
    const double tc = heat::hertz_impact_duration(0.5 * m, e_star, 0.5 * radius, 1.0);
    const double rc = heat::hertz_impact_radius(0.5 * m, e_star, 0.5 * radius, 1.0);
    const double e = heat::impact_heat(side, side, tc, rc, 0.0, 600.0);
    ASSERT_GT(e, 0.0);
    const double c = m * specific_heat;
    std::printf("clump impact: E %.6g J, received %.17g J\n", e, c * heat.mean_temperature(sys, 0));
    EXPECT_NEAR(c * heat.mean_temperature(sys, 0), e, formula_tolerance * e);
    EXPECT_NEAR(c * (600.0 - heat.mean_temperature(sys, 1)), e, 1e-9 * e); // 600 K: rounding
    EXPECT_EQ(heat.external_heat(), 0.0);
}

TEST(CollisionBodies, RoundSuperquadricOnAHotWallTakesTheWallImpactHeat) {
    // A superquadric with equal half axes is a sphere: its R* against a plane is R, m* = m.
    dynamics::SceneSpec s = empty_scene();
    s.shapes.push_back(ellipsoid(Vec3(radius, radius, radius)));
    s.walls.push_back({"floor", dynamics::PlaneWall{Vec3::Zero(), Vec3::UnitZ()}, 0});
    s.particles.push_back(body_at(0, 0, Vec3(0, 0, radius + 0.5e-3), Vec3(0, 0, -0.8)));
    dynamics::System sys(s);
    HeatSpec h = heat_of(s, heat::HeatModel::lumped);
    h.wall_temperature = {500.0};
    h.particle_temperature = {0.0};
    ThermalSystem heat(h, sys);
    double r_eff = 0.0;
    for (int k = 0; k < h.step_multiple; ++k) {
        sys.step();
        for (const dynamics::ContactOnset& e : sys.contact_onsets()) {
            EXPECT_EQ(e.wall, 0);
            EXPECT_NEAR(e.speed, 0.8, 1e-12);
            r_eff = e.r_eff;
        }
        heat.after_step(sys);
    }
    ASSERT_EQ(heat.collisions(), 1);
    // The superquadric's local radius at the touching point (Newton's contact point: 1e-6).
    EXPECT_NEAR(r_eff, radius, 1e-6 * radius);
    const double m = sys.particles().mass[0];
    const double tc = heat::hertz_impact_duration(m, e_star, r_eff, 0.8);
    const double rc = heat::hertz_impact_radius(m, e_star, r_eff, 0.8);
    const double e = heat::impact_heat(side, side, tc, rc, 0.0, 500.0);
    EXPECT_NEAR(heat.external_heat(), e, formula_tolerance * e);
    EXPECT_NEAR(m * specific_heat * heat.mean_temperature(sys, 0), e, formula_tolerance * e);
}

TEST(CollisionBodies, RoundSuperquadricOnAHotMeshFloorTakesTheWallImpactHeat) {
    // As on the plane: a mesh wall's contact is an element contact of body_forces, so the onset
    // is recorded there, with the mesh wall's index after the analytic walls (none here: 0).
    const double l = 0.05;
    dynamics::SceneSpec s = empty_scene();
    s.shapes.push_back(ellipsoid(Vec3(radius, radius, radius)));
    s.mesh_walls.push_back(
        {"floor",
         std::make_shared<const geometry::MeshWall>(
             std::vector<Vec3>{Vec3(-l, -l, -l), Vec3(l, -l, -l), Vec3(l, l, -l), Vec3(-l, l, -l)},
             std::vector<std::array<int, 3>>{{0, 1, 2}, {0, 2, 3}}, "test floor"),
         0});
    s.particles.push_back(body_at(0, 0, Vec3(0.01, -0.02, -l + radius + 0.5e-3), Vec3(0, 0, -0.8)));
    dynamics::System sys(s);
    HeatSpec h = heat_of(s, heat::HeatModel::lumped);
    h.mesh_wall_temperature = {500.0};
    h.particle_temperature = {0.0};
    ThermalSystem heat(h, sys);
    double r_eff = 0.0;
    for (int k = 0; k < h.step_multiple; ++k) {
        sys.step();
        for (const dynamics::ContactOnset& e : sys.contact_onsets()) {
            EXPECT_EQ(e.wall, 0);
            EXPECT_NEAR(e.speed, 0.8, 1e-12);
            r_eff = e.r_eff;
        }
        heat.after_step(sys);
    }
    ASSERT_EQ(heat.collisions(), 1);
    EXPECT_NEAR(r_eff, radius, 1e-6 * radius); // Newton's contact point: 1e-6
    const double m = sys.particles().mass[0];
    const double tc = heat::hertz_impact_duration(m, e_star, r_eff, 0.8);
    const double rc = heat::hertz_impact_radius(m, e_star, r_eff, 0.8);
    const double e = heat::impact_heat(side, side, tc, rc, 0.0, 500.0);
    EXPECT_NEAR(heat.external_heat(), e, formula_tolerance * e);
    EXPECT_NEAR(m * specific_heat * heat.mean_temperature(sys, 0), e, formula_tolerance * e);
}

TEST(CollisionBodies, ABodyAddedDuringTheRunRecordsItsFirstImpact) {
    // The round superquadric above, added after 10 steps 5 um above the hot floor at 0.8 m/s:
    // it touches in its first step (dt 1e-5 s), which records the impact as for a placed body.
    dynamics::SceneSpec s = empty_scene();
    s.shapes.push_back(ellipsoid(Vec3(radius, radius, radius)));
    s.walls.push_back({"floor", dynamics::PlaneWall{Vec3::Zero(), Vec3::UnitZ()}, 0});
    s.particles.push_back(body_at(0, 0, Vec3(0.02, 0, radius + 1e-3), Vec3::Zero()));
    dynamics::System sys(s);
    HeatSpec h = heat_of(s, heat::HeatModel::lumped);
    h.wall_temperature = {500.0};
    h.materials[0].initial_temperature = 0.0; // the added body starts at 0 K
    ThermalSystem heat(h, sys);
    for (int k = 0; k < 10; ++k) {
        sys.step();
        heat.after_step(sys);
    }
    const std::int64_t added = sys.particles().id[sys.add_body(
        0, 0, Vec3(0, 0, radius + 5e-6), Vec3(0, 0, -0.8), Vec3::Zero(), Quat::Identity())];
    double r_eff = 0.0;
    for (int k = 10; k < h.step_multiple; ++k) {
        sys.step();
        for (const dynamics::ContactOnset& e : sys.contact_onsets()) {
            EXPECT_EQ(e.id_i, added);
            r_eff = e.r_eff;
        }
        heat.after_step(sys);
    }
    ASSERT_EQ(heat.collisions(), 1);
    // The store may reorder particles: find the added body by its id.
    const auto& ids = sys.particles().id;
    const auto k = static_cast<std::size_t>(std::find(ids.begin(), ids.end(), added) - ids.begin());
    const double m = sys.particles().mass[k];
    const double tc = heat::hertz_impact_duration(m, e_star, r_eff, 0.8);
    const double rc = heat::hertz_impact_radius(m, e_star, r_eff, 0.8);
    const double e = heat::impact_heat(side, side, tc, rc, 0.0, 500.0);
    EXPECT_NEAR(m * specific_heat * heat.mean_temperature(sys, k), e, formula_tolerance * e);
}

/// A closed box of 27 bodies (dumbbell clumps, ellipsoids, cubes in turn) with random
/// velocities and no gravity. Material 0 hot lumped (600 K), material 1 cold resolved (300 K).
dynamics::SceneSpec body_box(bool record) {
    dynamics::SceneSpec s = empty_scene();
    s.record_contact_onsets = record;
    s.materials.push_back({"b", youngs, poisson, density, 0.9, 0.3, 0.0});
    s.shapes.push_back(dumbbell(2.5e-3));
    s.shapes.push_back(ellipsoid(Vec3(4e-3, 3e-3, 2.5e-3)));
    s.shapes.push_back(cube(3e-3));
    const double l = 0.045; // m
    for (int a = 0; a < 3; ++a) {
        const Vec3 n = Vec3::Unit(a);
        s.walls.push_back({"lo", dynamics::PlaneWall{Vec3::Zero(), n}, 0});
        s.walls.push_back({"hi", dynamics::PlaneWall{l * n, -n}, 0});
    }
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int k = 0; k < 27; ++k) {
        const Vec3 x = Vec3(k % 3 + 0.5, (k / 3) % 3 + 0.5, k / 9 + 0.5) * (l / 3.0);
        dynamics::ParticleSpec p = body_at(k % 3, k % 2, x, Vec3(u(rng), u(rng), u(rng)));
        p.omega = Vec3(u(rng), u(rng), u(rng)) * 50.0;
        s.particles.push_back(p);
    }
    return s;
}

HeatSpec body_box_heat(const dynamics::SceneSpec& s, bool collisions) {
    HeatSpec h = heat_of(s, heat::HeatModel::lumped);
    h.materials[1].model = heat::HeatModel::resolved;
    h.materials[0].initial_temperature = 600.0;
    h.step_multiple = 100;
    h.collision_conduction = collisions;
    return h;
}

TEST(CollisionBodies, ClosedBoxOfCollidingBodiesConservesHeat) {
    const dynamics::SceneSpec s = body_box(true);
    dynamics::System sys(s);
    ThermalSystem heat(body_box_heat(s, true), sys);
    const test::ClosedHeatRun run = test::run_closed_heat(sys, heat, 10000);
    std::printf("body box: %ld impacts, drift %.3g, range [%.12g, %.12g] K, mean %.6g K\n",
                heat.collisions(), run.drift, run.lowest, run.highest,
                heat.thermal_energy() / heat.heat_capacity());
    EXPECT_GT(heat.collisions(), 30); // many impacts, or the test proves nothing
    // Each impact's heat enters one body and leaves the other as the same number; the resolved
    // solves leave a relative residual below 1e-12 (as validations 26, 29).
    EXPECT_LT(run.drift, 1e-9);
    EXPECT_NEAR(heat.external_heat(), 0.0, 1e-15 * run.initial_energy); // adiabatic walls
    // Maximum principle of the lagged exchange (dt G / C_patch <= 0.5), K.
    EXPECT_GE(run.lowest, 300.0 - 1e-6);
    EXPECT_LE(run.highest, 600.0 + 1e-6);
    EXPECT_GT(heat.thermal_energy() / heat.heat_capacity(), 300.0);
}

TEST(CollisionBodies, FlagOffChangesNothingAndRecordingLeavesTheMechanicsAlone) {
    // Three runs of the body box: no recording; recording without collision conduction;
    // recording with it. Positions and orientations are bit-identical in all three, and
    // temperatures in the first two.
    const dynamics::SceneSpec plain = body_box(false);
    const dynamics::SceneSpec rec = body_box(true);
    dynamics::System s0(plain);
    dynamics::System s1(rec);
    dynamics::System s2(rec);
    ThermalSystem h0(body_box_heat(plain, false), s0);
    ThermalSystem h1(body_box_heat(rec, false), s1);
    ThermalSystem h2(body_box_heat(rec, true), s2);
    long onsets = 0;
    for (int k = 0; k < 3000; ++k) {
        s0.step();
        s1.step();
        s2.step();
        EXPECT_TRUE(s0.contact_onsets().empty());
        onsets += static_cast<long>(s1.contact_onsets().size());
        h0.after_step(s0);
        h1.after_step(s1);
        h2.after_step(s2);
    }
    EXPECT_GT(onsets, 10);
    EXPECT_EQ(h1.collisions(), 0);
    EXPECT_GT(h2.collisions(), 10);
    for (std::size_t i = 0; i < s0.particles().size(); ++i) {
        EXPECT_EQ(s0.particles().x[i], s1.particles().x[i]);
        EXPECT_EQ(s0.particles().x[i], s2.particles().x[i]);
        EXPECT_EQ(s0.particles().q[i].coeffs(), s2.particles().q[i].coeffs());
        EXPECT_EQ(h0.mean_temperature(s0, i), h1.mean_temperature(s1, i));
    }
    double hot0 = 0.0;
    double hot2 = 0.0;
    for (std::size_t i = 0; i < s0.particles().size(); ++i) {
        if (s0.particles().material[i] == 0) {
            hot0 += h0.mean_temperature(s0, i);
            hot2 += h2.mean_temperature(s2, i);
        }
    }
    EXPECT_LT(hot2, hot0); // impacts move heat out of the hot bodies
}

} // namespace
} // namespace kiln::thermal
