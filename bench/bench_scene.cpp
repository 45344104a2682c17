// Whole-scene throughput: the LIGGGHTS pouring scene (../shared/peers/liggghts/in.pour_spheres):
// spheres of r = 2 mm, 2500 kg/m^3, E = 5 MPa, nu = 0.45, e = 0.3, mu = 0.5 in a 0.1 x 0.1 x 0.2 m
// box, dt = 1e-5 s. Reports particle-steps per second for the falling phase and for a settled bed.

#include "dynamics/system.hpp"

#include <benchmark/benchmark.h>

namespace {

using kiln::Vec3;
using namespace kiln::dynamics;

SceneSpec pour(long n) {
    SceneSpec s;
    s.materials.push_back({"glass", 5e6, 0.45, 2500, 0.3, 0.5, 0.0});
    s.time_step = 1e-5;
    s.skin = 1e-3;
    const Vec3 lo(-0.05, -0.05, 0.0);
    const Vec3 hi(0.05, 0.05, 0.2);
    for (int a = 0; a < 3; ++a) {
        s.walls.push_back({"lo", PlaneWall{lo, Vec3::Unit(a)}, 0});
        s.walls.push_back({"hi", PlaneWall{hi, -Vec3::Unit(a)}, 0});
    }
    InsertSpec ins;
    ins.region = {Vec3(-0.048, -0.048, 0.01), Vec3(0.048, 0.048, 0.19)};
    ins.count = n;
    ins.size.radius = 0.002;
    ins.velocity = Vec3(0, 0, -0.5);
    s.inserts.push_back(ins);
    return s;
}

void BM_PourFalling(benchmark::State& state) {
    const long n = state.range(0);
    System sys(pour(n));
    for (auto _ : state) {
        sys.step();
    }
    state.counters["particle_steps_per_s"] = benchmark::Counter(
        static_cast<double>(state.iterations() * n), benchmark::Counter::kIsRate);
}

void BM_PourSettled(benchmark::State& state) {
    const long n = state.range(0);
    System sys(pour(n));
    for (int k = 0; k < 40000; ++k) { // settle first; set-up outside the loop is not timed
        sys.step();
    }
    for (auto _ : state) {
        sys.step();
    }
    state.counters["particle_steps_per_s"] = benchmark::Counter(
        static_cast<double>(state.iterations() * n), benchmark::Counter::kIsRate);
    state.counters["contacts_per_particle"] =
        static_cast<double>(sys.counters().particle_contacts) / static_cast<double>(n);
}

BENCHMARK(BM_PourFalling)->Arg(5000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PourSettled)->Arg(5000)->Unit(benchmark::kMicrosecond)->Iterations(2000);

} // namespace
