// Triangulated shape surfaces (geometry/surface_mesh.hpp).

#include "geometry/surface_mesh.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <map>
#include <numbers>
#include <utility>

using kiln::Vec3;
namespace g = kiln::geometry;

TEST(SurfaceMesh, SuperquadricMeshIsClosedOutwardAndConverges) {
    g::Superquadric q;
    q.half_axes = Vec3(1.0, 2.0, 0.5);
    q.e1 = 0.5;
    q.e2 = 0.8;
    const double exact = q.volume();
    double prev = 1.0;
    for (const int n : {16, 32, 64}) {
        const g::SurfaceMesh m = g::surface_mesh(q, n);
        // Closed: every directed edge appears once and its reverse once.
        std::map<std::pair<int, int>, int> edges;
        for (const auto& t : m.triangles) {
            for (int k = 0; k < 3; ++k) {
                ++edges[{t[static_cast<std::size_t>(k)], t[static_cast<std::size_t>((k + 1) % 3)]}];
            }
        }
        for (const auto& [e, count] : edges) {
            EXPECT_EQ(count, 1);
            EXPECT_EQ(edges.count({e.second, e.first}), 1U);
        }
        // Outward: positive volume, converging to the beta-function volume.
        const double err = std::abs(m.volume() / exact - 1.0);
        EXPECT_GT(m.volume(), 0.0);
        EXPECT_LT(err, prev);
        prev = err;
    }
    constexpr double kVolume = 5e-3; // inscribed polyhedron at n = 64: O(n^-2) deficit
    EXPECT_LT(prev, kVolume);
}

TEST(SurfaceMesh, PosedCopyMovesEveryVertex) {
    const g::SurfaceMesh m = g::surface_mesh(g::Sphere{0.5}, 8);
    const kiln::Quat q(Eigen::AngleAxisd(0.5 * std::numbers::pi, Vec3::UnitZ()));
    const g::SurfaceMesh p = g::posed(m, Vec3(1, 2, 3), q);
    ASSERT_EQ(p.vertices.size(), m.vertices.size());
    for (std::size_t i = 0; i < m.vertices.size(); ++i) {
        EXPECT_LT((p.vertices[i] - (Vec3(1, 2, 3) + q * m.vertices[i])).norm(), 1e-12);
    }
    EXPECT_NEAR(p.volume(), m.volume(), 1e-12);
}
