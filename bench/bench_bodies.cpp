// Whole-scene cost of non-spherical particles: the same scene (a lattice of 343 particles of about
// 6 mm, collapsing under gravity into a box; lattice_scene.hpp) with spheres, 12- and 36-sphere
// clumps of the seed's 6 x 6 mm cylinder, and superquadrics of low (e = 0.8) and high (e = 0.3)
// blockiness. Reports particle-steps per second and wall time per element contact (ns). One
// thread; rates are per wall-clock second, so a busy host lowers them.

#include "geometry/superquadric.hpp"
#include "io/shape_reader.hpp"
#include "lattice_scene.hpp"

#include <benchmark/benchmark.h>
#include <optional>

namespace {

using kiln::Vec3;

/// kind: 0 spheres, 1 cylinder_12, 2 cylinder_36, 3 superquadric e = 0.8, 4 e = 0.3.
kiln::dynamics::SceneSpec scene(int kind) {
    if (kind == 0) {
        return kiln::bench::lattice_box_scene(std::nullopt, 3.3e-3); // the cylinder's volume
    }
    if (kind <= 2) {
        const auto name = kind == 1 ? "cylinder_12" : "cylinder_36";
        return kiln::bench::lattice_box_scene(kiln::io::read_shape_file(
            kiln::io::find_shape_file(name, kiln::io::default_shape_dirs())));
    }
    kiln::geometry::Superquadric q;
    q.half_axes = Vec3::Constant(3e-3);
    q.e1 = q.e2 = kind == 3 ? 0.8 : 0.3;
    return kiln::bench::lattice_box_scene(kiln::geometry::make_template("sq", q));
}

void BM_Bodies(benchmark::State& state) {
    const int kind = static_cast<int>(state.range(0));
    static const char* names[] = {"spheres", "clump_12", "clump_36", "superquadric_e0.8",
                                  "superquadric_e0.3"};
    kiln::bench::time_scene(state, scene(kind), 2000, names[kind]);
}
BENCHMARK(BM_Bodies)->DenseRange(0, 4)->Unit(benchmark::kMillisecond)->MinTime(2.0);

} // namespace
