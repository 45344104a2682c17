// Cost per pair of the superquadric narrow-phase methods (geometry/convex_contact.hpp) on random
// overlapping poses of an ellipsoid and a near-cube (blocky) pair. Run:
// build/bench/kiln_bench_shapes

#include "geometry/convex_contact.hpp"

#include <benchmark/benchmark.h>
#include <cmath>
#include <random>
#include <vector>

namespace {

using kiln::Quat;
using kiln::Vec3;
namespace g = kiln::geometry;

struct Pair {
    g::PosedSuperquadric a;
    g::PosedSuperquadric b;
};

/// 256 overlapping random poses of shape s with itself (overlap 1e-3 to 1e-2 of the size).
std::vector<Pair> poses(const g::Superquadric& s) {
    std::mt19937_64 rng(1);
    std::normal_distribution<double> nd;
    std::uniform_real_distribution<double> ud(-3.0, -2.0);
    std::vector<Pair> out;
    for (int i = 0; i < 256; ++i) {
        Pair p{{&s, Vec3::Zero(), Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized()},
               {&s, Vec3::Zero(), Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized()}};
        const Vec3 u = Vec3(nd(rng), nd(rng), nd(rng)).normalized();
        const double overlap = 2.0 * s.half_axes.maxCoeff() * std::pow(10.0, ud(rng));
        p.b.x = p.a.support(u) - overlap * u - p.b.support(-u);
        out.push_back(p);
    }
    return out;
}

/// Newton warm-started from the cold-start normal turned by 0.01 rad (one DEM step of motion).
void run_warm(benchmark::State& state, const g::Superquadric& s) {
    const std::vector<Pair> pairs = poses(s);
    std::vector<Vec3> warm;
    for (const Pair& p : pairs) {
        const Vec3 n = g::support_newton_contact(p.a, p.b).normal;
        warm.push_back((Quat(Eigen::AngleAxisd(0.01, n.unitOrthogonal())) * n).normalized());
    }
    std::size_t i = 0;
    for (auto _ : state) {
        const std::size_t k = i++ % pairs.size();
        benchmark::DoNotOptimize(g::support_newton_contact(pairs[k].a, pairs[k].b, &warm[k]));
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

void run(benchmark::State& state, const g::Superquadric& s, g::ConvexMethod m) {
    const std::vector<Pair> pairs = poses(s);
    std::size_t i = 0;
    for (auto _ : state) {
        const Pair& p = pairs[i++ % pairs.size()];
        benchmark::DoNotOptimize(g::convex_contact(p.a, p.b, m));
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

g::Superquadric shape(double e) {
    g::Superquadric s;
    s.half_axes = Vec3(1e-3, 2e-3, 3e-3);
    s.e1 = e;
    s.e2 = e;
    return s;
}

const g::Superquadric kEllipsoid = shape(1.0);
const g::Superquadric kBlocky = shape(0.3);

void BM_EllipsoidEpa(benchmark::State& st) {
    run(st, kEllipsoid, g::ConvexMethod::kCcdEpa);
}
void BM_EllipsoidMpr(benchmark::State& st) {
    run(st, kEllipsoid, g::ConvexMethod::kCcdMpr);
}
void BM_EllipsoidNewton(benchmark::State& st) {
    run(st, kEllipsoid, g::ConvexMethod::kSupportNewton);
}
void BM_EllipsoidNewtonWarm(benchmark::State& st) {
    run_warm(st, kEllipsoid);
}
void BM_BlockyNewtonWarm(benchmark::State& st) {
    run_warm(st, kBlocky);
}
void BM_BlockyEpa(benchmark::State& st) {
    run(st, kBlocky, g::ConvexMethod::kCcdEpa);
}
void BM_BlockyMpr(benchmark::State& st) {
    run(st, kBlocky, g::ConvexMethod::kCcdMpr);
}
void BM_BlockyNewton(benchmark::State& st) {
    run(st, kBlocky, g::ConvexMethod::kSupportNewton);
}

} // namespace

BENCHMARK(BM_EllipsoidEpa);
BENCHMARK(BM_EllipsoidMpr);
BENCHMARK(BM_EllipsoidNewton);
BENCHMARK(BM_EllipsoidNewtonWarm);
BENCHMARK(BM_BlockyEpa);
BENCHMARK(BM_BlockyMpr);
BENCHMARK(BM_BlockyNewton);
BENCHMARK(BM_BlockyNewtonWarm);
