// Whole-scene throughput: the LIGGGHTS pouring scene (../shared/peers/liggghts/in.pour_spheres):
// spheres of r = 2 mm, 2500 kg/m^3, E = 5 MPa, nu = 0.45, e = 0.3, mu = 0.5 in a 0.1 x 0.1 x 0.2 m
// box, dt = 1e-5 s. Reports particle-steps per second for the falling phase and for a settled bed,
// by number of spheres and of threads. Above 10 000 spheres the box is made taller (0.2 m per
// 10 000 spheres) so that they fit, as in the LIGGGHTS runs of notes/limits.md. Rates are per
// wall-clock second (threads), so a busy host lowers them.

#include "dynamics/system.hpp"

#include <algorithm>
#include <benchmark/benchmark.h>
#include <map>

namespace {

using kiln::Vec3;
using namespace kiln::dynamics;

SceneSpec pour(long n, int threads) {
    SceneSpec s;
    s.materials.push_back({"glass", 5e6, 0.45, 2500, 0.3, 0.5, 0.0});
    s.time_step = 1e-5;
    s.skin = 1e-3;
    s.threads = threads;
    const double height = 0.2 * std::max(1.0, static_cast<double>(n) / 10000.0);
    const Vec3 lo(-0.05, -0.05, 0.0);
    const Vec3 hi(0.05, 0.05, height);
    for (int a = 0; a < 3; ++a) {
        s.walls.push_back({"lo", PlaneWall{lo, Vec3::Unit(a)}, 0});
        s.walls.push_back({"hi", PlaneWall{hi, -Vec3::Unit(a)}, 0});
    }
    InsertSpec ins;
    ins.region = {Vec3(-0.048, -0.048, 0.01), Vec3(0.048, 0.048, height - 0.01)};
    ins.count = n;
    ins.size.radius = 0.002;
    ins.velocity = Vec3(0, 0, -0.5);
    s.inserts.push_back(ins);
    return s;
}

void report(benchmark::State& state, long n, const System& sys) {
    state.counters["particle_steps_per_s"] = benchmark::Counter(
        static_cast<double>(state.iterations() * n), benchmark::Counter::kIsRate);
    state.counters["ns_per_particle_step"] =
        benchmark::Counter(static_cast<double>(state.iterations() * n),
                           benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
    state.counters["contacts_per_particle"] =
        static_cast<double>(sys.counters().particle_contacts) / static_cast<double>(n);
    state.counters["threads"] = sys.threads();
}

/// Args: number of spheres, threads.
void BM_PourFalling(benchmark::State& state) {
    const long n = state.range(0);
    System sys(pour(n, static_cast<int>(state.range(1))));
    for (auto _ : state) {
        sys.step();
    }
    report(state, n, sys);
}

/// Args: number of spheres, threads. The bed is settled once per size (40 000 steps, not timed)
/// and reused for every thread count.
void BM_PourSettled(benchmark::State& state) {
    static std::map<long, SystemState> settled;
    const long n = state.range(0);
    if (settled.count(n) == 0) {
        System first(pour(n, 0));
        for (int k = 0; k < 40000; ++k) {
            first.step();
        }
        settled.emplace(n, first.save_state());
    }
    System sys(pour(n, static_cast<int>(state.range(1))));
    sys.restore_state(settled.at(n));
    for (auto _ : state) {
        sys.step();
    }
    report(state, n, sys);
}

BENCHMARK(BM_PourFalling)
    ->ArgsProduct({{5000, 10000, 50000}, {1, 2}})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime()
    ->Iterations(500);
BENCHMARK(BM_PourSettled)
    ->ArgsProduct({{5000, 10000}, {1, 2}})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime()
    ->Iterations(2000);

} // namespace
