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
//
// KILN_SCENE_FREE=1: the contact-free variant of the scene (free_scene below), whose step is the
// per-particle work alone: the floor under any step of that shape.
//
// KILN_AB=SWITCH: an A/B of one of System's switches (memo, separation and member_lanes keep the
// bits; box_lanes and convex_blocks change them at round-off, so their two runs part) inside one
// process, which a shared host's noise cannot tilt: two systems from the same start, the second
// with the switch off from the start, step in alternate chunks of 50 steps after the warm-up;
// prints the CPU time per step of each, their ratio (on / off) and whether the final positions
// are the same bits (exit status 1 if not). Runs of one binary against another drifted with the
// host's load by 10-40 % within minutes in session 33; two runs of this ratio in the same spell
// agreed to 3.5 % (separation on cubes: 0.521 and 0.539). A change under test can be given a
// switch of its own for the A/B and the switch removed after it.

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

/// The lattice scene of `kind`, its lattice spaced by `spacing` bounding diameters.
kiln::dynamics::SceneSpec scene(const std::string& kind, double spacing) {
    if (kind == "sphere") {
        return kiln::bench::lattice_box_scene(std::nullopt, 3.3e-3, spacing); // bench_bodies 0
    }
    if (kind == "sq08" || kind == "sq03") {
        kiln::geometry::Superquadric q;
        q.half_axes = kiln::Vec3::Constant(3e-3);
        q.e1 = q.e2 = kind == "sq08" ? 0.8 : 0.3;
        return kiln::bench::lattice_box_scene(kiln::geometry::make_template("sq", q), 0.0, spacing);
    }
    return kiln::bench::lattice_box_scene(
        kiln::io::read_shape_file(kiln::io::find_shape_file(kind, kiln::io::default_shape_dirs())),
        0.0, spacing);
}

/// The contact-free variant (KILN_SCENE_FREE=1): the same particles, walls and step, with the
/// lattice spaced by 1.5 bounding diameters, no gravity and no translation, every particle
/// spinning at 40 rad/s about a fixed world axis from its random orientation. Nothing touches
/// and no pair comes within its bounding spheres, so a step is the per-particle work alone
/// (kicks, drift, the rotation, the walls' tests, the neighbour list's entries): the least any
/// step of that shape costs, whatever its contacts cost.
kiln::dynamics::SceneSpec free_scene(const std::string& kind) {
    kiln::dynamics::SceneSpec spec = scene(kind, 1.5);
    spec.gravity = kiln::Vec3::Zero();
    for (auto& ins : spec.inserts) {
        ins.velocity = kiln::Vec3::Zero();
        ins.omega = kiln::Vec3(24.0, 24.0, 21.0); // |omega| = 40.0 rad/s (world)
    }
    return spec;
}

/// Turns switch `name` of `sys` on or off; false for an unknown name.
bool set_switch(kiln::dynamics::System& sys, const std::string& name, bool on) {
    if (name == "memo") {
        sys.use_plane_memo(on);
    } else if (name == "box_lanes") {
        sys.use_box_lanes(on);
    } else if (name == "member_lanes") {
        sys.use_member_lanes(on);
    } else if (name == "separation") {
        sys.use_separation_cache(on);
    } else if (name == "box_filter") {
        sys.use_box_filter(on);
    } else if (name == "convex_blocks") {
        sys.use_convex_blocks(on);
    } else {
        return false;
    }
    return true;
}

/// The KILN_AB mode (see the top of the file): `on` has run the warm-up with the switch on.
int ab_switch(const std::string& kind, const kiln::dynamics::SceneSpec& spec,
              kiln::dynamics::System& on, const std::string& name, int warmup, int steps) {
    kiln::dynamics::System off(spec);
    if (!set_switch(off, name, false) || !set_switch(on, name, true)) {
        std::fprintf(stderr, "KILN_AB: unknown switch %s\n", name.c_str());
        return 2;
    }
    // The warm-up of `off` with the switch off too: its state is the same bits if the switch
    // keeps them (checked at the end).
    for (int k = 0; k < warmup; ++k) {
        off.step();
    }
    constexpr int chunk = 50;
    double t_on = 0.0;
    double t_off = 0.0;
    for (int k = 0; k < steps; k += chunk) {
        const int n = std::min(chunk, steps - k);
        const double c0 = cpu_seconds();
        for (int i = 0; i < n; ++i) {
            on.step();
        }
        const double c1 = cpu_seconds();
        for (int i = 0; i < n; ++i) {
            off.step();
        }
        t_on += c1 - c0;
        t_off += cpu_seconds() - c1;
    }
    bool same = on.particles().size() == off.particles().size();
    for (std::size_t i = 0; same && i < on.particles().size(); ++i) {
        same = on.particles().x[i] == off.particles().x[i];
    }
    std::printf("%s ab %s on_us_per_step %.2f off_us_per_step %.2f on_over_off %.4f same_bits %s\n",
                kind.c_str(), name.c_str(), 1e6 * t_on / steps, 1e6 * t_off / steps, t_on / t_off,
                same ? "yes" : "no");
    return same ? 0 : 1;
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
    const char* free_env = std::getenv("KILN_SCENE_FREE");
    const bool free = free_env != nullptr && std::string(free_env) == "1";
    kiln::dynamics::SceneSpec spec = free ? free_scene(kind) : scene(kind, 1.02);
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
    if (const char* ab = std::getenv("KILN_AB"); ab != nullptr) {
        return ab_switch(kind, spec, sys, ab, warmup, steps);
    }
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
    std::fprintf(stderr,
                 "plane memo: %ld queries tried it, %ld answered (%ld certified by the overlap "
                 "held), %ld refills\n",
                 memo.tried, memo.answered, memo.held, memo.refills);
    std::fprintf(stderr, "element pairs queried %ld, proved apart by a cached direction %ld\n",
                 sys.narrow_phase_counters().calls, sys.separation_skips());
    std::fprintf(stderr, "box pairs in lanes %ld\n", sys.box_lane_pairs());
    std::fprintf(stderr,
                 "member builds %ld (list builds %ld), entries left out by the box test %ld\n",
                 sys.member_builds(), sys.neighbour_builds(), sys.box_filter_drops());
    return 0;
}
