// Validation 24: chain of three glass spheres with an imposed heat flow (seed V-6: Oschmann et al.
// 2016, Inv. V, L2073-2082, Fig. 11; seed notes lines 438-448 and 684). Q = 0.1569 W enters P1 at
// its outer pole and leaves P3 at its outer pole; P1-P2 and P2-P3 exchange heat by static contact
// conduction (Inv. V eq. 12, contact_conduction.hpp) as lagged per-patch heat rates. Three
// models: resolved with T_c = T_undist, resolved with T_c = T_mean, lumped.

#include "heat/contact_conduction.hpp"
#include "heat/lumped_model.hpp"
#include "heat/resolved_model.hpp"
#include "heat/spherical_grid.hpp"
#include "validation.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <gtest/gtest.h>
#include <memory>
#include <string>
#include <vector>

namespace kiln::validation {
namespace {

const heat::ThermalProperties glass{1.4, 2225.0, 835.0}; // seed Table 1, Inv. V (L1973)
constexpr double radius = 0.05;                          // m, d = 0.1 m
constexpr double overlap = 2.5e-3;                       // m
constexpr double heat_flow = 0.1569;                     // W, in at P1, out at P3
constexpr double t_initial = 398.15;                     // K
constexpr double dt = 0.1;                               // s (seed L1983)
constexpr double t_end = 6000.0;                         // s
constexpr double seed_p1 = 427.0;                        // K, read from Fig. 11a (text L2080)
constexpr double seed_p3 = 377.0;                        // K
const heat::SphericalResolution resolution{8, 16, 8};

/// Energy balance, relative to the heat supplied Q t: CHOLMOD solves to ~1e-15 relative and CG
/// stops at 1e-12 ||b|| with b ~ C T / dt, i.e. ~4e-7 J per step and particle against Q dt =
/// 1.6e-2 J; accumulated over 6e4 steps this stays below 1e-6 of Q t.
constexpr double balance_tolerance = 1e-6;
/// P2's mean temperature: the chain is antisymmetric about P2 and the grid is mirror-symmetric,
/// so P2 gains nothing; round-off only (K).
constexpr double p2_tolerance = 1e-6;
/// Lumped model against its exact discrete solution (lagged explicit contact, see below): a few
/// roundings per step over 6e4 steps (K).
constexpr double lumped_tolerance = 1e-9;

/// Resolved T_c = T_mean against the lumped model: identical recursions for the means, apart from
/// the solver's ~1e-12 relative error per step (K).
constexpr double mean_lumped_tolerance = 1e-6;
/// Steady state: the thermal step, the run length (8 lumped time constants C/H = 3.1e4 s) and
/// how far from steady the last tenth of the run may still move T1 - T2 (relative).
constexpr double dt_steady = 10.0; // s
constexpr double t_steady = 2.5e5; // s
constexpr double steady_tolerance = 1e-3;

enum class ContactTemperature { undisturbed, mean };

struct ChainResult {
    std::array<double, 3> mean{};   // volume-mean temperatures at t_end (K)
    std::array<double, 3> stored{}; // stored heat change (J)
    double supplied_p1 = 0.0;       // Q t + sum of contact heat into P1 (J)
    double q12 = 0.0;               // last contact heat rate P2 -> P1 (W)
    double seconds = 0.0;           // wall time (s)
    double t_undist_p1 = 0.0;       // P1's last contact temperature (K)
    double dt12_at_90 = 0.0;        // T1 - T2 (means) at 90 % of the run (K)
};

/// Body-frame contact data of one disc: point, outward normal.
struct Disc {
    Vec3 point;
    Vec3 normal;
};

ChainResult run_resolved(ContactTemperature mode, double step, double duration) {
    const auto grid =
        std::make_shared<const heat::ThermalGrid>(heat::make_spherical_grid(radius, resolution));
    const heat::SolverSettings solver{
        heat::cholmod_available() ? heat::SolverKind::cholmod : heat::SolverKind::cg, 1e-12, 2000};
    heat::ResolvedOperator op(grid, glass, step, {}, solver); // insulated apart from the contacts
    const double rc = heat::lens_contact_radius(overlap, radius, radius); // the seed's 1.11e-2 m
    const double h = heat::static_contact_conductance(glass.conductivity, glass.conductivity, rc);
    const Vec3 ez(0.0, 0.0, 1.0);
    // The chain lies along z; every body frame is the world frame. Contact points are at the
    // middle of the overlap, R - delta/2 from each centre.
    const double a = radius - 0.5 * overlap;
    const Disc p1_in{-radius * ez, -ez};
    const Disc p1_c{a * ez, ez};
    const Disc p2_lo{-a * ez, -ez};
    const Disc p2_hi{a * ez, ez};
    const Disc p3_c{-a * ez, -ez};
    const Disc p3_out{radius * ez, ez};
    auto patches = [&](const Disc& d) {
        return heat::contact_patches(*grid, d.point, d.normal, rc);
    };
    const std::vector<int> s1 = patches(p1_c);
    const std::vector<int> s2lo = patches(p2_lo);
    const std::vector<int> s2hi = patches(p2_hi);
    const std::vector<int> s3 = patches(p3_c);

    heat::TemperaturePool pool;
    for (int p = 0; p < 3; ++p) {
        (void)pool.add(grid->size(), t_initial);
    }
    std::array<double, 3> e0{};
    for (int p = 0; p < 3; ++p) {
        e0[p] = heat::stored_heat(op.cell_capacity(), pool.field(p));
    }
    const std::size_t nb = grid->boundary.size();
    std::array<std::vector<double>, 3> rate{std::vector<double>(nb), std::vector<double>(nb),
                                            std::vector<double>(nb)};
    auto contact_t = [&](int p, const std::vector<int>& s) {
        return mode == ContactTemperature::undisturbed
                   ? heat::undisturbed_temperature(*grid, resolution, pool.field(p), s)
                   : heat::mean_temperature(*grid, pool.field(p));
    };
    ChainResult r;
    const auto start = std::chrono::steady_clock::now();
    const int steps = static_cast<int>(std::lround(duration / step));
    for (int n = 0; n < steps; ++n) {
        // Lagged contact heat rates from the fields at t^n (seed notes §1.6: "= known").
        const double t1 = contact_t(0, s1);
        const double q12 = h * (contact_t(1, s2lo) - t1);               // into P1 (W)
        const double q23 = h * (contact_t(2, s3) - contact_t(1, s2hi)); // into P2 from P3 (W)
        for (auto& v : rate) {
            std::fill(v.begin(), v.end(), 0.0);
        }
        (void)heat::distribute_contact_heat(*grid, p1_in.point, p1_in.normal, rc, heat_flow,
                                            rate[0]);
        (void)heat::distribute_contact_heat(*grid, p1_c.point, p1_c.normal, rc, q12, rate[0]);
        (void)heat::distribute_contact_heat(*grid, p2_lo.point, p2_lo.normal, rc, -q12, rate[1]);
        (void)heat::distribute_contact_heat(*grid, p2_hi.point, p2_hi.normal, rc, q23, rate[1]);
        (void)heat::distribute_contact_heat(*grid, p3_c.point, p3_c.normal, rc, -q23, rate[2]);
        (void)heat::distribute_contact_heat(*grid, p3_out.point, p3_out.normal, rc, -heat_flow,
                                            rate[2]);
        for (int p = 0; p < 3; ++p) {
            heat::BoundaryLoad load;
            load.heat_rate = rate[static_cast<std::size_t>(p)];
            const heat::StepReport rep = op.step(pool.field(p), load);
            EXPECT_TRUE(rep.solve.converged);
        }
        r.supplied_p1 += step * (heat_flow + q12);
        r.q12 = q12;
        r.t_undist_p1 = t1;
        if (n == steps * 9 / 10) {
            r.dt12_at_90 = heat::mean_temperature(*grid, pool.field(0)) -
                           heat::mean_temperature(*grid, pool.field(1));
        }
    }
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    for (int p = 0; p < 3; ++p) {
        r.mean[p] = heat::mean_temperature(*grid, pool.field(p));
        r.stored[p] = heat::stored_heat(op.cell_capacity(), pool.field(p)) - e0[p];
    }
    return r;
}

/// Lumped chain with the same lagged contact coupling; returns the three temperatures at t_end.
std::array<double, 3> run_lumped(double h) {
    const double volume = 4.0 / 3.0 * 3.14159265358979323846 * radius * radius * radius;
    const double area = 4.0 * 3.14159265358979323846 * radius * radius;
    const heat::LumpedModel model(glass, volume, area);
    std::array<double, 3> t{t_initial, t_initial, t_initial};
    const int steps = static_cast<int>(std::lround(t_end / dt));
    for (int n = 0; n < steps; ++n) {
        const double q12 = h * (t[1] - t[0]);
        const double q23 = h * (t[2] - t[1]);
        t = {model.step(t[0], dt, 0.0, 0.0, 0.0, heat_flow + q12),
             model.step(t[1], dt, 0.0, 0.0, 0.0, q23 - q12),
             model.step(t[2], dt, 0.0, 0.0, 0.0, -q23 - heat_flow)};
    }
    return t;
}

TEST(Validation24, SphereChain) {
    reset_results();
    const double rc = heat::lens_contact_radius(overlap, radius, radius);
    const double h = heat::static_contact_conductance(glass.conductivity, glass.conductivity, rc);
    const double volume = 4.0 / 3.0 * 3.14159265358979323846 * radius * radius * radius;
    const double capacity = glass.density * glass.heat_capacity * volume; // J/K
    std::printf("r_c = %.5g m, H = %.5g W/K, C = %.5g J/K, C/H = %.5g s, lumped steady dT = "
                "%.4g K\n",
                rc, h, capacity, capacity / h, heat_flow / h);

    // Lumped: the antisymmetric mode x = T1 - T2 obeys x^{n+1} = x^n + dt (Q - H x^n) / C
    // (lagged contact, backward Euler with no implicit term), so x^n = (Q/H)(1 - (1 - H dt/C)^n).
    const std::array<double, 3> lumped = run_lumped(h);
    const int steps = static_cast<int>(std::lround(t_end / dt));
    const double x_exact = heat_flow / h * (1.0 - std::pow(1.0 - h * dt / capacity, steps));
    record("lumped T1 - T0 vs discrete exact", lumped[0] - t_initial, x_exact, lumped_tolerance,
           "K");
    EXPECT_NEAR(lumped[0] - t_initial, x_exact, lumped_tolerance);
    EXPECT_NEAR(lumped[1], t_initial, lumped_tolerance);
    EXPECT_NEAR(lumped[2] - t_initial, -x_exact, lumped_tolerance);

    // Energy bound: no model can raise P1's mean by more than Q t / C (all heat kept in P1).
    const double bound = heat_flow * t_end / capacity;
    record("upper bound Q t / C on T1 - T0", bound, seed_p1 - t_initial, 0.0, "K");
    // The seed's 427 K needs 29 K, about 30 times the bound: not reachable with its inputs.
    EXPECT_GT(seed_p1 - t_initial, 10.0 * bound);

    for (const ContactTemperature mode :
         {ContactTemperature::undisturbed, ContactTemperature::mean}) {
        const bool undist = mode == ContactTemperature::undisturbed;
        const std::string tag = undist ? "resolved T_undist" : "resolved T_mean";
        const ChainResult r = run_resolved(mode, dt, t_end);
        std::printf("%s: %.1f s wall, T = %.6f %.6f %.6f K, last q12 = %.5g W, T_c,1 = %.5f K\n",
                    tag.c_str(), r.seconds, r.mean[0], r.mean[1], r.mean[2], r.q12, r.t_undist_p1);
        const double supplied = heat_flow * t_end;
        const double closed = r.stored[0] + r.stored[1] + r.stored[2]; // in - out = 0
        record(tag + ": stored heat, whole chain", closed / supplied, 0.0, balance_tolerance,
               "of Q t");
        EXPECT_NEAR(closed / supplied, 0.0, balance_tolerance);
        record(tag + ": stored heat P1 vs supplied", r.stored[0] / r.supplied_p1, 1.0,
               balance_tolerance, "-");
        EXPECT_NEAR(r.stored[0] / r.supplied_p1, 1.0, balance_tolerance);
        record(tag + ": T2 - T0", r.mean[1] - t_initial, 0.0, p2_tolerance, "K");
        EXPECT_NEAR(r.mean[1], t_initial, p2_tolerance);
        EXPECT_LE(r.mean[0] - t_initial, bound);
        record(tag + ": T1 at 6000 s (seed 427 K)", r.mean[0], seed_p1, 0.0, "K");
        record(tag + ": T3 at 6000 s (seed 377 K)", r.mean[2], seed_p3, 0.0, "K");
        if (undist) {
            record(tag + ": T1 - T1,lumped", r.mean[0] - lumped[0], 0.0, 0.0, "K");
        } else {
            // With T_c = T_mean the contact rates depend on the means only, and the mean of the
            // resolved field obeys the lumped balance exactly: the two models coincide.
            record(tag + ": T1 - T1,lumped", r.mean[0] - lumped[0], 0.0, mean_lumped_tolerance,
                   "K");
            EXPECT_NEAR(r.mean[0], lumped[0], mean_lumped_tolerance);
        }
        record(tag + ": wall time", r.seconds, 0.0, 0.0, "s");
    }
}

TEST(Validation24, SteadyState) {
    // The seed's targets are called steady (Fig. 11); at 6000 s the chain is far from it (C/H =
    // 3.1e4 s), so the steady state is computed here with a larger thermal step. Lagged contact
    // rates stay stable at dt = 10 s (checked by the convergence below).
    const double rc = heat::lens_contact_radius(overlap, radius, radius);
    const double h = heat::static_contact_conductance(glass.conductivity, glass.conductivity, rc);
    const double lumped_steady = heat_flow / h; // T1 - T2 (K)
    for (const ContactTemperature mode :
         {ContactTemperature::undisturbed, ContactTemperature::mean}) {
        const bool undist = mode == ContactTemperature::undisturbed;
        const std::string tag = undist ? "steady, resolved T_undist" : "steady, resolved T_mean";
        const ChainResult r = run_resolved(mode, dt_steady, t_steady);
        const double d12 = r.mean[0] - r.mean[1];
        std::printf("%s: %.1f s wall, T = %.5f %.5f %.5f K, q12 = %.6g W\n", tag.c_str(), r.seconds,
                    r.mean[0], r.mean[1], r.mean[2], r.q12);
        record(tag + ": T1 - T2 drift over last 10 %", (d12 - r.dt12_at_90) / d12, 0.0,
               steady_tolerance, "-");
        EXPECT_LT(std::abs(d12 - r.dt12_at_90), steady_tolerance * std::abs(d12));
        record(tag + ": contact rate / Q", -r.q12 / heat_flow, 1.0, steady_tolerance, "-");
        EXPECT_NEAR(-r.q12 / heat_flow, 1.0, steady_tolerance);
        record(tag + ": T1 - T2 (seed ~29 K resolved, lumped 5.04 K)", d12, lumped_steady, 0.0,
               "K");
        if (!undist) {
            EXPECT_NEAR(d12, lumped_steady, steady_tolerance * lumped_steady);
        }
    }
}

} // namespace
} // namespace kiln::validation
