// Validation 04: energy conservation of elastic, frictionless spheres in a closed box, and the
// order at which the energy error shrinks with the time step (velocity Verlet is second order).

#include "dynamics/system.hpp"
#include "validation.hpp"

#include <cmath>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <random>
#include <vector>

namespace kiln::validation {
namespace {

/// Observed order of the energy error per halving of dt must be at least this: velocity Verlet is
/// second order for smooth forces; the Hertz force's unbounded second derivative at contact onset
/// (F ~ delta^1.5) may cost a little, so 1.8 rather than 2.
constexpr double min_order = 1.8;
/// Largest relative energy error at the finest step (dt/4, ~60 steps per contact); second-order
/// error (dt/t_c)^2 ~ 3e-4 per contact event, which averages out over the many contacts of the run.
constexpr double finest_bound = 1e-4;

struct Run {
    double dt;
    double max_rel_error;
    long contacts;
};

Run run(io::CaseSpec spec, double dt) {
    spec.scene.time_step = dt;
    dynamics::System sys(spec.scene);
    // Random velocities up to 1 m/s and spins up to 300 rad/s, the same for every dt.
    std::mt19937_64 rng(99);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    auto& p = sys.particles();
    for (std::size_t i = 0; i < p.size(); ++i) {
        p.v[i] = Vec3(u(rng), u(rng), u(rng)) / std::sqrt(3.0);
        p.omega[i] = 300.0 * Vec3(u(rng), u(rng), u(rng));
    }
    sys.refresh();
    const double e0 = sys.energies().total();
    double worst = 0.0;
    long contacts = 0;
    const long steps = std::lround(spec.run.end_time / dt);
    for (long s = 0; s < steps; ++s) {
        sys.step();
        worst = std::max(worst, std::abs(sys.energies().total() - e0) / e0);
        contacts += sys.counters().particle_contacts + sys.counters().wall_contacts;
    }
    return {dt, worst, contacts};
}

void check_law(io::CaseSpec spec, const std::string& label) {
    const double dt = spec.scene.time_step;
    std::vector<Run> runs;
    for (const double f : {1.0, 0.5, 0.25, 0.125}) {
        runs.push_back(run(spec, dt * f));
        ASSERT_GT(runs.back().contacts, 0) << "no collisions: the case tests nothing";
    }
    for (std::size_t k = 0; k < runs.size(); ++k) {
        record(fmt::format("{} max rel. energy error, dt = {:g} s", label, runs[k].dt),
               runs[k].max_rel_error, 0.0, k + 1 == runs.size() ? finest_bound : 0.0, "-");
    }
    // Least-squares slope of log(error) against log(dt) over the four steps: single halvings are
    // noisy because the trajectories (a chaotic many-body system) differ between step sizes.
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    const double n = static_cast<double>(runs.size());
    for (const Run& r : runs) {
        const double x = std::log(r.dt);
        const double y = std::log(r.max_rel_error);
        sx += x;
        sy += y;
        sxx += x * x;
        sxy += x * y;
    }
    const double order = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    record(label + " observed order (fit over dt..dt/8)", order, 2.0, min_order, "-");
    EXPECT_GE(order, min_order) << label;
    EXPECT_LT(runs.back().max_rel_error, finest_bound) << label;
}

TEST(Energy, HertzMindlinErrorShrinksAtSecondOrder) {
    reset_results();
    check_law(load_case(), "hertz");
}

TEST(Energy, LinearSpringErrorShrinksAtSecondOrder) {
    io::CaseSpec spec = load_case();
    // Stiffness with a contact time close to the Hertz one at 1 m/s: t = pi sqrt(m*/k), m* ~ 5e-6
    // kg.
    spec.scene.contact.law = contact::LinearSpringDashpot{2000.0, 2.0 / 7.0};
    spec.scene.contact.clamp_normal_force = false;
    check_law(spec, "linear");
}

} // namespace
} // namespace kiln::validation
