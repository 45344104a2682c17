// Fixed-work timing of the lattice scenes of bench_bodies.cpp and bench_polyhedra_scene.cpp, for
// A/B comparisons of two builds: the Google Benchmark binaries time as many steps as fit in their
// minimum time, so two builds of different speed time different parts of the collapsing lattice's
// transient (and different contact counts). Here both run the same steps: `warmup` untimed steps,
// then `steps` timed ones (process CPU time, s). Prints CPU time per step, contacts per particle,
// CPU time per contact (particle and wall contacts) and a checksum of the final positions (m,
// world frame), equal between builds that give the same bits, and last the wall-clock time per
// step (ms; the figure that threads shorten, where the CPU time sums over the threads).
//
// build/bench/kiln_scene_steps KIND WARMUP STEPS (KILN_PLANE_MEMO=0 in the environment: without
// the polyhedron pairs' memory; KILN_SCENE_THREADS=N: N threads, default 1), KIND: sphere, sq08,
// sq03 (superquadrics of e = 0.8, 0.3) or a shipped shape name (cube, icosahedron, cylinder_16,
// cylinder_12, ...).

#include "geometry/polyhedron_contact.hpp"
#include "geometry/superquadric.hpp"
#include "io/shape_reader.hpp"
#include "lattice_scene.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <optional>
#include <string>

namespace {

double cpu_seconds() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double wall_seconds() {
    timespec t{};
    clock_gettime(CLOCK_MONOTONIC, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

kiln::dynamics::SceneSpec scene(const std::string& kind) {
    if (kind == "sphere") {
        return kiln::bench::lattice_box_scene(std::nullopt, 3.3e-3); // bench_bodies kind 0
    }
    if (kind == "sq08" || kind == "sq03") {
        kiln::geometry::Superquadric q;
        q.half_axes = kiln::Vec3::Constant(3e-3);
        q.e1 = q.e2 = kind == "sq08" ? 0.8 : 0.3;
        return kiln::bench::lattice_box_scene(kiln::geometry::make_template("sq", q));
    }
    return kiln::bench::lattice_box_scene(
        kiln::io::read_shape_file(kiln::io::find_shape_file(kind, kiln::io::default_shape_dirs())));
}

} // namespace

int main(int argc, char** argv) {
    if (argc != 4) {
        std::fprintf(stderr, "usage: kiln_scene_steps KIND WARMUP STEPS\n");
        return 2;
    }
    const std::string kind = argv[1];
    const int warmup = std::atoi(argv[2]);
    const int steps = std::atoi(argv[3]);
    kiln::dynamics::SceneSpec spec = scene(kind);
    if (const char* threads = std::getenv("KILN_SCENE_THREADS"); threads != nullptr) {
        spec.threads = std::max(1, std::atoi(threads));
    }
    kiln::dynamics::System sys(spec);
    // KILN_PLANE_MEMO=0: without the polyhedron pairs' memory (same bits, for A/B in one binary).
    const char* memo_env = std::getenv("KILN_PLANE_MEMO");
    sys.use_plane_memo(memo_env == nullptr || std::string(memo_env) != "0");
    for (int k = 0; k < warmup; ++k) {
        sys.step();
    }
    // KILN_BOX_LANES=0: the timed steps take resting box pairs one at a time through
    // element_contact (from the same state as with them in lanes; other bits).
    const char* lanes_env = std::getenv("KILN_BOX_LANES");
    sys.use_box_lanes(lanes_env == nullptr || std::string(lanes_env) != "0");
    long contacts = 0;
    const double t0 = cpu_seconds();
    const double w0 = wall_seconds();
    for (int k = 0; k < steps; ++k) {
        sys.step();
        contacts += sys.counters().particle_contacts + sys.counters().wall_contacts;
    }
    const double t = cpu_seconds() - t0;
    const double w = wall_seconds() - w0;
    double checksum = 0.0;
    for (const kiln::Vec3& x : sys.particles().x) {
        checksum += x.x() + 2.0 * x.y() + 3.0 * x.z();
    }
    const double n = static_cast<double>(sys.particles().size());
    std::printf("%s cpu_ms_per_step %.4f contacts_per_particle %.4f cpu_ns_per_contact %.1f "
                "checksum %.17g wall_ms_per_step %.4f\n",
                kind.c_str(), 1e3 * t / steps, static_cast<double>(contacts) / (n * steps),
                contacts > 0 ? 1e9 * t / static_cast<double>(contacts) : 0.0, checksum,
                1e3 * w / steps);
    const auto& memo = kiln::geometry::plane_memo_counters();
    std::fprintf(stderr, "plane memo: %ld queries tried it, %ld answered, %ld refills\n",
                 memo.tried, memo.answered, memo.refills);
    std::fprintf(stderr, "element pairs queried %ld, proved apart by a cached direction %ld\n",
                 sys.narrow_phase_counters().calls, sys.separation_skips());
    std::fprintf(stderr, "box pairs in lanes %ld\n", sys.box_lane_pairs());
    return 0;
}
