#pragma once
// VTK output of shape surfaces (.vtp): a template's mesh for ParaView glyphs, or many posed copies.

#include "geometry/surface_mesh.hpp"

#include <filesystem>
#include <vector>

namespace kiln::io {

/// Writes a triangle mesh as VTK XML PolyData (points in m, frame of the mesh). Each triangle
/// carries the cell array "part" (the index of the mesh in `meshes`, e.g. the particle index).
/// Throws kiln::InputError when the file cannot be written.
void write_surface_vtp(const std::filesystem::path& file,
                       const std::vector<geometry::SurfaceMesh>& meshes);

} // namespace kiln::io
