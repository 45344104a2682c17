// Cost of the gap of two bodies that need not touch, as the heat of gas gaps and neighbour
// radiation finds it (thermal::core_distance: GJK with the nearest points,
// thermal/body_gap.hpp), for pairs of the showcase's shapes (cube, superball, 1:2:3 ellipsoid) in
// random orientations at gaps of 1e-3 to 0.3 of the larger bounding radius. Run:
// build/bench/kiln_bench_gaps

#include "io/shape_reader.hpp"
#include "thermal/body_gap.hpp"

#include <benchmark/benchmark.h>
#include <map>
#include <random>
#include <string>
#include <vector>

namespace {

using kiln::Quat;
using kiln::Vec3;
namespace g = kiln::geometry;

const g::ShapeTemplate& shape(const std::string& name) {
    static std::map<std::string, g::ShapeTemplate> cache;
    auto it = cache.find(name);
    if (it == cache.end()) {
        it = cache
                 .emplace(name, kiln::io::read_shape_file(kiln::io::find_shape_file(
                                    name, kiln::io::default_shape_dirs())))
                 .first;
    }
    return it->second;
}

/// The core of a shape template placed at x turned by q (world frame).
kiln::thermal::Core core(const g::ShapeTemplate& t, const Vec3& x, const Quat& q) {
    kiln::thermal::Core c;
    c.x = x;
    c.q = q;
    if (const auto* sq = std::get_if<g::Superquadric>(&t.shape)) {
        c.superquadric = sq;
    } else {
        c.polyhedron = &std::get<g::ConvexPolyhedron>(t.shape);
    }
    return c;
}

/// 256 poses of the pair (a, b): random orientations, b along a random direction from a, moved
/// out until the cores are apart by the gap drawn (GJK's own distance, bisected on the centre
/// distance to 1e-3 of the gap).
std::vector<std::pair<kiln::thermal::Core, kiln::thermal::Core>> poses(const std::string& a,
                                                                       const std::string& b) {
    const g::ShapeTemplate& ta = shape(a);
    const g::ShapeTemplate& tb = shape(b);
    const double ra = ta.bounding_radius();
    const double rb = tb.bounding_radius();
    const double tol = 1e-9 * std::max(ra, rb);
    std::mt19937_64 rng(17);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::uniform_real_distribution<double> lg(-3.0, std::log10(0.3));
    const auto unit = [&] {
        Vec3 v;
        do {
            v = Vec3(u(rng), u(rng), u(rng));
        } while (!(v.squaredNorm() > 1e-6 && v.squaredNorm() <= 1.0));
        return Vec3(v.normalized());
    };
    std::vector<std::pair<kiln::thermal::Core, kiln::thermal::Core>> out;
    while (out.size() < 256) {
        const Quat qa(Eigen::AngleAxisd(3.0 * u(rng), unit()));
        const Quat qb(Eigen::AngleAxisd(3.0 * u(rng), unit()));
        const Vec3 dir = unit();
        const double gap = std::pow(10.0, lg(rng)) * std::max(ra, rb);
        // Centre distance with the wanted gap: bisection between touching and the bounding
        // spheres' gap.
        double lo = 0.0;
        double hi = ra + rb + gap;
        for (int it = 0; it < 60 && hi - lo > 1e-3 * gap; ++it) {
            const double mid = 0.5 * (lo + hi);
            const auto d = kiln::thermal::core_distance(core(ta, Vec3::Zero(), qa),
                                                        core(tb, mid * dir, qb), tol);
            (d.overlap || d.distance < gap ? lo : hi) = mid;
        }
        out.emplace_back(core(ta, Vec3::Zero(), qa), core(tb, hi * dir, qb));
    }
    return out;
}

void run(benchmark::State& state, const std::string& a, const std::string& b) {
    const auto pairs = poses(a, b);
    const double tol = 1e-9 * std::max(shape(a).bounding_radius(), shape(b).bounding_radius());
    std::size_t k = 0;
    long iterations = 0;
    for (auto _ : state) {
        const auto& [ca, cb] = pairs[k++ % pairs.size()];
        const auto d = kiln::thermal::core_distance(ca, cb, tol);
        iterations += d.iterations;
        benchmark::DoNotOptimize(d);
    }
    state.counters["gjk_iterations"] =
        static_cast<double>(iterations) / static_cast<double>(state.iterations());
}

void BM_CubeCube(benchmark::State& s) {
    run(s, "cube", "cube");
}
void BM_CubeSuperball(benchmark::State& s) {
    run(s, "cube", "superball");
}
void BM_CubeEllipsoid(benchmark::State& s) {
    run(s, "cube", "ellipsoid_123");
}
void BM_SuperballSuperball(benchmark::State& s) {
    run(s, "superball", "superball");
}
void BM_SuperballEllipsoid(benchmark::State& s) {
    run(s, "superball", "ellipsoid_123");
}

BENCHMARK(BM_CubeCube);
BENCHMARK(BM_CubeSuperball);
BENCHMARK(BM_CubeEllipsoid);
BENCHMARK(BM_SuperballSuperball);
BENCHMARK(BM_SuperballEllipsoid);

} // namespace
