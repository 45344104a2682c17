// Validation 12: head-on elastic impact of two spheres described as superquadrics (e1 = e2 = 1,
// equal half-axes, random orientations), with the overlap and normal from the narrow phase
// (geometry::support_newton_contact) and the radius from the contact curvature
// (geometry::contact_curvature), against Hertz theory (Johnson 1985, Contact Mechanics, Sec. 11.1)
// in the setting of validation 01 (R = 10 mm, E = 48 GPa, nu = 0.2, 2800 kg/m^3, 10 m/s).
// Two checks: (1) the geometry alone, integrated here (velocity Verlet along the line of centres,
// the Hertz force written out): what a contact law receives; (2) the same impact run by System with
// the two bodies as superquadric particles (validation 01's case with the spheres replaced), which
// adds the body path of the step loop (element contacts, local radius, rotation).

#include "dynamics/system.hpp"
#include "geometry/convex_contact.hpp"
#include "validation.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <numbers>
#include <random>

namespace kiln::validation {
namespace {

/// Relative tolerance against Hertz theory: the 1 % asked for by the issue.
constexpr double hertz_tolerance = 0.01;
/// Relative: the same integration with the exact sphere geometry (delta = 2R - d, R* = R/2);
/// differences come from the narrow phase (1e-9 L gradient tolerance) and curvature (1e-8).
constexpr double geometry_tolerance = 1e-6;

constexpr double kRadius = 0.01;
constexpr double kYoung = 48e9;
constexpr double kPoisson = 0.2;
constexpr double kDensity = 2800.0;
constexpr double kSpeed = 10.0; // closing speed (m/s)
constexpr double kDt = 1e-8;    // s, about 4600 steps per contact as in validation 01

struct Impact {
    double max_overlap = 0.0;
    double max_force = 0.0;
    double contact_time = 0.0;
};

double e_star() {
    return 1.0 / (2.0 * (1.0 - kPoisson * kPoisson) / kYoung);
}

/// Integrates the approach along x; `superquadric` selects the geometry source.
Impact run(bool superquadric, const Quat& qa, const Quat& qb) {
    geometry::Superquadric s;
    s.half_axes = Vec3::Constant(kRadius);
    const double mass = kDensity * s.volume();
    const double m_star = 0.5 * mass;
    double x = 2.0 * kRadius + 1e-4; // centre distance (m)
    double v = -kSpeed;              // d(distance)/dt (m/s)
    Vec3 warm = Vec3::UnitX();
    bool touching = false;
    double t_first = 0.0;
    double t = 0.0;
    Impact out;
    const auto force = [&](double dist, double& overlap) {
        double r_eff = 0.5 * kRadius;
        overlap = 2.0 * kRadius - dist;
        if (superquadric) {
            const geometry::PosedSuperquadric a{&s, Vec3(dist, 0.0, 0.0), qa};
            const geometry::PosedSuperquadric b{&s, Vec3::Zero(), qb};
            const geometry::ConvexContact c = geometry::support_newton_contact(a, b, &warm);
            EXPECT_TRUE(c.converged);
            overlap = c.depth;
            if (c.touching) {
                warm = c.normal;
                r_eff = geometry::contact_curvature(a, b, c).effective_radius;
            }
        }
        return overlap > 0.0 ? 4.0 / 3.0 * e_star() * std::sqrt(r_eff) * std::pow(overlap, 1.5)
                             : 0.0;
    };
    double overlap = 0.0;
    double f = force(x, overlap);
    while (t < 1e-4) {
        v += 0.5 * kDt * f / m_star;
        x += kDt * v;
        t += kDt;
        f = force(x, overlap);
        v += 0.5 * kDt * f / m_star;
        if (overlap > 0.0 && !touching) {
            touching = true;
            t_first = t;
        }
        if (touching && overlap <= 0.0) {
            out.contact_time = t - t_first;
            break;
        }
        out.max_overlap = std::max(out.max_overlap, overlap);
        out.max_force = std::max(out.max_force, f);
    }
    return out;
}

TEST(SuperquadricSphereImpact, MatchesHertzTheory) {
    reset_results();
    const double m_star = 0.5 * kDensity * 4.0 / 3.0 * std::numbers::pi * std::pow(kRadius, 3);
    const double r_star = 0.5 * kRadius;
    const double delta =
        std::pow(15.0 * m_star * kSpeed * kSpeed / (16.0 * e_star() * std::sqrt(r_star)), 0.4);
    const double force = 4.0 / 3.0 * e_star() * std::sqrt(r_star) * std::pow(delta, 1.5);
    const double time =
        2.0 * 0.4 * std::tgamma(0.4) * std::tgamma(0.5) / std::tgamma(0.9) * delta / kSpeed;

    std::mt19937_64 rng(12);
    std::normal_distribution<double> nd;
    const Quat qa = Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized();
    const Quat qb = Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized();
    const Impact sq = run(true, qa, qb);
    const Impact sp = run(false, qa, qb);
    record("max overlap (superquadric)", sq.max_overlap, delta, hertz_tolerance, "m");
    record("max force (superquadric)", sq.max_force, force, hertz_tolerance, "N");
    record("contact time (superquadric)", sq.contact_time, time, hertz_tolerance, "s");
    EXPECT_NEAR(sq.max_overlap / delta, 1.0, hertz_tolerance);
    EXPECT_NEAR(sq.max_force / force, 1.0, hertz_tolerance);
    EXPECT_NEAR(sq.contact_time / time, 1.0, hertz_tolerance);
    record("max overlap vs sphere geometry", sq.max_overlap, sp.max_overlap, geometry_tolerance,
           "m");
    record("max force vs sphere geometry", sq.max_force, sp.max_force, geometry_tolerance, "N");
    record("contact time vs sphere geometry", sq.contact_time, sp.contact_time, geometry_tolerance,
           "s");
    EXPECT_NEAR(sq.max_overlap / sp.max_overlap, 1.0, geometry_tolerance);
    EXPECT_NEAR(sq.max_force / sp.max_force, 1.0, geometry_tolerance);
    EXPECT_NEAR(sq.contact_time / sp.contact_time, 1.0, geometry_tolerance);

    // Near the sphere the local radius is not continuous in the exponent: at the pole of a
    // superball the curvature is 0 for e < 1 and infinite for e > 1 (reported, see README.md).
    for (const double e : {0.95, 1.05}) {
        geometry::Superquadric s;
        s.half_axes = Vec3::Constant(kRadius);
        s.e1 = e;
        s.e2 = e;
        const auto k = s.principal_curvatures(Vec3(0.0, 0.0, kRadius));
        record("pole curvature, e = " + std::to_string(e).substr(0, 4) + " (info)", k[0],
               1.0 / kRadius, 0.0, "1/m");
        EXPECT_TRUE(e < 1.0 ? k[1] == 0.0 : std::isinf(k[0]));
    }
}

/// Validation 01's scene (two 10 mm spheres closing at 10 m/s, elastic, frictionless) with each
/// sphere replaced by a superquadric particle of equal half-axes, e1 = e2 = 1, random orientation.
dynamics::SceneSpec superquadric_scene() {
    const io::CaseSpec spec =
        io::read_case_file(std::string(KILN_CASE_DIR) + "/../01_hertz_impact/case.toml");
    dynamics::SceneSpec scene = spec.scene;
    geometry::Superquadric s;
    s.half_axes = Vec3::Constant(kRadius);
    scene.shapes.push_back(geometry::make_template("sphere_sq", s));
    for (dynamics::ParticleSpec& p : scene.particles) {
        p.shape = 0;
        p.radius = scene.shapes[0].bounding_radius();
        p.orientation.random = true;
    }
    return scene;
}

TEST(SuperquadricSphereImpact, InSystemMatchesHertzTheory) {
    const dynamics::SceneSpec scene = superquadric_scene();
    ASSERT_EQ(scene.particles.size(), 2U);
    const double m_star = 0.5 * kDensity * 4.0 / 3.0 * std::numbers::pi * std::pow(kRadius, 3);
    const double r_star = 0.5 * kRadius;
    const double speed = (scene.particles[0].v - scene.particles[1].v).norm();
    const double delta =
        std::pow(15.0 * m_star * speed * speed / (16.0 * e_star() * std::sqrt(r_star)), 0.4);
    const double force = 4.0 / 3.0 * e_star() * std::sqrt(r_star) * std::pow(delta, 1.5);
    const double time =
        2.0 * 0.4 * std::tgamma(0.4) * std::tgamma(0.5) / std::tgamma(0.9) * delta / speed;

    dynamics::System sys(scene);
    ASSERT_GE(sys.particles().shape[0], 0); // really bodies, not the sphere path
    const auto overlap = [&] {
        const ParticleStore& p = sys.particles();
        return 2.0 * kRadius - (p.x[0] - p.x[1]).norm();
    };
    double delta_max = 0.0;
    double force_max = 0.0;
    double t_start = -1.0;
    double t_end = -1.0;
    double prev_t = sys.time();
    double prev_d = overlap();
    while (sys.time() < 1e-4 && t_end < 0.0) {
        sys.step();
        const double d = overlap();
        delta_max = std::max(delta_max, d);
        force_max = std::max(force_max, sys.particles().force[0].norm());
        if (prev_d <= 0.0 && d > 0.0) {
            t_start = prev_t + (sys.time() - prev_t) * (-prev_d) / (d - prev_d);
        } else if (prev_d > 0.0 && d <= 0.0) {
            t_end = prev_t + (sys.time() - prev_t) * (-prev_d) / (d - prev_d);
        }
        prev_t = sys.time();
        prev_d = d;
    }
    ASSERT_GE(t_start, 0.0) << "no contact within 1e-4 s";
    ASSERT_GT(t_end, t_start) << "the contact did not end within 1e-4 s";
    record("System: max overlap", delta_max, delta, hertz_tolerance, "m");
    record("System: max force", force_max, force, hertz_tolerance, "N");
    record("System: contact time", t_end - t_start, time, hertz_tolerance, "s");
    EXPECT_NEAR(delta_max / delta, 1.0, hertz_tolerance);
    EXPECT_NEAR(force_max / force, 1.0, hertz_tolerance);
    EXPECT_NEAR((t_end - t_start) / time, 1.0, hertz_tolerance);
    EXPECT_EQ(sys.narrow_phase_counters().failures, 0);
}

} // namespace
} // namespace kiln::validation
