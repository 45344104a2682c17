// Gas-gap conduction and neighbour radiation of bodies (clumps, superquadrics, polyhedra, and
// spheres next to them): the gap from GJK on the shapes (thermal/body_gap.hpp), the sphere
// formulas of the heat library with each side's equivalent radius, exchanged conservatively.
#include "common/closed_heat_run.hpp"
#include "common/cube_template.hpp"
#include "dynamics/system.hpp"
#include "geometry/clump.hpp"
#include "geometry/shape.hpp"
#include "geometry/shape_metrics.hpp"
#include "heat/gas_conduction.hpp"
#include "heat/radiation.hpp"
#include "thermal/body_gap.hpp"
#include "thermal/thermal_system.hpp"

#include <cmath>
#include <cstdio>
#include <gtest/gtest.h>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace kiln::thermal {
namespace {

constexpr double density = 2500;      // kg/m^3
constexpr double specific_heat = 900; // J/(kg K)
constexpr double conductivity = 1.0;  // W/(m K)
constexpr double k_gas = 0.0263;      // W/(m K), air
/// GJK stops when its upper and lower bounds of the distance differ by 1e-9 of the bounding
/// radius; a gap of 0.1 R is then known to 1e-8 relative, the conductance (d ln H / d ln gap
/// ~ -1 at small gaps) to about as much: 1e-7 leaves a margin.
constexpr double gap_tolerance = 1e-7;

geometry::ShapeTemplate dumbbell(double r) {
    return geometry::make_template(
        "dumbbell",
        geometry::make_clump({{Vec3(0, 0, -0.8 * r), r}, {Vec3(0, 0, 0.8 * r), r}}, "test"));
}

geometry::ShapeTemplate ellipsoid(const Vec3& h) {
    geometry::Superquadric q;
    q.half_axes = h;
    return geometry::make_template("ellipsoid", q);
}

/// A unit vector across the dumbbell's member axis (body frame; make_clump picks the principal
/// frame, so the axis need not stay body z).
Vec3 across_dumbbell(const geometry::ShapeTemplate& t) {
    const auto& m = std::get<geometry::Clump>(t.shape).spheres;
    return (m[1].centre - m[0].centre).unitOrthogonal();
}

/// One material, no gravity, dt = 1e-5 s, the given shape templates.
dynamics::SceneSpec scene(std::vector<geometry::ShapeTemplate> shapes) {
    dynamics::SceneSpec s;
    s.materials.push_back({"a", 1e8, 0.3, density, 0.9, 0.3, 0.0});
    s.gravity = Vec3::Zero();
    s.time_step = 1e-5;
    s.shapes = std::move(shapes);
    return s;
}

/// A particle of template `shape` (-1: sphere of radius `r`) at `x` turned by `q`.
dynamics::ParticleSpec at(int shape, double r, const Vec3& x, const Quat& q = Quat::Identity()) {
    dynamics::ParticleSpec p;
    p.shape = shape;
    p.radius = r;
    p.x = x;
    p.orientation.fixed = q;
    return p;
}

HeatSpec heat_of(const dynamics::SceneSpec& s, heat::HeatModel model) {
    HeatSpec h;
    h.enabled = true;
    h.step_multiple = 1000;
    h.solver.tolerance = 1e-12;
    MaterialHeat m;
    m.enabled = true;
    m.conductivity = conductivity;
    m.specific_heat = specific_heat;
    m.initial_temperature = 300;
    m.model = model;
    m.cells_across = 6;
    h.materials.assign(s.materials.size(), m);
    return h;
}

/// Radius of the sphere of the template's volume (m).
double volume_radius(const geometry::ShapeTemplate& t) {
    return std::cbrt(3.0 * t.volume / (4.0 * std::numbers::pi));
}

/// Radius of the sphere of the template's surface area (m).
double area_radius(const geometry::ShapeTemplate& t) {
    return std::sqrt(geometry::surface_area(t.shape).value / (4.0 * std::numbers::pi));
}

/// Heat capacity rho c_p V of particle `k` of `s` (J/K).
double capacity(const dynamics::SceneSpec& s, std::size_t k) {
    const dynamics::ParticleSpec& p = s.particles[k];
    const double v = p.shape >= 0 ? s.shapes[static_cast<std::size_t>(p.shape)].volume
                                  : 4.0 / 3.0 * std::numbers::pi * std::pow(p.radius, 3);
    return density * specific_heat * v;
}

// ---- The gap ---------------------------------------------------------------------------------

TEST(BodyGaps, GjkFindsTheGapOfCubesEllipsoidsAndClumps) {
    const double a = 2e-3;
    const geometry::ShapeTemplate cube = test::cube_template(a);
    const Vec3 h(3e-3, 2e-3, 1.5e-3);
    dynamics::SceneSpec s = scene({cube, ellipsoid(h), dumbbell(1e-3)});
    const Quat turned(Eigen::AngleAxisd(std::numbers::pi / 4, Vec3::UnitZ()));
    // 0-1: face to face along x; 2-3: a cube edge (turned 45 deg about z) towards a face;
    // 4-5: ellipsoid tip to tip along x; 6-7: dumbbells side by side (nearest members, radius r)
    // along `side`, across their member axis.
    const double g = 0.3e-3;
    const Vec3 side = across_dumbbell(s.shapes[2]);
    s.particles = {at(0, 0, Vec3(0, 0, 0)),
                   at(0, 0, Vec3(2 * a + g, 0, 0)),
                   at(0, 0, Vec3(0, 0.05, 0), turned),
                   at(0, 0, Vec3(a * std::numbers::sqrt2 + a + g, 0.05, 0)),
                   at(1, 0, Vec3(0, 0.1, 0)),
                   at(1, 0, Vec3(2 * h.x() + g, 0.1, 0)),
                   at(2, 0, Vec3(0, 0.15, 0)),
                   at(2, 0, Vec3(0, 0.15, 0) + (2e-3 + g) * side)};
    const dynamics::System sys(s);
    for (std::size_t k = 0; k < 8; k += 2) {
        const BodyGap bg = body_gap(sys, k, k + 1);
        // GJK's tolerance (1e-9 of the bounding radius) plus rounding (m).
        EXPECT_NEAR(bg.gap, g, 1e-11) << "pair " << k;
        EXPECT_TRUE(bg.converged);
        EXPECT_NEAR((bg.point_j - bg.point_i).norm(), g, 1e-11);
        // From i to j: along +x, or across the dumbbells.
        EXPECT_NEAR(bg.normal.dot(k == 6 ? side : Vec3::UnitX()), 1.0, 1e-6);
    }
    EXPECT_DOUBLE_EQ(body_gap(sys, 6, 7).member_radius_i, 1e-3);
    EXPECT_EQ(body_gap(sys, 0, 1).member_radius_i, 0.0); // convex: no member
    // The turned cube's nearest point is its edge at x = a sqrt 2 (m).
    EXPECT_NEAR(body_gap(sys, 2, 3).point_i.x(), a * std::numbers::sqrt2, 1e-11);
}

TEST(BodyGaps, OverlappingConvexCoresGiveGapZeroAlongTheCentres) {
    const double a = 2e-3;
    dynamics::SceneSpec s = scene({test::cube_template(a)});
    s.particles = {at(0, 0, Vec3(0, 0, 0)), at(0, 0, Vec3(2 * a - 1e-5, 0, 0))};
    const dynamics::System sys(s);
    const BodyGap bg = body_gap(sys, 0, 1);
    EXPECT_EQ(bg.gap, 0.0);
    EXPECT_NEAR(bg.normal.x(), 1.0, 1e-12);
}

/// Are two gaps the same bits (gap, points, normal, radii, convergence)?
bool same_gap(const BodyGap& x, const BodyGap& y) {
    return x.gap == y.gap && x.point_i == y.point_i && x.point_j == y.point_j &&
           x.normal == y.normal && x.member_radius_i == y.member_radius_i &&
           x.member_radius_j == y.member_radius_j && x.converged == y.converged;
}

TEST(BodyGaps, ElementGapsWithACutoffLeaveOutOnlyPairsBeyondTheReach) {
    // Cubes, 1:2:3 ellipsoids, dumbbells and spheres at random poses and distances up to a few
    // sizes: with a cut-off, element_gaps must give the pairs of the full call in order, the
    // same bits, leaving out only pairs whose gap exceeds the gas-gap reach 2 cutoff R of their
    // largest equivalent spheres (a member's radius, a body's bounding radius).
    const double a = 1.5e-3;
    dynamics::SceneSpec s =
        scene({test::cube_template(a), ellipsoid(Vec3(1e-3, 2e-3, 3e-3)), dumbbell(1e-3)});
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const int kinds[] = {0, 1, 2, -1};
    for (int k = 0; k < 40; ++k) {
        const int shape = kinds[k % 4];
        const Vec3 x(u(rng), u(rng), u(rng));
        const Quat q = Quat(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng))).normalized();
        s.particles.push_back(at(shape, 1.2e-3, 6e-3 * x, q));
    }
    const dynamics::System sys(s);
    const ParticleStore& p = sys.particles();
    const double cutoff = 0.5;
    long kept = 0;
    long left_out = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        for (std::size_t j = i + 1; j < p.size(); ++j) {
            const std::vector<BodyGap> all = element_gaps(sys, i, j);
            const std::vector<BodyGap> cut = element_gaps(sys, i, j, cutoff);
            std::size_t next = 0;
            for (const BodyGap& g : all) {
                if (next < cut.size() && same_gap(g, cut[next])) {
                    ++next;
                    ++kept;
                    continue;
                }
                ++left_out;
                const double r_i = g.member_radius_i > 0.0 ? g.member_radius_i : p.radius[i];
                const double r_j = g.member_radius_j > 0.0 ? g.member_radius_j : p.radius[j];
                EXPECT_GT(g.gap, 2.0 * cutoff * (2.0 * r_i * r_j) / (r_i + r_j))
                    << "pair " << i << ", " << j << " left out within the reach";
            }
            EXPECT_EQ(next, cut.size()) << "pair " << i << ", " << j << ": an entry not in order";
        }
    }
    EXPECT_GT(kept, 50);      // the scene has pairs within reach ...
    EXPECT_GT(left_out, 500); // ... and many beyond it
}

TEST(BodyGaps, GjkStopsOnceTheGapIsProvedBeyondTheBound) {
    const geometry::ShapeTemplate t = ellipsoid(Vec3(1e-3, 2e-3, 3e-3));
    const auto& sq = std::get<geometry::Superquadric>(t.shape);
    Core a;
    a.superquadric = &sq;
    Core b = a;
    b.x = Vec3(9e-3, 1e-3, 0.5e-3);
    b.q = Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
    const double tol = 3e-12;
    const CoreDistance full = core_distance(a, b, tol);
    ASSERT_TRUE(full.converged);
    ASSERT_FALSE(full.beyond);
    // A bound well below the distance: stopped early, with a lower bound above the bound.
    const CoreDistance early = core_distance(a, b, tol, 0.5 * full.distance);
    EXPECT_TRUE(early.beyond);
    EXPECT_LT(early.iterations, full.iterations);
    EXPECT_GT(early.distance, 0.5 * full.distance);
    EXPECT_LE(early.distance, full.distance + tol);
    // A bound above the distance: the same iterations and answer as without one.
    const CoreDistance same = core_distance(a, b, tol, 2.0 * full.distance);
    EXPECT_FALSE(same.beyond);
    EXPECT_EQ(same.iterations, full.iterations);
    EXPECT_EQ(same.distance, full.distance);
    EXPECT_EQ(same.a, full.a);
    EXPECT_EQ(same.b, full.b);
}

/// Value of a counter `"key": N` in summary_json.
long summary_count(const ThermalSystem& heat, const std::string& key) {
    const std::string j = heat.summary_json();
    const std::size_t at = j.find("\"" + key + "\": ");
    return at == std::string::npos ? -1 : std::stol(j.substr(at + key.size() + 4));
}

// ---- Gas-gap conduction -------------------------------------------------------------------

/// One element pair of a gas-gap exchange: radii (m) and surface gap (m).
struct ElementPair {
    double r_i;
    double r_j;
    double gap;
};

/// One thermal step of a lumped pair at rest (600 K and 300 K) with gas: the heat into the cold
/// side must be dt sum H (600 - 300), H from gas_gap_conductance for each element pair's radii
/// and surface gap.
void check_pair(const dynamics::SceneSpec& s, const std::vector<ElementPair>& elements) {
    dynamics::System sys(s);
    HeatSpec h = heat_of(s, heat::HeatModel::lumped);
    h.gas.conductivity = k_gas;
    h.particle_temperature = {600.0, 300.0};
    ThermalSystem heat(h, sys);
    const double e0 = heat.thermal_energy();
    const double c1 = capacity(s, 1);
    heat.thermal_step(sys);
    double g = 0.0;
    for (const ElementPair& e : elements) {
        g += heat::gas_gap_conductance(e.r_i, e.r_j, e.r_i + e.r_j + e.gap, conductivity,
                                       conductivity, h.gas);
    }
    const double expected = heat.time_step() * g * 300.0 / c1; // K
    ASSERT_EQ(heat.counters().max_substeps, 1);
    EXPECT_GT(expected, 1e-6); // the gas moves a measurable amount
    EXPECT_NEAR(heat.mean_temperature(sys, 1) - 300.0, expected, gap_tolerance * expected);
    EXPECT_NEAR(heat.thermal_energy(), e0, 1e-14 * e0); // lumped: rounding only
    EXPECT_EQ(summary_count(heat, "gas_gap_pairs"), static_cast<long>(elements.size()));
}

TEST(BodyGaps, GasGapOfABodyPairMatchesTheLibraryForItsEquivalentRadius) {
    const double r = 1.5e-3;
    const double gap = 0.2 * r;
    {
        // Dumbbells side by side: every member pair within the cut-off is a sphere pair (exact
        // local geometry): two at the gap, two diagonal (H / R = 0.36 < 0.5).
        dynamics::SceneSpec s = scene({dumbbell(r)});
        s.particles = {at(0, 0, Vec3::Zero()),
                       at(0, 0, (2 * r + gap) * across_dumbbell(s.shapes[0]))};
        const double across = std::hypot(2 * r + gap, 1.6 * r) - 2 * r;
        check_pair(s, {{r, r, gap}, {r, r, across}, {r, r, across}, {r, r, gap}});
    }
    {
        // Ellipsoids tip to tip: the local radius of curvature at the tips, 1 / sqrt(k1 k2) with
        // k = a / b^2 and a / c^2 on the axis of half-axis a: R = b c / a. Cubes face to face:
        // the volume-equivalent spheres.
        const geometry::ShapeTemplate e = ellipsoid(Vec3(2e-3, 1.5e-3, 1.2e-3));
        dynamics::SceneSpec s = scene({e});
        s.particles = {at(0, 0, Vec3::Zero()), at(0, 0, Vec3(4e-3 + gap, 0, 0))};
        const double tip = 1.5e-3 * 1.2e-3 / 2e-3;
        check_pair(s, {{tip, tip, gap}});
        const geometry::ShapeTemplate c = test::cube_template(r);
        s = scene({c});
        s.particles = {at(0, 0, Vec3::Zero()), at(0, 0, Vec3(2 * r + gap, 0, 0))};
        check_pair(s, {{volume_radius(c), volume_radius(c), gap}});
        // A sphere next to a cube: the sphere keeps its radius.
        s.particles = {at(0, 0, Vec3::Zero()), at(-1, r, Vec3(2 * r + gap, 0, 0))};
        check_pair(s, {{volume_radius(c), r, gap}});
    }
}

TEST(BodyGaps, OneSphereClumpsExchangeAsTheirSpheres) {
    // A clump of one sphere is that sphere: its gas gap and its radiation through the body path
    // (GJK, member radius; area-equivalent radius = R) must give the sphere path's numbers. Gaps
    // from GJK (points: exact) and the same formulas: rounding only over 50 lumped steps.
    const double r = 1.5e-3;
    const double gap = 0.3 * r;
    const auto run = [&](bool clumps) {
        dynamics::SceneSpec s = scene(
            {geometry::make_template("ball", geometry::make_clump({{Vec3::Zero(), r}}, "test"))});
        const int shape = clumps ? 0 : -1;
        s.particles = {at(shape, r, Vec3::Zero()), at(shape, r, Vec3(2 * r + gap, 0, 0))};
        dynamics::System sys(s);
        HeatSpec h = heat_of(s, heat::HeatModel::lumped);
        h.gas.conductivity = k_gas;
        h.materials[0].emissivity = 0.9;
        h.particle_temperature = {900.0, 300.0};
        ThermalSystem heat(h, sys);
        for (int k = 0; k < 50; ++k) {
            heat.thermal_step(sys);
        }
        return heat.mean_temperature(sys, 1);
    };
    const double spheres = run(false);
    const double clumps = run(true);
    EXPECT_GT(spheres, 300.0 + 1.0); // heat moved
    EXPECT_NEAR(clumps, spheres, 1e-12 * spheres);
}

TEST(BodyGaps, ResolvedBodiesTakeTheGasHeatOnTheCellsFacingTheGap) {
    // A hot lumped cube and a cold resolved ellipsoid turned 90 deg about z, 0.2 mm apart along
    // x: the heat enters the ellipsoid's cells nearest the gap (in its body frame, the direction
    // q^-1 (-x)), so after 0.05 s (diffusion length sqrt(alpha t) ~ 0.15 mm) those are the
    // warmest and the far side has hardly warmed.
    const geometry::ShapeTemplate c = test::cube_template(1.5e-3);
    const geometry::ShapeTemplate e = ellipsoid(Vec3(2.5e-3, 1.5e-3, 1.2e-3));
    const Quat q(Eigen::AngleAxisd(std::numbers::pi / 2, Vec3::UnitZ()));
    dynamics::SceneSpec s = scene({c, e});
    s.materials.push_back({"b", 1e8, 0.3, density, 0.9, 0.3, 0.0});
    // q turns body x into world y and body y into world -x: the gap faces the ellipsoid's body +y
    // side, 1.5 mm from its centre (cube face at x = 1.5 mm, ellipsoid surface at 1.7 mm).
    dynamics::ParticleSpec hot = at(0, 0, Vec3::Zero());
    dynamics::ParticleSpec cold = at(1, 0, Vec3(1.5e-3 + 1.5e-3 + 0.2e-3, 0, 0), q);
    cold.material = 1;
    s.particles = {hot, cold};
    dynamics::System sys(s);
    HeatSpec h = heat_of(s, heat::HeatModel::lumped);
    h.materials[1].model = heat::HeatModel::resolved;
    h.materials[1].cells_across = 8;
    h.gas.conductivity = k_gas;
    h.particle_temperature = {600.0, 300.0};
    ThermalSystem heat(h, sys);
    const double e0 = heat.thermal_energy();
    for (int k = 0; k < 5; ++k) {
        heat.thermal_step(sys);
    }
    const std::vector<FieldView> views = heat.fields(sys, {});
    ASSERT_EQ(views.size(), 1U);
    const FieldView& v = views[0];
    // The body-frame direction towards the hot cube: q^-1 (-x).
    const Vec3 towards = q.conjugate() * Vec3(-1, 0, 0);
    double near = 0.0;
    double far = 0.0;
    double hottest_projection = 0.0;
    double hottest = 0.0;
    for (std::size_t k = 0; k < v.field.size(); ++k) {
        const double along = v.grid->node[k].dot(towards);
        if (v.field[k] > hottest) {
            hottest = v.field[k];
            hottest_projection = along;
        }
        if (along > 1.0e-3) {
            near = std::max(near, v.field[k] - 300.0);
        } else if (along < -1.0e-3) {
            far = std::max(far, v.field[k] - 300.0);
        }
    }
    std::printf("resolved gap: near side +%.4g K, far side +%.4g K\n", near, far);
    EXPECT_GT(hottest_projection, 1.0e-3);             // the warmest cell faces the gap
    EXPECT_GT(near, 100.0 * far);                      // the far side has hardly warmed yet
    EXPECT_NEAR(heat.thermal_energy(), e0, 1e-9 * e0); // the solves' residual 1e-12
}

/// 27 particles in a closed box without gravity, random velocities: dumbbells, ellipsoids, cubes
/// and spheres in turn; material 0 lumped at 600 K, material 1 resolved at 300 K.
dynamics::SceneSpec mixed_box(double spacing) {
    dynamics::SceneSpec s = scene(
        {dumbbell(1.5e-3), ellipsoid(Vec3(2.5e-3, 2e-3, 1.6e-3)), test::cube_template(1.8e-3)});
    s.materials.push_back({"b", 1e8, 0.3, density, 0.9, 0.3, 0.0});
    const double l = 3.0 * spacing; // m
    for (int a = 0; a < 3; ++a) {
        const Vec3 n = Vec3::Unit(a);
        s.walls.push_back({"lo", dynamics::PlaneWall{Vec3::Zero(), n}, 0});
        s.walls.push_back({"hi", dynamics::PlaneWall{l * n, -n}, 0});
    }
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int k = 0; k < 27; ++k) {
        const Vec3 x = Vec3(k % 3 + 0.5, (k / 3) % 3 + 0.5, k / 9 + 0.5) * spacing;
        dynamics::ParticleSpec p = at(k % 4 == 3 ? -1 : k % 4, 2e-3, x);
        p.material = k % 2;
        p.v = Vec3(u(rng), u(rng), u(rng)) * 0.5;
        p.omega = Vec3(u(rng), u(rng), u(rng)) * 50.0;
        s.particles.push_back(p);
    }
    return s;
}

HeatSpec mixed_heat(const dynamics::SceneSpec& s) {
    HeatSpec h = heat_of(s, heat::HeatModel::lumped);
    h.materials[1].model = heat::HeatModel::resolved;
    h.materials[0].initial_temperature = 600.0;
    h.step_multiple = 100;
    return h;
}

TEST(BodyGaps, ClosedBoxOfMixedBodiesWithGasConservesHeat) {
    const dynamics::SceneSpec s = mixed_box(6.5e-3);
    dynamics::System sys(s);
    HeatSpec h = mixed_heat(s);
    h.gas.conductivity = k_gas;
    ThermalSystem heat(h, sys);
    const test::ClosedHeatRun run = test::run_closed_heat(sys, heat, 5000);
    const long pairs = summary_count(heat, "gas_gap_pairs");
    std::printf("gas box: %ld gas pairs, drift %.3g, range [%.12g, %.12g] K\n", pairs, run.drift,
                run.lowest, run.highest);
    EXPECT_GT(pairs, 100); // many gaps, or the test proves nothing
    // What leaves one body enters the other as the same number; the resolved solves leave a
    // relative residual below 1e-12 per step (as validations 26, 29).
    EXPECT_LT(run.drift, 1e-9);
    EXPECT_NEAR(heat.external_heat(), 0.0, 1e-15 * run.initial_energy); // adiabatic walls
    // Maximum principle of the lagged exchange (dt G / C_patch <= 0.5), K.
    EXPECT_GE(run.lowest, 300.0 - 1e-6);
    EXPECT_LE(run.highest, 600.0 + 1e-6);
    EXPECT_GT(heat.thermal_energy() / heat.heat_capacity(), 300.0);
}

TEST(BodyGaps, OneAndTwoThreadsGiveTheSameTemperatures) {
    // With two threads the gaps of body pairs (gas and radiation) are found in parallel and
    // taken in pair order: the mixed box with gas and neighbour radiation ends with the same
    // temperature in every particle and the same heat bookkeeping as with one thread.
    const auto run = [](int threads) {
        dynamics::SceneSpec s = mixed_box(6.5e-3);
        s.threads = threads;
        auto sys = std::make_unique<dynamics::System>(s);
        HeatSpec h = mixed_heat(s);
        h.gas.conductivity = k_gas;
        h.materials[0].emissivity = 0.9;
        h.materials[1].emissivity = 0.7;
        auto heat = std::make_unique<ThermalSystem>(h, *sys);
        for (int k = 0; k < 3000; ++k) {
            sys->step();
            heat->after_step(*sys);
        }
        return std::make_pair(std::move(sys), std::move(heat));
    };
    const auto [sys1, heat1] = run(1);
    const auto [sys2, heat2] = run(2);
    ASSERT_EQ(sys2->threads(), 2);
    EXPECT_GT(summary_count(*heat1, "gas_gap_pairs"), 100); // or the test proves nothing
    EXPECT_GT(summary_count(*heat1, "radiation_pairs"), 100);
    EXPECT_EQ(summary_count(*heat1, "gas_gap_pairs"), summary_count(*heat2, "gas_gap_pairs"));
    EXPECT_EQ(summary_count(*heat1, "radiation_pairs"), summary_count(*heat2, "radiation_pairs"));
    // Tolerance: none. The same exchanges, summed in the same order.
    for (std::size_t i = 0; i < sys1->particles().size(); ++i) {
        EXPECT_EQ(heat1->mean_temperature(*sys1, i), heat2->mean_temperature(*sys2, i)) << i;
    }
    EXPECT_EQ(heat1->thermal_energy(), heat2->thermal_energy());
    EXPECT_EQ(heat1->external_heat(), heat2->external_heat());
}

TEST(BodyGaps, GasOffOrOutOfReachChangesNoBit) {
    // The mixed box with and without gas: the mechanics is the same bits (heat does not act on
    // it). Spread out (every gap far beyond the cut-off) the temperatures are too.
    const dynamics::SceneSpec near = mixed_box(6.5e-3);
    const dynamics::SceneSpec far = mixed_box(40e-3);
    for (const dynamics::SceneSpec* s : {&near, &far}) {
        dynamics::System s0(*s);
        dynamics::System s1(*s);
        HeatSpec h = mixed_heat(*s);
        ThermalSystem h0(h, s0);
        h.gas.conductivity = k_gas;
        ThermalSystem h1(h, s1);
        for (int k = 0; k < 1000; ++k) {
            s0.step();
            s1.step();
            h0.after_step(s0);
            h1.after_step(s1);
        }
        for (std::size_t i = 0; i < s0.particles().size(); ++i) {
            EXPECT_EQ(s0.particles().x[i], s1.particles().x[i]);
            if (s == &far) {
                EXPECT_EQ(h0.mean_temperature(s0, i), h1.mean_temperature(s1, i));
            }
        }
        if (s == &far) {
            EXPECT_EQ(summary_count(h1, "gas_gap_pairs"), 0);
        } else {
            EXPECT_GT(summary_count(h1, "gas_gap_pairs"), 0);
        }
    }
}

// ---- Neighbour radiation ------------------------------------------------------------------

TEST(BodyGaps, RadiatingBodyPairMatchesTheLibraryForItsAreaEquivalentRadius) {
    // Black cube and ellipsoid 0.3 mm apart, lumped, 1000 K and 300 K, no ambient: one step
    // moves dt K (T_j^4 - T_i^4) with K of the area-equivalent spheres that far apart.
    const geometry::ShapeTemplate c = test::cube_template(1.5e-3);
    const geometry::ShapeTemplate e = ellipsoid(Vec3(2e-3, 1.5e-3, 1.2e-3));
    const double gap = 0.3e-3;
    dynamics::SceneSpec s = scene({c, e});
    s.particles = {at(0, 0, Vec3::Zero()), at(1, 0, Vec3(1.5e-3 + 2e-3 + gap, 0, 0))};
    dynamics::System sys(s);
    HeatSpec h = heat_of(s, heat::HeatModel::lumped);
    h.materials[0].emissivity = 1.0;
    h.particle_temperature = {1000.0, 300.0};
    ThermalSystem heat(h, sys);
    const double e0 = heat.thermal_energy();
    heat.thermal_step(sys);
    const double r_i = area_radius(c);
    const double r_j = area_radius(e);
    const double k = heat::radiative_coefficient(r_i, r_j, r_i + r_j + gap, 1.0, 1.0);
    const double c1 = capacity(s, 1);
    const double expected = heat.time_step() * k * (std::pow(1000.0, 4) - std::pow(300.0, 4)) / c1;
    ASSERT_EQ(heat.counters().max_substeps, 1);
    EXPECT_GT(expected, 1e-3);
    EXPECT_NEAR(heat.mean_temperature(sys, 1) - 300.0, expected, gap_tolerance * expected);
    EXPECT_NEAR(heat.thermal_energy(), e0, 1e-14 * e0);
    EXPECT_EQ(summary_count(heat, "radiation_pairs"), 1);
}

TEST(BodyGaps, IsothermalEnclosureOfBodiesExchangesNothing) {
    // Grey bodies (lumped and resolved), neighbours and ambient all at T_a: nothing moves.
    const dynamics::SceneSpec s = mixed_box(6.5e-3);
    dynamics::System sys(s);
    HeatSpec h = mixed_heat(s);
    h.radiation_temperature = 500.0;
    for (MaterialHeat& m : h.materials) {
        m.emissivity = 0.7;
        m.initial_temperature = 500.0;
    }
    ThermalSystem heat(h, sys);
    for (int k = 0; k < 2000; ++k) {
        sys.step();
        heat.after_step(sys);
    }
    EXPECT_GT(summary_count(heat, "radiation_pairs"), 100);
    // Rounding of the linearised updates and of the solves (K, J).
    const auto [lo, hi] = heat.temperature_range();
    EXPECT_NEAR(lo, 500.0, 1e-9);
    EXPECT_NEAR(hi, 500.0, 1e-9);
    EXPECT_NEAR(heat.external_heat(), 0.0, 1e-9);
}

TEST(BodyGaps, ClosedRadiatingBedOfBodiesConservesHeat) {
    const dynamics::SceneSpec s = mixed_box(6.5e-3);
    dynamics::System sys(s);
    HeatSpec h = mixed_heat(s);
    h.materials[0].initial_temperature = 1000.0;
    for (MaterialHeat& m : h.materials) {
        m.emissivity = 0.8;
    }
    ThermalSystem heat(h, sys);
    const test::ClosedHeatRun run = test::run_closed_heat(sys, heat, 5000);
    const long pairs = summary_count(heat, "radiation_pairs");
    std::printf("radiating body bed: %ld pairs, drift %.3g, range [%.12g, %.12g] K\n", pairs,
                run.drift, run.lowest, run.highest);
    EXPECT_GT(pairs, 100);
    EXPECT_LT(run.drift, 1e-9); // the resolved solves' residual 1e-12 per step
    EXPECT_NEAR(heat.external_heat(), 0.0, 1e-15 * run.initial_energy);
    EXPECT_GE(run.lowest, 300.0 - 1e-6); // maximum principle of the lagged exchange (K)
    EXPECT_LE(run.highest, 1000.0 + 1e-6);
    EXPECT_GT(heat.thermal_energy() / heat.heat_capacity(), 300.0 + 1.0); // heat moved
}

TEST(BodyGaps, ABlackCubeAmongNeighboursAtTheAmbientLosesWhatItLosesAlone) {
    // The ambient share rule for bodies: what a cube sees of its six neighbours (area-equivalent
    // spheres, view area (A F)) it does not see of the ambient, so with the neighbours at T_a it
    // sits in an isothermal enclosure and loses sigma A (T^4 - T_a^4), as alone.
    const double a = 1.5e-3;
    const auto loss = [&](bool neighbours) {
        dynamics::SceneSpec s = scene({test::cube_template(a)});
        s.particles.push_back(at(0, 0, Vec3::Zero()));
        if (neighbours) {
            for (int k = 0; k < 6; ++k) {
                const Vec3 n = (k % 2 == 0 ? 1.0 : -1.0) * Vec3::Unit(k / 2);
                s.particles.push_back(at(0, 0, (2.5 * a) * n)); // gap 0.5 a
            }
        }
        dynamics::System sys(s);
        HeatSpec h = heat_of(s, heat::HeatModel::lumped);
        h.step_multiple = 100; // one thermal step of 1 ms
        h.radiation_temperature = 300.0;
        h.materials[0].emissivity = 1.0;
        h.particle_temperature.assign(s.particles.size(), 300.0);
        h.particle_temperature[0] = 600.0;
        ThermalSystem heat(h, sys);
        heat.thermal_step(sys);
        if (neighbours) {
            // The centre with each neighbour, and the 12 neighbour pairs at right angles (gap
            // 2.5 sqrt 2 a - cube: within the cut-off); opposite neighbours are beyond it.
            EXPECT_EQ(summary_count(heat, "radiation_pairs"), 18);
        }
        return capacity(s, 0) * (600.0 - heat.mean_temperature(sys, 0));
    };
    const double alone = loss(false);
    const double among = loss(true);
    std::printf("cube loss in 1 ms: alone %.9g J, among neighbours at T_a %.9g J\n", alone, among);
    // Equal at the start of the step; the ambient part is implicit (linearised) and the neighbour
    // part lagged over it: ~ dt 4 sigma A T^3 / C ~ 1e-5 of the loss (as for spheres).
    EXPECT_NEAR(among, alone, 1e-4 * alone);
    EXPECT_GT(alone, 0.0);
}

} // namespace
} // namespace kiln::thermal
