#pragma once
// The closed-box energy study shared by validations 04 (spheres) and 14 (clumps and
// superquadrics): elastic, frictionless particles with random velocities and spins, the largest
// relative deviation of the total energy over a run, and the observed order of that error in dt.

#include "dynamics/system.hpp"
#include "io/case_spec.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace kiln::validation {

/// Least-squares slope of log(y) against log(x).
inline double log_slope(const std::vector<double>& x, const std::vector<double>& y) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    const auto n = static_cast<double>(x.size());
    for (std::size_t k = 0; k < x.size(); ++k) {
        const double lx = std::log(x[k]);
        const double ly = std::log(y[k]);
        sx += lx;
        sy += ly;
        sxx += lx * lx;
        sxy += lx * ly;
    }
    return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

/// How the particles of a box run are set in motion (the same for every dt of a study).
struct BoxStart {
    std::uint64_t rng_base = 1000; ///< seed of realisation r is rng_base + r
    double spin = 300.0;           ///< spin components uniform in [-spin, spin] rad/s (world frame)
    bool bodies = false;           ///< also set the world angular momentum R I R^T w (rigid bodies)
};

/// One box run: the largest relative deviation of the total energy, the contact-steps seen
/// (particle and wall contacts summed over steps) and the narrow phase's failures.
struct BoxRun {
    double max_error = 0;
    long contact_steps = 0;
    long failures = 0;
};

/// Runs the box of `spec` at step dt with insertion seed and velocities of realisation r:
/// velocity components up to 1/sqrt(3) m/s, spins as `start` says, until the case's end time.
inline BoxRun box_run(io::CaseSpec spec, double dt, int r, const BoxStart& start) {
    spec.scene.time_step = dt;
    spec.scene.seed += static_cast<std::uint64_t>(r);
    dynamics::System sys(spec.scene);
    std::mt19937_64 rng(start.rng_base + static_cast<std::uint64_t>(r));
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    auto& p = sys.particles();
    for (std::size_t i = 0; i < p.size(); ++i) {
        p.v[i] = Vec3(u(rng), u(rng), u(rng)) / std::sqrt(3.0);
        const Vec3 w = start.spin * Vec3(u(rng), u(rng), u(rng));
        p.omega[i] = w;
        if (start.bodies) {
            const Mat3 rot = p.q[i].toRotationMatrix();
            p.ang_mom[i] = rot * (p.inertia[i].asDiagonal() * (rot.transpose() * w));
        }
    }
    sys.refresh();
    const double e0 = sys.energies().total();
    BoxRun out;
    const long steps = std::lround(spec.run.end_time / dt);
    for (long s = 0; s < steps; ++s) {
        sys.step();
        out.max_error = std::max(out.max_error, std::abs(sys.energies().total() - e0) / e0);
        out.contact_steps += sys.counters().particle_contacts + sys.counters().wall_contacts;
    }
    out.failures = sys.narrow_phase_counters().failures;
    return out;
}

} // namespace kiln::validation
