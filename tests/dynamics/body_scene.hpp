#pragma once
// Helpers shared by the tests of bodies in the step loop (test_bodies, test_polyhedra,
// test_body_rolling): templates by name, a one-material scene, a plane or mesh floor, placed
// bodies, a face-down polyhedron, the momenta the invariants are checked on, and the comparison
// of two runs bit for bit. World frame throughout.

#include "common/wall_box.hpp"
#include "dynamics/system.hpp"
#include "geometry/mesh_wall.hpp"
#include "geometry/polyhedron_contact.hpp"
#include "geometry/shape.hpp"
#include "io/shape_reader.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <memory>
#include <numbers>
#include <string>

namespace kiln::dynamics::test {

/// Template `name` from the shipped shapes/ folder.
inline geometry::ShapeTemplate shape(const std::string& name) {
    return io::read_shape_file(io::find_shape_file(name, io::default_shape_dirs()));
}

/// Superquadric template with half-axes (m, body frame) and exponents e1, e2.
inline geometry::ShapeTemplate superquadric(const Vec3& half_axes, double e1, double e2) {
    geometry::Superquadric q;
    q.half_axes = half_axes;
    q.e1 = e1;
    q.e2 = e2;
    return geometry::make_template("sq", q);
}

/// One material "m" (E = 1e7 Pa, nu = 0.3, 2500 kg/m^3, e = 0.5, mu = 0.3), dt = 2e-6 s, default
/// gravity (-9.81 m/s^2 along z).
inline SceneSpec base_scene() {
    SceneSpec s;
    s.materials.push_back({"m", 1e7, 0.3, 2500, 0.5, 0.3, 0.0});
    s.time_step = 2e-6;
    return s;
}

/// Adds a floor of material 0 at z = 0 facing +z: the analytic plane, or, when `mesh`, the top
/// face of the 20 mm box read from shapes/wall_box_20mm.stl (two triangles sharing a diagonal).
inline void add_floor(SceneSpec& s, bool mesh) {
    if (mesh) {
        const io::MeshInput m = kiln::test::wall_box_20mm();
        s.mesh_walls.push_back(
            {"floor", std::make_shared<const geometry::MeshWall>(m.points, m.triangles, "box"), 0});
    } else {
        s.walls.push_back({"floor", PlaneWall{Vec3::Zero(), Vec3::UnitZ()}, 0});
    }
}

/// Orientation (body -> world) that turns the first face of polyhedron `poly` to face down (its
/// outward normal along -z in the world frame).
inline Quat face_down(const geometry::ConvexPolyhedron& poly) {
    const Vec3 n = geometry::polyhedron_features(poly).face_normals.at(0);
    const Vec3 axis = n.cross(Vec3(0, 0, -1));
    if (axis.norm() < 1e-12) {
        return n.z() < 0 ? Quat::Identity()
                         : Quat(Eigen::AngleAxisd(std::numbers::pi, Vec3::UnitX()));
    }
    return Quat(Eigen::AngleAxisd(std::atan2(axis.norm(), -n.z()), axis.normalized()));
}

/// A particle of template `shape_index` at x (m) with velocity v (m/s), angular velocity omega
/// (rad/s) and orientation q (body -> world).
inline ParticleSpec body(int shape_index, const Vec3& x, const Vec3& v = Vec3::Zero(),
                         const Vec3& omega = Vec3::Zero(), const Quat& q = Quat::Identity()) {
    ParticleSpec p;
    p.shape = shape_index;
    p.x = x;
    p.v = v;
    p.omega = omega;
    p.orientation.fixed = q;
    return p;
}

/// Positions, velocities, orientations and angular momenta of two runs agree bit for bit.
inline void expect_same_bits(const ParticleStore& p, const ParticleStore& q) {
    ASSERT_EQ(p.size(), q.size());
    for (std::size_t i = 0; i < p.size(); ++i) {
        EXPECT_EQ(p.x[i], q.x[i]); // exact equality is the point
        EXPECT_EQ(p.v[i], q.v[i]);
        EXPECT_EQ(p.q[i].coeffs(), q.q[i].coeffs());
        EXPECT_EQ(p.ang_mom[i], q.ang_mom[i]);
    }
}

/// The element contacts of the last force evaluation of two runs (keys, histories, forces) agree
/// bit for bit; returns their number.
inline std::size_t expect_same_records(const System& a, const System& b) {
    const auto& ra = a.body_contacts();
    const auto& rb = b.body_contacts();
    EXPECT_EQ(ra.size(), rb.size());
    for (std::size_t k = 0; k < std::min(ra.size(), rb.size()); ++k) {
        EXPECT_EQ(ra[k].key.a, rb[k].key.a);
        EXPECT_EQ(ra[k].key.b, rb[k].key.b);
        EXPECT_EQ(ra[k].key.ea, rb[k].key.ea);
        EXPECT_EQ(ra[k].key.eb, rb[k].key.eb);
        EXPECT_EQ(ra[k].contact.shear, rb[k].contact.shear);
        EXPECT_EQ(ra[k].contact.force, rb[k].contact.force);
    }
    return rb.size();
}

/// Total linear momentum (kg m/s).
inline Vec3 momentum(const System& sys) {
    Vec3 m = Vec3::Zero();
    for (std::size_t i = 0; i < sys.particles().size(); ++i) {
        m += sys.particles().mass[i] * sys.particles().v[i];
    }
    return m;
}

/// Angular momentum about the origin (kg m^2/s): orbital plus spin.
inline Vec3 angular_momentum(const System& sys) {
    const ParticleStore& p = sys.particles();
    Vec3 l = Vec3::Zero();
    for (std::size_t i = 0; i < p.size(); ++i) {
        l += p.mass[i] * p.x[i].cross(p.v[i]);
        l += p.shape[i] >= 0 ? p.ang_mom[i] : Vec3(p.omega[i] / p.inv_inertia[i]);
    }
    return l;
}

} // namespace kiln::dynamics::test
