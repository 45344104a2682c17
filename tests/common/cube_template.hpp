#pragma once
// A cube as a closed triangle mesh and as a polyhedron shape template, for tests that need a
// flat-faced body without reading a shape file.

#include "geometry/polyhedron.hpp"
#include "geometry/shape.hpp"

#include <array>
#include <vector>

namespace kiln::test {

/// Vertices and outward triangles of a closed mesh (body frame).
struct TriangleMesh {
    std::vector<Vec3> vertices;
    std::vector<std::array<int, 3>> triangles;
};

/// Cube [-a, a]^3 as 8 vertices and 12 outward (counter-clockwise seen from outside) triangles,
/// every vertex turned by q about the origin (body frame).
inline TriangleMesh cube_mesh(double a, const Quat& q = Quat::Identity()) {
    TriangleMesh m;
    for (int k = 0; k < 8; ++k) {
        m.vertices.push_back(q * Vec3((k & 1) ? a : -a, (k & 2) ? a : -a, (k & 4) ? a : -a));
    }
    // The six faces as quads, each split into two triangles.
    const std::array<std::array<int, 4>, 6> quads = {
        {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}}};
    for (const auto& f : quads) {
        m.triangles.push_back({f[0], f[1], f[2]});
        m.triangles.push_back({f[0], f[2], f[3]});
    }
    return m;
}

/// Cube of edge 2 a centred on the origin (body frame) as a polyhedron shape template.
inline geometry::ShapeTemplate cube_template(double a) {
    const TriangleMesh m = cube_mesh(a);
    return geometry::make_template("cube",
                                   geometry::make_polyhedron(m.vertices, m.triangles, "test"));
}

} // namespace kiln::test
