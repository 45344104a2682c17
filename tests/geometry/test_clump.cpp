// Clump (union of spheres) mass properties, surface and shadow (geometry/clump.hpp).

#include "core/error.hpp"
#include "geometry/clump.hpp"
#include "geometry/rotation.hpp"
#include "geometry/shape_metrics.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <numbers>
#include <random>

using kiln::Mat3;
using kiln::Vec3;
namespace g = kiln::geometry;

namespace {
constexpr double kPi = std::numbers::pi;

double sphere_volume(double r) {
    return 4.0 / 3.0 * kPi * r * r * r;
}

/// Cap of a sphere of radius r cut at height h from its pole: volume and distance of the cap's
/// centroid from the sphere centre (standard results, e.g. Beyer, CRC Standard Math. Tables).
double cap_volume(double r, double h) {
    return kPi * h * h * (3.0 * r - h) / 3.0;
}
double cap_centroid(double r, double h) {
    return 3.0 * (2.0 * r - h) * (2.0 * r - h) / (4.0 * (3.0 * r - h));
}

/// Two overlapping spheres on the x axis: r1 at 0, r2 at d.
std::vector<g::ClumpSphere> pair(double r1, double r2, double d) {
    return {{Vec3::Zero(), r1}, {Vec3(d, 0, 0), r2}};
}
} // namespace

TEST(Clump, LensFormulaLimits) {
    EXPECT_DOUBLE_EQ(g::lens_volume(1.0, 2.0, 3.5), 0.0);
    EXPECT_NEAR(g::lens_volume(1.0, 2.0, 0.5), sphere_volume(1.0), 1e-15);
    // Equal spheres: the lens is two caps of height r - d/2.
    EXPECT_NEAR(g::lens_volume(1.0, 1.0, 1.2), 2.0 * cap_volume(1.0, 0.4), 1e-14);
}

TEST(Clump, TwoSphereUnionVolumeAndCentroidMatchLensFormulas) {
    const double r1 = 1.0;
    const double r2 = 0.7;
    const double d = 1.1;
    const g::MassProperties mp = g::union_mass_properties(pair(r1, r2, d), 1600);
    const double v = sphere_volume(r1) + sphere_volume(r2) - g::lens_volume(r1, r2, d);
    constexpr double kQuadrature = 2e-5; // relative error of the column rule at n = 1600
    EXPECT_NEAR(mp.volume / v, 1.0, kQuadrature);
    // Centroid: sphere 1 whole plus sphere 2 minus the lens. The lens is cut by the plane
    // x0 = (d^2 + r1^2 - r2^2) / (2 d) into a cap of sphere 2 (height h2 = r2 - (d - x0)) and a
    // cap of sphere 1 (height h1 = r1 - x0).
    const double x0 = (d * d + r1 * r1 - r2 * r2) / (2.0 * d);
    const double h1 = r1 - x0;
    const double h2 = r2 - (d - x0);
    const double c1 = cap_volume(r1, h1);
    const double c2 = cap_volume(r2, h2);
    const double v2 = sphere_volume(r2) - c1 - c2;
    const double m2 =
        sphere_volume(r2) * d - c2 * (d - cap_centroid(r2, h2)) - c1 * cap_centroid(r1, h1);
    EXPECT_NEAR(v2, v - sphere_volume(r1), 1e-14); // the two caps make up the lens
    const double xc = m2 / (sphere_volume(r1) + v2);
    EXPECT_NEAR(mp.centroid.x(), xc, kQuadrature * d);
    EXPECT_NEAR(mp.centroid.y(), 0.0, 1e-12);
    EXPECT_NEAR(mp.centroid.z(), 0.0, 1e-12);
}

TEST(Clump, QuadratureConvergesToTheLensVolume) {
    const auto spheres = pair(1.0, 1.0, 1.3);
    const double v = 2.0 * sphere_volume(1.0) - g::lens_volume(1.0, 1.0, 1.3);
    double prev = 1.0;
    std::vector<double> errs;
    for (const int n : {100, 200, 400, 800}) {
        const double err = std::abs(g::union_mass_properties(spheres, n).volume / v - 1.0);
        EXPECT_LT(err, prev);
        prev = err;
        errs.push_back(err);
    }
    // Observed order over 100..800 (square-root edges of the column length give about 1.5).
    const double order = std::log2(errs.front() / errs.back()) / 3.0;
    constexpr double kMinOrder = 1.2; // the rule is at least O(n^-1.2) on this union
    EXPECT_GT(order, kMinOrder);
    EXPECT_LT(errs.back(), 1e-4);
}

TEST(Clump, InertiaAgreesWithMonteCarlo) {
    const std::vector<g::ClumpSphere> s = {
        {Vec3(0, 0, 0), 1.0}, {Vec3(1.2, 0.3, 0), 0.8}, {Vec3(0.2, 1.0, 0.6), 0.6}};
    const g::MassProperties mp = g::union_mass_properties(s, 1200);
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 2.2);
    const int n = 2000000;
    const double box = std::pow(3.2, 3);
    Mat3 second = Mat3::Zero();
    Vec3 first = Vec3::Zero();
    double hits = 0;
    g::Clump c;
    c.spheres = s;
    for (int i = 0; i < n; ++i) {
        const Vec3 p(u(rng), u(rng), u(rng));
        if (c.contains(p)) {
            hits += 1;
            first += p;
            second += p * p.transpose();
        }
    }
    const double v = box * hits / n;
    const Vec3 cm = first / hits;
    const Mat3 sec_c = box / n * second - v * cm * cm.transpose();
    const Mat3 inertia = sec_c.trace() * Mat3::Identity() - sec_c;
    constexpr double kMc = 5e-3; // 2e6 samples: relative standard error about 1e-3
    EXPECT_NEAR(mp.volume / v, 1.0, kMc);
    EXPECT_LT((mp.centroid - cm).norm(), kMc);
    EXPECT_LT((mp.inertia_centroid - inertia).cwiseAbs().maxCoeff() / inertia.norm(), kMc);
}

TEST(Clump, SymmetricClumpsAreSymmetricTops) {
    // A dimer and a ring of four equal spheres are symmetric about an axis, so two of their
    // principal moments are equal; the column quadrature gives them apart by up to its error
    // (1.2e-6 of the moments for the LIGGGHTS dimer). make_clump makes moments equal within its
    // volume error estimate, so the step turns these clumps by the symmetric top's exact flow.
    // An asymmetric clump keeps three different moments.
    const g::Clump dimer = g::make_clump(pair(2e-3, 2e-3, 2e-3), "dimer", 1200);
    EXPECT_EQ(g::symmetric_axis(dimer.inertia_unit_density), 0); // the dimer's axis, body x
    std::vector<g::ClumpSphere> ring;
    for (int k = 0; k < 4; ++k) {
        const double a = 0.5 * kPi * k + 0.3; // not along the grid's axes
        ring.push_back({Vec3(std::cos(a), std::sin(a), 0.0) * 2e-3, 1.5e-3});
    }
    const g::Clump r = g::make_clump(ring, "ring", 1200);
    EXPECT_GE(g::symmetric_axis(r.inertia_unit_density), 0);
    const g::Clump odd = g::make_clump(
        {{Vec3(0, 0, 0), 1.0}, {Vec3(1.5, 0, 0), 0.8}, {Vec3(0, 1.0, 0), 0.5}}, "odd", 800);
    EXPECT_EQ(g::symmetric_axis(odd.inertia_unit_density), -1);
    EXPECT_FALSE(g::spherical_top(odd.inertia_unit_density));
    // equal_within: the closest pair to its mean, all three to theirs, or none.
    const Vec3 two = g::equal_within(Vec3(1.0, 2.0, 2.0 + 1e-7), 1e-6);
    EXPECT_EQ(two.x(), 1.0);
    EXPECT_EQ(two.y(), two.z());
    EXPECT_NEAR(two.y(), 2.0 + 5e-8, 1e-15);
    const Vec3 three = g::equal_within(Vec3(1.0, 1.0 + 1e-7, 1.0 - 1e-7), 1e-6);
    EXPECT_TRUE(three.x() == three.y() && three.y() == three.z());
    EXPECT_NEAR(three.x(), 1.0, 1e-15);
    EXPECT_EQ(g::equal_within(Vec3(1.0, 2.0, 2.0 + 1e-5), 1e-6), Vec3(1.0, 2.0, 2.0 + 1e-5));
    EXPECT_EQ(g::equal_within(Vec3(1.0, 2.0, 2.0 + 1e-7), 0.0), Vec3(1.0, 2.0, 2.0 + 1e-7));
}

TEST(Clump, MakeClumpMovesToPrincipalFrameIndependentlyOfInputPose) {
    const std::vector<g::ClumpSphere> s = {
        {Vec3(0, 0, 0), 1.0}, {Vec3(1.5, 0, 0), 0.8}, {Vec3(0, 1.0, 0), 0.5}};
    const g::Clump a = g::make_clump(s, "a", 800);
    const kiln::Quat rot(Eigen::AngleAxisd(1.0, Vec3(1, 2, 3).normalized()));
    std::vector<g::ClumpSphere> moved;
    for (const auto& sp : s) {
        moved.push_back({rot * sp.centre + Vec3(5, -3, 2), sp.radius});
    }
    const g::Clump b = g::make_clump(moved, "b", 800);
    constexpr double kGrid = 2e-4; // different grids on the two poses: quadrature error only
    EXPECT_NEAR(a.volume / b.volume, 1.0, kGrid);
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(a.inertia_unit_density[k] / b.inertia_unit_density[k], 1.0, kGrid);
    }
    // In the body frame the inertia tensor of the spheres' union is diagonal with those moments,
    // and the centre of mass is at the origin.
    const g::MassProperties body = g::union_mass_properties(b.spheres, 800);
    EXPECT_LT(body.centroid.norm(), kGrid);
    Mat3 expected = b.inertia_unit_density.asDiagonal();
    EXPECT_LT((body.inertia_centroid - expected).cwiseAbs().maxCoeff() / expected.norm(), kGrid);
    EXPECT_GT(b.template_axes.determinant(), 0.0);
}

TEST(Clump, SurfaceAndShadowOfTwoSpheresAreExact) {
    const double r = 1.0;
    const double d = 1.2;
    const g::Clump c = g::make_clump(pair(r, r, d), "pair", 400);
    // Each sphere loses a cap of height h = r - d/2, area 2 pi r h.
    const double area = 2.0 * (4.0 * kPi * r * r - 2.0 * kPi * r * (r - 0.5 * d));
    const g::Estimate s = g::surface_area(c);
    constexpr double kArea = 1e-6; // midpoint latitude bands, 8000 per sphere
    EXPECT_NEAR(s.value / area, 1.0, kArea);
    // Shadow across the axis: two discs minus their lens, 2 r^2 acos(d/2r) - d/2 sqrt(4r^2 - d^2).
    const double lens =
        2.0 * r * r * std::acos(d / (2.0 * r)) - 0.5 * d * std::sqrt(4 * r * r - d * d);
    const Vec3 across = c.template_axes.transpose() * Vec3::UnitZ(); // input z in the body frame
    const g::Estimate shadow = g::projected_area(c, across);
    constexpr double kShadow = 1e-5; // 4000 exact chords across the shadow
    EXPECT_NEAR(shadow.value / (2.0 * kPi * r * r - lens), 1.0, kShadow);
}

TEST(Clump, BadInputIsAnInputError) {
    EXPECT_THROW((void)g::make_clump({}, "x", 100), kiln::InputError);
    EXPECT_THROW((void)g::make_clump({{Vec3::Zero(), -1.0}}, "x", 100), kiln::InputError);
}

TEST(Clump, NormalForceOfAMemberSphereGivesATorque) {
    // Two-sphere clump along x, pressed on its right sphere by a purely normal force along -z: the
    // force does not pass through the centre of mass, so it turns the clump (the seed's Eq. 24,
    // tangential force only, would give no torque).
    const g::Clump c = g::make_clump(pair(1.0, 1.0, 1.5), "pair", 400);
    const kiln::Quat q = kiln::Quat::Identity();
    const Vec3 com(0.0, 0.0, 0.0);
    // Body x is the long axis (smallest moment); the right sphere's top point in the world frame.
    const Vec3 right = q * c.spheres[0].centre.cwiseAbs();
    const Vec3 point = right + Vec3(0.0, 0.0, 1.0);
    g::Wrench w;
    g::add_contact(w, com, point, Vec3(0.0, 0.0, -2.0));
    EXPECT_NEAR(w.force.z(), -2.0, 1e-15);
    EXPECT_NEAR(w.torque.y(), 2.0 * right.x(), 1e-12);
    EXPECT_GT(std::abs(w.torque.y()), 1.0);
    // The seed's averaging: two equal contacts with one partner, weight 1/2 each, sum to one.
    g::Wrench avg;
    g::add_contact(avg, com, point, Vec3(0.0, 0.0, -2.0), 0.5);
    g::add_contact(avg, com, point, Vec3(0.0, 0.0, -2.0), 0.5);
    EXPECT_LT((avg.force - w.force).norm(), 1e-15);
}
