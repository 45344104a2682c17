// Whole-scene cost of polyhedron particles, in the scene of bench_bodies.cpp (a lattice of 343
// particles collapsing under gravity into a box of plane walls): cubes (12 triangles, 6 faces),
// icosahedra (20 faces) and 16-edged cylinders (18 faces), all with the fast common plane; the
// cubes also with libccd GJK/EPA. Reports particle-steps per second and wall time per contact (ns).
// One thread; rates are per wall-clock second, so a busy host lowers them.

#include "dynamics/system.hpp"
#include "io/shape_reader.hpp"

#include <benchmark/benchmark.h>
#include <chrono>
#include <string>

namespace {

using kiln::Vec3;
using namespace kiln::dynamics;

/// kind: 0 cube, 1 icosahedron, 2 cylinder_16, 3 cube with GJK/EPA.
SceneSpec scene(int kind) {
    SceneSpec s;
    s.materials.push_back({"pom", 5e7, 0.35, 1380, 0.5, 0.3, 0.0});
    s.time_step = 5e-6;
    s.threads = 1;
    s.narrow_phase = kind == 3 ? NarrowPhase::gjk_epa : NarrowPhase::newton;
    InsertSpec ins;
    ins.kind = InsertSpec::Kind::lattice;
    ins.count = 343;
    ins.velocity = Vec3(0, 0, -0.2);
    ins.orientation.random = true;
    const char* names[] = {"cube", "icosahedron", "cylinder_16", "cube"};
    s.shapes.push_back(kiln::io::read_shape_file(
        kiln::io::find_shape_file(names[kind], kiln::io::default_shape_dirs())));
    ins.shape = 0;
    ins.size.radius = s.shapes[0].bounding_radius();
    const double a = 2.0 * ins.size.radius * 1.02;
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

void BM_PolyhedronScene(benchmark::State& state) {
    const int kind = static_cast<int>(state.range(0));
    System sys(scene(kind));
    for (int k = 0; k < 4000; ++k) { // collapse into a bed before timing
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
    static const char* labels[] = {"cube_common_plane", "icosahedron_common_plane",
                                   "cylinder_16_common_plane", "cube_gjk_epa"};
    state.SetLabel(labels[kind]);
}

BENCHMARK(BM_PolyhedronScene)->DenseRange(0, 3)->Unit(benchmark::kMillisecond)->MinTime(2.0);

} // namespace
