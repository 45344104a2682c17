// Settled-bed and pour harness of docs/performance.md for the sphere step loop, timed in CPU time
// (robust on a shared host). Scene: bench/liggghts/in.pour_spheres (r = 2 mm, 2500 kg/m^3,
// E = 5 MPa, nu = 0.45, e = 0.3, mu = 0.5, 0.1 x 0.1 x 0.2 m box, dt = 1e-5 s, one thread).
// usage: kiln_settled N [settle_steps=40000] [chunks=5] [chunk_steps=1000]
// Prints the pour's CPU time, a hash of positions, velocities and spins (world frame) after the
// settling steps (bit-identity checks of the step loop), then ns per particle-step of each timed
// chunk of the settled bed, best and median. The steps go through System::advance (the fused pass
// of the integrator; the same bits as a loop of step()).

#include "dynamics/system.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <vector>

namespace {

using kiln::Vec3;
using namespace kiln::dynamics;

double cpu_seconds() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

SceneSpec pour(long n) {
    SceneSpec s;
    s.materials.push_back({"glass", 5e6, 0.45, 2500, 0.3, 0.5, 0.0});
    s.time_step = 1e-5;
    s.skin = 1e-3;
    s.threads = 1;
    const Vec3 lo(-0.05, -0.05, 0.0);
    const Vec3 hi(0.05, 0.05, 0.2);
    for (int a = 0; a < 3; ++a) {
        s.walls.push_back({"lo", PlaneWall{lo, Vec3::Unit(a)}, 0});
        s.walls.push_back({"hi", PlaneWall{hi, -Vec3::Unit(a)}, 0});
    }
    InsertSpec ins;
    ins.region = {Vec3(-0.048, -0.048, 0.01), Vec3(0.048, 0.048, 0.19)};
    ins.count = n;
    ins.size.radius = 0.002;
    ins.velocity = Vec3(0, 0, -0.5);
    s.inserts.push_back(ins);
    return s;
}

// FNV-1a over the bits of x, v and omega of every particle.
std::uint64_t state_hash(const System& sys) {
    std::uint64_t h = 1469598103934665603ULL;
    const auto& p = sys.particles();
    for (const auto* field : {&p.x, &p.v, &p.omega}) {
        for (const Vec3& a : *field) {
            for (int q = 0; q < 3; ++q) {
                std::uint64_t b = 0;
                std::memcpy(&b, &a[q], sizeof b);
                h = (h ^ b) * 1099511628211ULL;
            }
        }
    }
    return h;
}

} // namespace

int main(int argc, char** argv) {
    const long n = argc > 1 ? std::atol(argv[1]) : 5000;
    const long settle = argc > 2 ? std::atol(argv[2]) : 40000;
    const int chunks = argc > 3 ? std::atoi(argv[3]) : 5;
    const long chunk_steps = argc > 4 ? std::atol(argv[4]) : 1000;
    System sys(pour(n));
    const double t0 = cpu_seconds();
    sys.advance(settle);
    const double t1 = cpu_seconds();
    std::printf("N %ld: %ld steps in %.3f s CPU (%.2f ns per particle-step), hash %016llx, "
                "contacts per particle %.3f\n",
                n, settle, t1 - t0, 1e9 * (t1 - t0) / static_cast<double>(n * settle),
                static_cast<unsigned long long>(state_hash(sys)),
                static_cast<double>(sys.counters().particle_contacts) / static_cast<double>(n));
    std::vector<double> ns;
    for (int c = 0; c < chunks; ++c) {
        const double a = cpu_seconds();
        sys.advance(chunk_steps);
        ns.push_back(1e9 * (cpu_seconds() - a) / static_cast<double>(n * chunk_steps));
    }
    std::sort(ns.begin(), ns.end());
    std::printf("settled: best %.2f, median %.2f ns per particle-step (%d chunks of %ld steps)\n",
                ns.front(), ns[ns.size() / 2], chunks, chunk_steps);
    return 0;
}
