#pragma once
// Triangulated surfaces of shape templates, for drawing particles as their real shapes (ParaView
// glyphs or per-particle copies). Body frame, metres.

#include "core/types.hpp"
#include "geometry/shape.hpp"

#include <array>
#include <vector>

namespace kiln::geometry {

/// Closed triangle mesh with outward (counter-clockwise seen from outside) triangles.
struct SurfaceMesh {
    std::vector<Vec3> vertices;                ///< vertex positions (m), body frame
    std::vector<std::array<int, 3>> triangles; ///< vertex indices, outward orientation

    /// Enclosed volume (m^3) by the divergence theorem; exact for the polyhedron.
    [[nodiscard]] double volume() const;
};

/// Surface of a shape: spheres and superquadrics from the parametric form with n latitude bands
/// and 4 n longitudes (poles shared); clumps as one closed sphere mesh per member (overlapping
/// parts stay inside the drawing, which is what a renderer needs); polyhedra as their own triangles
/// (n unused).
[[nodiscard]] SurfaceMesh surface_mesh(const Shape& s, int n = 16);

/// Copy of `mesh` placed at x (m, world) with orientation q (body -> world).
[[nodiscard]] SurfaceMesh posed(const SurfaceMesh& mesh, const Vec3& x, const Quat& q);

} // namespace kiln::geometry
