// Convex hull by CGAL (convex_hull_3 into a Surface_mesh); the only CGAL translation unit.

#include "geometry/hull.hpp"

#include "core/error.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>
#include <algorithm>
#include <array>
#include <fmt/format.h>
#include <map>
#include <numeric>
#include <tuple>
#include <utility>

namespace kiln::geometry {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;

/// Index of the point farthest by `dist` (ties: the first).
template <class F> std::size_t farthest(const std::vector<Vec3>& pts, F&& dist, double& d_max) {
    std::size_t best = 0;
    d_max = -1.0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const double d = dist(pts[i]);
        if (d > d_max) {
            d_max = d;
            best = i;
        }
    }
    return best;
}

/// Candidates tried for the third start point by split_third.
constexpr std::size_t kStartCandidates = 32;

/// Third point of the start triangle through pts[i0] and pts[i1]: `i2` if the triangle's plane has
/// input points on both sides (by more than tol, m), else the point farthest from the line i0-i1
/// among the next kStartCandidates that gives such a plane, else i2. A plane with points on both
/// sides supports no hull face, which is what CGAL's double erase needs (see convex_hull).
std::size_t split_third(const std::vector<Vec3>& pts, std::size_t i0, std::size_t i1,
                        std::size_t i2, double tol) {
    const Vec3& p0 = pts[i0];
    const Vec3 u = (pts[i1] - p0).normalized();
    const auto splits = [&](std::size_t k) {
        const Vec3 n = u.cross(pts[k] - p0);
        if (!(n.norm() > tol)) {
            return false;
        }
        const Vec3 nn = n.normalized();
        bool below = false;
        bool above = false;
        for (const Vec3& p : pts) {
            const double h = nn.dot(p - p0);
            below = below || h < -tol;
            above = above || h > tol;
        }
        return below && above;
    };
    if (splits(i2)) {
        return i2;
    }
    std::vector<std::pair<double, std::size_t>> by_distance;
    by_distance.reserve(pts.size());
    for (std::size_t k = 0; k < pts.size(); ++k) {
        if (k != i0 && k != i1 && k != i2) {
            by_distance.emplace_back(-(pts[k] - p0).cross(u).norm(), k);
        }
    }
    const std::size_t m = std::min(kStartCandidates, by_distance.size());
    std::partial_sort(by_distance.begin(), by_distance.begin() + static_cast<std::ptrdiff_t>(m),
                      by_distance.end());
    for (std::size_t c = 0; c < m; ++c) {
        if (splits(by_distance[c].second)) {
            return by_distance[c].second;
        }
    }
    return i2;
}

/// Refuses input without four affinely independent points (relative to its extent). Returns the
/// indices of three of them spanning a wide triangle through the body (the input's diameter and,
/// preferably, the point farthest from that line whose plane has points on both sides).
std::array<std::size_t, 3> check_not_flat(const std::vector<Vec3>& pts, const std::string& where) {
    if (pts.size() < 4) {
        throw InputError(fmt::format("{}: a polyhedron needs at least 4 points, the input has {}",
                                     where, pts.size()));
    }
    double d = 0.0;
    const std::size_t i0 = farthest(
        pts, [&](const Vec3& p) { return (p - pts[0]).norm(); }, d);
    const Vec3 p0 = pts[i0];
    const std::size_t i1 = farthest(
        pts, [&](const Vec3& p) { return (p - p0).norm(); }, d);
    const Vec3 p1 = pts[i1];
    const double extent = d;
    if (!(extent > 0.0)) {
        throw InputError(fmt::format("{}: all {} points coincide", where, pts.size()));
    }
    const Vec3 u = (p1 - p0) / extent;
    const std::size_t i2 = farthest(
        pts, [&](const Vec3& p) { return (p - p0).cross(u).norm(); }, d);
    const Vec3 p2 = pts[i2];
    if (d <= kHullFlatTolerance * extent) {
        throw InputError(fmt::format("{}: the points are collinear (no volume)", where));
    }
    const Vec3 n = u.cross(p2 - p0).normalized();
    (void)farthest(
        pts, [&](const Vec3& p) { return std::abs((p - p0).dot(n)); }, d);
    if (d <= kHullFlatTolerance * extent) {
        throw InputError(fmt::format(
            "{}: the points are coplanar (flat, no volume; largest distance from their plane "
            "{:.3g} of the extent)",
            where, d / extent));
    }
    return {i0, i1, split_third(pts, i0, i1, i2, kHullFlatTolerance * extent)};
}

/// The hull in an order that depends on its geometry only: vertices sorted by (x, y, z), each
/// triangle turned to start at its smallest index (orientation kept), triangles sorted. The order
/// CGAL returns follows its internal containers, and for some inputs the heap addresses (found on
/// Yade's random polyhedra: another malloc layout, e.g. another working directory or environment,
/// gave another vertex order and so round-off differences that a chaotic drop amplified).
Hull canonical_order(const Hull& in) {
    const std::size_t n = in.vertices.size();
    std::vector<int> order(n);
    std::iota(order.begin(), order.end(), 0);
    const auto key = [&](int i) {
        const Vec3& v = in.vertices[static_cast<std::size_t>(i)];
        return std::make_tuple(v.x(), v.y(), v.z());
    };
    std::sort(order.begin(), order.end(), [&](int a, int b) { return key(a) < key(b); });
    std::vector<int> new_index(n);
    Hull out;
    out.vertices.reserve(n);
    for (std::size_t k = 0; k < n; ++k) {
        new_index[static_cast<std::size_t>(order[k])] = static_cast<int>(k);
        out.vertices.push_back(in.vertices[static_cast<std::size_t>(order[k])]);
    }
    out.faces.reserve(in.faces.size());
    for (const auto& f : in.faces) {
        std::array<int, 3> g{new_index[static_cast<std::size_t>(f[0])],
                             new_index[static_cast<std::size_t>(f[1])],
                             new_index[static_cast<std::size_t>(f[2])]};
        std::rotate(g.begin(), std::min_element(g.begin(), g.end()), g.end());
        out.faces.push_back(g);
    }
    std::sort(out.faces.begin(), out.faces.end());
    return out;
}

} // namespace

Hull convex_hull(const std::vector<Vec3>& points, const std::string& where) {
    const std::array<std::size_t, 3> wide = check_not_flat(points, where);
    // CGAL 5.5's quickhull (Debian 12) starts from the first three distinct, non-collinear input
    // points; when they span a hull face and a fourth point lies within round-off of that face it
    // can erase one list node twice (CGAL issues 6543, 8625, 8761: a use after free that corrupts
    // the heap; found with valgrind on Yade's random polyhedra, bench/yade). The input therefore
    // starts with a wide triangle through the body: the diameter and a far point whose plane has
    // input points on both sides, so that the start triangle is no hull face; then the other
    // points in their order (the output order is made canonical at the end anyway).
    std::vector<Point> in;
    in.reserve(points.size());
    for (const std::size_t i : wide) {
        in.emplace_back(points[i].x(), points[i].y(), points[i].z());
    }
    for (std::size_t i = 0; i < points.size(); ++i) {
        if (i != wide[0] && i != wide[1] && i != wide[2]) {
            in.emplace_back(points[i].x(), points[i].y(), points[i].z());
        }
    }
    Mesh mesh;
    CGAL::convex_hull_3(in.begin(), in.end(), mesh);
    Hull h;
    std::map<Mesh::Vertex_index, int> index;
    for (const Mesh::Vertex_index v : mesh.vertices()) {
        const Point& p = mesh.point(v);
        index[v] = static_cast<int>(h.vertices.size());
        h.vertices.emplace_back(p.x(), p.y(), p.z());
    }
    for (const Mesh::Face_index f : mesh.faces()) {
        std::vector<int> poly;
        for (const Mesh::Vertex_index v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) {
            poly.push_back(index.at(v));
        }
        // convex_hull_3 returns triangles; a fan keeps the orientation if a face has more sides.
        for (std::size_t k = 1; k + 1 < poly.size(); ++k) {
            h.faces.push_back({poly[0], poly[k], poly[k + 1]});
        }
    }
    return canonical_order(h);
}

} // namespace kiln::geometry
