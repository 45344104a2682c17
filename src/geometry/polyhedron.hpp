#pragma once
// Convex polyhedron: a closed triangle mesh with outward (counter-clockwise seen from outside)
// faces. Mass properties by the divergence theorem, written as a sum of signed tetrahedra spanned
// by each face and a reference point (Mirtich, J. Graphics Tools 1 (1996) 31; closed-form
// tetrahedron moments after Tonon, J. Math. Stat. 1 (2004) 8; equation numbers not checked against
// the papers). The template is moved to its centre of mass and principal axes like the clumps. The
// hull of arbitrary input points is built by kiln_hull (CGAL), which is kept out of this library.

#include "core/types.hpp"
#include "geometry/mass_properties.hpp"

#include <array>
#include <string>
#include <vector>

namespace kiln::geometry {

/// The point of `vertices` (any frame; not empty) maximising d . x for a direction d in the same
/// frame: the support map of their convex hull (the first of equal ones).
[[nodiscard]] Vec3 farthest_vertex(const std::vector<Vec3>& vertices, const Vec3& d);

/// Convex polyhedron in its body frame (principal axes, origin at the centre of mass).
struct ConvexPolyhedron {
    std::vector<Vec3> vertices;               ///< vertex positions (m), body frame
    std::vector<std::array<int, 3>> faces;    ///< triangles, outward (counter-clockwise) order
    std::vector<std::array<int, 2>> edges;    ///< unique edges of the triangles (lower index first)
    double volume = 0.0;                      ///< volume (m^3)
    Vec3 inertia_unit_density = Vec3::Zero(); ///< principal moments per unit density (m^5)
    Mat3 template_axes = Mat3::Identity();    ///< v_body = R^T (v_input - c), R = template_axes
    Vec3 template_centroid = Vec3::Zero();    ///< centre of mass in the input frame (m)

    /// Support point: the vertex maximising d . x for a body-frame direction d (m, body frame).
    [[nodiscard]] Vec3 support(const Vec3& d_body) const;
    /// Surface area (m^2): sum of the triangle areas (exact).
    [[nodiscard]] double surface_area() const;
    /// Shadow area (m^2) on a plane normal to the body-frame direction u: 1/2 sum |n . u| A over
    /// the faces (exact for a convex body).
    [[nodiscard]] double projected_area(const Vec3& u_body) const;
    /// Radius of the smallest centred sphere enclosing the body (m): the farthest vertex.
    [[nodiscard]] double bounding_radius() const;
};

/// Volume, centroid and centroidal inertia per unit density of a closed, outward-oriented triangle
/// mesh (any frame). Exact up to round-off; the mesh need not be convex.
[[nodiscard]] MassProperties
polyhedron_mass_properties(const std::vector<Vec3>& vertices,
                           const std::vector<std::array<int, 3>>& faces);

/// Builds a polyhedron from the triangles of a convex hull (outward orientation) given in any
/// frame: checks that every vertex is on a face, that every edge is shared by exactly two triangles
/// in opposite directions and that the volume is positive, then moves it to the principal frame at
/// the centre of mass. Throws kiln::InputError prefixed by `where` otherwise.
[[nodiscard]] ConvexPolyhedron make_polyhedron(const std::vector<Vec3>& vertices,
                                               const std::vector<std::array<int, 3>>& faces,
                                               const std::string& where);

} // namespace kiln::geometry
