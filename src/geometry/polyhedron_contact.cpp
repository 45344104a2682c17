// Fast common plane between convex polyhedra, contact points and patch (see the header). The
// memory of a pair's last search is in polyhedron_memo.cpp, the parts both use in
// polyhedron_search.hpp.

#include "geometry/polyhedron_contact.hpp"

#include "core/error.hpp"
#include "geometry/convex_polygon.hpp"
#include "geometry/polyhedron_search.hpp"
#include "geometry/separating_axis.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <optional>
#include <utility>

namespace kiln::geometry {
namespace {
/// The vertex on a box's corner that d_body points to, where no other corner comes near along it,
/// else -1. That corner beats every other by at least min_k 2 h_k |g_k| (g = d along the axes);
/// where this exceeds what the vertices' distance from the exact corners (up to 1e-12 of the
/// radius along each axis, box_of) and the scan's round-off could make up, 2 sqrt(3) 1e-12 r |d|
/// + O(1e-16 r |d|), it is the vertex the scan finds. Not inlined: the callers' code, and so how
/// GCC contracts their products, stays as it was (test PatchOnDemandGivesTheSameNumbers).
[[gnu::noinline]] int box_support(const PolyhedronFeatures::Box& box, double radius,
                                  const Vec3& d_body) {
    const Vec3 g = box.along(d_body);
    const Vec3 lead = 2.0 * box.half.cwiseProduct(g.cwiseAbs());
    if (!(lead.minCoeff() > 1e-11 * radius * d_body.cwiseAbs().sum())) {
        return -1;
    }
    return box.corner[PolyhedronFeatures::Box::corner_of(g)];
}

/// The common plane's normal turned to the world (q * m, m in A's frame). One compiled copy for
/// every place that reports it: inlined, GCC contracts the product's multiply-adds per call site,
/// and the patch's normal and the plane's own (PatchOnDemandGivesTheSameNumbers) parted by an ulp
/// when the code around them changed.
[[gnu::noinline]] Vec3 world_normal(const Quat& q, const Vec3& m) {
    return q * m;
}
} // namespace

Vec3 PolyhedronFeatures::support(const Vec3& d_body) const {
    const int v = box ? box_support(*box, radius, d_body) : -1;
    return v >= 0 ? vertices[static_cast<std::size_t>(v)] : farthest_vertex(vertices, d_body);
}

namespace {

/// Largest angle (rad) between the normals of two adjacent triangles counted as one plane.
constexpr double kCoplanarAngle = 1e-9;

/// Size of a pair's vertex-face distance table (n_faces_a n_vertices_b + n_faces_b n_vertices_a)
/// below which the common plane keeps the full tables (a cube pair's 96 entries: the bounded
/// scan's bookkeeping cost 2-7 %, docs/performance.md, session 12).
constexpr std::size_t kBoundedTableEntries = 200;

int find_root(std::vector<int>& parent, int i) {
    while (parent[static_cast<std::size_t>(i)] != i) {
        parent[static_cast<std::size_t>(i)] =
            parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
        i = parent[static_cast<std::size_t>(i)];
    }
    return i;
}

/// The box of a polyhedron's features (PolyhedronFeatures::box), or none: six faces in three
/// opposite pairs with orthogonal normals, each pair at equal offsets, and eight vertices each on
/// a corner, all to 1e-12 (of 1 for the normals, of the radius for lengths). The closed-form
/// common plane then differs from the general one by round-off of that order. Axes along the body
/// frame's (to 1e-12) are taken as the identity (Box::aligned).
std::optional<PolyhedronFeatures::Box> box_of(const PolyhedronFeatures& f) {
    constexpr double tol = 1e-12;
    if (f.face_normals.size() != 6 || f.vertices.size() != 8 || f.edges.size() != 12) {
        return std::nullopt;
    }
    PolyhedronFeatures::Box b;
    std::array<bool, 6> used{};
    int axis = 0;
    for (int k = 0; k < 6; ++k) {
        if (used[static_cast<std::size_t>(k)]) {
            continue;
        }
        const Vec3& nk = f.face_normals[static_cast<std::size_t>(k)];
        for (int l = k + 1; l < 6; ++l) {
            const auto ul = static_cast<std::size_t>(l);
            if (!used[ul] && (nk + f.face_normals[ul]).norm() <= tol) {
                used[static_cast<std::size_t>(k)] = used[ul] = true;
                const double ok = f.face_offsets[static_cast<std::size_t>(k)];
                const double ol = f.face_offsets[ul];
                if (std::abs(ok - ol) > tol * f.radius) {
                    return std::nullopt; // not centred on the origin
                }
                b.axes.col(axis) = nk;
                b.half[axis] = 0.5 * (ok + ol);
                b.plus[static_cast<std::size_t>(axis)] = k;
                b.minus[static_cast<std::size_t>(axis)] = l;
                ++axis;
                break;
            }
        }
    }
    if (axis != 3) {
        return std::nullopt;
    }
    for (int i = 0; i < 3; ++i) {
        for (int j = i + 1; j < 3; ++j) {
            if (std::abs(b.axes.col(i).dot(b.axes.col(j))) > tol) {
                return std::nullopt;
            }
        }
    }
    // Every vertex on a corner: its heights along the axes are the half extents.
    const auto corners = [&f](const PolyhedronFeatures::Box& box) {
        for (const Vec3& v : f.vertices) {
            for (int i = 0; i < 3; ++i) {
                if (std::abs(std::abs(box.axes.col(i).dot(v)) - box.half[i]) > tol * f.radius) {
                    return false;
                }
            }
        }
        return true;
    };
    if (!corners(b)) {
        return std::nullopt;
    }
    // Faces along the body frame's axes (a mesh drawn axis-aligned; the hull's normals may carry
    // round-off of 1e-16): the axes become the identity, column k along e_k, each axis's faces
    // swapped where its normal points along -e_k.
    PolyhedronFeatures::Box id;
    id.axes = Mat3::Identity();
    // (Orthogonal axes each within tol of some +-e_k take distinct k.)
    for (int i = 0; i < 3; ++i) {
        const Vec3 n = b.axes.col(i);
        int k = 0;
        n.cwiseAbs().maxCoeff(&k);
        const double sign = n[k] > 0.0 ? 1.0 : -1.0;
        const auto uk = static_cast<std::size_t>(k);
        if ((n - sign * Vec3::Unit(k)).norm() > tol) {
            return b;
        }
        const auto ui = static_cast<std::size_t>(i);
        id.half[k] = b.half[i];
        id.plus[uk] = sign > 0.0 ? b.plus[ui] : b.minus[ui];
        id.minus[uk] = sign > 0.0 ? b.minus[ui] : b.plus[ui];
    }
    id.aligned = true;
    return corners(id) ? id : b;
}

/// box_of with Box::corner filled in, or none where two vertices share a corner.
std::optional<PolyhedronFeatures::Box> box_with_corners(const PolyhedronFeatures& f) {
    std::optional<PolyhedronFeatures::Box> b = box_of(f);
    if (!b) {
        return b;
    }
    std::array<bool, 8> seen{};
    for (std::size_t i = 0; i < f.vertices.size(); ++i) {
        const std::size_t s = PolyhedronFeatures::Box::corner_of(b->along(f.vertices[i]));
        if (seen[s]) {
            return std::nullopt;
        }
        seen[s] = true;
        b->corner[s] = static_cast<int>(i);
    }
    return b;
}

} // namespace

void band_vertices(const PosedPolyhedron& p, const double* h, double top, double sign, double band,
                   NearVertices& out) {
    out.clear();
    const std::vector<Vec3>& vs = p.shape->vertices;
    for (std::size_t i = 0; i < vs.size(); ++i) {
        // below < band exactly when the rounded 1 - below / band is positive (band > 0: a
        // quotient below 1 rounds to at most 1 - 2^-53), so the division runs only in the band.
        const double below = sign * (top - h[i]);
        if (below < band) {
            out.emplace_back(p.x + p.q * vs[i], 1.0 - below / band);
        }
    }
}

PolyhedronFeatures polyhedron_features(const ConvexPolyhedron& p) {
    PolyhedronFeatures f;
    f.vertices = p.vertices;
    f.radius = p.bounding_radius();
    const std::size_t nt = p.faces.size();
    std::vector<Vec3> area(nt);
    std::map<std::array<int, 2>, int> tri_of; // directed edge -> triangle
    for (std::size_t t = 0; t < nt; ++t) {
        const auto& tri = p.faces[t];
        const Vec3& a = p.vertices[static_cast<std::size_t>(tri[0])];
        area[t] = (p.vertices[static_cast<std::size_t>(tri[1])] - a)
                      .cross(p.vertices[static_cast<std::size_t>(tri[2])] - a);
        for (std::size_t k = 0; k < 3; ++k) {
            tri_of[{tri[k], tri[(k + 1) % 3]}] = static_cast<int>(t);
        }
    }
    // Merge adjacent triangles of one plane (union-find over shared edges).
    std::vector<int> parent(nt);
    std::iota(parent.begin(), parent.end(), 0);
    for (const auto& [e, t] : tri_of) {
        const auto it = tri_of.find({e[1], e[0]});
        if (it == tri_of.end()) {
            continue;
        }
        const Vec3 n0 = area[static_cast<std::size_t>(t)].normalized();
        const Vec3 n1 = area[static_cast<std::size_t>(it->second)].normalized();
        if (n0.dot(n1) > 0.0 && n0.cross(n1).norm() < kCoplanarAngle) {
            parent[static_cast<std::size_t>(find_root(parent, t))] = find_root(parent, it->second);
        }
    }
    std::vector<int> face_of(nt, -1);
    std::vector<Vec3> sum;
    for (std::size_t t = 0; t < nt; ++t) {
        const auto r = static_cast<std::size_t>(find_root(parent, static_cast<int>(t)));
        if (face_of[r] < 0) {
            face_of[r] = static_cast<int>(sum.size());
            sum.emplace_back(Vec3::Zero());
        }
        face_of[t] = face_of[r];
        sum[static_cast<std::size_t>(face_of[t])] += area[t];
    }
    f.face_normals.resize(sum.size());
    f.face_offsets.assign(sum.size(), -std::numeric_limits<double>::infinity());
    for (std::size_t g = 0; g < sum.size(); ++g) {
        f.face_normals[g] = sum[g].normalized();
    }
    for (std::size_t t = 0; t < nt; ++t) {
        const auto g = static_cast<std::size_t>(face_of[t]);
        for (const int v : p.faces[t]) {
            f.face_offsets[g] = std::max(
                f.face_offsets[g], f.face_normals[g].dot(p.vertices[static_cast<std::size_t>(v)]));
        }
    }
    f.inradius = std::numeric_limits<double>::infinity();
    for (const double o : f.face_offsets) {
        f.inradius = std::min(f.inradius, o);
    }
    // Volume-equivalent radius, the expression of dynamics::equivalent_radius (the template's
    // volume is the polyhedron's).
    f.r_equiv = std::cbrt(3.0 * p.volume / (4.0 * std::numbers::pi));
    for (const auto& e : p.edges) {
        const auto t0 = tri_of.find({e[0], e[1]});
        const auto t1 = tri_of.find({e[1], e[0]});
        if (t0 == tri_of.end() || t1 == tri_of.end()) {
            continue;
        }
        const int g0 = face_of[static_cast<std::size_t>(t0->second)];
        const int g1 = face_of[static_cast<std::size_t>(t1->second)];
        if (g0 != g1) {
            f.edges.push_back({e[0], e[1], g0, g1});
        }
    }
    f.edge_arcs.reserve(f.edges.size());
    for (const auto& e : f.edges) {
        const Vec3& n0 = f.face_normals[static_cast<std::size_t>(e[2])];
        const Vec3& n1 = f.face_normals[static_cast<std::size_t>(e[3])];
        const Vec3& v0 = f.vertices[static_cast<std::size_t>(e[0])];
        f.edge_arcs.push_back({n1.cross(n0), f.vertices[static_cast<std::size_t>(e[1])] - v0});
    }
    f.box = box_with_corners(f);
    return f;
}

namespace search {

/// B's pose and vertices in A's frame (enough for A's face stage, which rejects most near misses).
void make_relative(const PosedPolyhedron& a, const PosedPolyhedron& b, Relative& r) {
    r.pruned = false;
    r.faces = false;
    const Quat qab = a.q.conjugate() * b.q;
    r.rot = qab.toRotationMatrix();
    r.shift = a.q.conjugate() * (b.x - a.x);
    const PolyhedronFeatures& fb = *b.shape;
    r.vb.resize(fb.vertices.size());
    for (std::size_t j = 0; j < fb.vertices.size(); ++j) {
        r.vb[j] = r.rot * fb.vertices[j] + r.shift;
    }
    // A new pose: no plane of B turned yet (the numbers restart after 2^32 - 1 poses).
    const std::size_t nfb = fb.face_normals.size();
    r.nb.resize(nfb);
    r.ob.resize(nfb);
    r.face_pose.resize(nfb, 0);
    if (++r.pose == 0) {
        std::fill(r.face_pose.begin(), r.face_pose.end(), 0U);
        r.pose = 1;
    }
}

[[gnu::noinline]] void relative_face(const PolyhedronFeatures& fb, Relative& r, std::size_t k) {
    r.nb[k] = r.rot * fb.face_normals[k];
    r.ob[k] = fb.face_offsets[k] + r.nb[k].dot(r.shift);
    r.face_pose[k] = r.pose;
}

/// B's face planes in A's frame (after make_relative): those not turned yet.
void relative_faces(const PolyhedronFeatures& fb, Relative& r) {
    if (r.faces) {
        return;
    }
    r.faces = true;
    for (std::size_t k = 0; k < fb.face_normals.size(); ++k) {
        need_face(fb, r, k);
    }
}

/// The Gauss-map arcs of B's kept edges (after the prune; turns the planes they read).
void relative_arcs(const PolyhedronFeatures& fb, Relative& r) {
    r.arcs.resize(fb.edges.size());
    for (const int e : r.edges_b) {
        const auto k = static_cast<std::size_t>(e);
        need_face(fb, r, static_cast<std::size_t>(fb.edges[k][2]));
        need_face(fb, r, static_cast<std::size_t>(fb.edges[k][3]));
        const Vec3 c = -r.nb[static_cast<std::size_t>(fb.edges[k][2])];
        const Vec3 d = -r.nb[static_cast<std::size_t>(fb.edges[k][3])];
        r.arcs[k] = {c, d, d.cross(c)};
    }
}

/// Squared distance (m^2) from the segment p0-p1 to the point c.
double segment_point_distance2(const Vec3& p0, const Vec3& p1, const Vec3& c) {
    const Vec3 d = p1 - p0;
    const double dd = d.squaredNorm();
    const double t = dd > 0.0 ? std::clamp((c - p0).dot(d) / dd, 0.0, 1.0) : 0.0;
    return (p0 + t * d - c).squaredNorm();
}

} // namespace search

namespace {

using namespace search;
using detail::clip_convex_into;
using detail::clip_edge;
using detail::hull_2d_into;
using detail::section_into;
using detail::Vec2;

/// Gauss-map test of Gregorius (2013): do the arcs (a, b) of A's edge and (c, d) of B's negated
/// edge cross, i.e. does the edge pair span a face of the Minkowski difference?
bool is_minkowski_face(const Vec3& a, const Vec3& b, const Vec3& bxa, const Vec3& c, const Vec3& d,
                       const Vec3& dxc) {
    const double cba = c.dot(bxa);
    const double dba = d.dot(bxa);
    if (!(cba * dba < 0.0)) {
        return false; // B's arc on one side of A's great circle: most pairs end here
    }
    const double adc = a.dot(dxc);
    const double bdc = b.dot(dxc);
    return adc * bdc < 0.0 && cba * bdc > 0.0;
}

/// Edges of a body (vertices and distances beyond the other body's face planes in `t`, its
/// reach set) that pass within the reach of the other body, to the test's precision: dropped are
/// edges whose two ends lie beyond one face plane by more than the reach and edges farther than
/// `reach` from the other body's bounding sphere (centre `centre`, radius `radius`). Their
/// indices go to `kept`, in order. The filled columns (the face stages' planes, the deepest
/// among them) drop most edges far from the contact, so only the others read their ends' rows.
void keep_edges(const std::vector<std::array<int, 4>>& edges, PlaneDistances& t, double reach,
                const Vec3& centre, double radius, std::vector<int>& kept) {
    kept.clear();
    const double far2 = (radius + reach) * (radius + reach);
    const std::vector<Vec3>& v = t.vertices();
    t.set_reach(reach);
    for (std::size_t e = 0; e < edges.size(); ++e) {
        const auto i0 = static_cast<std::size_t>(edges[e][0]);
        const auto i1 = static_cast<std::size_t>(edges[e][1]);
        if (!t.both_beyond(i0, i1) && segment_point_distance2(v[i0], v[i1], centre) <= far2) {
            kept.push_back(static_cast<int>(e));
        }
    }
}

/// keep_edges from the full tables (the path for small bodies): edges of a body (vertices `v`;
/// their distances beyond the other body's nf face planes in `dist`, vertex-major) that pass within
/// `reach` of the other body, to the test's precision: dropped are edges farther than `reach` from
/// the other body's bounding sphere (centre `centre`, radius `radius`) and edges whose two ends lie
/// beyond one face plane by more than `reach`. Their indices go to `kept`, in order.
void keep_edges_by_masks(const std::vector<std::array<int, 4>>& edges, const std::vector<Vec3>& v,
                         const std::vector<double>& dist, std::size_t nf, double reach,
                         const Vec3& centre, double radius, std::vector<int>& kept) {
    kept.clear();
    const double far2 = (radius + reach) * (radius + reach);
    if (nf <= 64) {
        // One bit per face plane and vertex: set when the vertex lies beyond the plane by more
        // than reach. An edge has both ends beyond one plane exactly when the masks of its ends
        // share a bit, so the plane test costs one AND per edge after nv x nf comparisons
        // (without branches) instead of up to 2 nf per edge (the loop below; the same set kept).
        thread_local std::vector<std::uint64_t> beyond;
        beyond.resize(v.size());
        for (std::size_t i = 0; i < v.size(); ++i) {
            const double* d = dist.data() + i * nf;
            std::uint64_t mask = 0;
            for (std::size_t k = 0; k < nf; ++k) {
                mask |= static_cast<std::uint64_t>(d[k] > reach) << k;
            }
            beyond[i] = mask;
        }
        for (std::size_t e = 0; e < edges.size(); ++e) {
            const auto i0 = static_cast<std::size_t>(edges[e][0]);
            const auto i1 = static_cast<std::size_t>(edges[e][1]);
            if ((beyond[i0] & beyond[i1]) == 0 &&
                segment_point_distance2(v[i0], v[i1], centre) <= far2) {
                kept.push_back(static_cast<int>(e));
            }
        }
        return;
    }
    std::size_t hint = 0; // the plane that dropped the last edge: it often drops the next too
    for (std::size_t e = 0; e < edges.size(); ++e) {
        const auto i0 = static_cast<std::size_t>(edges[e][0]);
        const auto i1 = static_cast<std::size_t>(edges[e][1]);
        if (segment_point_distance2(v[i0], v[i1], centre) > far2) {
            continue;
        }
        const double* d0 = dist.data() + i0 * nf;
        const double* d1 = dist.data() + i1 * nf;
        if (std::min(d0[hint], d1[hint]) > reach) {
            continue;
        }
        bool beyond = false;
        for (std::size_t k = 0; k < nf; ++k) {
            if (std::min(d0[k], d1[k]) > reach) {
                hint = k;
                beyond = true;
                break;
            }
        }
        if (!beyond) {
            kept.push_back(static_cast<int>(e));
        }
    }
}

/// Appends p to pts unless a point within tol is already there.
void add_unique(std::vector<Vec3>& pts, const Vec3& p, double tol2) {
    for (const Vec3& q : pts) {
        if ((q - p).squaredNorm() <= tol2) {
            return;
        }
    }
    pts.push_back(p);
}

/// Depth along the normal m (unit, from B to A, A's body frame) as the patch takes it: the
/// distance between the deepest vertices of A and B along m (m).
struct PlaneDepth {
    double d_a;            // min over A's vertices of m . x (m)
    double d_b;            // max over B's vertices of m . x (m)
    std::size_t deepest_a; // a vertex of A where d_a is reached (the first)
    std::size_t deepest_b; // a vertex of B where d_b is reached (the first)
};

/// `heights`: m . x of each vertex kept as well, A's in ha and B's in hb (sized by the caller).
template <bool heights = false>
PlaneDepth plane_depth(const PolyhedronFeatures& fa, const Relative& r, const Vec3& m,
                       double* ha = nullptr, double* hb = nullptr) {
    // m . x over each body's vertices: the extremes and where they are first reached.
    PlaneDepth p{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                 0, 0};
    for (std::size_t i = 0; i < fa.vertices.size(); ++i) {
        const double h = m.dot(fa.vertices[i]);
        if constexpr (heights) {
            ha[i] = h;
        }
        if (h < p.d_a) {
            p.d_a = h;
            p.deepest_a = i;
        }
    }
    for (std::size_t j = 0; j < r.vb.size(); ++j) {
        const double h = m.dot(r.vb[j]);
        if constexpr (heights) {
            hb[j] = h;
        }
        if (h > p.d_b) {
            p.d_b = h;
            p.deepest_b = j;
        }
    }
    return p;
}

/// The lists of NearBand from the heights of plane_depth (A's vertices lowest along m, B's
/// highest; depth = d_b - d_a > 0).
void near_band(const PosedPolyhedron& a, const PosedPolyhedron& b, const PlaneDepth& pd,
               const double* ha, const double* hb, const NearBand& near) {
    const double band = near.fraction * (pd.d_b - pd.d_a);
    band_vertices(a, ha, pd.d_a, -1.0, band, *near.a);
    band_vertices(b, hb, pd.d_b, 1.0, band, *near.b);
}

/// Points and patch for the normal m (unit, from B to A), all in A's body frame; the result's
/// vectors are converted to the world frame of A at the end. `point_only`: the points and the
/// patch polygon are left empty (depth, normal, point and patch_area the same numbers).
PolyhedronContact patch_in_a(const PosedPolyhedron& a, const PosedPolyhedron& b, Relative& r,
                             const Vec3& m, bool point_only = false) {
    const PolyhedronFeatures& fa = *a.shape;
    const PolyhedronFeatures& fb = *b.shape;
    const double scale = fa.radius + fb.radius;
    PolyhedronContact c;
    const PlaneDepth pd = plane_depth(fa, r, m);
    const double d_a = pd.d_a;
    const double d_b = pd.d_b;
    c.depth = d_b - d_a;
    c.touching = c.depth > 0.0;
    const double s = 0.5 * (d_a + d_b);
    const Vec3 u = m.unitOrthogonal();
    const Vec3 v = m.cross(u);

    // Patch: section of A by the CP clipped by the section of B. (Per-thread buffers: a resting
    // face-on-face pair builds it every step.)
    thread_local std::vector<Vec2> section; // a section's points, then the clip's scratch
    thread_local std::vector<Vec2> poly;    // A's hull, clipped to the patch
    thread_local std::vector<Vec2> hull_b;
    const double area_tol = 1e-24 * scale * scale;
    section_into(fa.vertices, fa.edges, m, s, u, v, section);
    hull_2d_into(section, area_tol, poly);
    section_into(r.vb, fb.edges, m, s, u, v, section);
    hull_2d_into(section, area_tol, hull_b);
    if (poly.size() >= 3 && hull_b.size() >= 3) {
        clip_convex_into(poly, hull_b, section);
    } else {
        poly.clear();
    }
    double area2 = 0.0;
    Vec2 moment = Vec2::Zero();
    detail::accumulate_polygon(poly, area2, moment);
    const bool has_patch = area2 > 2.0 * area_tol;

    // Vertices of A n B: edges of each body clipped by the other's face planes. Read for the
    // result's points and, without a patch, for the contact point: with point_only and a patch
    // they are not needed and not computed.
    // With the edge lists of the plane search, only the edges it kept: a dropped edge lies wholly
    // outside one face plane of the other body, so its clip is empty anyway.
    thread_local std::vector<Vec3> raw;
    thread_local std::vector<Vec3> pts;
    raw.clear();
    pts.clear();
    if (!point_only || !has_patch) {
        relative_faces(fb, r); // (the boxes' closed form and the memory turn only a few)
        const auto clip_a = [&](const std::array<int, 4>& e) {
            clip_edge(fa.vertices[static_cast<std::size_t>(e[0])],
                      fa.vertices[static_cast<std::size_t>(e[1])], r.nb, r.ob, raw);
        };
        const auto clip_b = [&](const std::array<int, 4>& e) {
            clip_edge(r.vb[static_cast<std::size_t>(e[0])], r.vb[static_cast<std::size_t>(e[1])],
                      fa.face_normals, fa.face_offsets, raw);
        };
        if (r.pruned) {
            for (const int e : r.edges_a) {
                clip_a(fa.edges[static_cast<std::size_t>(e)]);
            }
            for (const int e : r.edges_b) {
                clip_b(fb.edges[static_cast<std::size_t>(e)]);
            }
        } else {
            for (const auto& e : fa.edges) {
                clip_a(e);
            }
            for (const auto& e : fb.edges) {
                clip_b(e);
            }
        }
        const double tol2 = 1e-24 * scale * scale;
        for (const Vec3& p : raw) {
            add_unique(pts, p, tol2);
        }
    }

    Vec3 point_a;
    if (has_patch) {
        const Vec2 cen = moment / (3.0 * area2);
        point_a = s * m + cen.x() * u + cen.y() * v;
        c.patch_area = 0.5 * area2;
    } else if (!pts.empty()) {
        Vec3 mean = Vec3::Zero();
        for (const Vec3& p : pts) {
            mean += p;
        }
        mean /= static_cast<double>(pts.size());
        point_a = mean + (s - m.dot(mean)) * m;
    } else {
        // No points (touching at a vertex or edge to round-off): midpoint of the deepest points.
        point_a =
            0.5 * (fa.support(-m) + (r.rot * b.shape->support(r.rot.transpose() * m) + r.shift));
    }
    c.normal = world_normal(a.q, m);
    c.point = a.x + a.q * point_a;
    if (point_only) {
        return c;
    }
    c.points.reserve(pts.size());
    for (const Vec3& p : pts) {
        c.points.emplace_back(a.x + a.q * p);
    }
    if (has_patch) {
        c.patch.reserve(poly.size());
        for (const Vec2& p : poly) {
            c.patch.emplace_back(a.x + a.q * (s * m + p.x() * u + p.y() * v));
        }
    }
    return c;
}

} // namespace

namespace search {

/// The edge-edge stage over the kept edges r.edges_a x r.edges_b (arcs set): raises best (the
/// largest separation, m) and sets best_m (A's frame, from B to A) and c.feature when an edge pair
/// spanning a face of the Minkowski difference gives a larger one; `second` (m) is raised to the
/// largest of the other values met (the runner-up, for the memory's tie test).
void edge_stage(const PolyhedronFeatures& fa, const PolyhedronFeatures& fb, const Relative& r,
                double& best_out, Vec3& best_m, PolyhedronContact& c, double& second_out) {
    double best = best_out;
    double second = second_out;
    int iterations = c.iterations;
    bool raised = false;
    Vec3 winner_m = best_m;
    for (const int ia : r.edges_a) {
        const auto& ea = fa.edges[static_cast<std::size_t>(ia)];
        const Vec3& na0 = fa.face_normals[static_cast<std::size_t>(ea[2])];
        const Vec3& na1 = fa.face_normals[static_cast<std::size_t>(ea[3])];
        const Vec3& bxa = fa.edge_arcs[static_cast<std::size_t>(ia)][0]; // na1 x na0
        const Vec3& pa = fa.vertices[static_cast<std::size_t>(ea[0])];
        const Vec3& da = fa.edge_arcs[static_cast<std::size_t>(ia)][1]; // v1 - v0
        for (const int ib : r.edges_b) {
            const auto k = static_cast<std::size_t>(ib);
            const auto& arc = r.arcs[k];
            if (!is_minkowski_face(na0, na1, bxa, arc[0], arc[1], arc[2])) {
                continue;
            }
            const auto& eb = fb.edges[k];
            ++iterations;
            const Vec3& pb = r.vb[static_cast<std::size_t>(eb[0])];
            const Vec3 db = r.vb[static_cast<std::size_t>(eb[1])] - pb;
            Vec3 n = da.cross(db);
            const double len = n.norm();
            if (len <= 1e-12 * da.norm() * db.norm()) {
                continue; // parallel edges: covered by the face planes
            }
            n /= len;
            if (n.dot(pa) < 0.0) {
                n = -n; // outward from A (A's centre is the origin)
            }
            const double sep = n.dot(pb - pa);
            if (sep > best) {
                second = best;
                best = sep;
                winner_m = -n;
                raised = true;
            } else {
                second = std::max(second, sep);
            }
        }
    }
    if (raised) {
        best_m = winner_m;
        c.feature = CommonPlaneFeature::kEdgeEdge;
    }
    best_out = best;
    second_out = second;
    c.iterations = iterations;
}

/// Separations (m) along the face planes of `t`'s other body that can be the largest, as the
/// full face stage gives them (the smallest distance of the vertices beyond each plane): sep[k]
/// is computed for every face whose upper bound `bound[k]` (m) is not below the largest
/// separation found so far (or `floor`, a value the search's answer reaches anyway), and is
/// -infinity for the others, which therefore cannot be the largest nor tie it. The face of the
/// largest bound goes first, so that the others meet a high bar. With `bound` empty every face is
/// computed.
void face_separations(PlaneDistances& t, const std::vector<double>& bound, double floor,
                      std::vector<double>& sep) {
    const std::size_t nf = t.faces();
    if (bound.empty()) {
        sep.resize(nf);
        for (std::size_t k = 0; k < nf; ++k) {
            sep[k] = t.separation(k);
        }
        return;
    }
    sep.assign(nf, -std::numeric_limits<double>::infinity());
    const auto first =
        static_cast<std::size_t>(std::max_element(bound.begin(), bound.end()) - bound.begin());
    sep[first] = t.separation(first);
    double bar = std::max(floor, sep[first]);
    for (std::size_t k = 0; k < nf; ++k) {
        if (k != first && !(bound[k] < bar)) {
            sep[k] = t.separation(k);
            bar = std::max(bar, sep[k]);
        }
    }
}

/// Signed distances (m) of the vertices `v` beyond the face planes (n, o) of the other body,
/// vertex-major: dist[i * nf + k] = n_k . v_i - o_k; sep[k] = the smallest over the vertices (the
/// separation along face k). Returns whether a vertex lies strictly inside the other body (all its
/// distances negative). Vertex by vertex, so the faces' running minima are independent of each
/// other (no chain of dependent minima per face) and the table is written in order.
bool face_distances(const std::vector<Vec3>& n, const std::vector<double>& o,
                    const std::vector<Vec3>& v, std::vector<double>& dist,
                    std::vector<double>& sep) {
    const std::size_t nf = n.size();
    dist.resize(nf * v.size());
    sep.assign(nf, std::numeric_limits<double>::infinity());
    bool inside = false;
    for (std::size_t i = 0; i < v.size(); ++i) {
        const Vec3& x = v[i];
        double* row = dist.data() + i * nf;
        double top = -std::numeric_limits<double>::infinity();
        for (std::size_t k = 0; k < nf; ++k) {
            const double d = n[k].dot(x) - o[k];
            row[k] = d;
            sep[k] = std::min(sep[k], d);
            top = std::max(top, d);
        }
        inside = inside || top < 0.0;
    }
    return inside;
}

/// The first kept edge of one body (vertices `v`, A's frame) that crosses the other body (face
/// planes n, o in A's frame), i.e. has a piece of positive length inside every face plane; -1:
/// none.
int edge_crosses(const std::vector<std::array<int, 4>>& edges, const std::vector<int>& kept,
                 const std::vector<Vec3>& v, const std::vector<Vec3>& n,
                 const std::vector<double>& o) {
    for (const int e : kept) {
        const Vec3& p0 = v[static_cast<std::size_t>(edges[static_cast<std::size_t>(e)][0])];
        const Vec3 d = v[static_cast<std::size_t>(edges[static_cast<std::size_t>(e)][1])] - p0;
        double t0 = 0.0;
        double t1 = 1.0;
        for (std::size_t k = 0; k < n.size() && t0 < t1; ++k) {
            const double den = n[k].dot(d);
            const double num = o[k] - n[k].dot(p0);
            if (den == 0.0) {
                t1 = num < 0.0 ? -1.0 : t1;
            } else if (den > 0.0) {
                t1 = std::min(t1, num / den);
            } else {
                t0 = std::max(t0, num / den);
            }
        }
        if (t0 < t1) {
            return e;
        }
    }
    return -1;
}

} // namespace search

namespace {

/// The full search of the fast common plane (after make_relative): sets best (the largest
/// separation, m), best_m (A's frame, from B to A), c.feature and c.iterations, and the prune's
/// lists in r. False when a separating direction proved the pair apart: c is then the answer.
/// `scan`: which face stages (see detail::FaceScan).
bool full_search(const PosedPolyhedron& a, const PosedPolyhedron& b, detail::FaceScan scan,
                 Relative& r, double& best, Vec3& best_m, PolyhedronContact& c) {
    const PolyhedronFeatures& fa = *a.shape;
    const PolyhedronFeatures& fb = *b.shape;
    const std::size_t nfa = fa.face_normals.size();
    const std::size_t nfb = fb.face_normals.size();
    thread_local std::vector<double> sep;
    thread_local std::vector<double> bound;
    // The bounded scan (only the faces that can be the largest; the rest of the table of
    // distances where the prune and the certificates read it, PlaneDistances) pays where a face
    // plane's scan is long and a vertex's row short: bodies with more vertices than faces, in a
    // table too large for the bookkeeping to vanish in (measured, docs/performance.md,
    // "Polyhedron search with bounded face stages (session 12)": 1.3x for `cylinder_16` pairs,
    // 1.05x for `cylinder_8`; icosahedra, 12 vertices and 20 faces, and cubes, a table of 96,
    // do not gain). Others take the full tables: every vertex against every face plane, vertex
    // by vertex, the inside-vertex certificates in the same pass. Same answer, bit for bit.
    const std::size_t nva = fa.vertices.size();
    const std::size_t nvb = r.vb.size();
    const bool bounded = scan == detail::FaceScan::bounded ||
                         (scan == detail::FaceScan::automatic && nva + nvb > nfa + nfb &&
                          nfa * nvb + nfb * nva >= kBoundedTableEntries);
    r.full_tables = !bounded;
    // Upper bounds of the face separations (m), so that a face that cannot be the largest is
    // not scanned: the smallest distance of B's vertices beyond A's face plane k is at most the
    // distance of any point of B's hull, e.g. of c_B - rho_B n_k with c_B B's centre and rho_B
    // its inscribed radius (the ball of radius rho_B about the centre lies inside every face
    // plane): n_k . c_B - o_k - rho_B; for B's face k (in A's frame) and A's vertices,
    // -o_k - rho_A. Slack against round-off and the merged faces: their normals are within 1e-9
    // rad of the triangles' (polyhedron_features), so the offsets within 1e-9 of the radius of
    // the triangles' planes; 1e-8 of the sum of the radii covers both.
    const double slack = 1e-8 * (fa.radius + fb.radius);
    std::optional<PlaneDistances> tb; // B's vertices beyond A's planes (bounded)
    bool b_in_a = false;              // certificates of the full tables
    bool a_in_b = false;
    if (bounded) {
        tb.emplace(fa.face_normals, fa.face_offsets, r.vb, r.dist_b);
        bound.resize(nfa);
        for (std::size_t k = 0; k < nfa; ++k) {
            bound[k] = fa.face_normals[k].dot(r.shift) - fa.face_offsets[k] - fb.inradius + slack;
        }
        face_separations(*tb, bound, -std::numeric_limits<double>::infinity(), sep);
    } else {
        b_in_a = face_distances(fa.face_normals, fa.face_offsets, r.vb, r.dist_b.dist, sep);
    }
    for (std::size_t k = 0; k < nfa; ++k) {
        ++c.iterations;
        if (sep[k] > best) {
            best = sep[k];
            best_m = -fa.face_normals[k];
            c.feature = CommonPlaneFeature::kFaceOfA;
        }
    }
    std::optional<PlaneDistances> ta; // A's vertices beyond B's planes (bounded)
    if (best <= 0.0) {
        relative_faces(fb, r);
        if (bounded) {
            ta.emplace(r.nb, r.ob, fa.vertices, r.dist_a);
            bound.resize(nfb);
            for (std::size_t k = 0; k < nfb; ++k) {
                bound[k] = -r.ob[k] - fa.inradius + slack;
            }
            face_separations(*ta, bound, best, sep);
            if (*std::max_element(sep.begin(), sep.end()) > 0.0) {
                // A gap: the loop below stops at the first separating face in order, which a
                // skipped face may be, so every face's separation is needed.
                bound.clear();
                face_separations(*ta, bound, best, sep);
            }
        } else {
            a_in_b = face_distances(r.nb, r.ob, fa.vertices, r.dist_a.dist, sep);
        }
        // The faces in order up to the first that separates (a gap ends the search).
        for (std::size_t k = 0; k < nfb && best <= 0.0; ++k) {
            ++c.iterations;
            if (sep[k] > best) {
                best = sep[k];
                best_m = r.nb[k];
                c.feature = CommonPlaneFeature::kFaceOfB;
            }
        }
    }
    if (best <= 0.0) {
        // Exact prune of the edge stage. If the deepest plane is an edge-edge one with overlap
        // d* < D = -best, the origin's nearest point on the Minkowski difference lies on the
        // face spanned by the two edges, i.e. points of the two edges are d* apart: each edge
        // passes within D of the other body. An edge farther than D from the other body's
        // bounding sphere, or whose two ends lie beyond one face plane of the other body by
        // more than D, is farther than D from that body and cannot carry the optimum, so it is
        // dropped (slack: 1e-9 of the size against round-off).
        const double reach = -best + 1e-9 * (fa.radius + fb.radius);
        if (bounded) {
            keep_edges(fa.edges, *ta, reach, r.shift, fb.radius, r.edges_a);
            keep_edges(fb.edges, *tb, reach, Vec3::Zero(), fa.radius, r.edges_b);
        } else {
            keep_edges_by_masks(fa.edges, fa.vertices, r.dist_a.dist, nfb, reach, r.shift,
                                fb.radius, r.edges_a);
            keep_edges_by_masks(fb.edges, r.vb, r.dist_b.dist, nfa, reach, Vec3::Zero(), fa.radius,
                                r.edges_b);
        }
        r.pruned = true;
        relative_arcs(fb, r);
        double second = -std::numeric_limits<double>::infinity(); // not read here
        edge_stage(fa, fb, r, best, best_m, c, second);
        // The prune's argument needs overlapping bodies: when they are apart, the separating
        // edge pair may lie farther apart than D and be dropped, and the search would report a
        // contact that is not there (found by a random-pose test against
        // find_separating_direction). So a "touching" answer of a pruned search is kept only
        // with a certificate of overlap: a vertex of one body inside the other (the distances
        // beyond the face planes, computed here where not yet) or a kept edge crossing the
        // other body. Otherwise a separating direction is searched, and without one the edge
        // stage runs again over every edge pair (the search before the prune, exact in both
        // cases).
        const bool pruned_some =
            r.edges_a.size() < fa.edges.size() || r.edges_b.size() < fb.edges.size();
        const auto inside = [&] {
            return bounded ? tb->any_inside() || ta->any_inside() : b_in_a || a_in_b;
        };
        if (best <= 0.0 && pruned_some && !inside() &&
            edge_crosses(fa.edges, r.edges_a, fa.vertices, r.nb, r.ob) < 0 &&
            edge_crosses(fb.edges, r.edges_b, r.vb, fa.face_normals, fa.face_offsets) < 0) {
            Vec3 m;
            if (find_separating_direction(a, b, 1e-12 * (fa.radius + fb.radius), m)) {
                c.depth = overlap_along(a, b, m);
                c.normal = m;
                return false;
            }
            r.edges_a.resize(fa.edges.size());
            std::iota(r.edges_a.begin(), r.edges_a.end(), 0);
            r.edges_b.resize(fb.edges.size());
            std::iota(r.edges_b.begin(), r.edges_b.end(), 0);
            relative_arcs(fb, r);
            edge_stage(fa, fb, r, best, best_m, c, second);
        }
    }
    return true;
}

/// The fast common plane; the patch as `with_patch` says, or (with `need_patch`) as it decides.
/// `scan`: which face stages (see detail::FaceScan).
/// `point_only`: points and patch polygon left empty (see patch_in_a).
PolyhedronContact common_plane(const PosedPolyhedron& a, const PosedPolyhedron& b, bool with_patch,
                               const PatchTest* need_patch, detail::FaceScan scan,
                               PlaneMemo* memo = nullptr, bool point_only = false,
                               const NearBand* near = nullptr) {
    PolyhedronContact c;
    const PolyhedronFeatures& fa = *a.shape;
    const PolyhedronFeatures& fb = *b.shape;
    const double dist = (b.x - a.x).norm();
    // (A norm is finite exactly when its square is: Eigen's norm() is sqrt(squaredNorm()).)
    if (!std::isfinite(dist) || !std::isfinite(a.q.squaredNorm()) ||
        !std::isfinite(b.q.squaredNorm())) {
        c.converged = false;
        return c;
    }
    if (dist > fa.radius + fb.radius) {
        c.depth = fa.radius + fb.radius - dist;
        return c;
    }
    thread_local Relative r;
    make_relative(a, b, r);

    // Largest separation (smallest overlap) over the candidate planes, in A's frame. m is the
    // normal from B to A.
    double best = -std::numeric_limits<double>::infinity();
    Vec3 best_m = Vec3::UnitX();
    if (scan == detail::FaceScan::automatic && fa.box && fb.box) {
        // Two boxes: the closed form (box_plane.cpp), and no memory (it costs less than one).
        const detail::BoxPlane bp = detail::box_plane(fa, fb, r.rot, r.shift);
        best = bp.best;
        best_m = bp.normal;
        c.feature = bp.feature;
        c.iterations += bp.candidates;
    } else {
        // A resting pair's memory first (same answer); the full search when it cannot tell.
        const bool from_memo = memo != nullptr && memo_search(fa, fb, r, *memo, best, best_m, c);
        if (memo != nullptr && !from_memo) {
            c = PolyhedronContact{};
            best = -std::numeric_limits<double>::infinity();
            best_m = Vec3::UnitX();
            r.pruned = false;
        }
        if (!from_memo && !full_search(a, b, scan, r, best, best_m, c)) {
            return c; // apart along a searched direction
        }
        if (memo != nullptr && !from_memo) {
            if (best < 0.0) {
                refill_memo(fa, fb, r, best, *memo);
            } else {
                memo->valid = false;
            }
        }
    }
    if (best > 0.0) {
        c.depth = -best;
        c.normal = world_normal(a.q, best_m);
        return c;
    }
    if (!with_patch) {
        c.touching = true;
        c.depth = -best;
        c.normal = world_normal(a.q, best_m);
        c.point = 0.5 * (a.support(-c.normal) + b.support(c.normal));
        return c;
    }
    if (need_patch != nullptr) {
        // The depth as the patch would give it (its own vertex loops), so the numbers do not
        // depend on the decision.
        thread_local std::vector<double> ha;
        thread_local std::vector<double> hb;
        PlaneDepth pd;
        if (near != nullptr) {
            ha.resize(fa.vertices.size());
            hb.resize(r.vb.size());
            pd = plane_depth<true>(fa, r, best_m, ha.data(), hb.data());
        } else {
            pd = plane_depth(fa, r, best_m);
        }
        c.depth = pd.d_b - pd.d_a;
        c.touching = c.depth > 0.0;
        if (near != nullptr && c.touching) {
            near_band(a, b, pd, ha.data(), hb.data(), *near);
        }
        c.normal = world_normal(a.q, best_m);
        // The deepest vertices of the loops above (A's frame; B's already turned into it), not
        // two more support searches.
        c.point = a.x + a.q * (0.5 * (fa.vertices[pd.deepest_a] + r.vb[pd.deepest_b]));
        if (!(*need_patch)(c)) {
            return c;
        }
    }
    PolyhedronContact p = patch_in_a(a, b, r, best_m, point_only);
    p.feature = c.feature;
    p.iterations = c.iterations;
    return p;
}

} // namespace

double polyhedron_overlap_along(const PosedPolyhedron& a, const PosedPolyhedron& b, const Vec3& m) {
    // The largest height of a body's vertices along d, in four running maxima (the largest of a
    // set does not depend on the order it is taken in): a chain of dependent maxima, one per
    // vertex, was the loop's critical path (`cylinder_16`: 32 vertices per body).
    const auto top = [](const std::vector<Vec3>& vs, const Vec3& d) {
        constexpr double lowest = -std::numeric_limits<double>::infinity();
        double h0 = lowest;
        double h1 = lowest;
        double h2 = lowest;
        double h3 = lowest;
        const std::size_t n = vs.size();
        std::size_t i = 0;
        for (; i + 4 <= n; i += 4) {
            h0 = std::max(h0, d.dot(vs[i]));
            h1 = std::max(h1, d.dot(vs[i + 1]));
            h2 = std::max(h2, d.dot(vs[i + 2]));
            h3 = std::max(h3, d.dot(vs[i + 3]));
        }
        for (; i < n; ++i) {
            h0 = std::max(h0, d.dot(vs[i]));
        }
        return std::max(std::max(h0, h1), std::max(h2, h3));
    };
    // A box's highest corner along d in closed form, sum_k h_k |u_k . d| (u_k its face normals):
    // the largest of its eight corners' heights in exact arithmetic, so the same number as the
    // vertex scan to round-off (test PolyhedronOverlapFromHeightsAgreesWithTheSupportForm).
    const auto height = [&top](const PolyhedronFeatures& f, const Vec3& d) {
        if (!f.box) {
            return top(f.vertices, d);
        }
        return f.box->half.dot(f.box->along(d).cwiseAbs());
    };
    const Vec3 mb = b.q.conjugate() * m;
    const Vec3 ma = a.q.conjugate() * m;
    return m.dot(b.x - a.x) + height(*b.shape, mb) + height(*a.shape, -ma);
}

PolyhedronContact polyhedron_contact(const PosedPolyhedron& a, const PosedPolyhedron& b,
                                     bool with_patch) {
    return common_plane(a, b, with_patch, nullptr, detail::FaceScan::automatic);
}

PolyhedronContact polyhedron_contact(const PosedPolyhedron& a, const PosedPolyhedron& b,
                                     const PatchTest& need_patch) {
    return common_plane(a, b, true, &need_patch, detail::FaceScan::automatic);
}

PolyhedronContact polyhedron_contact(const PosedPolyhedron& a, const PosedPolyhedron& b,
                                     const PatchTest& need_patch, PlaneMemo& memo) {
    return common_plane(a, b, true, &need_patch, detail::FaceScan::automatic, &memo);
}

PolyhedronContact polyhedron_contact_point(const PosedPolyhedron& a, const PosedPolyhedron& b,
                                           const PatchTest& need_patch, PlaneMemo* memo,
                                           const NearBand* near) {
    return common_plane(a, b, true, &need_patch, detail::FaceScan::automatic, memo, true, near);
}

namespace detail {

PolyhedronContact polyhedron_contact_with(const PosedPolyhedron& a, const PosedPolyhedron& b,
                                          FaceScan scan, bool with_patch) {
    return common_plane(a, b, with_patch, nullptr, scan);
}

Vec3 patch_point(const PosedPolyhedron& a, const PosedPolyhedron& b, const Vec3& m) {
    thread_local Relative r;
    make_relative(a, b, r);
    return patch_in_a(a, b, r, m, true).point;
}

} // namespace detail

PolyhedronContact contact_patch_along(const PosedPolyhedron& a, const PosedPolyhedron& b,
                                      const Vec3& m) {
    thread_local Relative r;
    make_relative(a, b, r);
    relative_faces(*b.shape, r);
    return patch_in_a(a, b, r, a.q.conjugate() * m.normalized());
}

} // namespace kiln::geometry
