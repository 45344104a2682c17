// Validation 11: multi-sphere approximations of the 6 x 6 mm cylinder of Oschmann (2019),
// Investigation II: captured volume fraction of the 36-sphere (2.4 mm) and 12-sphere (3.5 mm)
// clumps against the seed's 81.4 % and 76.04 %, the 36-sphere clump's shadow areas against the
// seed's Table 2 (2.61e-5 and 3.42e-5 m^2), and the density correction against 1691 kg/m^3. The
// layouts are reconstructed (the text has no figure); see README.md for the assumptions.

#include "geometry/shape_metrics.hpp"
#include "io/shape_reader.hpp"
#include "validation.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <numbers>

namespace kiln::validation {
namespace {

/// Absolute tolerance on the captured volume fraction: the layout is reconstructed from words and
/// the seed does not say how it integrated the union (its own 1691 kg/m^3 implies 81.6 %, not
/// 81.4 %); 0.5 percentage points is that uncertainty, not a quadrature error (1e-5).
constexpr double volume_fraction_tolerance = 0.005;
/// Relative tolerance on the shadow areas: the seed prints 3 digits and computed them by an
/// unstated method; our areas are exact to 1e-5 for our layout.
constexpr double shadow_tolerance = 0.01;
/// Relative tolerance on the corrected density: inherits the volume-fraction uncertainty
/// (0.5 points of 81 %).
constexpr double density_tolerance = 0.007;
/// Largest acceptable quadrature error estimate of the union volume (relative).
constexpr double quadrature_tolerance = 1e-4;

geometry::ShapeTemplate load(const std::string& name) {
    return io::read_shape_file(io::find_shape_file(name, io::default_shape_dirs()));
}

/// Captured fraction of a ring layout built in code (alternatives of README.md, info only).
double alternative(int per_ring, bool centre, int layers, double radius, bool staggered) {
    std::vector<geometry::ClumpSphere> s;
    const double zmax = 3e-3 - radius;
    for (int l = 0; l < layers; ++l) {
        const double z = layers == 1 ? 0.0 : -zmax + 2.0 * zmax * l / (layers - 1);
        const double phase = staggered && l % 2 == 1 ? std::numbers::pi / per_ring : 0.0;
        for (int k = 0; k < per_ring; ++k) {
            const double a = phase + 2.0 * std::numbers::pi * k / per_ring;
            s.push_back(
                {Vec3((3e-3 - radius) * std::cos(a), (3e-3 - radius) * std::sin(a), z), radius});
        }
        if (centre) {
            s.push_back({Vec3(0, 0, z), radius});
        }
    }
    const geometry::Clump c = geometry::make_clump(s, "alternative", 1200);
    return c.volume / (std::numbers::pi * 9e-6 * 6e-3);
}

TEST(ClumpCylinder, CapturedVolumeShadowAndDensityMatchTheSeed) {
    reset_results();
    const auto c36 = load("cylinder_36");
    const auto c12 = load("cylinder_12");
    const double cylinder = c36.reference.volume();
    ASSERT_NEAR(cylinder, std::numbers::pi * 9e-6 * 6e-3, 1e-20);

    const double f36 = c36.volume / cylinder;
    const double f12 = c12.volume / cylinder;
    record("36 spheres captured volume fraction", f36, 0.814, volume_fraction_tolerance, "-");
    record("12 spheres captured volume fraction", f12, 0.7604, volume_fraction_tolerance, "-");
    EXPECT_NEAR(f36, 0.814, volume_fraction_tolerance);
    EXPECT_NEAR(f12, 0.7604, volume_fraction_tolerance);
    for (const auto* t : {&c36, &c12}) {
        const auto& clump = std::get<geometry::Clump>(t->shape);
        record(t->name + " quadrature error estimate", clump.volume_error / clump.volume, 0.0,
               quadrature_tolerance, "-");
        EXPECT_LT(clump.volume_error / clump.volume, quadrature_tolerance);
    }

    // Shadows of the 36-sphere clump: end-on (along the cylinder axis = body x, smallest moment)
    // and side-on (any body direction normal to it).
    const auto& clump = std::get<geometry::Clump>(c36.shape);
    const double end_on = geometry::projected_area(clump, Vec3::UnitX()).value;
    const double side_on = geometry::projected_area(clump, Vec3::UnitY()).value;
    record("36 spheres shadow end-on (0 deg)", end_on, 2.61e-5, shadow_tolerance, "m^2");
    record("36 spheres shadow side-on (90 deg)", side_on, 3.42e-5, shadow_tolerance, "m^2");
    EXPECT_NEAR(end_on / 2.61e-5, 1.0, shadow_tolerance);
    EXPECT_NEAR(side_on / 3.42e-5, 1.0, shadow_tolerance);

    const auto corrected = load("cylinder_36_corrected");
    const double rho = 1380.0 * corrected.density_factor();
    record("corrected density (POM 1380)", rho, 1691.0, density_tolerance, "kg/m^3");
    EXPECT_NEAR(rho / 1691.0, 1.0, density_tolerance);

    // Alternative layouts (reported only; README.md explains why they were rejected).
    record("alt 36: 8+1 per layer, staggered", alternative(8, true, 4, 1.2e-3, true), 0.814, 0.0,
           "-");
    record("alt 12: 3 layers of 4", alternative(4, false, 3, 1.75e-3, false), 0.7604, 0.0, "-");
    record("alt 12: 3 layers of 4, staggered", alternative(4, false, 3, 1.75e-3, true), 0.7604, 0.0,
           "-");
    record("alt 12: 2 layers of 6, staggered", alternative(6, false, 2, 1.75e-3, true), 0.7604, 0.0,
           "-");
    record("alt 12: 2 layers of 5 + centre", alternative(5, true, 2, 1.75e-3, false), 0.7604, 0.0,
           "-");
    record("alt 12: 4 layers of 3, staggered", alternative(3, false, 4, 1.75e-3, true), 0.7604, 0.0,
           "-");
}

} // namespace
} // namespace kiln::validation
