// Transfer-grid kernels (src/fluid, docs/performance.md): deposition cost per particle by shape
// and sub-grid resolution (sub-cells per volume-equivalent diameter 4, 8, 16 with fluid cells of
// two diameters), the interpolation back and the spreading of a source, and a mixed bed on one
// and two threads. Run: build/bench/kiln_bench_transfer

#include "fluid/exchange.hpp"
#include "fluid/footprints.hpp"
#include "io/shape_reader.hpp"

#include <benchmark/benchmark.h>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace {

using kiln::Quat;
using kiln::Vec3;
namespace f = kiln::fluid;
namespace g = kiln::geometry;

const std::vector<std::string> kShapes = {"sphere", "cube", "icosahedron", "superball", "clump"};

g::ShapeTemplate shape(int kind) {
    const std::string& name = kShapes[static_cast<std::size_t>(kind)];
    if (name == "sphere") {
        return g::make_template("sphere", g::Sphere{1.4e-3}); // the 2.8 mm spheres of the seed
    }
    if (name == "clump") { // 6 x 6 mm cylinder of 12 spheres (shapes/cylinder_12.toml)
        return kiln::io::read_shape_file(std::string(KILN_SOURCE_DIR) + "/shapes/cylinder_12.toml");
    }
    return kiln::io::read_shape_file(std::string(KILN_SOURCE_DIR) + "/shapes/" + name + ".toml");
}

double equivalent_diameter(const g::ShapeTemplate& t) {
    return std::cbrt(6.0 * t.volume / std::numbers::pi);
}

/// n particles of the given templates (chosen in turn) at random positions and orientations in
/// a cube filled to a solid fraction of 0.3, on a grid of cells of two equivalent diameters of
/// the first template with 2 `per_diameter` sub-cells per cell edge.
struct Bed {
    std::vector<f::DepositTemplate> templates;
    std::vector<int> kind;
    std::vector<Vec3> pos;
    std::vector<Quat> rot;
    f::TransferGrid grid{Vec3::Zero(), {1, 1, 1}, 1.0, 1};

    Bed(const std::vector<g::ShapeTemplate>& shapes, std::size_t n, int per_diameter) {
        double volume = 0.0;
        for (std::size_t p = 0; p < n; ++p) {
            volume += shapes[p % shapes.size()].volume;
        }
        const double side = std::cbrt(volume / 0.3);
        const double cell = 2.0 * equivalent_diameter(shapes[0]);
        const int cells = static_cast<int>(std::ceil(side / cell));
        grid = f::TransferGrid(Vec3::Zero(), {cells, cells, cells}, cell, 2 * per_diameter);
        for (const auto& s : shapes) {
            templates.push_back(f::make_deposit_template(s));
        }
        std::mt19937_64 rng(1);
        std::uniform_real_distribution<double> u(0.0, side);
        std::normal_distribution<double> nd;
        for (std::size_t p = 0; p < n; ++p) {
            kind.push_back(static_cast<int>(p % shapes.size()));
            pos.emplace_back(u(rng), u(rng), u(rng));
            rot.push_back(Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized());
        }
    }
    void deposit(f::Footprints& fp, int threads) const {
        f::compute_footprints(grid, templates, {kind, pos, rot}, fp, threads);
    }
};

constexpr std::size_t kParticles = 2000;

void add_counters(benchmark::State& state, const f::Footprints& fp, std::size_t n) {
    double sub = 0.0;
    for (const auto c : fp.sub_cells) {
        sub += static_cast<double>(c);
    }
    state.counters["time_per_particle"] =
        benchmark::Counter(static_cast<double>(n), benchmark::Counter::kIsIterationInvariantRate |
                                                       benchmark::Counter::kInvert);
    state.counters["sub_cells"] = sub / static_cast<double>(n);
    state.counters["cells"] = static_cast<double>(fp.cell.size()) / static_cast<double>(n);
    state.counters["too_small"] = static_cast<double>(fp.too_small);
}

// Footprints of 2000 particles of one shape: args (shape, sub-cells per diameter).
void BM_Deposit(benchmark::State& state) {
    const Bed bed({shape(static_cast<int>(state.range(0)))}, kParticles,
                  static_cast<int>(state.range(1)));
    f::Footprints fp;
    for (auto _ : state) {
        bed.deposit(fp, 1);
        benchmark::DoNotOptimize(fp.cell.data());
    }
    state.SetLabel(kShapes[static_cast<std::size_t>(state.range(0))]);
    add_counters(state, fp, kParticles);
}
BENCHMARK(BM_Deposit)->ArgsProduct({{0, 1, 2, 3, 4}, {4, 8, 16}})->Unit(benchmark::kMicrosecond);

// Gas velocity averaged over each particle's sub-cells (cube bed), args: sub-cells per diameter.
void BM_Interpolate(benchmark::State& state) {
    const Bed bed({shape(1)}, kParticles, static_cast<int>(state.range(0)));
    f::Footprints fp;
    bed.deposit(fp, 1);
    std::vector<Vec3> field(fp.cells, Vec3(0.1, 0.2, 1.0));
    std::vector<Vec3> out(kParticles);
    for (auto _ : state) {
        f::interpolate(fp, field, out, 1);
        benchmark::DoNotOptimize(out.data());
    }
    state.counters["time_per_particle"] = benchmark::Counter(
        kParticles, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_Interpolate)->Arg(4)->Arg(8)->Arg(16)->Unit(benchmark::kMicrosecond);

// Drag reaction spread over the sub-cells (cube bed), args: sub-cells per diameter.
void BM_Spread(benchmark::State& state) {
    const Bed bed({shape(1)}, kParticles, static_cast<int>(state.range(0)));
    f::Footprints fp;
    bed.deposit(fp, 1);
    std::vector<Vec3> force(kParticles, Vec3(1e-4, 0.0, 2e-4));
    std::vector<Vec3> out(fp.cells);
    for (auto _ : state) {
        f::spread(fp, force, out, 1);
        benchmark::DoNotOptimize(out.data());
    }
    state.counters["time_per_particle"] = benchmark::Counter(
        kParticles, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_Spread)->Arg(4)->Arg(8)->Arg(16)->Unit(benchmark::kMicrosecond);

// A mixed bed of 4000 particles (all five shapes) at 8 sub-cells per diameter: footprints,
// porosity, one vector source and the interpolation back. Args: threads.
void BM_BedCoupling(benchmark::State& state) {
    std::vector<g::ShapeTemplate> shapes;
    for (int k = 0; k < 5; ++k) {
        shapes.push_back(shape(k));
    }
    constexpr std::size_t kBed = 4000;
    const Bed bed(shapes, kBed, 8);
    const int threads = static_cast<int>(state.range(0));
    f::Footprints fp;
    std::vector<double> solid(bed.grid.cell_count());
    std::vector<Vec3> force(kBed, Vec3(1e-4, 0.0, 2e-4));
    std::vector<Vec3> cells(bed.grid.cell_count());
    std::vector<Vec3> gas(kBed);
    for (auto _ : state) {
        bed.deposit(fp, threads);
        f::solid_volume(fp, solid, threads);
        f::spread(fp, force, cells, threads);
        f::interpolate(fp, cells, gas, threads);
        benchmark::DoNotOptimize(gas.data());
    }
    state.counters["time_per_particle"] = benchmark::Counter(
        kBed, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_BedCoupling)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

} // namespace
