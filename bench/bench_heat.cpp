// Cost of one resolved heat update of a ~1000-cell particle (issue 6 targets: <= 15 us at cell
// Fourier number ~0.03, BiCGSTAB path <= 30 us; <= 45 us at Fo ~3 with a factor-once direct
// solve). Set-up of limits.md Part B: 4 mm cube, k = 1 W/(m K), rho c = 2.1e6 J/(m^3 K),
// h = 500 W/(m^2 K), ambient varying slowly from step to step; tolerance 1e-8 (relative residual).

#include "heat/cartesian_grid.hpp"
#include "heat/resolved_model.hpp"
#include "heat/spherical_grid.hpp"

#include <benchmark/benchmark.h>
#include <cmath>
#include <memory>
#include <vector>

namespace {

using namespace kiln::heat;

const ThermalProperties props{1.0, 2100.0, 1000.0}; // rho c = 2.1e6 J/(m^3 K)

std::shared_ptr<const ThermalGrid> cube_grid() {
    // Box faces through cell centres: 9 cells across the edge give 10^3 = 1000 cells (half cells
    // at faces, quarter cells at edges; a merge threshold of 0.1 keeps the quarter and eighth
    // cells, so the benchmark has exactly the 1000 unknowns of limits.md Part B).
    static const auto g = std::make_shared<const ThermalGrid>(make_cartesian_grid(
        Box{kiln::Vec3::Constant(0.002)}, {.cells_across = 9, .merge_fraction = 0.1}));
    return g;
}

std::shared_ptr<const ThermalGrid> sphere_grid() {
    // 1 + 8 x 8 x 16 = 1025 cells (seed Inv. VI used 1 + 10 x 8 x 16).
    static const auto g =
        std::make_shared<const ThermalGrid>(make_spherical_grid(0.002, {8, 8, 16}));
    return g;
}

/// Time step giving cell Fourier number `fo` for the cube's cell size.
double step_for(double fo) {
    const double dx = 0.004 / 9.0;
    return fo * dx * dx / props.diffusivity();
}

void run(benchmark::State& state, const std::shared_ptr<const ThermalGrid>& g, SolverKind kind,
         double fo, bool extrapolate = false) {
    const std::vector<double> h{500.0};
    ResolvedOperator op(g, props, step_for(fo), h, {kind, 1e-8, 1000});
    std::vector<double> t(static_cast<std::size_t>(g->size()), 300.0);
    std::vector<double> previous(extrapolate ? t.size() : 0, 300.0);
    long s = 0;
    for (auto _ : state) {
        const double ambient =
            400.0 + 50.0 * std::sin(2.0 * 3.14159265 * static_cast<double>(s) / 200.0);
        const StepReport r = op.step(t, {.ambient = ambient}, previous);
        benchmark::DoNotOptimize(r);
        ++s;
    }
    state.counters["cells"] = g->size();
    state.counters["iters/step"] =
        static_cast<double>(op.total_iterations()) / static_cast<double>(op.total_solves());
}

void BM_CubeCG_Fo003(benchmark::State& s) {
    run(s, cube_grid(), SolverKind::cg, 0.03);
}
void BM_CubeBiCGSTAB_Fo003(benchmark::State& s) {
    run(s, cube_grid(), SolverKind::bicgstab, 0.03);
}
void BM_CubeCG_Fo3(benchmark::State& s) {
    run(s, cube_grid(), SolverKind::cg, 3.0);
}
void BM_CubeBiCGSTAB_Fo3(benchmark::State& s) {
    run(s, cube_grid(), SolverKind::bicgstab, 3.0);
}
void BM_SphereCG_Fo003(benchmark::State& s) {
    run(s, sphere_grid(), SolverKind::cg, 0.03);
}
void BM_SphereBiCGSTAB_Fo003(benchmark::State& s) {
    run(s, sphere_grid(), SolverKind::bicgstab, 0.03);
}
/// With the time-extrapolated initial guess (a second field per particle).
void BM_CubeCGExtrapolated_Fo003(benchmark::State& s) {
    run(s, cube_grid(), SolverKind::cg, 0.03, true);
}
void BM_CubeBiCGSTABExtrapolated_Fo003(benchmark::State& s) {
    run(s, cube_grid(), SolverKind::bicgstab, 0.03, true);
}
void BM_CubeCGExtrapolated_Fo3(benchmark::State& s) {
    run(s, cube_grid(), SolverKind::cg, 3.0, true);
}
BENCHMARK(BM_CubeCG_Fo003);
BENCHMARK(BM_CubeCGExtrapolated_Fo003);
BENCHMARK(BM_CubeBiCGSTABExtrapolated_Fo003);
BENCHMARK(BM_CubeCGExtrapolated_Fo3);
BENCHMARK(BM_CubeBiCGSTAB_Fo003);
BENCHMARK(BM_CubeCG_Fo3);
BENCHMARK(BM_CubeBiCGSTAB_Fo3);
BENCHMARK(BM_SphereCG_Fo003);
BENCHMARK(BM_SphereBiCGSTAB_Fo003);

#if KILN_HAVE_CHOLMOD
void BM_CubeCholmod_Fo003(benchmark::State& s) {
    run(s, cube_grid(), SolverKind::cholmod, 0.03);
}
void BM_CubeCholmod_Fo3(benchmark::State& s) {
    run(s, cube_grid(), SolverKind::cholmod, 3.0);
}
void BM_SphereCholmod_Fo3(benchmark::State& s) {
    run(s, sphere_grid(), SolverKind::cholmod, 3.0);
}
BENCHMARK(BM_CubeCholmod_Fo003);
BENCHMARK(BM_CubeCholmod_Fo3);
BENCHMARK(BM_SphereCholmod_Fo3);

/// One-off cost of building the operator with a CHOLMOD factorisation (per template).
void BM_CubeCholmodFactorise(benchmark::State& state) {
    const std::vector<double> h{500.0};
    for (auto _ : state) {
        ResolvedOperator op(cube_grid(), props, step_for(3.0), h, {SolverKind::cholmod, 1e-8, 1});
        benchmark::DoNotOptimize(&op);
    }
}
BENCHMARK(BM_CubeCholmodFactorise)->Unit(benchmark::kMicrosecond);
#endif

/// Building the 1000-cell cut-cell grid of a superquadric (once per template and resolution).
void BM_SuperquadricGridBuild(benchmark::State& state) {
    for (auto _ : state) {
        const ThermalGrid g = make_cartesian_grid(
            Superquadric{kiln::Vec3(0.002, 0.0016, 0.0012), 0.5, 0.8}, {.cells_across = 14});
        benchmark::DoNotOptimize(g.volume.data());
        state.counters["cells"] = g.size();
    }
}
BENCHMARK(BM_SuperquadricGridBuild)->Unit(benchmark::kMillisecond);

/// Speed/accuracy trade on the set-up of validation 20 (glass sphere R = 50 mm, Bi = 1,
/// dt = t_end/400 with t_end at Fo = 1/3): cost per step of each grid whose error that case
/// reports. Arguments: grid kind (0 spherical n_r x 4 x 8, 1 Cartesian), resolution, solver.
void BM_SphereTradeoff(benchmark::State& state) {
    const ThermalProperties glass{1.4, 2225.0, 835.0};
    const double r = 0.05;
    const int res = static_cast<int>(state.range(1));
    const auto g = state.range(0) == 0
                       ? std::make_shared<const ThermalGrid>(make_spherical_grid(r, {res, 4, 8}))
                       : std::make_shared<const ThermalGrid>(
                             make_cartesian_grid(Sphere{r}, {.cells_across = res}));
    const SolverKind kind = state.range(2) == 0 ? SolverKind::cg : SolverKind::cholmod;
    if (kind == SolverKind::cholmod && !cholmod_available()) {
        state.SkipWithError("no CHOLMOD");
        return;
    }
    const double dt = (1.0 / 3.0) * r * r / glass.diffusivity() / 400.0;
    const std::vector<double> h{1.0 * glass.conductivity / r};
    ResolvedOperator op(g, glass, dt, h, {kind, 1e-10, 5000});
    std::vector<double> t(static_cast<std::size_t>(g->size()), 1.0);
    for (auto _ : state) {
        benchmark::DoNotOptimize(op.step(t, {.ambient = 0.0}));
    }
    state.counters["cells"] = g->size();
    state.counters["iters/step"] =
        static_cast<double>(op.total_iterations()) / static_cast<double>(op.total_solves());
}
BENCHMARK(BM_SphereTradeoff)
    ->ArgsProduct({{0}, {5, 10, 20, 40}, {0, 1}})
    ->ArgsProduct({{1}, {8, 12, 16, 24}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);

} // namespace
