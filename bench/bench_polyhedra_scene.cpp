// Whole-scene cost of polyhedron particles, in the scene of bench_bodies.cpp (a lattice of 343
// particles collapsing under gravity into a box of plane walls; lattice_scene.hpp): cubes (12
// triangles, 6 faces), icosahedra (20 faces) and 16-edged cylinders (18 faces), all with the fast
// common plane; the cubes also with libccd GJK/EPA. Reports particle-steps per second and wall time
// per contact (ns). One thread; rates are per wall-clock second, so a busy host lowers them.

#include "io/shape_reader.hpp"
#include "lattice_scene.hpp"

#include <benchmark/benchmark.h>

namespace {

using namespace kiln::dynamics;

/// kind: 0 cube, 1 icosahedron, 2 cylinder_16, 3 cube with GJK/EPA.
SceneSpec scene(int kind) {
    const char* names[] = {"cube", "icosahedron", "cylinder_16", "cube"};
    SceneSpec s = kiln::bench::lattice_box_scene(kiln::io::read_shape_file(
        kiln::io::find_shape_file(names[kind], kiln::io::default_shape_dirs())));
    s.narrow_phase = kind == 3 ? NarrowPhase::gjk_epa : NarrowPhase::newton;
    return s;
}

void BM_PolyhedronScene(benchmark::State& state) {
    const int kind = static_cast<int>(state.range(0));
    static const char* labels[] = {"cube_common_plane", "icosahedron_common_plane",
                                   "cylinder_16_common_plane", "cube_gjk_epa"};
    kiln::bench::time_scene(state, scene(kind), 4000, labels[kind]);
}

BENCHMARK(BM_PolyhedronScene)->DenseRange(0, 3)->Unit(benchmark::kMillisecond)->MinTime(2.0);

} // namespace
