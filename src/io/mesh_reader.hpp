#pragma once
// Surface mesh files for polyhedron templates: Wavefront .obj (v and f records) and STL (ASCII and
// binary). Only the points and triangles are read; the hull and mass properties are
// kiln::geometry's.

#include "core/types.hpp"

#include <array>
#include <filesystem>
#include <vector>

namespace kiln::io {

/// Points and triangles of a mesh file, scaled to metres.
struct MeshInput {
    std::vector<Vec3> points;                  ///< vertices (m), file frame times the scale
    std::vector<std::array<int, 3>> triangles; ///< faces as read (polygons fanned), may be empty
};

/// Reads a .obj or .stl file (by extension, case-insensitive), multiplying coordinates by `scale`
/// (e.g. 1e-3 for a file in mm). STL vertices are merged by exact coordinates. Throws
/// kiln::InputError naming the file (and line for text formats) on unreadable input, and when the
/// file has faces that do not close the surface (an edge not shared by exactly two faces).
[[nodiscard]] MeshInput read_mesh_file(const std::filesystem::path& file, double scale);

/// As above; with `require_closed = false` open surfaces are accepted (mesh walls).
[[nodiscard]] MeshInput read_mesh_file(const std::filesystem::path& file, double scale,
                                       bool require_closed);

} // namespace kiln::io
