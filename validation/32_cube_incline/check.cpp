// Validation 32: a cube on an inclined plane sticks below the friction angle and slides above it
// with the rigid-body acceleration g (sin a - mu cos a), without toppling. See README.md.

#include "dynamics/system.hpp"
#include "geometry/polyhedron_contact.hpp"
#include "validation.hpp"

#include <cmath>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <numbers>

namespace kiln::validation {
namespace {

constexpr double g = 9.81;
constexpr double mu = 0.5;
/// Time to settle on the plane before measuring (s): the landing transient of 10 um.
constexpr double settle = 0.05;
/// Sliding: relative deviation of the fitted acceleration from g (sin a - mu cos a). The contact
/// point moves between the lower vertices as the cube pitches on its tangential spring; 2 %.
constexpr double accel_tolerance = 0.02;
/// Sticking: largest drift along the slope over the 0.1 s measured, relative to the edge 2.26 mm
/// (the Mindlin spring creeps by its elastic displacement only, about a micrometre).
constexpr double stick_tolerance = 1e-3;
/// No toppling: largest spin allowed while sliding (rad/s).
constexpr double max_spin = 1.0;

struct Slide {
    double accel = 0; ///< least-squares slope of v_x over the measured window (m/s^2)
    double drift = 0; ///< x displacement over the window (m)
    double max_w = 0; ///< largest spin in the window (rad/s)
};

Slide run(double angle_deg) {
    io::CaseSpec spec = load_case();
    const double a = angle_deg * std::numbers::pi / 180.0;
    spec.scene.gravity = g * Vec3(std::sin(a), 0.0, -std::cos(a));
    // A face down: the template's first face normal turned to -z.
    const auto& cube = std::get<geometry::ConvexPolyhedron>(spec.scene.shapes.at(0).shape);
    const Vec3 n = geometry::polyhedron_features(cube).face_normals.at(0);
    const Vec3 axis = n.cross(Vec3(0, 0, -1));
    spec.scene.particles.at(0).orientation.fixed =
        axis.norm() < 1e-12
            ? (n.z() < 0 ? Quat::Identity()
                         : Quat(Eigen::AngleAxisd(std::numbers::pi, Vec3::UnitX())))
            : Quat(Eigen::AngleAxisd(std::atan2(axis.norm(), -n.z()), axis.normalized()));
    spec.scene.allow_unsafe_time_step = false;
    dynamics::System sys(spec.scene);
    const auto& p = sys.particles();
    const long settle_steps = std::lround(settle / sys.dt());
    const long steps = std::lround(spec.run.end_time / sys.dt());
    double st = 0, sv = 0, stt = 0, stv = 0;
    long n_fit = 0;
    double x0 = 0;
    Slide out;
    for (long s = 0; s < steps; ++s) {
        sys.step();
        if (s == settle_steps) {
            x0 = p.x[0].x();
        }
        if (s > settle_steps) {
            const double t = sys.time();
            const double v = p.v[0].x();
            st += t;
            sv += v;
            stt += t * t;
            stv += t * v;
            ++n_fit;
            out.max_w = std::max(out.max_w, p.omega[0].norm());
        }
    }
    const auto nf = static_cast<double>(n_fit);
    out.accel = (nf * stv - st * sv) / (nf * stt - st * st);
    out.drift = p.x[0].x() - x0;
    return out;
}

TEST(CubeIncline, SticksBelowTheFrictionAngle) {
    reset_results();
    for (const double angle : {10.0, 20.0, 25.0}) {
        const Slide s = run(angle);
        record(fmt::format("drift / edge at {:g} deg", angle), s.drift / 2.26e-3, 0.0,
               stick_tolerance, "-");
        EXPECT_LT(std::abs(s.drift) / 2.26e-3, stick_tolerance) << angle << " deg";
    }
}

TEST(CubeIncline, SlidesAboveItWithTheRigidBodyAcceleration) {
    for (const double angle : {30.0, 40.0, 50.0}) {
        const double a = angle * std::numbers::pi / 180.0;
        const double expected = g * (std::sin(a) - mu * std::cos(a));
        const Slide s = run(angle);
        record(fmt::format("acceleration at {:g} deg", angle), s.accel, expected, accel_tolerance,
               "m/s^2");
        record(fmt::format("largest spin at {:g} deg", angle), s.max_w, 0.0, max_spin, "rad/s");
        EXPECT_NEAR(s.accel / expected, 1.0, accel_tolerance) << angle << " deg";
        EXPECT_LT(s.max_w, max_spin) << angle << " deg: the cube tumbles";
    }
}

} // namespace
} // namespace kiln::validation
