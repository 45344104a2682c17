#pragma once
// A cube as a polyhedron shape template, for tests that need a flat-faced body without reading a
// shape file.

#include "geometry/polyhedron.hpp"
#include "geometry/shape.hpp"

#include <array>
#include <vector>

namespace kiln::test {

/// Cube of edge 2 a centred on the origin (body frame), 12 outward triangles.
inline geometry::ShapeTemplate cube_template(double a) {
    std::vector<Vec3> v;
    for (int k = 0; k < 8; ++k) {
        v.emplace_back((k & 1) ? a : -a, (k & 2) ? a : -a, (k & 4) ? a : -a);
    }
    const std::vector<std::array<int, 4>> quads = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                                   {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    std::vector<std::array<int, 3>> f;
    for (const auto& q : quads) {
        f.push_back({q[0], q[1], q[2]});
        f.push_back({q[0], q[2], q[3]});
    }
    return geometry::make_template("cube", geometry::make_polyhedron(v, f, "test"));
}

} // namespace kiln::test
