// Validation 05: spheres poured into a box settle (kinetic energy decays by orders of magnitude)
// into a bed whose solid fraction lies in the random-packing band.

#include "dynamics/system.hpp"
#include "validation.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <numbers>

namespace kiln::validation {
namespace {

/// Settled: final kinetic energy below this fraction of its peak during the fall.
constexpr double settled_ratio = 1e-4;
/// Random loose packing of frictional spheres, the lower edge of the band (Onoda & Liniger 1990,
/// Phys. Rev. Lett. 64:2727: 0.555 in the limit of zero gravity; Silbert 2010, Soft Matter 6:2918:
/// 0.55 for mu -> infinity).
constexpr double loose_packing = 0.55;
/// Random close packing, the upper edge (Scott & Kilgour 1969, J. Phys. D 2:863: 0.637).
constexpr double close_packing = 0.64;
/// Distance kept from walls, floor and free surface when sampling the solid fraction: the ordering
/// walls impose on a packing fades within 3-4 diameters.
constexpr double margin_diameters = 3.0;
/// Sub-samples per axis for spheres cut by the sampling box (volume error ~1e-3 per cut sphere).
constexpr int subsamples = 24;

/// Volume of the sphere (c, r) inside box b: exact when inside, sampled when cut by the boundary.
double volume_in_box(const Vec3& c, double r, const Aabb& b) {
    const double full = 4.0 / 3.0 * std::numbers::pi * r * r * r;
    if (((c.array() - r) >= b.lo.array()).all() && ((c.array() + r) <= b.hi.array()).all()) {
        return full;
    }
    if (((c.array() + r) <= b.lo.array()).any() || ((c.array() - r) >= b.hi.array()).any()) {
        return 0.0;
    }
    const double h = 2.0 * r / subsamples;
    long in = 0;
    for (int i = 0; i < subsamples; ++i) {
        for (int j = 0; j < subsamples; ++j) {
            for (int k = 0; k < subsamples; ++k) {
                const Vec3 q = c - Vec3::Constant(r) + h * Vec3(i + 0.5, j + 0.5, k + 0.5);
                if ((q - c).squaredNorm() <= r * r && b.contains(q)) {
                    ++in;
                }
            }
        }
    }
    return static_cast<double>(in) * h * h * h;
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

    const auto& p = sys.particles();
    const double d = 2.0 * p.radius[0];
    double top = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        top = std::max(top, p.x[i].z() + p.radius[i]);
    }
    const double m = margin_diameters * d;
    const Aabb sample{Vec3(-0.03 + m, -0.03 + m, m), Vec3(0.03 - m, 0.03 - m, top - m)};
    ASSERT_GT(sample.extent().z(), 3.0 * d) << "bed too shallow to sample";
    double solid = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        solid += volume_in_box(p.x[i], p.radius[i], sample);
    }
    const double fraction = solid / sample.extent().prod();
    record("bed height (top of highest sphere)", top, 0.0, 0.0, "m");
    record("solid fraction in the central region", fraction, 0.5 * (loose_packing + close_packing),
           0.5 * (close_packing - loose_packing), "-");
    record("mean coordination number (particle contacts)",
           2.0 * static_cast<double>(sys.counters().particle_contacts) /
               static_cast<double>(p.size()),
           0.0, 0.0, "-");
    EXPECT_GT(fraction, loose_packing);
    EXPECT_LT(fraction, close_packing);
}

} // namespace
} // namespace kiln::validation
