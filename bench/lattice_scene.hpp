#pragma once
// The whole-scene benchmark shared by bench_bodies.cpp and bench_polyhedra_scene.cpp: a simple
// cubic lattice of 343 particles (spheres or one body template) moving down at 0.2 m/s into a box
// of six plane walls (the top one 5 cm above the lattice), collapsing under gravity into a bed;
// after a warm-up each timed iteration is one step. One thread; rates are per wall-clock second,
// so a busy host lowers them.

#include "dynamics/system.hpp"
#include "geometry/shape.hpp"

#include <benchmark/benchmark.h>
#include <chrono>
#include <optional>

namespace kiln::bench {

/// The scene: material "pom" (E = 5e7 Pa, nu = 0.35, 1380 kg/m^3, e = 0.5, mu = 0.3), dt = 5e-6 s,
/// one thread, random orientations; particles of template `shape`, or spheres of radius
/// `sphere_radius` (m) when there is none. The lattice spacing is `spacing` bounding diameters
/// (1.02 unless given).
inline dynamics::SceneSpec lattice_box_scene(const std::optional<geometry::ShapeTemplate>& shape,
                                             double sphere_radius = 0.0, double spacing = 1.02) {
    using dynamics::InsertSpec;
    using dynamics::PlaneWall;
    dynamics::SceneSpec s;
    s.materials.push_back({"pom", 5e7, 0.35, 1380, 0.5, 0.3, 0.0});
    s.time_step = 5e-6;
    s.threads = 1;
    InsertSpec ins;
    ins.kind = InsertSpec::Kind::lattice;
    ins.count = 343;
    ins.velocity = Vec3(0, 0, -0.2);
    ins.orientation.random = true;
    if (shape) {
        s.shapes.push_back(*shape);
        ins.shape = 0;
        ins.size.radius = s.shapes[0].bounding_radius();
    } else {
        ins.size.radius = sphere_radius;
    }
    const double a = 2.0 * ins.size.radius * spacing;
    ins.spacing = a;
    const Vec3 hi(7 * a + 1e-4, 7 * a + 1e-4, 7 * a + 1e-4);
    ins.region = {Vec3::Zero(), hi};
    for (int k = 0; k < 3; ++k) {
        s.walls.push_back({"lo", PlaneWall{Vec3::Zero(), Vec3::Unit(k)}, 0});
        s.walls.push_back(
            {"hi", PlaneWall{hi + Vec3(0, 0, k == 2 ? 0.05 : 0.0), -Vec3::Unit(k)}, 0});
    }
    s.inserts.push_back(ins);
    return s;
}

/// Builds `spec`, runs `warmup` steps (the collapse into a bed), then times one step per
/// iteration and reports particle-steps per second, contacts per particle and wall time per
/// contact (ns, particle and wall contacts), labelled `label`.
inline void time_scene(benchmark::State& state, const dynamics::SceneSpec& spec, int warmup,
                       const char* label) {
    dynamics::System sys(spec);
    for (int k = 0; k < warmup; ++k) {
        sys.step();
    }
    long contacts = 0;
    double seconds = 0.0;
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        sys.step();
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        contacts += sys.counters().particle_contacts + sys.counters().wall_contacts;
    }
    const double n = static_cast<double>(sys.particles().size());
    state.counters["particle_steps_per_s"] = benchmark::Counter(
        static_cast<double>(state.iterations()) * n, benchmark::Counter::kIsRate);
    state.counters["contacts_per_particle"] =
        static_cast<double>(contacts) / (n * static_cast<double>(state.iterations()));
    state.counters["ns_per_contact"] =
        contacts > 0 ? 1e9 * seconds / static_cast<double>(contacts) : 0;
    state.SetLabel(label);
}

} // namespace kiln::bench
