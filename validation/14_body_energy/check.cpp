// Validation 14: elastic, frictionless clumps and superquadrics in a closed box conserve the total
// energy (translational + rotational + elastic) with an error that shrinks with the time step at
// the order of velocity Verlet with the symmetric rotation splitting (2). See README.md.

#include "dynamics/system.hpp"
#include "energy_box.hpp"
#include "validation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <string>
#include <vector>

namespace kiln::validation {
namespace {

/// Least observed order (fit over dt..dt/4): second-order scheme; four chaotic realisations per
/// step size scatter the fitted slope by about 0.2 (validation 04 measured 0.06 with twelve).
constexpr double min_order = 1.7;
/// Least observed order of superquadrics with Hertz and R* frozen at first touch. The force is
/// conservative, but the narrow phase's stalled Newton searches (a few per thousand queries, more
/// at smaller dt) fall back to an upper bound of the MTD, a residual that does not shrink at second
/// order: the linear law on the same case measures 1.73 over dt..dt/4 and 1.64 with dt/8 added,
/// first_touch 1.62 and 1.56 (README).
constexpr double min_order_first_touch = 1.5;
/// Largest relative energy error of a conservative run at dt/4: contact-onset residues and spring
/// excursions of 16-24 bodies (validation 04 allows 1e-4 for 300 spheres at dt/8).
constexpr double finest_bound = 1e-3;
/// Independent runs (insertion seed and velocities) per step size.
constexpr int realisations = 4;
/// Step sizes relative to the case's time step.
constexpr std::array<double, 3> step_factors{1.0, 0.5, 0.25};

/// Velocities, spins up to 100 rad/s and the matching angular momenta; seed 2000 + r.
constexpr BoxStart start{2000, 100.0, true};

/// Runs the step-size study; returns the observed order. `strict`: assert `least_order` (unless
/// `check_order` is false) and the bound at dt/4.
double check_box(const io::CaseSpec& spec, const std::string& label, bool strict,
                 double least_order = min_order, bool check_order = true) {
    std::vector<double> dts;
    std::vector<double> mean_error;
    double finest_worst = 0.0;
    for (const double f : step_factors) {
        const double dt = spec.scene.time_step * f;
        double sum = 0.0;
        double hi = 0.0;
        for (int r = 0; r < realisations; ++r) {
            const BoxRun b = box_run(spec, dt, r, start);
            EXPECT_GT(b.contact_steps, 0) << "no collisions: the case tests nothing";
            EXPECT_EQ(b.failures, 0) << label;
            sum += b.max_error;
            hi = std::max(hi, b.max_error);
        }
        dts.push_back(dt);
        mean_error.push_back(sum / realisations);
        finest_worst = hi;
        record(fmt::format("{} max rel. energy error (mean of runs) at dt = {:g} s", label, dt),
               mean_error.back(), 0.0, 0.0, "-");
        record(fmt::format("{} max rel. energy error (worst run) at dt = {:g} s", label, dt), hi,
               0.0, strict && f == step_factors.back() ? finest_bound : 0.0, "-");
    }
    const double order = log_slope(dts, mean_error);
    record(label + " observed order (fit over dt..dt/4)", order, 2.0,
           strict && check_order ? 2.0 - least_order : 0, "-");
    if (strict && check_order) {
        EXPECT_GE(order, least_order) << label;
    }
    if (strict) {
        EXPECT_LT(finest_worst, finest_bound) << label;
    }
    return order;
}

io::CaseSpec with_law(io::CaseSpec spec, bool hertz) {
    if (hertz) {
        spec.scene.contact.law = contact::HertzMindlin{};
    } else {
        spec.scene.contact.law = contact::LinearSpringDashpot{2000.0, 2.0 / 7.0};
        spec.scene.contact.clamp_normal_force = false;
    }
    return spec;
}

TEST(BodyEnergy, ClumpsConserveEnergyAtSecondOrder) {
    reset_results();
    check_box(with_law(load_case("case_clumps.toml"), true), "clumps hertz", true);
    check_box(with_law(load_case("case_clumps.toml"), false), "clumps linear", true);
}

TEST(BodyEnergy, SuperquadricsConserveEnergyAtSecondOrderWithTheLinearLaw) {
    check_box(with_law(load_case("case_superquadrics.toml"), false), "superquadrics linear", true);
}

TEST(BodyEnergy, CubesWithSuperquadricsKeepTheEnergyErrorBounded) {
    // Polyhedron-superquadric pairs (libccd's EPA, the refined normal; a pair touching at the
    // last step refined from its last normal) beside cube pairs and superquadric pairs, linear
    // law. The worst error at dt/4 is bounded as for the other bodies; the order is recorded, not
    // asserted: cubes alone in the same box measure 0.7 (README, "Cubes with superquadrics").
    // With the contact point of a polyhedron-superquadric pair midway between the two supports
    // (before session 20) the error was 1 % at every dt.
    check_box(with_law(load_case("case_cubes_superquadrics.toml"), false),
              "cubes and superquadrics linear", true, min_order, false);
}

io::CaseSpec with_radius(io::CaseSpec spec, dynamics::BodyRadius r) {
    spec.scene.body_radius = r;
    return spec;
}

TEST(BodyEnergy, SuperquadricsWithHertzFirstTouchConserveEnergyAtSecondOrder) {
    // R* frozen at the first step of each contact (the default): the Hertz force of a contact is
    // the gradient of 8/15 E* sqrt(R*) delta^(5/2), so the error is the integrator's (README).
    check_box(with_radius(with_law(load_case("case_superquadrics.toml"), true),
                          dynamics::BodyRadius::first_touch),
              "superquadrics hertz first_touch", true, min_order_first_touch);
}

TEST(BodyEnergy, SuperquadricsWithHertzPerStepAreRecorded) {
    // R* follows the local curvature, which changes along a contact: the Hertz force is then not
    // the gradient of a potential and energy is conserved only up to that model error (README).
    check_box(with_radius(with_law(load_case("case_superquadrics.toml"), true),
                          dynamics::BodyRadius::per_step),
              "superquadrics hertz per_step", false);
}

} // namespace
} // namespace kiln::validation
