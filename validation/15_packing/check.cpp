// Validation 15: solid fraction of random packings of spheroids and superballs poured under
// gravity, against Donev et al. 2004 (ellipsoids) and Delaney & Cleary 2010 (superballs). See
// README.md.

#include "dynamics/system.hpp"
#include "geometry/shape.hpp"
#include "validation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fmt/format.h>
#include <fstream>
#include <future>
#include <gtest/gtest.h>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace kiln::validation {
namespace {

/// Distance of the measuring region from the side walls and the floor (m): 1.25 particle widths,
/// where the wall's layering of the packing has decayed to a few per cent.
constexpr double wall_margin = 2.5e-3;
/// Distance of the measuring region below the highest particle centre (m).
constexpr double top_margin = 3.0e-3;
/// Sample points in the measuring region: statistical error sqrt(phi (1 - phi) / N) = 0.002.
constexpr int samples = 60000;
/// Allowed deviation of the rise over spheres from the reference rise: the references are
/// frictionless compressed (Donev) or expanded (Delaney & Cleary) packings, this is a damped pour
/// of 400 particles in a 14 mm box; both are read from figures (+-0.01).
constexpr double rise_tolerance = 0.03;
/// Band of random packings of frictionless spheres: random loose to random close packing
/// (Onoda & Liniger 1990; Scott & Kilgour 1969).
constexpr double sphere_low = 0.60;
constexpr double sphere_high = 0.655;
/// Settled: kinetic energy per particle below this fraction of m g d (weight times a diameter).
constexpr double settled = 1e-3;
/// A pour that is not yet settled at the case's end time (0.5 s) runs on in slices of this length
/// (s) until it is, up to max_pour_time: the criterion is rest, not a fixed time (a blocky pour
/// can still creep at 0.5 s; README, "Settling").
constexpr double settle_slice = 0.05;
constexpr double max_pour_time = 1.0;

/// The case with this insert: a template name, or "sphere" for 1 mm spheres; `seed` replaces the
/// case's random seed (insertion positions and orientations) when it is not 0.
io::CaseSpec case_for(const std::string& shape, long seed = 0) {
    const std::string file = std::string(KILN_CASE_DIR) + "/case.toml";
    std::ifstream in(file);
    std::stringstream ss;
    ss << in.rdbuf();
    std::string text = ss.str();
    const std::string key = "shape = \"prolate_15\"";
    const auto at = text.find(key);
    EXPECT_NE(at, std::string::npos);
    text.replace(at, key.size(),
                 shape == "sphere" ? "radius = 1.0e-3" : "shape = \"" + shape + "\"");
    if (seed != 0) {
        const std::string old_seed = "seed = 15";
        text.replace(text.find(old_seed), old_seed.size(), fmt::format("seed = {}", seed));
    }
    if (shape == "prolate_20") {
        // Random placement fills at most ~0.3 of the region with bounding spheres (radius 2 mm):
        // 300 of these still give a bed about 19 mm deep.
        const std::string count = "count = 400";
        text.replace(text.find(count), count.size(), "count = 300");
    }
    return io::read_case_text(text, file);
}

struct Packing {
    double phi = 0;
    double kinetic_per_weight = 0;
    /// Simulated time at which the pour was stopped (s): the case's end time, or later when it was
    /// not yet at rest then.
    double time = 0;
    long failures = 0;
    /// Cubic order of the orientations against the box axes in the measuring region (see
    /// cubic_order); 0 for spheres.
    double order = 0;
    /// Spheres only: mean local bond order q6 of the spheres in the measuring region (see
    /// local_q6); 0 for other shapes.
    double q6 = 0;
};

/// Cubic orientational order of a body against the box axes: S = (5 sum_kl R_kl^4 - 9) / 6 for its
/// rotation matrix R (body to world). Invariant under the 24 rotations of the cube, so it suits
/// superballs: S = 1 when the body's axes lie along the box axes, and its mean is 0 over uniformly
/// random orientations (a component of a random unit vector has <u^4> = 1/5, so <sum R_kl^4> =
/// 9/5). The flat floor and walls of a pour of near-cubes template such alignment.
double cubic_order(const Quat& q) {
    const Eigen::Matrix3d r = q.toRotationMatrix();
    return (5.0 * r.array().pow(4).sum() - 9.0) / 6.0;
}

/// Local bond-orientational order q6 of a particle whose bonds to its neighbours are `bonds`
/// (Steinhardt, Nelson & Ronchetti 1983, PRB 28, 784): q6 = sqrt(4 pi / 13 sum_m |q6m|^2), with
/// q6m the mean of Y6m over the bond directions. A perfect fcc shell of 12 gives 0.575, hcp 0.485;
/// disordered dense packings of spheres give about 0.35-0.45, so a high mean flags order against
/// the walls (the box is 7 diameters wide).
double local_q6(const std::vector<Vec3>& bonds) {
    if (bonds.empty()) {
        return 0.0;
    }
    double sum = 0.0;
    for (int m = 0; m <= 6; ++m) {
        double re = 0.0;
        double im = 0.0;
        for (const Vec3& b : bonds) {
            const double theta = std::acos(std::clamp(b.z() / b.norm(), -1.0, 1.0));
            const double phi = std::atan2(b.y(), b.x());
            const double y = std::sph_legendre(6, static_cast<unsigned>(m), theta);
            re += y * std::cos(m * phi);
            im += y * std::sin(m * phi);
        }
        const double n = static_cast<double>(bonds.size());
        // |q6,-m| = |q6m| for real bonds, so the m > 0 terms count twice.
        sum += (m == 0 ? 1.0 : 2.0) * (re * re + im * im) / (n * n);
    }
    return std::sqrt(4.0 * M_PI / 13.0 * sum);
}

/// Neighbours of a sphere for q6: centres closer than this multiple of the sum of the radii,
/// inside the first minimum of the pair distribution of dense random packings (about 1.3).
constexpr double q6_cutoff = 1.2;

/// True when the world point p is inside particle i.
bool inside(const dynamics::System& sys, std::size_t i, const Vec3& p) {
    const ParticleStore& s = sys.particles();
    const Vec3 d = p - s.x[i];
    if (d.squaredNorm() >= s.radius[i] * s.radius[i]) {
        return false;
    }
    if (s.shape[i] < 0) {
        return true;
    }
    const auto& t = sys.spec().shapes[static_cast<std::size_t>(s.shape[i])];
    return std::get<geometry::Superquadric>(t.shape).inside_outside(s.q[i].conjugate() * d) < 0.0;
}

Packing pour(const std::string& shape, long seed = 0) {
    const io::CaseSpec spec = case_for(shape, seed);
    dynamics::System sys(spec.scene);
    const auto run_for = [&](double duration) {
        const long steps = std::lround(duration / spec.scene.time_step);
        for (long k = 0; k < steps; ++k) {
            sys.step();
        }
    };
    const ParticleStore& p = sys.particles();
    const auto kinetic_per_weight = [&] {
        double weight = 0.0;
        for (std::size_t i = 0; i < p.size(); ++i) {
            weight += p.mass[i] * 9.81 * 2e-3;
        }
        return sys.energies().kinetic / weight;
    };
    Packing out;
    run_for(spec.run.end_time);
    out.time = spec.run.end_time;
    while (kinetic_per_weight() >= settled && out.time + 0.5 * settle_slice < max_pour_time) {
        run_for(settle_slice);
        out.time += settle_slice;
    }
    double top = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        top = std::max(top, p.x[i].z());
    }
    out.kinetic_per_weight = kinetic_per_weight();
    out.failures = sys.narrow_phase_counters().failures;
    const Vec3 lo(wall_margin, wall_margin, wall_margin);
    const Vec3 hi(0.014 - wall_margin, 0.014 - wall_margin, top - top_margin);
    EXPECT_GT(hi.z() - lo.z(), 5e-3) << shape << ": bed too shallow to measure";
    std::mt19937_64 rng(15);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    long hits = 0;
    for (int k = 0; k < samples; ++k) {
        const Vec3 x = lo + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(hi - lo);
        for (std::size_t i = 0; i < p.size(); ++i) {
            if (inside(sys, i, x)) {
                ++hits;
                break;
            }
        }
    }
    out.phi = static_cast<double>(hits) / samples;
    if (shape != "sphere") {
        long n = 0;
        for (std::size_t i = 0; i < p.size(); ++i) {
            const bool in_region =
                (p.x[i].array() > lo.array()).all() && (p.x[i].array() < hi.array()).all();
            if (in_region) {
                out.order += cubic_order(p.q[i]);
                ++n;
            }
        }
        out.order /= static_cast<double>(std::max(n, 1L));
    } else {
        long n = 0;
        for (std::size_t i = 0; i < p.size(); ++i) {
            if ((p.x[i].array() <= lo.array()).any() || (p.x[i].array() >= hi.array()).any()) {
                continue;
            }
            std::vector<Vec3> bonds;
            for (std::size_t j = 0; j < p.size(); ++j) {
                const Vec3 b = p.x[j] - p.x[i];
                const double reach = q6_cutoff * (p.radius[i] + p.radius[j]);
                if (j != i && b.squaredNorm() < reach * reach) {
                    bonds.push_back(b);
                }
            }
            out.q6 += local_q6(bonds);
            ++n;
        }
        out.q6 /= static_cast<double>(std::max(n, 1L));
    }
    return out;
}

TEST(Packing, BondOrderOfFccAndHcpShells) {
    // The diagnostic of order in the sphere pours: the 12 neighbours of an fcc site (the
    // permutations of (+-1, +-1, 0)) give q6 = 0.57452, those of an hcp site 0.48476 (Steinhardt
    // et al. 1983; Lechner & Dellago 2008, Table I), whatever the shell's rotation.
    std::vector<Vec3> fcc;
    for (int a = -1; a <= 1; a += 2) {
        for (int b = -1; b <= 1; b += 2) {
            fcc.emplace_back(a, b, 0.0);
            fcc.emplace_back(a, 0.0, b);
            fcc.emplace_back(0.0, a, b);
        }
    }
    EXPECT_NEAR(local_q6(fcc), 0.57452, 1e-5);
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).matrix();
    for (Vec3& b : fcc) {
        b = turn * b;
    }
    EXPECT_NEAR(local_q6(fcc), 0.57452, 1e-5);
    // hcp: six neighbours in the basal plane, three above and three below, mirror images.
    std::vector<Vec3> hcp;
    for (int k = 0; k < 6; ++k) {
        hcp.emplace_back(std::cos(k * M_PI / 3.0), std::sin(k * M_PI / 3.0), 0.0);
    }
    for (int k = 0; k < 3; ++k) {
        const double a = M_PI / 6.0 + k * 2.0 * M_PI / 3.0;
        const Vec3 in_plane = Vec3(std::cos(a), std::sin(a), 0.0) / std::sqrt(3.0);
        hcp.push_back(in_plane + Vec3(0, 0, std::sqrt(2.0 / 3.0)));
        hcp.push_back(in_plane - Vec3(0, 0, std::sqrt(2.0 / 3.0)));
    }
    EXPECT_NEAR(local_q6(hcp), 0.48476, 1e-5);
}

TEST(Packing, CubicOrderIsOneWhenAlignedAndZeroWhenRandom) {
    // The measure of orientational order used for the superballs: 1 for any of the cube's
    // rotations, 0 on average over uniformly random orientations (200 000 samples: standard error
    // of the mean about 0.001, so 0.01 is ten of them).
    EXPECT_NEAR(cubic_order(Quat::Identity()), 1.0, 1e-12);
    EXPECT_NEAR(cubic_order(Quat(Eigen::AngleAxisd(0.5 * M_PI, Vec3::UnitX()))), 1.0, 1e-12);
    std::mt19937_64 rng(3);
    std::normal_distribution<double> g(0.0, 1.0);
    double sum = 0.0;
    constexpr int n = 200000;
    for (int k = 0; k < n; ++k) {
        sum += cubic_order(Quat(g(rng), g(rng), g(rng), g(rng)).normalized());
    }
    EXPECT_NEAR(sum / n, 0.0, 0.01);
}

/// Pours of (shape, seed) run at the same time, one thread each (seed 0: the case's seed). The
/// pours are separate systems sharing no state (the narrow phase's scratch is per thread), so the
/// results are the bits of one pour per process; only the wall time shrinks.
std::vector<Packing> pour_all(const std::vector<std::pair<std::string, long>>& runs) {
    std::vector<std::future<Packing>> futures;
    for (const auto& [shape, seed] : runs) {
        futures.push_back(std::async(std::launch::async,
                                     [shape = shape, seed = seed] { return pour(shape, seed); }));
    }
    std::vector<Packing> out;
    for (auto& f : futures) {
        out.push_back(f.get());
    }
    return out;
}

/// Mean of the solid fractions of `count` pours from `first` on, the standard deviation of one
/// pour and the standard error of the mean.
struct SeedMean {
    double mean = 0.0;
    double deviation = 0.0;
    double standard_error = 0.0;
};

SeedMean seed_mean(const std::vector<Packing>& k, std::size_t first, std::size_t count) {
    SeedMean m;
    for (std::size_t i = first; i < first + count; ++i) {
        m.mean += k[i].phi;
    }
    m.mean /= static_cast<double>(count);
    double var = 0.0;
    for (std::size_t i = first; i < first + count; ++i) {
        var += (k[i].phi - m.mean) * (k[i].phi - m.mean);
    }
    var /= static_cast<double>(count - 1);
    m.deviation = std::sqrt(var);
    m.standard_error = std::sqrt(var / static_cast<double>(count));
    return m;
}

/// Seeds poured for each shape of the spheroid test (spheres, 1.5:1, 2:1), whose means are
/// compared: with round-off alone one spheroid pour moved by about 0.02 (rises +0.066 to +0.085
/// over sessions 6-12, README), two thirds of the tolerance, so one pour per shape could not tell.
constexpr long spheroid_seeds = 4;

TEST(Packing, SpheroidsRiseAboveSpheresAsDonev2004) {
    reset_results();
    const char* const shapes[] = {"sphere", "prolate_15", "prolate_20"};
    std::vector<std::pair<std::string, long>> runs;
    for (const char* shape : shapes) {
        for (long seed = 1; seed <= spheroid_seeds; ++seed) {
            runs.emplace_back(shape, seed);
        }
    }
    const std::vector<Packing> k = pour_all(runs);
    const auto n = static_cast<std::size_t>(spheroid_seeds);
    for (std::size_t i = 0; i < k.size(); ++i) {
        const auto& [shape, seed] = runs[i];
        record(fmt::format("{} seed {}: solid fraction", shape, seed), k[i].phi, 0.0, 0.0, "-");
        record(fmt::format("{} seed {}: pour time (s)", shape, seed), k[i].time, 0.0, 0.0, "s");
        if (i < static_cast<std::size_t>(spheroid_seeds)) {
            record(fmt::format("{} seed {}: mean local bond order q6", shape, seed), k[i].q6, 0.0,
                   0.0, "-");
        }
        EXPECT_LT(k[i].kinetic_per_weight, settled) << shape << " seed " << seed;
        EXPECT_EQ(k[i].failures, 0) << shape << " seed " << seed;
    }
    // The band of random packings is checked on the mean of the sphere pours: single pours scatter
    // by about 0.006 (the measuring region holds some 100 spheres) and two of seven seeds came out
    // above 0.655 with the same local order q6 as the others (README, "Spheroids: four seeds").
    const SeedMean sphere = seed_mean(k, 0, n);
    EXPECT_GT(sphere.mean, sphere_low);
    EXPECT_LT(sphere.mean, sphere_high);
    record("spheres: mean solid fraction", sphere.mean, 0.5 * (sphere_low + sphere_high),
           0.5 * (sphere_high - sphere_low), "-");
    record("spheres: standard error of the mean", sphere.standard_error, 0.0, 0.0, "-");

    // Donev et al. 2004, Fig. 2 (spheroids, maximally random jammed): 0.64 for spheres, about 0.70
    // at aspect ratio 1.5 and 0.69 at 2 (read from the figure).
    struct Row {
        const char* label;
        double reference_rise;
    };
    const Row rows[] = {{"spheroid 1.5:1", 0.70 - 0.64}, {"spheroid 2:1", 0.69 - 0.64}};
    for (std::size_t r = 0; r < 2; ++r) {
        const SeedMean s = seed_mean(k, (r + 1) * n, n);
        const double rise = s.mean - sphere.mean;
        record(fmt::format("{}: mean solid fraction", rows[r].label), s.mean,
               0.64 + rows[r].reference_rise, rise_tolerance, "-");
        record(fmt::format("{}: standard deviation of one pour", rows[r].label), s.deviation, 0.0,
               0.0, "-");
        record(fmt::format("{}: rise of the means over spheres", rows[r].label), rise,
               rows[r].reference_rise, rise_tolerance, "-");
        record(fmt::format("{}: standard error of the rise", rows[r].label),
               std::hypot(s.standard_error, sphere.standard_error), 0.0, 0.0, "-");
        EXPECT_NEAR(rise, rows[r].reference_rise, rise_tolerance) << rows[r].label;
    }
}

/// Seeds of the m = 4 pours whose mean is compared with Delaney & Cleary's m = 5 value: one pour
/// scatters by about 0.013 in solid fraction (README, "Seed spread"), as much as the margin.
constexpr long m4_seeds = 6;

TEST(Packing, SuperballsPackDenserWithBlockiness) {
    // Delaney & Cleary 2010: superballs pack denser the blockier they are, from 0.64 (m = 2/e = 2)
    // to about 0.82 at m = 5 (partly ordered). Checked: the rise with blockiness, and the mean of
    // six m = 4 pours (seeds 1-6) below m = 5's value. The sphere pour of the case's own seed is
    // the baseline of the rise, so that this test stands alone.
    std::vector<std::pair<std::string, long>> runs = {{"sphere", 0}, {"superball_067", 0}};
    for (long seed = 1; seed <= m4_seeds; ++seed) {
        runs.emplace_back("superball_050", seed);
    }
    const std::vector<Packing> k = pour_all(runs);
    const Packing& sphere = k[0];
    const Packing& m3 = k[1];
    double order = 0.0;
    for (long seed = 1; seed <= m4_seeds; ++seed) {
        const Packing& p = k[static_cast<std::size_t>(seed + 1)];
        record(fmt::format("superball m = 4 seed {}: solid fraction", seed), p.phi, 0.0, 0.0, "-");
        record(fmt::format("superball m = 4 seed {}: pour time (s)", seed), p.time, 0.0, 0.0, "s");
        order += p.order / m4_seeds;
        EXPECT_LT(p.kinetic_per_weight, settled) << "m = 4, seed " << seed;
        EXPECT_EQ(p.failures, 0) << "m = 4, seed " << seed;
    }
    const SeedMean m4 = seed_mean(k, 2, static_cast<std::size_t>(m4_seeds));
    const double mean = m4.mean;
    record("superball m = 3: solid fraction", m3.phi, 0.0, 0.0, "-");
    record("superball m = 3: pour time (s)", m3.time, 0.0, 0.0, "s");
    record("superball m = 4: mean solid fraction of 6 seeds", mean, 0.82, 0.0, "-");
    record("superball m = 4: standard deviation of one pour", m4.deviation, 0.0, 0.0, "-");
    record("superball m = 4: standard error of the mean", m4.standard_error, 0.0, 0.0, "-");
    record("superball m = 3: cubic order against the box (0 random, 1 aligned)", m3.order, 0.0, 0.0,
           "-");
    record("superball m = 4: mean cubic order against the box", order, 0.0, 0.0, "-");
    EXPECT_GT(m3.phi, sphere.phi);
    EXPECT_GT(mean, m3.phi);
    EXPECT_LT(mean, 0.82);
    EXPECT_LT(m3.kinetic_per_weight, settled);
    EXPECT_EQ(m3.failures, 0);
}

/// The seed-to-seed spread behind the superball tolerance (README, "Seed spread"): not part of the
/// check (each pour takes 10-25 minutes). Run one pour per process:
///   KILN_PACKING_SPREAD=superball_050:3 kiln_val_15_packing
///       --gtest_also_run_disabled_tests --gtest_filter='*SeedSpread'
/// and it prints the solid fraction of that shape poured with that seed.
TEST(Packing, DISABLED_SeedSpread) {
    const char* arg = std::getenv("KILN_PACKING_SPREAD");
    ASSERT_NE(arg, nullptr) << "set KILN_PACKING_SPREAD=shape:seed";
    const std::string s(arg);
    const auto colon = s.find(':');
    ASSERT_NE(colon, std::string::npos) << "KILN_PACKING_SPREAD=shape:seed, got " << s;
    const std::string shape = s.substr(0, colon);
    const long seed = std::stol(s.substr(colon + 1));
    const Packing k = pour(shape, seed);
    std::printf("spread %s seed %ld: solid fraction %.4f, cubic order %.3f, q6 %.3f, "
                "kinetic/weight %.3g, pour time %.2f s, failures %ld\n",
                shape.c_str(), seed, k.phi, k.order, k.q6, k.kinetic_per_weight, k.time,
                k.failures);
}

} // namespace
} // namespace kiln::validation
