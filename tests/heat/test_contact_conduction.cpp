// Static contact conduction (Batchelor & O'Brien / Zhou et al., seed Inv. V eq. 12), contact
// radius, distribution of a contact heat rate over boundary patches, undisturbed temperature.

#include "core/error.hpp"
#include "heat/cartesian_grid.hpp"
#include "heat/contact_conduction.hpp"
#include "heat/spherical_grid.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <limits>
#include <vector>

namespace kiln::heat {
namespace {

/// Closed-form values evaluated in a different order: a few roundings.
constexpr double formula_tolerance = 1e-14;
/// Per-patch shares sum to the rate up to the roundings of one sum over <= ~100 patches.
constexpr double conservation_ulps = 8.0;

TEST(ContactConduction, ConductanceFormula) {
    // Equal conductivities: H = 2 k c r_c (seed notes §5.1 V-5/V-6: G = 2 k r_c for c = 1).
    const double k = 1.4;
    const double rc = 1.11e-2;
    EXPECT_NEAR(static_contact_conductance(k, k, rc), 2.0 * k * rc, formula_tolerance);
    // Different conductivities: harmonic combination 4 r_c / (1/k_i + 1/k_j).
    const double ki = 1.4;
    const double kj = 237.0;
    EXPECT_NEAR(static_contact_conductance(ki, kj, rc, 0.5), 4.0 * 0.5 * rc * ki * kj / (ki + kj),
                formula_tolerance);
    // Symmetric in the pair, exactly.
    EXPECT_EQ(static_contact_conductance(ki, kj, rc), static_contact_conductance(kj, ki, rc));
    // Limits: no contact -> no conductance; one conductor -> 4 c r_c k_i (the other side is
    // isothermal); linear in r_c and in c.
    EXPECT_EQ(static_contact_conductance(ki, kj, 0.0), 0.0);
    EXPECT_NEAR(static_contact_conductance(ki, 1e300, rc) / (4.0 * rc * ki), 1.0,
                formula_tolerance);
    EXPECT_NEAR(static_contact_conductance(ki, kj, 2.0 * rc) /
                    static_contact_conductance(ki, kj, rc),
                2.0, formula_tolerance);
    // Seed V-6 value: 2 x 1.4 x 1.11e-2 = 0.03108 W/K, i.e. dT = 0.1569 / H = 5.05 K (notes §5.1).
    EXPECT_NEAR(0.1569 / static_contact_conductance(k, k, rc), 5.048, 1e-3);
}

TEST(ContactConduction, SoftenedModulusCorrection) {
    // Seed notes §2.4: (10 MPa / 50 GPa)^0.2 = (14 MPa / 70 GPa)^0.2 = 0.182.
    EXPECT_NEAR(softened_modulus_correction(10e6, 50e9), 0.182, 5e-4);
    EXPECT_NEAR(softened_modulus_correction(14e6, 70e9), softened_modulus_correction(10e6, 50e9),
                formula_tolerance);
    EXPECT_EQ(softened_modulus_correction(70e9, 70e9), 1.0);
    EXPECT_THROW((void)softened_modulus_correction(0.0, 70e9), InputError);
}

TEST(ContactConduction, ContactRadii) {
    const double r = 0.05;
    const double delta = 2.5e-3;
    // Hertz: a^2 = R* delta, R* = R / 2 for equal spheres: 7.9e-3 m (seed notes §2.4).
    EXPECT_NEAR(hertz_contact_radius(delta, r, r), std::sqrt(0.5 * r * delta), formula_tolerance);
    // Lens radius: the seed's r_c = 1.11e-2 m (printed to 3 digits).
    EXPECT_NEAR(lens_contact_radius(delta, r, r), std::sqrt(r * delta - delta * delta / 4.0),
                formula_tolerance);
    EXPECT_NEAR(lens_contact_radius(delta, r, r), 1.11e-2, 0.005e-2);
    // Sphere on a (nearly) flat partner: a^2 = 2 R delta - delta^2; Hertz: R* -> R.
    const double flat = 1e7;
    // The partner's curvature R / R_j = 5e-9 changes a ~ 1e-2 m by ~1e-10 m.
    constexpr double flat_partner_tolerance = 1e-9;
    EXPECT_NEAR(lens_contact_radius(delta, r, flat), std::sqrt(2 * r * delta - delta * delta),
                flat_partner_tolerance);
    EXPECT_NEAR(hertz_contact_radius(delta, r, flat), std::sqrt(r * delta), flat_partner_tolerance);
    // Pair order does not matter.
    EXPECT_NEAR(lens_contact_radius(delta, 0.03, 0.05), lens_contact_radius(delta, 0.05, 0.03),
                formula_tolerance);
    // Overlap form of the conductance = Hertz radius x correction.
    EXPECT_NEAR(static_contact_conductance(1.4, 14.9, delta, r, r, 10e6, 50e9),
                static_contact_conductance(1.4, 14.9, hertz_contact_radius(delta, r, r),
                                           softened_modulus_correction(10e6, 50e9)),
                formula_tolerance);
    EXPECT_EQ(hertz_contact_radius(0.0, r, r), 0.0);
    EXPECT_THROW((void)hertz_contact_radius(-1e-3, r, r), InputError);
    EXPECT_THROW((void)lens_contact_radius(0.2, r, r), InputError);
    EXPECT_THROW((void)static_contact_conductance(0.0, 1.0, 1e-3), InputError);
    EXPECT_THROW((void)static_contact_conductance(1.0, 1.0, -1e-3), InputError);
}

/// Checks that distributing `rate` at (point, normal, rc) adds exactly `rate` to patches that face
/// the contact.
void check_distribution(const ThermalGrid& g, const Vec3& point, const Vec3& normal, double rc,
                        double rate) {
    std::vector<double> q(g.boundary.size(), 0.0);
    const std::vector<int> used = distribute_contact_heat(g, point, normal, rc, rate, q);
    ASSERT_FALSE(used.empty());
    double sum = 0.0;
    for (const double x : q) {
        sum += x;
    }
    EXPECT_NEAR(sum, rate,
                conservation_ulps * std::numeric_limits<double>::epsilon() * std::abs(rate));
    for (const int b : used) {
        EXPECT_GT(g.boundary[static_cast<std::size_t>(b)].area_normal.dot(normal), 0.0);
        EXPECT_EQ(q[static_cast<std::size_t>(b)] > 0.0, rate > 0.0);
    }
}

TEST(ContactConduction, DistributionIsConservative) {
    const double r = 0.05;
    const ThermalGrid sph = make_spherical_grid(r, {6, 12, 16});
    const ThermalGrid cart = make_cartesian_grid(Sphere{r}, {.cells_across = 12});
    const std::vector<Vec3> dirs{Vec3(0, 0, 1), Vec3(0, 0, -1), Vec3(1, 0, 0), Vec3(0.3, -0.5, 0.8),
                                 Vec3(-0.7, 0.1, 0.2)};
    for (const Vec3& d : dirs) {
        const Vec3 n = d.normalized();
        for (const double rc : {1e-5, 5e-3, 1.11e-2, 3e-2}) {
            for (const double rate : {0.1569, -3.7e-4, 12.5}) {
                check_distribution(sph, r * n, n, rc, rate);
                check_distribution(cart, r * n, n, rc, rate);
            }
        }
    }
    // The seed's disc (r_c = 11.1 mm at the pole) on a 16-band grid covers the first band only.
    const ThermalGrid g = make_spherical_grid(r, {6, 16, 16});
    EXPECT_EQ(contact_patches(g, Vec3(0, 0, r), Vec3(0, 0, 1), 1.11e-2).size(), 16U);
    // A disc smaller than every patch falls back to the nearest patch.
    EXPECT_EQ(contact_patches(g, Vec3(r, 0, 0), Vec3(1, 0, 0), 1e-6).size(), 1U);
    std::vector<double> wrong(3, 0.0);
    EXPECT_THROW((void)distribute_contact_heat(g, Vec3(0, 0, r), Vec3(0, 0, 1), 1e-2, 1.0, wrong),
                 InputError);
}

TEST(ContactConduction, SwappingThePairFlipsTheSign) {
    // Two spheres along z with different fields: the rate into i computed from i's view is the
    // exact negative of the rate into j computed from j's view, and the per-patch rates of both
    // particles sum to zero.
    const double r = 0.05;
    const SphericalResolution res{5, 10, 12};
    const ThermalGrid g = make_spherical_grid(r, res);
    std::vector<double> ti(static_cast<std::size_t>(g.size()));
    std::vector<double> tj(ti.size());
    for (std::size_t c = 0; c < ti.size(); ++c) {
        ti[c] = 400.0 + 30.0 * g.node[c].z() + 2.0 * g.node[c].x();
        tj[c] = 350.0 - 50.0 * g.node[c].z() * g.node[c].z();
    }
    const double rc = 1.11e-2;
    const Vec3 up(0, 0, 1);
    const std::vector<int> pi = contact_patches(g, r * up, up, rc);
    const std::vector<int> pj = contact_patches(g, -r * up, -up, rc);
    const double ui = undisturbed_temperature(g, res, ti, pi);
    const double uj = undisturbed_temperature(g, res, tj, pj);
    const double h_ij = static_contact_conductance(1.4, 14.9, rc);
    const double h_ji = static_contact_conductance(14.9, 1.4, rc);
    const double q_into_i = h_ij * (uj - ui);
    const double q_into_j = h_ji * (ui - uj);
    EXPECT_EQ(q_into_i, -q_into_j);
    std::vector<double> qi(g.boundary.size(), 0.0);
    std::vector<double> qj(g.boundary.size(), 0.0);
    (void)distribute_contact_heat(g, r * up, up, rc, q_into_i, qi);
    (void)distribute_contact_heat(g, -r * up, -up, rc, q_into_j, qj);
    double total = 0.0;
    for (std::size_t b = 0; b < qi.size(); ++b) {
        total += qi[b] + qj[b];
    }
    EXPECT_NEAR(total, 0.0,
                conservation_ulps * std::numeric_limits<double>::epsilon() * std::abs(q_into_i));
}

TEST(ContactConduction, UndisturbedTemperature) {
    const double r = 0.05;
    const SphericalResolution res{6, 12, 12};
    const ThermalGrid g = make_spherical_grid(r, res);
    const Vec3 up(0, 0, 1);
    const std::vector<int> patches = contact_patches(g, r * up, up, 1.5e-2);
    ASSERT_FALSE(patches.empty());
    // Uniform field: the undisturbed value is that temperature.
    std::vector<double> t(static_cast<std::size_t>(g.size()), 398.15);
    EXPECT_NEAR(undisturbed_temperature(g, res, t, patches), 398.15, formula_tolerance * 398.15);
    // Linear field: every node of a row lies on the tangent, so each row gives its outer node;
    // the result is the area-weighted mean of the outer nodes.
    for (std::size_t c = 0; c < t.size(); ++c) {
        t[c] = 300.0 + 1000.0 * g.node[c].z();
    }
    double expect = 0.0;
    double area = 0.0;
    for (const int b : patches) {
        const BoundaryFace& f = g.boundary[static_cast<std::size_t>(b)];
        expect += f.area * t[static_cast<std::size_t>(f.cell)];
        area += f.area;
    }
    expect /= area;
    // The tangent test compares extrapolated values ~ 1e2 K: a few roundings of 1e2.
    constexpr double field_tolerance = 1e-10;
    EXPECT_NEAR(undisturbed_temperature(g, res, t, patches), expect, field_tolerance);
    // A disturbance of the two outer shells under the contact (the contact heat): each row now
    // ends at shell n_r - 2, below the disturbed layer.
    std::vector<double> d = t;
    double expect_d = 0.0;
    for (const int b : patches) {
        const BoundaryFace& f = g.boundary[static_cast<std::size_t>(b)];
        const int jk = f.cell - spherical_index(res, res.n_r, 0, 0);
        const int j = jk / res.n_phi;
        const int k = jk % res.n_phi;
        d[static_cast<std::size_t>(spherical_index(res, res.n_r, j, k))] += 50.0;
        d[static_cast<std::size_t>(spherical_index(res, res.n_r - 1, j, k))] += 10.0;
        expect_d += f.area * t[static_cast<std::size_t>(spherical_index(res, res.n_r - 2, j, k))];
    }
    expect_d /= area;
    EXPECT_NEAR(undisturbed_temperature(g, res, d, patches), expect_d, field_tolerance);
    EXPECT_THROW((void)undisturbed_temperature(g, res, d, std::vector<int>{}), InputError);
    EXPECT_THROW((void)undisturbed_temperature(g, res, std::vector<double>(3, 0.0), patches),
                 InputError);
}

} // namespace
} // namespace kiln::heat
