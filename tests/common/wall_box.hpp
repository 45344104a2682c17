#pragma once
// The 20 mm box of shapes/wall_box_20mm.stl, read once per call in metres: the mesh floor of the
// dynamics tests and the mesh-wall tests (its top face is the plane z = 0, facing +z). Needs the
// compile definition KILN_SOURCE_DIR (the source tree).

#include "io/mesh_reader.hpp"

#include <filesystem>

namespace kiln::test {

/// Points (m, file frame x 1e-3) and triangles of shapes/wall_box_20mm.stl.
inline io::MeshInput wall_box_20mm() {
    return io::read_mesh_file(
        std::filesystem::path(KILN_SOURCE_DIR) / "shapes" / "wall_box_20mm.stl", 1e-3);
}

} // namespace kiln::test
