// Rolling resistance on body contacts and the effective radius of bodies against curved walls.

#include "body_scene.hpp"
#include "dynamics/body_contact.hpp"
#include "geometry/clump.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <numbers>
#include <vector>

namespace kiln::dynamics {
namespace {

using test::base_scene;
using test::body;
using test::superquadric;

constexpr double g = 9.81;        // m/s^2
constexpr double mu_r = 0.05;     // rolling friction coefficient of the tests (-)
constexpr double v0 = 0.2;        // initial rolling speed (m/s)
constexpr double t_settle = 0.01; // s; the drop onto the static overlap has rung down by then
constexpr double t_end = 0.11;    // s

/// Rolls particle 0 of `s` along +x on a floor (it starts rolling without slip about the world y
/// axis at height `h`) and returns its mean deceleration between t_settle and t_end (m/s^2).
double deceleration(SceneSpec s, double radius, const Quat& q) {
    s.walls.push_back({"floor", PlaneWall{Vec3::Zero(), Vec3::UnitZ()}, 0});
    s.contact.rolling = contact::RollingModel::constant_torque;
    s.particles.push_back(body(0, Vec3(0, 0, radius), Vec3(v0, 0, 0), Vec3(0, v0 / radius, 0), q));
    System sys(s);
    double v1 = 0.0;
    const long n1 = std::lround(t_settle / s.time_step);
    const long n2 = std::lround(t_end / s.time_step);
    for (long k = 0; k < n2; ++k) {
        sys.step();
        if (k + 1 == n1) {
            v1 = sys.particles().v[0].x();
        }
    }
    EXPECT_GT(sys.counters().wall_contacts, 0);
    // Still rolling, not sliding: the contact point is (almost) at rest.
    const ParticleStore& p = sys.particles();
    const Vec3 slip = p.v[0] + p.omega[0].cross(Vec3(0, 0, -radius));
    constexpr double rolling = 1e-3; // m/s, residual slip of the tangential spring
    EXPECT_LT(std::abs(slip.x()), rolling);
    return (v1 - p.v[0].x()) / (t_end - t_settle);
}

/// Relative error allowed on the deceleration: the normal force oscillates about the weight after
/// the landing (damped, e = 0.5) and the tangential spring stores a little energy (measured
/// 2e-4 for both bodies).
constexpr double law_tolerance = 2e-3;

TEST(BodyRolling, SuperquadricSphereDeceleratesAsTheConstantTorqueLawSays) {
    // A superquadric with exponents 1 and equal half-axes is a sphere: R* = r on the floor, torque
    // mu_r r m g, and rolling without slip gives a = mu_r g r^2 / (I/m + r^2) = 5/7 mu_r g.
    constexpr double r = 2e-3;
    SceneSpec s = base_scene();
    s.materials[0].friction = 0.5;
    s.materials[0].rolling_friction = mu_r;
    s.shapes.push_back(superquadric(Vec3::Constant(r), 1.0, 1.0));
    const double expected = 5.0 / 7.0 * mu_r * g;
    EXPECT_NEAR(deceleration(s, r, Quat::Identity()) / expected, 1.0, law_tolerance);
    // Without the rolling friction coefficient the same body rolls on (the law is what slows it).
    s.materials[0].rolling_friction = 0.0;
    EXPECT_LT(std::abs(deceleration(s, r, Quat::Identity())), law_tolerance * expected);
}

TEST(BodyRolling, TwoSphereClumpRollingOnBothSpheresDeceleratesAsTheLawSays) {
    // Two overlapping spheres on one axis, rolling about that axis on both: each sphere contact has
    // R* = r, so the torques sum to mu_r r m g; a = mu_r g r^2 / (I_axis/m + r^2).
    constexpr double r = 1.5e-3;
    SceneSpec s = base_scene();
    s.materials[0].friction = 0.5;
    s.materials[0].rolling_friction = mu_r;
    const geometry::Clump c =
        geometry::make_clump({{Vec3(0, -1.2e-3, 0), r}, {Vec3(0, 1.2e-3, 0), r}}, "dumbbell");
    s.shapes.push_back(geometry::make_template("dumbbell", c));
    // Body-frame axis through both centres, turned onto world y.
    const Vec3 axis = (c.spheres[1].centre - c.spheres[0].centre).normalized();
    const Vec3 turn = axis.cross(Vec3::UnitY());
    const Quat q =
        turn.norm() < 1e-12
            ? Quat::Identity()
            : Quat(Eigen::AngleAxisd(std::atan2(turn.norm(), axis.y()), turn.normalized()));
    const double inertia_axis =
        axis.dot(s.shapes[0].inertia_unit_density.asDiagonal() * axis) / s.shapes[0].volume;
    const double expected = mu_r * g * r * r / (inertia_axis + r * r);
    EXPECT_NEAR(deceleration(s, r, q) / expected, 1.0, law_tolerance);
}

TEST(BodyRolling, SuperquadricInsideACylinderWallFeelsTheConcaveCurvature) {
    // A sphere-shaped superquadric touching the inside of a cylinder: the wall is curved along its
    // circumference only, so the relative curvatures are 1/r (along the axis) and 1/r - 1/R
    // (around it), and R* = 1/sqrt(1/r (1/r - 1/R)) (Johnson 1985, Sec. 4.2).
    constexpr double r = 2e-3;
    constexpr double wall = 5e-3;
    const geometry::ShapeTemplate t = superquadric(Vec3::Constant(r), 1.0, 1.0);
    std::vector<Element> e;
    const Quat q(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized())); // any pose: it is a sphere
    append_elements(&t, Vec3(wall - r + 1e-6, 0, 0), q, t.bounding_radius(), e);
    const CylinderWall cyl{Vec3::Zero(), Vec3::UnitZ(), wall};
    const ElementContact c = element_wall_contact(e[0], cyl);
    ASSERT_TRUE(c.touching);
    constexpr double overlap_rounding = 1e-12; // m, support point of an exact sphere
    EXPECT_NEAR(c.overlap, 1e-6, overlap_rounding);
    const double expected = 1.0 / std::sqrt(1.0 / r * (1.0 / r - 1.0 / wall));
    constexpr double curvature_rounding = 1e-6; // relative; curvature tensor of the implicit form
    EXPECT_NEAR(c.r_eff / expected, 1.0, curvature_rounding);
    // A plane through the same point keeps R* = r: only the cylinder is concave.
    const ElementContact flat =
        element_wall_contact(e[0], PlaneWall{Vec3(wall, 0, 0), Vec3(-1, 0, 0)});
    EXPECT_NEAR(flat.r_eff / r, 1.0, curvature_rounding);
}

TEST(BodyRolling, SphereInsideACylinderWallGetsTheBodyRuleRadius) {
    // The sphere kernel's cylinder rule (also used by clump members) is the body rule for a sphere:
    // R* = 1/sqrt(1/r (1/r - 1/R)) = 2.58 mm for r = 2 mm in R = 5 mm (Johnson 1985, Sec. 4.2),
    // not 1/(1/r - 1/R) = 3.33 mm; in a tube narrower than 2r the smaller relative curvature is
    // floored at 1/(2r) on both paths. Checked against the superquadric sphere at the same place.
    constexpr double r = 2e-3;
    const geometry::ShapeTemplate t = superquadric(Vec3::Constant(r), 1.0, 1.0);
    constexpr double curvature_rounding = 1e-6; // relative; curvature tensor of the implicit form
    for (const double wall : {5e-3, 3e-3, 20e-3}) {
        const CylinderWall cyl{Vec3::Zero(), Vec3::UnitZ(), wall};
        const Vec3 x(wall - r + 1e-6, 0, 0);
        const WallContact sphere = wall_contact(cyl, x, r);
        std::vector<Element> e;
        append_elements(&t, x, Quat::Identity(), t.bounding_radius(), e);
        const ElementContact body = element_wall_contact(e[0], cyl);
        ASSERT_TRUE(body.touching);
        // The body rule floors at 1/(2L), L its bounding radius, which carries a 1e-3 margin.
        constexpr double margin = 1e-3;
        EXPECT_NEAR(sphere.r_eff / body.r_eff, 1.0, wall < 2.0 * r ? margin : curvature_rounding)
            << "R = " << wall;
        const double expected = 1.0 / std::sqrt(1.0 / r * std::max(1.0 / r - 1.0 / wall, 0.5 / r));
        EXPECT_NEAR(sphere.r_eff / expected, 1.0, 1e-14) << "R = " << wall; // closed form
    }
    EXPECT_NEAR(
        wall_contact(CylinderWall{Vec3::Zero(), Vec3::UnitZ(), 5e-3}, Vec3(3e-3, 0, 0), r).r_eff,
        2e-3 * std::sqrt(5.0 / 3.0), 1e-15);
}

TEST(BodyRolling, EllipsoidInsideACylinderWallUsesItsOwnCurvatures) {
    // Ellipsoid with half-axes (a, b, c) touching the wall with the tip of a (along the wall's
    // radius), b around the circumference, c along the axis. At that tip the body curvatures are
    // a/b^2 (around) and a/c^2 (along); the wall removes 1/R from the first only.
    constexpr double a = 3e-3;
    constexpr double b = 2e-3;
    constexpr double c = 1.5e-3;
    constexpr double wall = 10e-3;
    const geometry::ShapeTemplate t = superquadric(Vec3(a, b, c), 1.0, 1.0);
    // Body x along world x (radius), body y along world y (around), body z along the axis.
    std::vector<Element> e;
    append_elements(&t, Vec3(wall - a + 1e-7, 0, 0), Quat::Identity(), t.bounding_radius(), e);
    const ElementContact ct =
        element_wall_contact(e[0], CylinderWall{Vec3::Zero(), Vec3::UnitZ(), wall});
    ASSERT_TRUE(ct.touching);
    const double k_around = a / (b * b) - 1.0 / wall;
    const double k_along = a / (c * c);
    const double expected = 1.0 / std::sqrt(k_around * k_along);
    constexpr double curvature_rounding = 1e-6; // relative
    EXPECT_NEAR(ct.r_eff / expected, 1.0, curvature_rounding);
    // Turned by 90 degrees about x (c around, b along): the wall now reduces a/c^2.
    std::vector<Element> f;
    append_elements(&t, Vec3(wall - a + 1e-7, 0, 0),
                    Quat(Eigen::AngleAxisd(0.5 * std::numbers::pi, Vec3::UnitX())),
                    t.bounding_radius(), f);
    const ElementContact cf =
        element_wall_contact(f[0], CylinderWall{Vec3::Zero(), Vec3::UnitZ(), wall});
    ASSERT_TRUE(cf.touching);
    const double turned = 1.0 / std::sqrt((a / (c * c) - 1.0 / wall) * (a / (b * b)));
    EXPECT_NEAR(cf.r_eff / turned, 1.0, curvature_rounding);
}

} // namespace
} // namespace kiln::dynamics
