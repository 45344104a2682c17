// Convex hull by CGAL (convex_hull_3 into a Surface_mesh); the only CGAL translation unit.

#include "geometry/hull.hpp"

#include "core/error.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>
#include <fmt/format.h>
#include <map>

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

/// Refuses input without four affinely independent points (relative to its extent).
void check_not_flat(const std::vector<Vec3>& pts, const std::string& where) {
    if (pts.size() < 4) {
        throw InputError(fmt::format("{}: a polyhedron needs at least 4 points, the input has {}",
                                     where, pts.size()));
    }
    double d = 0.0;
    const Vec3 p0 = pts[farthest(
        pts, [&](const Vec3& p) { return (p - pts[0]).norm(); }, d)];
    const Vec3 p1 = pts[farthest(
        pts, [&](const Vec3& p) { return (p - p0).norm(); }, d)];
    const double extent = d;
    if (!(extent > 0.0)) {
        throw InputError(fmt::format("{}: all {} points coincide", where, pts.size()));
    }
    const Vec3 u = (p1 - p0) / extent;
    const Vec3 p2 = pts[farthest(
        pts, [&](const Vec3& p) { return (p - p0).cross(u).norm(); }, d)];
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
}

} // namespace

Hull convex_hull(const std::vector<Vec3>& points, const std::string& where) {
    check_not_flat(points, where);
    std::vector<Point> in;
    in.reserve(points.size());
    for (const Vec3& p : points) {
        in.emplace_back(p.x(), p.y(), p.z());
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
    return h;
}

} // namespace kiln::geometry
