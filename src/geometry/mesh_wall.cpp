// Triangle-mesh walls: cell grid, sphere and polyhedron contacts (see the header).

#include "geometry/mesh_wall.hpp"

#include "core/error.hpp"
#include "geometry/convex_polygon.hpp"
#include "geometry/depth_refinement.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <map>
#include <numeric>

namespace kiln::geometry {

namespace {

/// Largest angle (rad) between the normals of adjacent triangles of one facet: STL files store
/// single-precision coordinates, which tilt the normals of coplanar triangles by ~1e-7 rad.
constexpr double kFacetAngle = 1e-6;
/// Barycentric coordinate (or edge parameter) below which a closest point counts as on the edge (or
/// at the vertex): round-off must not split one feature into two.
constexpr double kOnEdge = 1e-9;
/// A point within this fraction of the sphere radius of a contact plane lies on it.
constexpr double kOnPlane = 1e-9;
/// 1 - cos of the angle below which a contact normal is its triangle's normal (~1e-6 rad).
constexpr double kParallel = 5e-13;
/// Most cells of the grid; the cell side grows until the grid fits.
constexpr double kMaxCells = 2.0e6;

int root(std::vector<int>& parent, int i) {
    while (parent[static_cast<std::size_t>(i)] != i) {
        parent[static_cast<std::size_t>(i)] =
            parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
        i = parent[static_cast<std::size_t>(i)];
    }
    return i;
}

/// Closest point of triangle (a, b, c) to p (Ericson 2005, Sec. 5.1.5) and its region: 0 inside,
/// 1 + k on edge k (from vertex k to k + 1), 4 + k at vertex k.
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, int& region) {
    const Vec3 ab = b - a;
    const Vec3 ac = c - a;
    const Vec3 ap = p - a;
    const double d1 = ab.dot(ap);
    const double d2 = ac.dot(ap);
    if (d1 <= 0.0 && d2 <= 0.0) {
        region = 4;
        return a;
    }
    const Vec3 bp = p - b;
    const double d3 = ab.dot(bp);
    const double d4 = ac.dot(bp);
    if (d3 >= 0.0 && d4 <= d3) {
        region = 5;
        return b;
    }
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        const double t = d1 / (d1 - d3);
        region = t < kOnEdge ? 4 : (t > 1.0 - kOnEdge ? 5 : 1);
        return a + ab * t;
    }
    const Vec3 cp = p - c;
    const double d5 = ab.dot(cp);
    const double d6 = ac.dot(cp);
    if (d6 >= 0.0 && d5 <= d6) {
        region = 6;
        return c;
    }
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        const double t = d2 / (d2 - d6);
        region = t < kOnEdge ? 4 : (t > 1.0 - kOnEdge ? 6 : 3);
        return a + ac * t;
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
        const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        region = t < kOnEdge ? 5 : (t > 1.0 - kOnEdge ? 6 : 2);
        return b + (c - b) * t;
    }
    // Inside. A point on an edge to round-off (Ericson's sums are then of order eps instead of
    // 0) is classified as on the edge, so that two triangles sharing it report the same feature.
    const double denom = 1.0 / (va + vb + vc);
    const double wa = va * denom;
    const double wb = vb * denom;
    const double wc = vc * denom;
    const bool on_bc = wa < kOnEdge;
    const bool on_ca = wb < kOnEdge;
    const bool on_ab = wc < kOnEdge;
    if (on_ab && on_ca) {
        region = 4;
    } else if (on_ab && on_bc) {
        region = 5;
    } else if (on_bc && on_ca) {
        region = 6;
    } else if (on_ab) {
        region = 1;
    } else if (on_bc) {
        region = 2;
    } else if (on_ca) {
        region = 3;
    } else {
        region = 0;
    }
    return a + ab * wb + ac * wc;
}

} // namespace

MeshWall::MeshWall(std::vector<Vec3> vertices, std::vector<std::array<int, 3>> triangles,
                   const std::string& where)
    : vertices_(std::move(vertices)), triangles_(std::move(triangles)) {
    if (triangles_.empty()) {
        throw InputError(fmt::format("{}: a mesh wall needs at least one triangle", where));
    }
    const int nv = static_cast<int>(vertices_.size());
    std::map<std::array<int, 2>, int> edge_id;
    for (std::size_t t = 0; t < triangles_.size(); ++t) {
        const auto& tri = triangles_[t];
        for (const int v : tri) {
            if (v < 0 || v >= nv) {
                throw InputError(
                    fmt::format("{}: triangle {} has a vertex index out of range", where, t));
            }
        }
        const Vec3 area = (vertices_[static_cast<std::size_t>(tri[1])] -
                           vertices_[static_cast<std::size_t>(tri[0])])
                              .cross(vertices_[static_cast<std::size_t>(tri[2])] -
                                     vertices_[static_cast<std::size_t>(tri[0])]);
        if (!(area.norm() > 0.0)) {
            throw InputError(fmt::format("{}: triangle {} has zero area", where, t));
        }
        normals_.push_back(area.normalized());
        std::array<int, 3> ids{};
        for (std::size_t k = 0; k < 3; ++k) {
            const int i = tri[k];
            const int j = tri[(k + 1) % 3];
            const std::array<int, 2> key{std::min(i, j), std::max(i, j)};
            const auto [it, added] = edge_id.emplace(key, static_cast<int>(edges_.size()));
            if (added) {
                edges_.push_back(key);
            }
            ids[k] = it->second;
        }
        tri_edges_.push_back(ids);
    }
    // Facets: triangles joined across shared edges when their normals agree.
    std::vector<std::vector<int>> tris_of_edge(edges_.size());
    for (std::size_t t = 0; t < triangles_.size(); ++t) {
        for (const int e : tri_edges_[t]) {
            tris_of_edge[static_cast<std::size_t>(e)].push_back(static_cast<int>(t));
        }
    }
    std::vector<int> parent(triangles_.size());
    std::iota(parent.begin(), parent.end(), 0);
    for (const auto& ts : tris_of_edge) {
        for (std::size_t i = 1; i < ts.size(); ++i) {
            const Vec3& n0 = normals_[static_cast<std::size_t>(ts[0])];
            const Vec3& n1 = normals_[static_cast<std::size_t>(ts[i])];
            if (n0.dot(n1) > 0.0 && n0.cross(n1).norm() < kFacetAngle) {
                parent[static_cast<std::size_t>(root(parent, ts[0]))] = root(parent, ts[i]);
            }
        }
    }
    facet_of_.assign(triangles_.size(), -1);
    std::vector<int> facet_of_root(triangles_.size(), -1);
    for (std::size_t t = 0; t < triangles_.size(); ++t) {
        const auto r = static_cast<std::size_t>(root(parent, static_cast<int>(t)));
        if (facet_of_root[r] < 0) {
            facet_of_root[r] = static_cast<int>(facet_triangles_.size());
            facet_triangles_.emplace_back();
            facet_normals_.emplace_back(Vec3::Zero());
        }
        facet_of_[t] = facet_of_root[r];
        facet_triangles_[static_cast<std::size_t>(facet_of_[t])].push_back(static_cast<int>(t));
        facet_normals_[static_cast<std::size_t>(facet_of_[t])] += normals_[t];
    }
    for (std::size_t f = 0; f < facet_normals_.size(); ++f) {
        facet_normals_[f].normalize();
        double o = 0.0;
        int n = 0;
        for (const int t : facet_triangles_[f]) {
            for (const int v : triangles_[static_cast<std::size_t>(t)]) {
                o += facet_normals_[f].dot(vertices_[static_cast<std::size_t>(v)]);
                ++n;
            }
        }
        facet_offsets_.push_back(o / n);
    }

    // Uniform grid: cell side = mean triangle extent, enlarged until the grid is small enough.
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
    Vec3 hi = -lo;
    double extent = 0.0;
    for (const auto& tri : triangles_) {
        Vec3 tlo = vertices_[static_cast<std::size_t>(tri[0])];
        Vec3 thi = tlo;
        for (const int v : tri) {
            tlo = tlo.cwiseMin(vertices_[static_cast<std::size_t>(v)]);
            thi = thi.cwiseMax(vertices_[static_cast<std::size_t>(v)]);
        }
        extent += (thi - tlo).maxCoeff();
        lo = lo.cwiseMin(tlo);
        hi = hi.cwiseMax(thi);
    }
    cell_ = extent / static_cast<double>(triangles_.size());
    const auto count = [&](double h) {
        return ((hi - lo) / h).array().floor().cwiseMax(0.0).matrix() + Vec3::Ones();
    };
    while (count(cell_).prod() > kMaxCells) {
        cell_ *= 1.5;
    }
    origin_ = lo;
    const Vec3 d = count(cell_);
    dims_ = {static_cast<int>(d.x()), static_cast<int>(d.y()), static_cast<int>(d.z())};
    const auto n_cells = static_cast<std::size_t>(dims_[0]) * static_cast<std::size_t>(dims_[1]) *
                         static_cast<std::size_t>(dims_[2]);
    std::vector<std::vector<int>> bins(n_cells);
    for (std::size_t t = 0; t < triangles_.size(); ++t) {
        Vec3 tlo = vertices_[static_cast<std::size_t>(triangles_[t][0])];
        Vec3 thi = tlo;
        for (const int v : triangles_[t]) {
            tlo = tlo.cwiseMin(vertices_[static_cast<std::size_t>(v)]);
            thi = thi.cwiseMax(vertices_[static_cast<std::size_t>(v)]);
        }
        const auto a = cell_of(tlo);
        const auto b = cell_of(thi);
        for (int i = a[0]; i <= b[0]; ++i) {
            for (int j = a[1]; j <= b[1]; ++j) {
                for (int k = a[2]; k <= b[2]; ++k) {
                    bins[cell_index(i, j, k)].push_back(static_cast<int>(t));
                }
            }
        }
    }
    cell_start_.assign(n_cells + 1, 0);
    for (std::size_t c = 0; c < n_cells; ++c) {
        cell_start_[c + 1] = cell_start_[c] + static_cast<int>(bins[c].size());
        cell_items_.insert(cell_items_.end(), bins[c].begin(), bins[c].end());
    }
}

std::size_t MeshWall::cell_index(int i, int j, int k) const {
    const auto nx = static_cast<std::size_t>(dims_[0]);
    const auto ny = static_cast<std::size_t>(dims_[1]);
    return (static_cast<std::size_t>(k) * ny + static_cast<std::size_t>(j)) * nx +
           static_cast<std::size_t>(i);
}

std::array<int, 3> MeshWall::cell_of(const Vec3& x) const {
    std::array<int, 3> c{};
    for (int a = 0; a < 3; ++a) {
        const double f = std::floor((x[a] - origin_[a]) / cell_);
        c[static_cast<std::size_t>(a)] = static_cast<int>(
            std::clamp(f, 0.0, static_cast<double>(dims_[static_cast<std::size_t>(a)] - 1)));
    }
    return c;
}

void MeshWall::candidates(const Vec3& lo, const Vec3& hi, std::vector<int>& out) const {
    out.clear();
    const Vec3 grid_hi = origin_ + cell_ * Vec3(dims_[0], dims_[1], dims_[2]);
    if ((hi.array() < origin_.array()).any() || (lo.array() > grid_hi.array()).any()) {
        return;
    }
    const auto a = cell_of(lo);
    const auto b = cell_of(hi);
    for (int i = a[0]; i <= b[0]; ++i) {
        for (int j = a[1]; j <= b[1]; ++j) {
            for (int k = a[2]; k <= b[2]; ++k) {
                const std::size_t c = cell_index(i, j, k);
                out.insert(out.end(), cell_items_.begin() + cell_start_[c],
                           cell_items_.begin() + cell_start_[c + 1]);
            }
        }
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
}

void MeshWall::file_by_region(MeshContact m, int t, int region, std::vector<MeshContact>& out,
                              std::vector<MeshContact>& edges,
                              std::vector<MeshContact>& verts) const {
    const auto ti = static_cast<std::size_t>(t);
    if (region == 0) {
        m.feature = MeshFeature::kFace;
        m.id = t;
        out.push_back(m);
    } else if (region <= 3) {
        m.feature = MeshFeature::kEdge;
        m.id = tri_edges_[ti][static_cast<std::size_t>(region - 1)];
        edges.push_back(m);
    } else {
        m.feature = MeshFeature::kVertex;
        m.id = triangles_[ti][static_cast<std::size_t>(region - 4)];
        verts.push_back(m);
    }
}

void MeshWall::sphere_contacts(const Vec3& c, double r, std::vector<MeshContact>& out) const {
    out.clear();
    thread_local std::vector<int> tris;
    candidates(c - Vec3::Constant(r), c + Vec3::Constant(r), tris);
    thread_local std::vector<MeshContact> edges;
    thread_local std::vector<MeshContact> verts;
    edges.clear();
    verts.clear();
    for (const int t : tris) {
        const auto& tri = triangles_[static_cast<std::size_t>(t)];
        const Vec3& a = vertices_[static_cast<std::size_t>(tri[0])];
        const double h = normals_[static_cast<std::size_t>(t)].dot(c - a);
        if (h <= 0.0 || h >= r) {
            continue; // behind the one-sided wall, or too far from its plane
        }
        int region = 0;
        const Vec3 q = closest_on_triangle(c, a, vertices_[static_cast<std::size_t>(tri[1])],
                                           vertices_[static_cast<std::size_t>(tri[2])], region);
        const double dist = (c - q).norm();
        if (dist >= r) {
            continue;
        }
        MeshContact m;
        m.normal = (c - q) / dist;
        m.depth = r - dist;
        m.point = q;
        // Temporarily 1 when the contact represents the triangle's plane (see the thinning).
        m.patch_area =
            1.0 - m.normal.dot(normals_[static_cast<std::size_t>(t)]) < kParallel ? 1.0 : 0.0;
        file_by_region(m, t, region, out, edges, verts);
    }
    thin(out, edges, verts, r);
}

void MeshWall::thin(std::vector<MeshContact>& out, std::vector<MeshContact>& edges,
                    std::vector<MeshContact>& verts, double r) const {
    // Feature hierarchy: face > edge > vertex (Santasusana et al. 2016). An edge or vertex contact
    // is dropped when it was already found from another triangle (same id), when a triangle in
    // face contact contains it, or when it lies on the plane of an accepted contact that
    // represents a plane: a face contact, or an edge or vertex contact whose normal is its
    // triangle's normal (the centre right above the feature). The last rule removes the
    // neighbours of a flat surface that the contact circle reaches across their edges.
    const double on_plane = kOnPlane * r;
    const auto covered_by_plane = [&](const Vec3& q) {
        for (const MeshContact& a : out) {
            if (a.patch_area > 0.0 && std::abs(a.normal.dot(q - a.point)) <= on_plane) {
                return true;
            }
        }
        return false;
    };
    for (MeshContact& m : out) {
        m.patch_area = 1.0; // marks "represents a plane" while thinning; reset below
    }
    const std::size_t n_faces = out.size();
    const auto face_has_edge = [&](int e) {
        for (std::size_t i = 0; i < n_faces; ++i) {
            const auto& te = tri_edges_[static_cast<std::size_t>(out[i].id)];
            if (std::find(te.begin(), te.end(), e) != te.end()) {
                return true;
            }
        }
        return false;
    };
    // Plane-like edge and vertex contacts first, then the deeper ones.
    const auto order = [](const MeshContact& x, const MeshContact& y) {
        return x.patch_area > y.patch_area || (x.patch_area == y.patch_area && x.depth > y.depth);
    };
    std::sort(edges.begin(), edges.end(), order);
    std::sort(verts.begin(), verts.end(), order);
    for (const MeshContact& m : edges) {
        const bool seen = std::any_of(out.begin() + static_cast<std::ptrdiff_t>(n_faces), out.end(),
                                      [&](const MeshContact& o) { return o.id == m.id; });
        if (!seen && !face_has_edge(m.id) && !covered_by_plane(m.point)) {
            out.push_back(m);
        }
    }
    const std::size_t n_face_edge = out.size();
    for (const MeshContact& m : verts) {
        bool covered = std::any_of(out.begin() + static_cast<std::ptrdiff_t>(n_face_edge),
                                   out.end(), [&](const MeshContact& o) { return o.id == m.id; });
        for (std::size_t i = 0; i < n_face_edge && !covered; ++i) {
            if (out[i].feature == MeshFeature::kFace) {
                const auto& tri = triangles_[static_cast<std::size_t>(out[i].id)];
                covered = std::find(tri.begin(), tri.end(), m.id) != tri.end();
            } else {
                const auto& e = edges_[static_cast<std::size_t>(out[i].id)];
                covered = e[0] == m.id || e[1] == m.id;
            }
        }
        if (!covered && !covered_by_plane(m.point)) {
            out.push_back(m);
        }
    }
    for (MeshContact& m : out) {
        m.patch_area = 0.0;
    }
}

namespace {

/// A posed polyhedron in the world frame: vertices, face half-spaces n . x <= o, feature edges.
struct WorldBody {
    std::vector<Vec3> pts;
    std::vector<Vec3> fn;
    std::vector<double> fo;
    const std::vector<std::array<int, 4>>* edges = nullptr;
};

void to_world(const PosedPolyhedron& p, WorldBody& w) {
    const PolyhedronFeatures& f = *p.shape;
    const Mat3 rot = p.q.toRotationMatrix();
    w.pts.resize(f.vertices.size());
    for (std::size_t i = 0; i < w.pts.size(); ++i) {
        w.pts[i] = p.x + rot * f.vertices[i];
    }
    w.fn.resize(f.face_normals.size());
    w.fo.resize(f.face_normals.size());
    for (std::size_t k = 0; k < w.fn.size(); ++k) {
        w.fn[k] = rot * f.face_normals[k];
        w.fo[k] = f.face_offsets[k] + w.fn[k].dot(p.x);
    }
    w.edges = &f.edges;
}

/// 2D box (basis u, v) of the part of the body below the plane n . x = o: the hull of its vertices
/// below the plane and of its section by the plane.
std::array<detail::Vec2, 2> box_below(const WorldBody& b, const Vec3& n, double o, const Vec3& u,
                                      const Vec3& v) {
    detail::Vec2 lo = detail::Vec2::Constant(std::numeric_limits<double>::infinity());
    detail::Vec2 hi = -lo;
    for (const detail::Vec2& q : detail::section(b.pts, *b.edges, n, o, u, v)) {
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
    }
    for (const Vec3& x : b.pts) {
        if (n.dot(x) < o) {
            const detail::Vec2 q(u.dot(x), v.dot(x));
            lo = lo.cwiseMin(q);
            hi = hi.cwiseMax(q);
        }
    }
    return {lo, hi};
}

/// Deepest point below the plane n . x = o of the body inside the prism over triangle t (exact:
/// the body's edges clipped to the prism's sides and the prism's corner lines clipped to the
/// body). Raises depth (m) and sets deepest when a deeper point is found.
void deepest_in_prism(const WorldBody& b, const std::array<Vec3, 3>& t, const Vec3& n, double o,
                      double& depth, Vec3& deepest) {
    thread_local std::vector<Vec3> side_n(3);
    thread_local std::vector<double> side_o(3);
    thread_local std::vector<Vec3> clipped;
    for (std::size_t e = 0; e < 3; ++e) {
        side_n[e] = (t[(e + 1) % 3] - t[e]).cross(n).normalized();
        side_o[e] = side_n[e].dot(t[e]);
    }
    clipped.clear();
    for (const auto& e : *b.edges) {
        detail::clip_edge(b.pts[static_cast<std::size_t>(e[0])],
                          b.pts[static_cast<std::size_t>(e[1])], side_n, side_o, clipped);
    }
    for (const Vec3& t0 : t) {
        // The corner line t0 + lambda n clipped to the body: its lowest end.
        double lo = -std::numeric_limits<double>::infinity();
        double hi = std::numeric_limits<double>::infinity();
        for (std::size_t q = 0; q < b.fn.size() && lo <= hi; ++q) {
            const double den = b.fn[q].dot(n);
            const double num = b.fo[q] - b.fn[q].dot(t0);
            if (den > 0.0) {
                hi = std::min(hi, num / den);
            } else if (den < 0.0) {
                lo = std::max(lo, num / den);
            } else if (num < 0.0) {
                hi = -std::numeric_limits<double>::infinity();
            }
        }
        if (lo <= hi) {
            clipped.emplace_back(t0 + lo * n);
        }
    }
    for (const Vec3& x : clipped) {
        const double d = o - n.dot(x);
        if (d > depth) {
            depth = d;
            deepest = x;
        }
    }
}

/// True when the 2D box of triangle t2 misses the box [lo, hi].
bool misses(const std::array<detail::Vec2, 3>& t2, const std::array<detail::Vec2, 2>& box) {
    const detail::Vec2 tlo = t2[0].cwiseMin(t2[1]).cwiseMin(t2[2]);
    const detail::Vec2 thi = t2[0].cwiseMax(t2[1]).cwiseMax(t2[2]);
    return (thi.array() < box[0].array()).any() || (tlo.array() > box[1].array()).any();
}

} // namespace

double MeshWall::signed_distance(const Vec3& x) const {
    double best = std::numeric_limits<double>::infinity();
    double side = 1.0;
    for (std::size_t t = 0; t < triangles_.size(); ++t) {
        const auto c = corners(static_cast<int>(t));
        int region = 0;
        const Vec3 q = closest_on_triangle(x, c[0], c[1], c[2], region);
        const double d = (x - q).norm();
        const double s = normals_[t].dot(x - q);
        // Ties (a shared edge or vertex): the triangle seen most squarely decides the side.
        if (d < best * (1.0 - 1e-12) ||
            (d <= best * (1.0 + 1e-12) && std::abs(s) > std::abs(side))) {
            best = std::min(best, d);
            side = s;
        }
    }
    return side < 0.0 ? -best : best;
}

std::array<Vec3, 3> MeshWall::corners(int t) const {
    const auto& tri = triangles_[static_cast<std::size_t>(t)];
    return {vertices_[static_cast<std::size_t>(tri[0])],
            vertices_[static_cast<std::size_t>(tri[1])],
            vertices_[static_cast<std::size_t>(tri[2])]};
}

void MeshWall::polyhedron_contacts(const PosedPolyhedron& p, std::vector<MeshContact>& out) const {
    out.clear();
    thread_local std::vector<int> tris;
    const Vec3 reach = Vec3::Constant(p.shape->radius);
    candidates(p.x - reach, p.x + reach, tris);
    if (tris.empty()) {
        return;
    }
    thread_local WorldBody body;
    to_world(p, body);
    thread_local std::vector<std::pair<int, int>> by_facet; // (facet, triangle)
    by_facet.clear();
    for (const int t : tris) {
        by_facet.emplace_back(facet_of_[static_cast<std::size_t>(t)], t);
    }
    std::sort(by_facet.begin(), by_facet.end());
    for (std::size_t i = 0; i < by_facet.size();) {
        const int facet = by_facet[i].first;
        std::size_t j = i;
        while (j < by_facet.size() && by_facet[j].first == facet) {
            ++j;
        }
        const Vec3& n = facet_normals_[static_cast<std::size_t>(facet)];
        const double o = facet_offsets_[static_cast<std::size_t>(facet)];
        const Vec3 u = n.unitOrthogonal();
        const Vec3 v = n.cross(u);
        const auto project = [&](const std::array<Vec3, 3>& t) {
            return std::array<detail::Vec2, 3>{detail::Vec2(u.dot(t[0]), v.dot(t[0])),
                                               detail::Vec2(u.dot(t[1]), v.dot(t[1])),
                                               detail::Vec2(u.dot(t[2]), v.dot(t[2]))};
        };
        double depth = 0.0;
        Vec3 deepest = Vec3::Zero();
        if (n.dot(p.x) - o > 0.0 && n.dot(p.support(-n)) < o) {
            const auto below = box_below(body, n, o, u, v);
            for (std::size_t k = i; k < j; ++k) {
                const auto t = corners(by_facet[k].second);
                if (!misses(project(t), below)) {
                    deepest_in_prism(body, t, n, o, depth, deepest);
                }
            }
        }
        if (depth > 0.0) {
            MeshContact m;
            m.feature = MeshFeature::kFacet;
            m.id = facet;
            m.normal = n;
            m.depth = depth;
            // Patch: the body's section half way through the overlap, clipped by the triangles.
            const double level = o - 0.5 * depth;
            const double scale2 = p.shape->radius * p.shape->radius;
            const std::vector<detail::Vec2> sec = detail::hull_2d(
                detail::section(body.pts, *body.edges, n, level, u, v), 1e-24 * scale2);
            double area2 = 0.0;
            detail::Vec2 moment = detail::Vec2::Zero();
            if (sec.size() >= 3) {
                std::array<detail::Vec2, 2> box{sec[0], sec[0]};
                for (const detail::Vec2& q : sec) {
                    box[0] = box[0].cwiseMin(q);
                    box[1] = box[1].cwiseMax(q);
                }
                for (std::size_t k = i; k < j; ++k) {
                    const auto t2 = project(corners(by_facet[k].second));
                    if (!misses(t2, box)) {
                        detail::accumulate_polygon(
                            detail::clip_convex(sec,
                                                std::vector<detail::Vec2>(t2.begin(), t2.end())),
                            area2, moment);
                    }
                }
            }
            if (area2 > 2e-24 * scale2) {
                const detail::Vec2 c = moment / (3.0 * area2);
                m.point = level * n + c.x() * u + c.y() * v;
                m.patch_area = 0.5 * area2;
            } else {
                m.point = deepest + (level - n.dot(deepest)) * n;
            }
            out.push_back(m);
        }
        i = j;
    }
}

} // namespace kiln::geometry

namespace kiln::geometry {

namespace {

/// Corners of a triangle within this fraction of its longest edge of its support along a contact
/// normal belong to the touched feature (EPA's normal is accurate to ~1e-5 of the length scale).
constexpr double kTie = 1e-3;

} // namespace

int MeshWall::superquadric_contacts(const PosedSuperquadric& s, double r,
                                    std::vector<MeshContact>& out) const {
    out.clear();
    thread_local std::vector<int> tris;
    candidates(s.x - Vec3::Constant(r), s.x + Vec3::Constant(r), tris);
    thread_local std::vector<MeshContact> edges;
    thread_local std::vector<MeshContact> verts;
    edges.clear();
    verts.clear();
    int failures = 0;
    // Facets with a plane contact (the deep point over one of their triangles): the other
    // triangles of such a facet can only add contacts on that plane, which the thinning drops, so
    // their GJK/EPA queries are skipped.
    thread_local std::vector<int> plane_facets;
    plane_facets.clear();
    for (const int t : tris) {
        const Vec3& n = normals_[static_cast<std::size_t>(t)];
        const auto c = corners(t);
        const Vec3 deep = s.support(-n);
        if (n.dot(s.x - c[0]) > 0.0 && n.dot(c[0] - deep) > 0.0) {
            int region = 0;
            const Vec3 foot = deep + n.dot(c[0] - deep) * n;
            if ((foot - closest_on_triangle(deep, c[0], c[1], c[2], region)).norm() <=
                kOnEdge * r) {
                plane_facets.push_back(facet_of_[static_cast<std::size_t>(t)]);
            }
        }
    }
    const auto on_plane_facet = [&](int t) {
        return std::find(plane_facets.begin(), plane_facets.end(),
                         facet_of_[static_cast<std::size_t>(t)]) != plane_facets.end();
    };
    for (const int t : tris) {
        const Vec3& n = normals_[static_cast<std::size_t>(t)];
        const auto c = corners(t);
        if (n.dot(s.x - c[0]) <= 0.0) {
            continue; // centre behind the one-sided wall
        }
        const Vec3 deep = s.support(-n);
        const double plane_depth = n.dot(c[0] - deep);
        if (!(plane_depth > 0.0)) {
            continue;
        }
        int region = 0;
        const Vec3 q = closest_on_triangle(deep, c[0], c[1], c[2], region);
        const Vec3 foot = deep + plane_depth * n; // deep point projected on the plane
        MeshContact m;
        const bool over = (foot - q).norm() <= kOnEdge * r;
        if (!over && on_plane_facet(t)) {
            continue;
        }
        if (over) {
            // Over the triangle or its boundary: the plane's contact.
            m.normal = n;
            m.depth = plane_depth;
            m.point = foot;
            m.patch_area = 1.0; // represents the plane (see thin)
        } else {
            const SupportTriangle tri{c, (c[0] + c[1] + c[2]) / 3.0};
            const ConvexContact cc = ccd_contact(s, tri, false);
            if (!cc.converged) {
                ++failures;
                continue;
            }
            if (!cc.touching || cc.normal.dot(n) <= 0.0) {
                continue; // apart, or pushed through the back of the one-sided wall
            }
            // The overlap along EPA's normal exceeds the depth where EPA's normal errs, most on
            // shallow contacts across an edge (docs/theory/shapes.md, "Depth along a normal"):
            // the normal is refined as for a polyhedron and a superquadric (translation rounds,
            // the triangle's normal, an edge step per edge), each step kept only where the
            // overlap along it is smaller.
            Vec3 nc = cc.normal;
            double depth = overlap_along(s, tri, nc);
            if (!(depth > 0.0)) {
                continue;
            }
            refine_normal(s, tri, nc, depth);
            keep_if_smaller(s, tri, n, nc, depth);
            for (int k = 0; k < 3; ++k) {
                const Vec3 e =
                    (c[static_cast<std::size_t>((k + 1) % 3)] - c[static_cast<std::size_t>(k)])
                        .normalized();
                edge_normal(s, tri, e, nc, depth);
            }
            if (!(depth > 0.0) || nc.dot(n) <= 0.0) {
                continue;
            }
            const double top = std::max({nc.dot(c[0]), nc.dot(c[1]), nc.dot(c[2])});
            const double edge_max =
                std::max({(c[1] - c[0]).norm(), (c[2] - c[1]).norm(), (c[0] - c[2]).norm()});
            std::array<int, 3> hit{};
            int n_hit = 0;
            for (int k = 0; k < 3; ++k) {
                if (top - nc.dot(c[static_cast<std::size_t>(k)]) <= kTie * edge_max) {
                    hit[static_cast<std::size_t>(n_hit++)] = k;
                }
            }
            m.normal = nc;
            m.depth = depth;
            m.patch_area = 0.0;
            if (n_hit == 1) {
                region = 4 + hit[0];
                m.point = c[static_cast<std::size_t>(hit[0])];
            } else if (n_hit == 2) {
                // Edge k runs from corner k to k + 1: corners {0, 1} -> 0, {1, 2} -> 1, {0, 2}
                // -> 2.
                const int k = hit[1] - hit[0] == 2 ? 2 : hit[0];
                region = 1 + k;
                const Vec3& e0 = c[static_cast<std::size_t>(k)];
                const Vec3 e = c[static_cast<std::size_t>((k + 1) % 3)] - e0;
                const Vec3 touch = s.support(-nc) + depth * nc;
                m.point = e0 + std::clamp(e.dot(touch - e0) / e.squaredNorm(), 0.0, 1.0) * e;
            } else {
                // Normal along the triangle's: the boundary feature nearest to the deep point.
                m.point = q;
            }
        }
        file_by_region(m, t, region, out, edges, verts);
    }
    thin(out, edges, verts, r);
    for (MeshContact& m : out) {
        m.point -= 0.5 * m.depth * m.normal; // half way through the overlap, as on analytic walls
    }
    return failures;
}

} // namespace kiln::geometry
