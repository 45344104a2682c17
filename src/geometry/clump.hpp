#pragma once
// Multi-sphere clump: a rigid union of (possibly overlapping) spheres. Mass properties are
// integrated over the UNION, never the sum of the spheres (which would count overlaps twice).

#include "core/types.hpp"
#include "geometry/mass_properties.hpp"

#include <vector>

namespace kiln::geometry {

/// One sphere of a clump (body frame).
struct ClumpSphere {
    Vec3 centre = Vec3::Zero(); ///< centre (m), body frame
    double radius = 0.0;        ///< radius (m)
};

/// Rigid union of spheres. After make_clump() the body frame is the principal frame with the
/// origin at the centre of mass of the union.
struct Clump {
    std::vector<ClumpSphere> spheres;         ///< member spheres, body frame
    Vec3 inertia_unit_density = Vec3::Zero(); ///< principal moments per unit density (m^5)
    double volume = 0.0;                      ///< volume of the union (m^3)
    double volume_error = 0.0; ///< estimated absolute quadrature error of the volume (m^3)
    /// Rotation from the frame the spheres were given in to the body frame: v_body = R^T (v - c).
    Mat3 template_axes = Mat3::Identity();
    Vec3 template_centroid = Vec3::Zero(); ///< centre of mass in the input frame (m)

    /// Radius of the smallest sphere about the centre of mass containing every member (m).
    [[nodiscard]] double bounding_radius() const;
    /// True when the body-frame point lies in at least one member sphere.
    [[nodiscard]] bool contains(const Vec3& p_body) const;
};

/// Principal moments (any unit) with those that differ by no more than the relative tolerance
/// `tol` (of the largest) made equal: all three to their mean, else the closest two. make_clump
/// applies it with the quadrature's relative volume error, so that a clump symmetric about an
/// axis (a ring of equal spheres, a dimer), whose equal moments the column quadrature gives apart
/// by up to its error, is a symmetric top (geometry::symmetric_axis) and turns by its exact flow.
[[nodiscard]] Vec3 equal_within(const Vec3& moments, double tol);

/// Resultant force (N) and torque about the centre of mass (N m) on a rigid body, world frame.
struct Wrench {
    Vec3 force = Vec3::Zero();  ///< total force (N), world frame
    Vec3 torque = Vec3::Zero(); ///< total torque about the centre of mass (N m), world frame
};

/// Adds one sub-sphere contact of a clump: force = normal + tangential contact force (N, world),
/// applied at `point` (m, world); `com` is the clump's centre of mass (m, world). Both parts give a
/// torque: a member sphere's normal force does not pass through the clump's centre of mass. (The
/// seed's Eq. 24, Oschmann 2019 L357, keeps only the tangential part, which is wrong for clumps.)
/// `weight` is 1, or 1/j for the seed's averaging over j simultaneous contacts with one partner
/// (its Eq. 23).
inline void add_contact(Wrench& w, const Vec3& com, const Vec3& point, const Vec3& force,
                        double weight = 1.0) {
    w.force += weight * force;
    w.torque += (point - com).cross(weight * force);
}

/// Mass properties of a union of spheres by column quadrature: an n x n midpoint grid over the
/// union's x-y bounding box, and along each column the exact union of the spheres' z intervals with
/// exact integrals of 1, z, z^2. The error comes from the x-y rule only and is O(n^-1.5) (the
/// column length has square-root edges); see tests/geometry/test_clump.cpp for its convergence.
[[nodiscard]] MassProperties union_mass_properties(const std::vector<ClumpSphere>& spheres, int n);

/// Builds a clump from spheres given in any frame: integrates the union at resolution n (and n/2
/// for the error estimate), then moves the spheres to the principal frame at the centre of mass.
/// Throws kiln::InputError (prefixed by `where`) on an empty list or a non-positive radius.
[[nodiscard]] Clump make_clump(const std::vector<ClumpSphere>& spheres, const std::string& where,
                               int n = 1200);

/// Volume (m^3) of the intersection lens of two spheres of radii r1, r2 at centre distance d (m)
/// (exact; used as the reference in tests).
[[nodiscard]] double lens_volume(double r1, double r2, double d);

} // namespace kiln::geometry
