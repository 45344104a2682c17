// Validation 34: angle of repose of cubes and of volume-equivalent spheres poured from a narrow
// source onto a bounded plate, same material and sliding friction, no rolling resistance: the cubes
// pile steeper (shape alone). See README.md.

#include "dynamics/system.hpp"
#include "validation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <gtest/gtest.h>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace kiln::validation {
namespace {

/// Plate radius (m): plate_r20.stl.
constexpr double plate_radius = 0.020;
/// Volume-equivalent diameter of both grains (m): sphere r = 1.4 mm, cube edge 2.26 mm.
constexpr double diameter = 2.8e-3;
/// Grains poured per heap: more than a cone of 35-40 degrees on the plate holds (~400 at a solid
/// fraction of 0.6, with the layer inside the rim), so that the heap reaches the rim and the
/// surplus spills over it (README: 44 cubes and 66 spheres fell off).
constexpr int poured = 480;
/// Time between two grains leaving the source (s): 250 grains/s, a thin stream (a
/// grain waits when the source is occupied: 170-230 grains/s were reached).
constexpr double pour_interval = 4e-3;
/// Source: a disc of this radius (m) on the axis, kept `source_gap` (m) above the top of the heap
/// under it (at least `source_floor` above the plate), releasing grains downwards at
/// `release_speed` (m/s): they land at about 0.55 m/s, gently enough not to flatten the heap.
constexpr double source_radius = 2.0e-3;
constexpr double source_gap = 2.0 * diameter;
constexpr double source_floor = 6.0e-3;
constexpr double release_speed = 0.4;
/// At rest: kinetic energy (translation + rotation) of the grains on the plate below this fraction
/// of (number of grains) x m g d, checked every `rest_check` s after the pour has ended. 1e-5
/// is a mean speed of 0.7 mm/s, a quarter of a diameter per second.
constexpr double at_rest = 1e-5;
constexpr double rest_check = 0.01;
/// Slope fit window, as fractions of the plate radius: away from the apex (where the stream
/// lands) and from the rim (where the heap meets the 1.4 mm lip).
constexpr double fit_inner = 0.2;
constexpr double fit_outer = 0.8;
/// Surface grains: no other grain centre higher up within this horizontal distance (m). 0.6 d
/// exceeds the offset d / sqrt(3) of a grain nested under three touching grains, so the second
/// layer is covered; the fit uses every exposed grain.
constexpr double cover_radius = 0.6 * diameter;
/// Azimuthal sectors for the spread of the slope around the heap.
constexpr int sectors = 8;
/// Cubes must pile steeper than spheres by at least this much (deg). The references give the sign
/// only (README); 5 deg is twice the combined standard error of the two fitted angles (the spread
/// of the 8 sector slopes, 4-6 deg, over sqrt(8): about 2.6 deg), so a pass is not scatter.
constexpr double min_difference_deg = 5.0;
/// Largest static overlap allowed (fraction of the diameter): the soft material must not change
/// the geometry of the heap (its contacts: grains on the plate; see pour()).
constexpr double max_overlap = 0.01;

/// Seed of the pour (release points and cube orientations). 34 unless the environment variable
/// KILN_REPOSE_SEED gives another (an unsigned integer), to sample the scatter of the angles with
/// another pour; the default run is unchanged.
std::uint64_t pour_seed() {
    const char* arg = std::getenv("KILN_REPOSE_SEED");
    return arg != nullptr && *arg != '\0' ? std::strtoull(arg, nullptr, 10) : 34;
}

/// The case, with cubes or with spheres of the same volume.
io::CaseSpec case_for(bool cubes) {
    const std::string file = std::string(KILN_CASE_DIR) + "/case.toml";
    std::ifstream in(file);
    std::stringstream ss;
    ss << in.rdbuf();
    std::string text = ss.str();
    if (!cubes) {
        const std::string key = "shape = \"cube\"";
        const auto at = text.find(key);
        EXPECT_NE(at, std::string::npos);
        text.replace(at, key.size(), "radius = 1.4e-3");
    }
    return io::read_case_text(text, file);
}

struct SurfacePoint {
    int sector = 0;
    double r = 0; ///< distance from the plate axis (m)
    double z = 0; ///< height of the grain centre above the plate (m)
};

struct Heap {
    double angle_deg = 0;         ///< slope of the line fitted to all surface points (deg)
    double sector_spread = 0;     ///< standard deviation of the 8 sector slopes (deg)
    double slope = 0;             ///< fitted dz/dr (-)
    double intercept = 0;         ///< fitted z at r = 0 (m)
    double rest_ratio = 0;        ///< kinetic energy / (n m g d) at the end
    double end_time = 0;          ///< simulated time at rest (s)
    double largest_overlap = 0;   ///< largest overlap / diameter at the end, on the plate (-)
    double off_plate_overlap = 0; ///< the same among grains that fell off (recorded only)
    double apex = 0;              ///< highest grain centre (m)
    long on_plate = 0;            ///< grains on the plate at the end
    long failures = 0;            ///< narrow-phase failures (contacts skipped)
    std::vector<SurfacePoint> surface;
};

/// Least-squares line z = a + b r through the points; returns {a, b}.
std::pair<double, double> fit_line(const std::vector<SurfacePoint>& pts) {
    double n = 0, sr = 0, sz = 0, srr = 0, srz = 0;
    for (const SurfacePoint& p : pts) {
        n += 1;
        sr += p.r;
        sz += p.z;
        srr += p.r * p.r;
        srz += p.r * p.z;
    }
    const double b = (n * srz - sr * sz) / (n * srr - sr * sr);
    return {(sz - b * sr) / n, b};
}

/// Kinetic energy of the grains on the plate (J) and their number.
std::pair<double, long> plate_kinetic(const dynamics::System& sys) {
    const ParticleStore& p = sys.particles();
    double ke = 0;
    long n = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        if (p.x[i].z() < -1e-3) {
            continue; // fell off
        }
        ++n;
        ke += 0.5 * p.mass[i] * p.v[i].squaredNorm();
        ke += p.shape[i] < 0 ? 0.5 * p.omega[i].squaredNorm() / p.inv_inertia[i]
                             : 0.5 * p.omega[i].dot(p.ang_mom[i]);
    }
    return {ke, n};
}

/// Height of the highest grain centre (m) within horizontal distance `reach` (m) of the axis among
/// the grains slower than 0.1 m/s (the heap, not the falling stream); 0 when there is none.
double heap_top(const dynamics::System& sys, double reach) {
    const ParticleStore& p = sys.particles();
    double top = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        if (p.x[i].head<2>().norm() < reach && p.v[i].norm() < 0.1) {
            top = std::max(top, p.x[i].z());
        }
    }
    return top;
}

/// True when no grain is within `clearance` of the source point x.
bool source_clear(const dynamics::System& sys, const Vec3& x, double clearance) {
    const ParticleStore& p = sys.particles();
    return std::none_of(p.x.begin(), p.x.end(),
                        [&](const Vec3& y) { return (y - x).norm() < clearance; });
}

Heap pour(bool cubes) {
    io::CaseSpec spec = case_for(cubes);
    dynamics::System sys(spec.scene);
    const double dt = sys.dt();
    std::mt19937_64 rng(pour_seed());
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::normal_distribution<double> gauss(0.0, 1.0);
    const double grain_mass = sys.particles().mass.at(0);
    const double bounding = sys.particles().radius.at(0);
    const long interval_steps = std::lround(pour_interval / dt);
    const long check_steps = std::lround(rest_check / dt);
    const long max_steps = std::lround(spec.run.end_time / dt);
    int released = 1; // the case's [[particle]] is the first grain
    long last_release = 0;
    Heap out;
    for (long s = 1; s <= max_steps; ++s) {
        if (released < poured && s - last_release >= interval_steps) {
            Vec3 x(0, 0,
                   std::max(source_floor, heap_top(sys, source_radius + diameter) + source_gap));
            do {
                x.x() = source_radius * u(rng);
                x.y() = source_radius * u(rng);
            } while (x.head<2>().norm() > source_radius);
            if (source_clear(sys, x, 1.9 * bounding)) {
                if (cubes) {
                    const Quat q =
                        Quat(gauss(rng), gauss(rng), gauss(rng), gauss(rng)).normalized();
                    sys.add_body(0, 0, x, Vec3(0, 0, -release_speed), Vec3::Zero(), q);
                } else {
                    sys.add_particle(0, 0.5 * diameter, x, Vec3(0, 0, -release_speed),
                                     Vec3::Zero());
                }
                ++released;
                last_release = s;
            }
        }
        sys.step();
        if (s % 20000 == 0) {
            std::printf("  %s t = %.2f s: %d released\n", cubes ? "cubes" : "spheres", sys.time(),
                        released);
            std::fflush(stdout);
        }
        if (released == poured && s - last_release > check_steps && s % check_steps == 0) {
            const auto [ke, n] = plate_kinetic(sys);
            out.rest_ratio = ke / (static_cast<double>(n) * grain_mass * 9.81 * diameter);
            if (s % (10 * check_steps) == 0) {
                std::printf("  %s t = %.2f s: %ld on the plate, E_kin / (n m g d) = %.3g\n",
                            cubes ? "cubes" : "spheres", sys.time(), n, out.rest_ratio);
            }
            if (out.rest_ratio < at_rest) {
                break;
            }
        }
    }
    EXPECT_EQ(released, poured) << "the source was blocked";
    out.end_time = sys.time();
    out.failures = sys.narrow_phase_counters().failures;

    // Surface: the grains on the plate that no other grain covers (see cover_radius).
    const ParticleStore& p = sys.particles();
    for (std::size_t i = 0; i < p.size(); ++i) {
        const Vec3& x = p.x[i];
        const double r = x.head<2>().norm();
        if (x.z() < -1e-3 || r > plate_radius) {
            continue;
        }
        ++out.on_plate;
        out.apex = std::max(out.apex, x.z());
        bool covered = false;
        for (std::size_t j = 0; j < p.size() && !covered; ++j) {
            covered = p.x[j].z() > x.z() && (p.x[j] - x).head<2>().norm() < cover_radius;
        }
        if (!covered) {
            const double phi = std::atan2(x.y(), x.x()) + std::numbers::pi;
            const int sector =
                std::min(sectors - 1, static_cast<int>(phi / (2 * std::numbers::pi) * sectors));
            out.surface.push_back(SurfacePoint{sector, r, x.z()});
        }
    }
    std::vector<SurfacePoint> window;
    for (const SurfacePoint& pt : out.surface) {
        if (pt.r >= fit_inner * plate_radius && pt.r <= fit_outer * plate_radius) {
            window.push_back(pt);
        }
    }
    const auto [a, b] = fit_line(window);
    out.intercept = a;
    out.slope = b;
    out.angle_deg = std::atan(-b) * 180.0 / std::numbers::pi;
    double s1 = 0, s2 = 0;
    for (int k = 0; k < sectors; ++k) {
        std::vector<SurfacePoint> one;
        std::copy_if(window.begin(), window.end(), std::back_inserter(one),
                     [k](const SurfacePoint& q) { return q.sector == k; });
        const double angle = std::atan(-fit_line(one).second) * 180.0 / std::numbers::pi;
        s1 += angle;
        s2 += angle * angle;
    }
    out.sector_spread = std::sqrt(std::max(0.0, s2 / sectors - (s1 / sectors) * (s1 / sectors)));

    std::vector<dynamics::ContactRecord> contacts;
    sys.collect_contacts(contacts);
    // The heap's contacts: both grains (or the grain at a wall) on the plate, the rule of
    // plate_kinetic. A grain that left the plate may still be falling or striking the catch floor
    // when the heap comes to rest (seed 34 after session 29: one hit it at ~0.8 m/s at the stop,
    // 2.3 % of d mid-impact, where Hertz gives up to ~8 %); its overlap is recorded apart.
    const auto on_plate = [&](std::uint32_t i) { return p.x[i].z() >= -1e-3; };
    for (const auto& c : contacts) {
        const bool heap = on_plate(c.i) && (c.wall || on_plate(c.j));
        double& worst = heap ? out.largest_overlap : out.off_plate_overlap;
        worst = std::max(worst, c.overlap / diameter);
    }
    return out;
}

/// Writes the surface points and the fitted line for plot_repose.py.
void write_profile(const std::string& name, const Heap& h) {
    std::ofstream f(std::filesystem::path(KILN_RESULT_DIR) / ("profile_" + name + ".csv"));
    f << "# fit: z = " << h.intercept << " + " << h.slope << " r (m), window " << fit_inner << " - "
      << fit_outer << " of r_plate = " << plate_radius << "\n";
    f << "sector,r,z\n";
    f.precision(8);
    for (const SurfacePoint& p : h.surface) {
        f << p.sector << ',' << p.r << ',' << p.z << '\n';
    }
}

TEST(AngleOfRepose, CubesPileSteeperThanSpheres) {
    reset_results();
    std::printf("  pour seed %llu\n", static_cast<unsigned long long>(pour_seed()));
    record("pour seed", static_cast<double>(pour_seed()), 0.0, 0.0, "-");
    const Heap cubes = pour(true);
    const Heap spheres = pour(false);
    for (const auto& [name, h] : {std::pair<std::string, const Heap&>{"spheres", spheres},
                                  std::pair<std::string, const Heap&>{"cubes", cubes}}) {
        write_profile(name, h);
        record(name + ": angle of repose", h.angle_deg, 0.0, 0.0, "deg");
        record(name + ": spread of the 8 sector angles", h.sector_spread, 0.0, 0.0, "deg");
        record(name + ": grains on the plate", static_cast<double>(h.on_plate), 0.0, 0.0, "-");
        record(name + ": apex height", h.apex, 0.0, 0.0, "m");
        record(name + ": time to rest", h.end_time, 0.0, 0.0, "s");
        record(name + ": E_kin / (n m g d) at the end", h.rest_ratio, 0.0, at_rest, "-");
        record(name + ": largest overlap / d", h.largest_overlap, 0.0, max_overlap, "-");
        record(name + ": largest overlap / d off the plate (not checked)", h.off_plate_overlap, 0.0,
               0.0, "-");
        EXPECT_LT(h.rest_ratio, at_rest) << name << " not at rest";
        EXPECT_LT(h.largest_overlap, max_overlap) << name;
        EXPECT_EQ(h.failures, 0) << name;
    }
    record("cubes - spheres", cubes.angle_deg - spheres.angle_deg, min_difference_deg, 0.0,
           "deg (at least)");
    EXPECT_GT(cubes.angle_deg - spheres.angle_deg, min_difference_deg);
}

} // namespace
} // namespace kiln::validation
