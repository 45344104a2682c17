#pragma once
// Convex hull of a point cloud (CGAL convex_hull_3), in its own library kiln_hull: CGAL compiles
// with -frounding-math and takes long to build, so it stays out of kiln_geometry and hot loops.

#include "core/types.hpp"

#include <array>
#include <string>
#include <vector>

namespace kiln::geometry {

/// Closed triangulated hull: only the extreme points, outward (counter-clockwise) triangles.
struct Hull {
    std::vector<Vec3> vertices;            ///< hull vertices (m), input frame
    std::vector<std::array<int, 3>> faces; ///< triangles, outward orientation
};

/// Relative tolerance of the degeneracy checks: points closer than this times the cloud's extent
/// to a common line or plane count as collinear or coplanar.
inline constexpr double kHullFlatTolerance = 1e-9;

/// Convex hull of `points` (m). Throws kiln::InputError "<where>: <reason>" for fewer than 4
/// points, coincident, collinear or coplanar (flat) input. Canonical order: vertices sorted by
/// (x, y, z), each triangle starting at its smallest vertex index, triangles sorted, so the result
/// depends on the point set only (not on the input order, CGAL's start or heap addresses), except
/// for the diagonals chosen in faces with more than three vertices.
[[nodiscard]] Hull convex_hull(const std::vector<Vec3>& points, const std::string& where);

} // namespace kiln::geometry
