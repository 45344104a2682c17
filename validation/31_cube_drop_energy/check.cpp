// Validation 31: an elastic, frictionless cube dropped on a plane face-, edge- and corner-down
// keeps its total energy (kinetic + rotational + potential + elastic) up to an integrator error
// that shrinks with the time step. See README.md.

#include "dynamics/system.hpp"
#include "geometry/polyhedron_contact.hpp"
#include "validation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <string>
#include <vector>

namespace kiln::validation {
namespace {

/// Step sizes relative to the case's time step.
constexpr std::array<double, 3> step_factors{1.0, 0.5, 0.25};
/// Largest relative energy error at dt/4 (of the energy above the plane): one body, a few
/// contact onsets of a sharp feature; the sphere drop of validation 04 reaches 1e-5.
constexpr double finest_bound = 2e-3;
/// The error must fall by at least this factor from dt to dt/4 (second order would give 16).
constexpr double min_reduction = 3.0;

/// A rotation (body -> world) that points the body-frame direction d straight down.
Quat pointing_down(const Vec3& d) {
    const Vec3 u = d.normalized();
    const Vec3 down(0, 0, -1);
    const Vec3 axis = u.cross(down);
    if (axis.norm() < 1e-12) {
        return u.dot(down) > 0 ? Quat::Identity() : Quat(Eigen::AngleAxisd(M_PI, Vec3::UnitX()));
    }
    return Quat(Eigen::AngleAxisd(std::atan2(axis.norm(), u.dot(down)), axis.normalized()));
}

/// Body-frame directions of the features that lead (m for the corner, unit for face and edge).
struct Leading {
    Vec3 face;   ///< outward face normal
    Vec3 edge;   ///< bisector of the normals of two adjacent faces
    Vec3 corner; ///< a vertex
};

/// The leading features picked by geometry, not by their index in the template: the face normal
/// closest to a fixed body direction, the adjacent face normal closest to a second one, the vertex
/// farthest along a third. So the scenario does not depend on the vertex and face order the hull
/// happens to produce.
Leading leading_features(const geometry::PolyhedronFeatures& f) {
    const auto best = [](const std::vector<Vec3>& v, const Vec3& g, auto&& keep) {
        const Vec3* out = nullptr;
        for (const Vec3& x : v) {
            if (keep(x) && (out == nullptr || x.dot(g) > out->dot(g))) {
                out = &x;
            }
        }
        return *out;
    };
    const auto any = [](const Vec3&) { return true; };
    const Vec3 n0 = best(f.face_normals, Vec3(0.9, 0.3, 0.1), any);
    const Vec3 n1 = best(f.face_normals, Vec3(0.1, 0.9, 0.3),
                         [&](const Vec3& n) { return std::abs(n.dot(n0)) < 0.5; });
    return {n0, n0 + n1, best(f.vertices, Vec3(0.3, 0.1, 0.9), any)};
}

struct Drop {
    double max_error = 0;   ///< max |E - E0| / (E0 - E_rest) (-)
    long contact_steps = 0; ///< steps with a wall contact
    double max_omega = 0;   ///< largest spin seen (rad/s)
};

Drop drop(io::CaseSpec spec, const Quat& q, double dt) {
    spec.scene.time_step = dt;
    spec.scene.particles.at(0).orientation.fixed = q;
    dynamics::System sys(spec.scene);
    // Energy above the cube resting on a face: the scale of the relative error.
    const auto& p = sys.particles();
    const double e0 = sys.energies().total();
    const double rest = p.mass[0] * 9.81 * 1.13e-3;
    Drop out;
    const long steps = std::lround(spec.run.end_time / dt);
    for (long s = 0; s < steps; ++s) {
        sys.step();
        out.max_error =
            std::max(out.max_error, std::abs(sys.energies().total() - e0) / (e0 - rest));
        out.contact_steps += sys.counters().wall_contacts > 0 ? 1 : 0;
        out.max_omega = std::max(out.max_omega, p.omega[0].norm());
    }
    return out;
}

TEST(CubeDrop, FaceEdgeAndCornerKeepTheirEnergy) {
    reset_results();
    const io::CaseSpec spec = load_case();
    const auto& cube = std::get<geometry::ConvexPolyhedron>(spec.scene.shapes.at(0).shape);
    const geometry::PolyhedronFeatures f = geometry::polyhedron_features(cube);
    ASSERT_EQ(f.face_normals.size(), 6U);
    const Leading lead = leading_features(f);
    const std::array<std::pair<std::string, Quat>, 3> cases{
        {{"face", pointing_down(lead.face)},
         {"edge", pointing_down(lead.edge)},
         {"corner", pointing_down(lead.corner)}}};
    // A small tilt (0.1 rad) so that the contact is off-centre and the cube rocks and spins: the
    // torques and the rotation update are tested too.
    const Quat tilt(Eigen::AngleAxisd(0.1, Vec3(1.0, 0.3, 0.0).normalized()));
    for (const auto& [label, q0] : cases) {
        const Quat q = tilt * q0;
        std::vector<double> errors;
        for (const double fac : step_factors) {
            const double dt = spec.scene.time_step * fac;
            const Drop d = drop(spec, q, dt);
            EXPECT_GT(d.contact_steps, 10) << label << ": the cube never touched the plane";
            errors.push_back(d.max_error);
            record(fmt::format("{} max rel. energy error at dt = {:g} s", label, dt), d.max_error,
                   0.0, fac == step_factors.back() ? finest_bound : 0.0, "-");
            record(fmt::format("{} largest spin at dt = {:g} s", label, dt), d.max_omega, 0.0, 0.0,
                   "rad/s");
        }
        const double reduction = errors.front() / errors.back();
        record(label + " error reduction dt -> dt/4", reduction, 16.0, 0.0, "-");
        EXPECT_LT(errors.back(), finest_bound) << label;
        EXPECT_GT(reduction, min_reduction) << label;
    }
}

/// A rotation (body -> world) that turns the body-frame direction d onto the world direction t.
Quat pointing(const Vec3& d, const Vec3& t) {
    const Vec3 u = d.normalized();
    const Vec3 w = t.normalized();
    const Vec3 axis = u.cross(w);
    if (axis.norm() < 1e-12) {
        return u.dot(w) > 0 ? Quat::Identity() : Quat(Eigen::AngleAxisd(M_PI, u.unitOrthogonal()));
    }
    return Quat(Eigen::AngleAxisd(std::atan2(axis.norm(), u.dot(w)), axis.normalized()));
}

/// Largest relative energy error of a cube pair at dt/4: two bodies, whose common-plane contact
/// point is the patch centroid rather than the gradient point (docs/theory/contact.md).
constexpr double pair_finest_bound = 2e-3;

/// Two elastic cubes in free space, the first moving at 0.5 m/s towards the second with feature
/// direction d0 (body frame of the first) leading and the second presenting a face; both
/// tilted and spinning a little so that the impact is off-centre. Returns the largest
/// |E - E0| / E0 over the run (E: kinetic + rotational + elastic) and the contact steps.
Drop pair(io::CaseSpec spec, const Vec3& d0, const Vec3& face, dynamics::NarrowPhase method,
          double dt) {
    spec.scene.time_step = dt;
    spec.scene.narrow_phase = method;
    spec.scene.walls.clear();
    spec.scene.gravity.setZero();
    dynamics::ParticleSpec a = spec.scene.particles.at(0);
    dynamics::ParticleSpec b = a;
    const Quat tilt(Eigen::AngleAxisd(0.1, Vec3(0.2, 1.0, 0.4).normalized()));
    a.orientation.fixed = tilt * pointing(d0, Vec3::UnitX());
    b.orientation.fixed = tilt.conjugate() * pointing(face, -Vec3::UnitX());
    // Each body's extent along the line of approach: 10 um apart at the start.
    const auto& cube = std::get<geometry::ConvexPolyhedron>(spec.scene.shapes.at(0).shape);
    const double ha = Vec3::UnitX().dot(
        a.orientation.fixed * cube.support(a.orientation.fixed.conjugate() * Vec3::UnitX()));
    const double hb = Vec3::UnitX().dot(
        b.orientation.fixed * cube.support(b.orientation.fixed.conjugate() * -Vec3::UnitX()));
    a.x = Vec3(-ha - 5e-6, 0.2e-3, -0.1e-3);
    b.x = Vec3(-hb + 5e-6, -0.2e-3, 0.1e-3);
    a.v = Vec3(0.5, 0.0, 0.0);
    b.v = Vec3::Zero();
    a.omega = Vec3(0.0, 30.0, -20.0);
    b.omega = Vec3(10.0, 0.0, 15.0);
    spec.scene.particles = {a, b};
    dynamics::System sys(spec.scene);
    const double e0 = sys.energies().total();
    Drop out;
    // They touch after ~2e-5 s, the Hertz contact lasts ~1e-4 s; 1e-3 s lets the cubes part (and a
    // possible second touch of the rocking pair happen).
    const long steps = std::lround(1e-3 / dt);
    for (long s = 0; s < steps; ++s) {
        sys.step();
        out.max_error = std::max(out.max_error, std::abs(sys.energies().total() - e0) / e0);
        out.contact_steps += sys.counters().particle_contacts > 0 ? 1 : 0;
        out.max_omega = std::max(out.max_omega, sys.particles().omega[0].norm());
    }
    return out;
}

TEST(CubePair, FaceEdgeAndCornerCollisionsKeepTheirEnergy) {
    const io::CaseSpec spec = load_case();
    const auto& cube = std::get<geometry::ConvexPolyhedron>(spec.scene.shapes.at(0).shape);
    const geometry::PolyhedronFeatures f = geometry::polyhedron_features(cube);
    const Leading lead = leading_features(f);
    const Vec3 n0 = lead.face;
    const std::array<std::pair<std::string, Vec3>, 3> cases{
        {{"face", lead.face}, {"edge", lead.edge}, {"corner", lead.corner}}};
    for (const auto method : {dynamics::NarrowPhase::newton, dynamics::NarrowPhase::gjk_epa}) {
        const std::string tag =
            method == dynamics::NarrowPhase::newton ? "common plane" : "GJK/EPA";
        for (const auto& [label, d0] : cases) {
            std::vector<double> errors;
            for (const double fac : step_factors) {
                const double dt = spec.scene.time_step * fac;
                const Drop d = pair(spec, d0, n0, method, dt);
                EXPECT_GT(d.contact_steps, 10) << label << ": the cubes never touched";
                errors.push_back(d.max_error);
                record(
                    fmt::format("pair {} {} max rel. energy error at dt = {:g} s", tag, label, dt),
                    d.max_error, 0.0, fac == step_factors.back() ? pair_finest_bound : 0.0, "-");
            }
            const double reduction = errors.front() / errors.back();
            record(fmt::format("pair {} {} error reduction dt -> dt/4", tag, label), reduction,
                   16.0, 0.0, "-");
            EXPECT_LT(errors.back(), pair_finest_bound) << tag << " " << label;
            EXPECT_GT(reduction, min_reduction) << tag << " " << label;
        }
    }
}

} // namespace
} // namespace kiln::validation
