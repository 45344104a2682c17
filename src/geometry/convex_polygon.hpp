#pragma once
// Small convex-polygon and clipping helpers shared by the polyhedron and mesh-wall contacts
// (internal to kiln_geometry): 2D hull, convex clipping, plane sections, segment clipping.

#include "core/types.hpp"

#include <algorithm>
#include <array>
#include <vector>

namespace kiln::geometry::detail {

using Vec2 = Eigen::Vector2d;

/// z component of the cross product of two 2D vectors.
inline double cross2(const Vec2& a, const Vec2& b) {
    return a.x() * b.y() - a.y() * b.x();
}

/// Convex hull (counter-clockwise, no collinear points) of the 2D points `p`: Andrew's monotone
/// chain. `p` is sorted in place and the hull written to `h`; with fewer than three points the hull
/// is the sorted points. Into caller's buffers, so that a query per step allocates nothing.
/// Not inlined (nor is clip_convex_into): GCC contracts a * b - c * d into a fused multiply-add
/// on one side or the other depending on the code around it, and inlined into the polyhedron
/// patch the cross products rounded otherwise than before, which moved a pile's bits.
[[gnu::noinline]] inline void hull_2d_into(std::vector<Vec2>& p, double tol, std::vector<Vec2>& h) {
    std::sort(p.begin(), p.end(), [](const Vec2& u, const Vec2& v) {
        return u.x() < v.x() || (u.x() == v.x() && u.y() < v.y());
    });
    if (p.size() < 3) {
        h = p;
        return;
    }
    h.resize(2 * p.size());
    std::size_t k = 0;
    for (const Vec2& q : p) {
        while (k >= 2 && cross2(h[k - 1] - h[k - 2], q - h[k - 2]) <= tol) {
            --k;
        }
        h[k++] = q;
    }
    for (std::size_t i = p.size() - 1, t = k + 1; i > 0; --i) {
        while (k >= t && cross2(h[k - 1] - h[k - 2], p[i - 1] - h[k - 2]) <= tol) {
            --k;
        }
        h[k++] = p[i - 1];
    }
    h.resize(k > 0 ? k - 1 : 0);
}

/// As hull_2d_into, returning the hull.
inline std::vector<Vec2> hull_2d(std::vector<Vec2> p, double tol) {
    std::vector<Vec2> h;
    hull_2d_into(p, tol, h);
    return h;
}

/// Clips the convex polygon `subject` (in place) by the convex counter-clockwise polygon `clip`
/// (Sutherland-Hodgman); `scratch` is working storage.
[[gnu::noinline]] inline void clip_convex_into(std::vector<Vec2>& subject,
                                               const std::vector<Vec2>& clip,
                                               std::vector<Vec2>& scratch) {
    for (std::size_t i = 0; i < clip.size() && !subject.empty(); ++i) {
        const Vec2& c0 = clip[i];
        const Vec2 e = clip[(i + 1) % clip.size()] - c0;
        scratch.clear();
        for (std::size_t k = 0; k < subject.size(); ++k) {
            const Vec2& p = subject[k];
            const Vec2& q = subject[(k + 1) % subject.size()];
            const double sp = cross2(e, p - c0);
            const double sq = cross2(e, q - c0);
            if (sp >= 0.0) {
                scratch.push_back(p);
            }
            if ((sp >= 0.0) != (sq >= 0.0)) {
                scratch.emplace_back(p + (q - p) * (sp / (sp - sq)));
            }
        }
        subject.swap(scratch);
    }
}

/// As clip_convex_into, returning the clipped polygon.
inline std::vector<Vec2> clip_convex(std::vector<Vec2> subject, const std::vector<Vec2>& clip) {
    std::vector<Vec2> scratch;
    clip_convex_into(subject, clip, scratch);
    return subject;
}

/// Section of a polyhedron (vertices pts, feature edges) by the plane m . x = s, as 2D points in
/// the basis (u, v), into `out` (cleared first).
inline void section_into(const std::vector<Vec3>& pts, const std::vector<std::array<int, 4>>& edges,
                         const Vec3& m, double s, const Vec3& u, const Vec3& v,
                         std::vector<Vec2>& out) {
    out.clear();
    for (const auto& e : edges) {
        const Vec3& p0 = pts[static_cast<std::size_t>(e[0])];
        const Vec3& p1 = pts[static_cast<std::size_t>(e[1])];
        const double d0 = m.dot(p0) - s;
        const double d1 = m.dot(p1) - s;
        if ((d0 <= 0.0) == (d1 <= 0.0)) {
            continue;
        }
        const Vec3 x = p0 + (p1 - p0) * (d0 / (d0 - d1));
        out.emplace_back(u.dot(x), v.dot(x));
    }
}

/// As section_into, returning the points.
inline std::vector<Vec2> section(const std::vector<Vec3>& pts,
                                 const std::vector<std::array<int, 4>>& edges, const Vec3& m,
                                 double s, const Vec3& u, const Vec3& v) {
    std::vector<Vec2> out;
    section_into(pts, edges, m, s, u, v, out);
    return out;
}

/// Clips the segment p0 p1 to the half-spaces n_k . x <= o_k and appends the ends of what is left.
inline void clip_edge(const Vec3& p0, const Vec3& p1, const std::vector<Vec3>& n,
                      const std::vector<double>& o, std::vector<Vec3>& out) {
    const Vec3 d = p1 - p0;
    double t0 = 0.0;
    double t1 = 1.0;
    for (std::size_t k = 0; k < n.size(); ++k) {
        const double den = n[k].dot(d);
        const double num = o[k] - n[k].dot(p0);
        if (den == 0.0) {
            if (num < 0.0) {
                return;
            }
        } else if (den > 0.0) {
            t1 = std::min(t1, num / den);
        } else {
            t0 = std::max(t0, num / den);
        }
        if (t0 > t1) {
            return;
        }
    }
    out.emplace_back(p0 + t0 * d);
    out.emplace_back(p0 + t1 * d);
}

/// Area (m^2) and centroid of a counter-clockwise polygon, accumulated: area2 += twice the area,
/// moment += 3 * twice the area * centroid (so centroid = moment / (3 area2)).
inline void accumulate_polygon(const std::vector<Vec2>& poly, double& area2, Vec2& moment) {
    for (std::size_t k = 0; k < poly.size(); ++k) {
        const Vec2& p = poly[k];
        const Vec2& q = poly[(k + 1) % poly.size()];
        const double w = cross2(p, q);
        area2 += w;
        moment += w * (p + q);
    }
}

} // namespace kiln::geometry::detail
