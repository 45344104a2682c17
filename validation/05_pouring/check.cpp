// Validation 05: spheres poured into a box settle (kinetic energy decays by orders of magnitude)
// into a bed whose solid fraction lies in the random-packing band.

#include "dynamics/system.hpp"
#include "validation.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <numbers>
#include <variant>
#include <vector>

namespace kiln::validation {
namespace {

/// Settled: final kinetic energy below this fraction of its peak during the fall (four orders of
/// magnitude; a bed still flowing or rattling keeps far more).
constexpr double settled_ratio = 1e-4;
/// Random loose packing of frictional spheres, the lower edge of the band (Onoda & Liniger 1990,
/// Phys. Rev. Lett. 64:2727: 0.555 in the limit of zero gravity; Silbert 2010, Soft Matter 6:2918:
/// about 0.55 for mu -> infinity).
constexpr double loose_packing = 0.55;
/// Random close packing, the upper edge (Scott & Kilgour 1969, J. Phys. D 2:863: 0.637).
constexpr double close_packing = 0.64;
/// Distance kept from side walls, floor and free surface when sampling the solid fraction: the
/// layering a flat wall imposes fades within 3 diameters (profile in README.md).
constexpr double margin_diameters = 3.0;
/// Sub-samples per axis for spheres cut by an edge or corner of the sampling box (spheres cut by
/// one face are exact caps); the fraction is then within 5e-5 of a 192^3 sampling.
constexpr int subsamples = 32;

/// Volume of the cap of height h cut from a sphere of radius r (m^3).
double cap_volume(double r, double h) {
    return std::numbers::pi * h * h * (3.0 * r - h) / 3.0;
}

/// Volume of the sphere (c, r) inside box b (m^3): exact when the sphere is inside, outside or cut
/// by one face; sampled (ratio of sub-sample points, so the sphere's own discretisation cancels)
/// when cut by an edge or a corner.
double volume_in_box(const Vec3& c, double r, const Aabb& b) {
    const double full = 4.0 / 3.0 * std::numbers::pi * r * r * r;
    int cuts = 0;
    double cut_volume = full;
    for (int a = 0; a < 3; ++a) {
        if (c[a] + r <= b.lo[a] || c[a] - r >= b.hi[a]) {
            return 0.0;
        }
        if (c[a] - r < b.lo[a]) {
            ++cuts;
            cut_volume = full - cap_volume(r, b.lo[a] - (c[a] - r));
        }
        if (c[a] + r > b.hi[a]) {
            ++cuts;
            cut_volume = full - cap_volume(r, c[a] + r - b.hi[a]);
        }
    }
    if (cuts <= 1) {
        return cut_volume;
    }
    const double h = 2.0 * r / subsamples;
    long in_sphere = 0;
    long in_both = 0;
    for (int i = 0; i < subsamples; ++i) {
        for (int j = 0; j < subsamples; ++j) {
            for (int k = 0; k < subsamples; ++k) {
                const Vec3 q = c - Vec3::Constant(r) + h * Vec3(i + 0.5, j + 0.5, k + 0.5);
                if ((q - c).squaredNorm() <= r * r) {
                    ++in_sphere;
                    in_both += b.contains(q) ? 1 : 0;
                }
            }
        }
    }
    return full * static_cast<double>(in_both) / static_cast<double>(in_sphere);
}

/// Solid fraction of the particles inside box b (-).
double solid_fraction(const ParticleStore& p, const Aabb& b) {
    double solid = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        solid += volume_in_box(p.x[i], p.radius[i], b);
    }
    return solid / b.extent().prod();
}

/// The box enclosed by the scene's axis-aligned plane walls (m, world).
Aabb container(const dynamics::SceneSpec& scene) {
    Aabb box{Vec3::Constant(-1e300), Vec3::Constant(1e300)};
    for (const auto& w : scene.walls) {
        const auto& plane = std::get<dynamics::PlaneWall>(w.shape);
        for (int a = 0; a < 3; ++a) {
            if (plane.normal[a] > 0.5) {
                box.lo[a] = plane.point[a];
            } else if (plane.normal[a] < -0.5) {
                box.hi[a] = plane.point[a];
            }
        }
    }
    return box;
}

/// Particle-particle contacts of each particle (touching: centre distance below r_i + r_j).
struct Contacts {
    std::vector<int> count;      ///< contacts per particle
    std::vector<double> overlap; ///< sum of the overlaps of its contacts (m)
};

Contacts contacts_per_particle(const ParticleStore& p) {
    Contacts c{std::vector<int>(p.size(), 0), std::vector<double>(p.size(), 0.0)};
    for (std::size_t i = 0; i < p.size(); ++i) {
        for (std::size_t j = i + 1; j < p.size(); ++j) {
            const double rsum = p.radius[i] + p.radius[j];
            const double dist2 = (p.x[i] - p.x[j]).squaredNorm();
            if (dist2 < rsum * rsum) {
                const double overlap = rsum - std::sqrt(dist2);
                ++c.count[i];
                ++c.count[j];
                c.overlap[i] += overlap;
                c.overlap[j] += overlap;
            }
        }
    }
    return c;
}

TEST(Pouring, BedSettlesIntoRandomPacking) {
    reset_results();
    const io::CaseSpec spec = load_case();
    dynamics::System sys(spec.scene);
    const long steps = std::lround(spec.run.end_time / sys.dt());
    double peak = 0.0;
    for (long s = 0; s < steps; ++s) {
        sys.step();
        if (s % 100 == 0) {
            peak = std::max(peak, sys.energies().kinetic);
        }
    }
    sys.check_finite();
    const double final_ke = sys.energies().kinetic;
    record("final / peak kinetic energy", final_ke / peak, 0.0, settled_ratio, "-");
    EXPECT_LT(final_ke / peak, settled_ratio);

    // Sampling box: the container's side walls and floor moved in by the margin; its top is the
    // margin below the top of the highest sphere.
    const auto& p = sys.particles();
    const Aabb box = container(spec.scene);
    const double d = 2.0 * p.radius[0];
    double top = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        top = std::max(top, p.x[i].z() + p.radius[i]);
    }
    const Vec3 m = Vec3::Constant(margin_diameters * d);
    const Aabb sample{box.lo + m, Vec3(box.hi.x() - m.x(), box.hi.y() - m.y(), top - m.z())};
    ASSERT_GT(sample.extent().z(), 3.0 * d) << "bed too shallow to sample";
    const double fraction = solid_fraction(p, sample);
    const double mid = 0.5 * (sample.lo.z() + sample.hi.z());
    Aabb lower = sample;
    lower.hi.z() = mid;
    Aabb upper = sample;
    upper.lo.z() = mid;
    record("bed height (top of highest sphere)", top, 0.0, 0.0, "m");
    record("solid fraction in the central region", fraction, 0.5 * (loose_packing + close_packing),
           0.5 * (close_packing - loose_packing), "-");
    record("solid fraction in the lower half of the region", solid_fraction(p, lower), 0.0, 0.0,
           "-");
    record("solid fraction in the upper half of the region", solid_fraction(p, upper), 0.0, 0.0,
           "-");
    EXPECT_GT(fraction, loose_packing);
    EXPECT_LT(fraction, close_packing);

    // Coordination: over all particles (walls, floor and surface included) and over the particles
    // whose centres lie in the sampling box.
    const Contacts c = contacts_per_particle(p);
    long z_sum = 0;
    long z_inner = 0;
    long n_inner = 0;
    long rattlers = 0;
    double overlap_inner = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        z_sum += c.count[i];
        if (sample.contains(p.x[i])) {
            ++n_inner;
            z_inner += c.count[i];
            rattlers += c.count[i] < 2 ? 1 : 0;
            overlap_inner += c.overlap[i];
        }
    }
    EXPECT_EQ(z_sum, 2 * sys.counters().particle_contacts) << "contact count differs from kiln's";
    record("mean coordination number (all particles)",
           static_cast<double>(z_sum) / static_cast<double>(p.size()), 0.0, 0.0, "-");
    record("mean coordination number (central region)",
           static_cast<double>(z_inner) / static_cast<double>(n_inner), 0.0, 0.0, "-");
    record("particles with fewer than 2 contacts (central region)", static_cast<double>(rattlers),
           0.0, 0.0, "-");
    record("mean overlap / diameter (central region)",
           overlap_inner / static_cast<double>(z_inner) / d, 0.0, 0.0, "-");
    record("largest overlap / diameter", sys.counters().max_overlap_ratio, 0.0, 0.0, "-");
}

} // namespace
} // namespace kiln::validation
