// Whole-scene cost of non-spherical particles: the same scene (a lattice of 343 particles of about
// 6 mm, collapsing under gravity into a box) with spheres, 12- and 36-sphere clumps of the seed's
// 6 x 6 mm cylinder, and superquadrics of low (e = 0.8) and high (e = 0.3) blockiness. Reports
// particle-steps per second and wall time per element contact (ns). One thread; rates are per
// wall-clock second, so a busy host lowers them.

#include "dynamics/system.hpp"
#include "geometry/superquadric.hpp"
#include "io/shape_reader.hpp"

#include <benchmark/benchmark.h>
#include <chrono>
#include <string>

namespace {

using kiln::Vec3;
using namespace kiln::dynamics;

/// kind: 0 spheres, 1 cylinder_12, 2 cylinder_36, 3 superquadric e = 0.8, 4 e = 0.3.
SceneSpec scene(int kind) {
    SceneSpec s;
    s.materials.push_back({"pom", 5e7, 0.35, 1380, 0.5, 0.3, 0.0});
    s.time_step = 5e-6;
    s.threads = 1;
    InsertSpec ins;
    ins.kind = InsertSpec::Kind::lattice;
    ins.count = 343;
    ins.velocity = Vec3(0, 0, -0.2);
    ins.orientation.random = true;
    if (kind == 0) {
        ins.size.radius = 3.3e-3; // volume of the 6 x 6 mm cylinder
    } else if (kind <= 2) {
        const auto name = kind == 1 ? "cylinder_12" : "cylinder_36";
        s.shapes.push_back(kiln::io::read_shape_file(
            kiln::io::find_shape_file(name, kiln::io::default_shape_dirs())));
    } else {
        kiln::geometry::Superquadric q;
        q.half_axes = Vec3::Constant(3e-3);
        q.e1 = q.e2 = kind == 3 ? 0.8 : 0.3;
        s.shapes.push_back(kiln::geometry::make_template("sq", q));
    }
    if (kind > 0) {
        ins.shape = 0;
        ins.size.radius = s.shapes[0].bounding_radius();
    }
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

void BM_Bodies(benchmark::State& state) {
    const int kind = static_cast<int>(state.range(0));
    System sys(scene(kind));
    for (int k = 0; k < 2000; ++k) { // collapse into a bed before timing
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
    static const char* names[] = {"spheres", "clump_12", "clump_36", "superquadric_e0.8",
                                  "superquadric_e0.3"};
    state.SetLabel(names[kind]);
}
BENCHMARK(BM_Bodies)->DenseRange(0, 4)->Unit(benchmark::kMillisecond)->MinTime(2.0);

} // namespace
