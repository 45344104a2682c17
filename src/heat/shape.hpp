#pragma once
// Shapes as seen by the heat module: an implicit function (inside test and signed-distance
// estimate) and a closed surface triangulation, both in the body frame with the centre of mass at
// the origin. The Cartesian cut-cell grid (cartesian_grid.hpp) is written once against these
// queries, so a new shape only has to provide them.

#include "core/types.hpp"

#include <array>
#include <variant>
#include <vector>

namespace kiln::heat {

/// Sphere of radius `radius` (m) centred at the body origin.
struct Sphere {
    double radius = 1.0; ///< (m)
};

/// Cuboid with half edge lengths `half` (m) along the body axes, centred at the body origin.
struct Box {
    Vec3 half = Vec3::Ones(); ///< half edge lengths (m), body frame
};

/// Superquadric (Barr 1981; Jaklic, Leonardis & Solina 2000, eq. 2.10 for the inside-outside
/// function): ((|x/a|^(2/e2) + |y/b|^(2/e2))^(e2/e1) + |z/c|^(2/e1)) <= 1. Only the convex range
/// 0.1 <= e1, e2 <= 2 is accepted.
struct Superquadric {
    Vec3 half = Vec3::Ones(); ///< semi-axes a, b, c (m), body frame
    double e1 = 1.0;          ///< north-south (z) shape exponent (-)
    double e2 = 1.0;          ///< east-west (x-y) shape exponent (-)
};

/// Convex polyhedron, the intersection of the half-spaces of its faces. Build it with
/// make_convex_polyhedron (which derives the planes); body frame.
struct ConvexPolyhedron {
    std::vector<Vec3> vertices;            ///< vertex positions (m), body frame
    std::vector<std::array<int, 3>> faces; ///< outward (counter-clockwise) triangles
    std::vector<Vec3> normals;             ///< unit outward normals of the distinct face planes
    std::vector<double> offsets;           ///< plane offsets (m): inside where n . x <= offset
};

/// Rigid union of spheres (a clump), body frame. `volume` and `area` are the union's reference
/// values supplied by the caller (a geometry template: column quadrature and exposed-area
/// integration); 0 when unknown, then exact_volume / reference_area refuse.
struct Clump {
    std::vector<Vec3> centres; ///< member centres (m), body frame
    std::vector<double> radii; ///< member radii (m)
    double volume = 0.0;       ///< reference volume of the union (m^3), 0 = unknown
    double area = 0.0;         ///< reference surface area of the union (m^2), 0 = unknown
};

/// Every shape the heat module can grid. Adding a shape = adding an alternative plus the queries
/// in shape.cpp.
using Shape = std::variant<Sphere, Box, Superquadric, ConvexPolyhedron, Clump>;

/// Polyhedron from a closed, outward-oriented triangle mesh of a convex body (body frame, m):
/// one plane per distinct face plane (coplanar triangles share one). Throws InputError for fewer
/// than 4 triangles, a degenerate triangle or a vertex outside a face plane (not convex).
[[nodiscard]] ConvexPolyhedron make_convex_polyhedron(std::vector<Vec3> vertices,
                                                      std::vector<std::array<int, 3>> faces);

/// Closed triangulated surface, outward-oriented (counter-clockwise seen from outside), body frame.
struct SurfaceMesh {
    std::vector<Vec3> vertices;                ///< vertex positions (m), body frame
    std::vector<std::array<int, 3>> triangles; ///< vertex indices per triangle
    /// Sum of triangle areas (m^2).
    [[nodiscard]] double area() const;
    /// Enclosed volume by the divergence theorem (m^3).
    [[nodiscard]] double volume() const;
};

/// Throws InputError when a shape's parameters are out of range (non-positive sizes, exponents
/// outside the convex range).
void validate(const Shape& shape);

/// Signed distance estimate (m): negative inside, zero on the surface, exact for sphere and box,
/// F / |grad F| (first order in the distance) for the superquadric; polyhedron: the largest
/// plane distance (exact inside, a lower bound of the distance outside); clump: the smallest
/// member distance (exact outside, inside a lower bound of the depth). `x` in the body frame (m).
[[nodiscard]] double level(const Shape& shape, const Vec3& x);

/// True when `x` (body frame, m) lies inside or on the surface.
[[nodiscard]] bool inside(const Shape& shape, const Vec3& x);

/// Half extents of the body-frame bounding box (m).
[[nodiscard]] Vec3 half_extent(const Shape& shape);

/// Exact volume (m^3); superquadric: 2 a b c e1 e2 B(e1/2 + 1, e1) B(e2/2, e2/2) (Jaklic,
/// Leonardis & Solina 2000, ch. 2, volume of a superellipsoid via the beta function B);
/// polyhedron: divergence theorem over its faces; clump: the supplied reference volume.
[[nodiscard]] double exact_volume(const Shape& shape);

/// Exact surface area (m^2) of sphere, box and polyhedron; for the superquadric (no closed form)
/// the Richardson extrapolation of two fine triangulations (edges 1/50 and 1/100 of the smallest
/// semi-axis; the triangulation error is second order in the edge length); clump: the supplied
/// reference area.
[[nodiscard]] double reference_area(const Shape& shape);

/// Closed surface triangulation with edges no longer than about `edge` (m). Sphere and
/// superquadric: a cube's faces split into quads and projected radially onto the surface (both are
/// star-shaped about the origin); box: its own faces; polyhedron: each face triangle split into
/// n x n similar triangles; clump: every member's sphere mesh, each triangle clipped against the
/// radical planes of the members overlapping it (on a member sphere, "inside member j" is exactly
/// one side of that plane), so only the union's outer surface remains, seams included.
[[nodiscard]] SurfaceMesh surface_mesh(const Shape& shape, double edge);

} // namespace kiln::heat
