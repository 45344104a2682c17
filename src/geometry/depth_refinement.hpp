#pragma once
// Refinement of a contact normal between two overlapping convex bodies given by support maps
// (superquadrics, polyhedra, any type with a world-frame `support(d)`, a centre `x` and a
// `length_scale()`), so that the overlap measured along it comes close to the penetration depth.
//
// Why: a caller that takes the overlap along a normal found by libccd's EPA measures an upper
// bound of the depth, min over unit m of overlap_along(a, b, m) (convex_contact.hpp). EPA stops
// when its polytope is within its tolerance of the Minkowski difference, so its normal is off by
// an angle that grows as the contact gets shallower (the overlap along it exceeds the depth by up
// to about tolerance / depth in scaled lengths, polyhedron_contact.hpp): on pairs of a polyhedron
// and a superquadric 1e-6 of the length scale deep, the overlap along EPA's normal was up to 100
// times the depth (docs/theory/shapes.md, "Depth along a normal").
//
// How: with E = A - B = {x - y} (the centres' difference lies inside it when the bodies
// overlap), the overlap along m is h_E(-m), h the support function, and the penetration depth d*
// is the distance from the origin to the boundary of E (van den Bergen 2003, Sec. 4.3.4): the
// boundary point nearest to the origin is p* = -d* m*, m* the best normal. Moving A by t m moves
// E by t m; the shortest vector from B to the moved A is the point of E + t m nearest to the
// origin, i.e. t m plus the point of E nearest to -t m. For m = m* and t > d*, -t m* lies on the
// outward normal of E at p*, so that point is p* and the shortest vector is (t - d*) m*: m* is a
// fixed point. From a trial normal m with overlap s along it, t = s + margin (the moved bodies
// are apart by at least the margin along m), the direction of the shortest vector is the next
// trial normal; where E's boundary is locally a sphere of radius R the angle to m* shrinks by
// about (t - d*) / (R + t - d*) per round, and a flat face gives its normal at once. The
// shortest vector comes from GJK's distance algorithm (Gilbert, Johnson & Keerthi 1988, in the
// form of van den Bergen 2003, Sec. 4.3.2; the nearest point of a simplex after Ericson 2005,
// Sec. 5.1.5).
//
// The refinement never makes the answer worse: a round's normal is kept only when the overlap
// along it, measured exactly from the supports, is smaller. Normal convention as in
// convex_contact.hpp: m points from B towards A (world frame).

#include "core/types.hpp"
#include "geometry/separating_axis.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

namespace kiln::geometry {

namespace detail {

/// Nearest point to the origin of the triangle (a, b, c) (Ericson 2005, Sec. 5.1.5, with the
/// query point at the origin); `keep` gets the vertices (indices 0-2) of the feature it lies on,
/// `nkeep` their count.
inline Vec3 nearest_on_triangle(const Vec3& a, const Vec3& b, const Vec3& c,
                                std::array<int, 3>& keep, int& nkeep) {
    const Vec3 ab = b - a;
    const Vec3 ac = c - a;
    const double d1 = -ab.dot(a);
    const double d2 = -ac.dot(a);
    if (d1 <= 0.0 && d2 <= 0.0) {
        keep = {0, 0, 0};
        nkeep = 1;
        return a;
    }
    const double d3 = -ab.dot(b);
    const double d4 = -ac.dot(b);
    if (d3 >= 0.0 && d4 <= d3) {
        keep = {1, 0, 0};
        nkeep = 1;
        return b;
    }
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        keep = {0, 1, 0};
        nkeep = 2;
        return a + (d1 / (d1 - d3)) * ab;
    }
    const double d5 = -ab.dot(c);
    const double d6 = -ac.dot(c);
    if (d6 >= 0.0 && d5 <= d6) {
        keep = {2, 0, 0};
        nkeep = 1;
        return c;
    }
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        keep = {0, 2, 0};
        nkeep = 2;
        return a + (d2 / (d2 - d6)) * ac;
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
        keep = {1, 2, 0};
        nkeep = 2;
        return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
    }
    const double den = 1.0 / (va + vb + vc);
    keep = {0, 1, 2};
    nkeep = 3;
    return a + (vb * den) * ab + (vc * den) * ac;
}

/// Nearest point v to the origin of the simplex w[0..n) (1 to 4 points; with 4, the last one is
/// the newest support point, which brought the set nearer); w is reduced to the points of the
/// feature v lies on. False only when no finite point was found.
inline bool nearest_on_simplex(std::array<Vec3, 4>& w, int& n, Vec3& v) {
    if (n == 1) {
        v = w[0];
        return true;
    }
    if (n == 2) {
        const Vec3 d = w[1] - w[0];
        const double dd = d.squaredNorm();
        const double t = dd > 0.0 ? -w[0].dot(d) / dd : 0.0;
        if (t <= 0.0) {
            n = 1;
            v = w[0];
        } else if (t >= 1.0) {
            w[0] = w[1];
            n = 1;
            v = w[0];
        } else {
            v = w[0] + t * d;
        }
        return true;
    }
    std::array<int, 3> keep{};
    int nkeep = 0;
    if (n == 3) {
        v = nearest_on_triangle(w[0], w[1], w[2], keep, nkeep);
        const std::array<Vec3, 3> old{w[0], w[1], w[2]};
        for (int i = 0; i < nkeep; ++i) {
            w[static_cast<std::size_t>(i)] =
                old[static_cast<std::size_t>(keep[static_cast<std::size_t>(i)])];
        }
        n = nkeep;
        return true;
    }
    // Four points: the last one (the new support point) brought the set nearer to the origin,
    // so the nearest point lies on one of the three faces through it (without orientation
    // tests, which fail on the nearly flat tetrahedra of curved bodies at round-off; the origin
    // lying inside is not detected, callers query bodies that are apart).
    static constexpr std::array<std::array<int, 3>, 3> faces{{{0, 1, 3}, {0, 2, 3}, {1, 2, 3}}};
    double best = std::numeric_limits<double>::infinity();
    std::array<Vec3, 3> best_w{};
    int best_n = 0;
    for (const auto& f : faces) {
        const std::array<Vec3, 3> tri{w[static_cast<std::size_t>(f[0])],
                                      w[static_cast<std::size_t>(f[1])],
                                      w[static_cast<std::size_t>(f[2])]};
        const Vec3 p = nearest_on_triangle(tri[0], tri[1], tri[2], keep, nkeep);
        const double p2 = p.squaredNorm();
        if (p2 < best) {
            best = p2;
            v = p;
            for (int i = 0; i < nkeep; ++i) {
                best_w[static_cast<std::size_t>(i)] =
                    tri[static_cast<std::size_t>(keep[static_cast<std::size_t>(i)])];
            }
            best_n = nkeep;
        }
    }
    if (!std::isfinite(best)) {
        return false;
    }
    for (int i = 0; i < best_n; ++i) {
        w[static_cast<std::size_t>(i)] = best_w[static_cast<std::size_t>(i)];
    }
    n = best_n;
    return true;
}

} // namespace detail

/// GJK distance: the shortest vector v (m, world frame) from B to A moved by `shift` (m, world
/// frame), i.e. the point of the Minkowski difference (A + shift) - B nearest to the origin, to a
/// relative accuracy of about `rel_tol` in |v| (or the round-off of the support points, about
/// 1e-14 of the bodies' size, where that is larger); past `max_iterations`, or where a new
/// support point brings the simplex no nearer (round-off), the best v found. False when the
/// bodies were not proved apart (a support plane with the origin outside: then they overlap or
/// touch, or GJK ran out of iterations first). `start` (optional, world frame): a guess of the
/// direction of v; the search then begins with the support point of the difference along -start
/// instead of from the line of centres (a guess near the answer saves about a third of the
/// iterations of refine_normal's rounds).
template <class A, class B>
[[nodiscard]] bool shortest_vector(const A& a, const B& b, const Vec3& shift, Vec3& v,
                                   double rel_tol = 1e-12, int max_iterations = 128,
                                   const Vec3* start = nullptr) {
    const auto support = [&](const Vec3& d) { return Vec3(a.support(d) + shift - b.support(-d)); };
    v = a.x + shift - b.x; // a point of the difference (the centres lie inside their bodies)
    // Round-off of v . p: the support points carry coordinates of the bodies' size.
    const double floor = 1e-14 * (a.length_scale() + b.length_scale() + shift.norm());
    std::array<Vec3, 4> w{};
    int n = 0;
    bool apart = false; // v . p > 0 once: every point of the difference lies beyond a plane
    if (start != nullptr) {
        // The first iteration along the guess: its support point is a point of the difference,
        // and start . p > 0 puts the whole difference beyond a plane as v . p > 0 does.
        w[0] = support(-*start);
        n = 1;
        apart = start->dot(w[0]) > 0.0;
        v = w[0];
    }
    for (int it = 0; it < max_iterations; ++it) {
        const double vv = v.squaredNorm();
        if (!(vv > floor * floor)) {
            return false; // touching to round-off (or not a number)
        }
        const Vec3 p = support(-v);
        const double vp = v.dot(p);
        apart = apart || vp > 0.0;
        // v . v - v . p bounds (|v| - distance) |v| (van den Bergen 2003, Sec. 4.3.2).
        if (vv - vp <= rel_tol * vv + floor * std::sqrt(vv)) {
            return apart;
        }
        const std::array<Vec3, 4> before = w;
        const int n_before = n;
        const Vec3 v_before = v;
        w[static_cast<std::size_t>(n++)] = p;
        if (!detail::nearest_on_simplex(w, n, v)) {
            return false;
        }
        // A new simplex that brings v no nearer (round-off) ends the search with the last v.
        if (n_before > 0 && !(v.squaredNorm() < vv)) {
            w = before;
            n = n_before;
            v = v_before;
            return apart;
        }
    }
    return apart;
}

/// Do the polyhedron p and the superquadric s overlap, as shown by a point of one body about
/// which a ball lies inside the other? (p: a PosedPolyhedron or any type with
/// `shape->face_normals`, `shape->face_offsets` and `shape->radius` in the body frame, `support`,
/// `x` and `q`; s: a PosedSuperquadric or any type with `shape->inside_outside` in the body frame,
/// `support`, `x` and `q`.) The points tried are p's support along -m and s's along m (m: unit,
/// world frame, from s towards p, e.g. a pair's last normal). If x lies in A and the ball of radius
/// r about x in B, the overlap along every unit n is h_A(-n) + h_B(n) >= -n.x + n.(x + r n) = r, so
/// no plane separates the bodies: true here means shortest_vector(p, s, 0, v) cannot prove them
/// apart. The balls are far above the round-off of the supports (1e-16 of the size): for p's
/// point, F < -1e-6 in s's frame (F + 1 scales as the distance from the centre to the power
/// 2/e1), so the point moved out from s's centre by a factor 1 + 1e-6 e1 / 2 still lies inside
/// and, s being convex, so does a ball of about 1e-6 e1 / 2 times s's inradius (at least that of
/// the octahedron on its half-axes, which every superquadric with exponents up to 2 contains);
/// for s's point, p's face planes (unit normals) lie 1e-9 of p's bounding radius beyond it.
template <class P, class S>
[[nodiscard]] bool overlap_proved(const P& p, const S& s, const Vec3& m) {
    if (s.shape->inside_outside(s.q.conjugate() * Vec3(p.support(-m) - s.x)) < -1e-6) {
        return true; // a vertex of p inside s: p's edge or corner in s
    }
    const auto& f = *p.shape;
    const Vec3 x = p.q.conjugate() * Vec3(s.support(m) - p.x);
    const double margin = -1e-9 * f.radius;
    for (std::size_t k = 0; k < f.face_normals.size(); ++k) {
        if (!(f.face_normals[k].dot(x) - f.face_offsets[k] < margin)) {
            return false;
        }
    }
    return true; // s's deepest point inside p: s against a face of p
}

/// Takes the unit direction `cand` (world, from b towards a) as the normal m when the overlap
/// along it is smaller than `overlap` (then updated); returns whether it did.
template <class A, class B>
bool keep_if_smaller(const A& a, const B& b, const Vec3& cand, Vec3& m, double& overlap) {
    const double o = overlap_along(a, b, cand);
    if (o < overlap) {
        overlap = o;
        m = cand;
        return true;
    }
    return false;
}

/// Refines the unit normal m (world frame, from b towards a) of two overlapping bodies, and
/// `overlap` = overlap_along(a, b, m) (m), by rounds of the translation described above (at most
/// `rounds`). A round's normal is kept only when the overlap along it is smaller, so `overlap`
/// never grows; it stays an upper bound of the penetration depth.
template <class A, class B>
void refine_normal(const A& a, const B& b, Vec3& m, double& overlap, int rounds = 3) {
    const double scale = a.length_scale() + b.length_scale();
    // Gap of the moved bodies: large against GJK's accuracy (1e-8 of |v| here), small against
    // the curvature radii so that a round gains much. Three rounds at that accuracy did as well
    // as six at 1e-12 in refine_polyhedron_normal on the pairs of a polyhedron and a superquadric
    // of tests/geometry/test_depth_refinement.cpp (the overlap within 3e-12 of the scale of the
    // exact depth or of the best sampled direction), at about 0.8 of the cost (session 19).
    const double margin = 1e-4 * scale;
    for (int r = 0; r < rounds; ++r) {
        Vec3 v;
        // The shortest vector of the moved bodies lies near m (exactly along it at the best
        // normal), so the search starts there.
        if (!shortest_vector(a, b, Vec3((overlap + margin) * m), v, 1e-8, 128, &m)) {
            break;
        }
        const double len = v.norm();
        if (!(len > 0.0)) {
            break;
        }
        const Vec3 cand = v / len;
        const double o = overlap_along(a, b, cand);
        if (!(o < overlap)) {
            break;
        }
        const double gain = overlap - o;
        m = cand;
        overlap = o;
        if (gain <= 1e-12 * scale) {
            break;
        }
    }
}

/// The best normal with an edge of a polytope (a or b; unit direction e, world frame) as the
/// contact feature, started from m (unit, world, from b towards a): such a normal is
/// perpendicular to the edge, and on the circle of those the overlap is smooth while the
/// polytope's support along it is the edge, so its minimum is a root of the derivative (Danskin:
/// the gradient of the overlap is s_b(m) - s_a(-m)), found by the secant method. Sets m and
/// overlap and returns true when the overlap along the result is smaller than `overlap`.
template <class A, class B>
bool edge_normal(const A& a, const B& b, const Vec3& e, Vec3& m, double& overlap) {
    Vec3 u = m - m.dot(e) * e;
    const double len = u.norm();
    if (!(len > 0.5)) {
        return false; // m far from perpendicular: not this edge's contact
    }
    u /= len;
    const Vec3 w = e.cross(u);
    const auto normal = [&](double phi) { return Vec3(std::cos(phi) * u + std::sin(phi) * w); };
    // Derivative of the overlap along the circle at phi.
    const auto slope = [&](double phi) {
        const Vec3 n = normal(phi);
        const Vec3 tangent = -std::sin(phi) * u + std::cos(phi) * w;
        return tangent.dot(Vec3(b.support(n) - a.support(-n)));
    };
    const double scale = a.length_scale() + b.length_scale();
    double x0 = 0.0;
    double g0 = slope(x0);
    double x1 = g0 > 0.0 ? -1e-3 : 1e-3;
    double g1 = slope(x1);
    for (int it = 0; it < 30 && std::abs(g1) > 1e-15 * scale; ++it) {
        if (!(g1 != g0)) {
            break;
        }
        const double x2 = x1 - g1 * (x1 - x0) / (g1 - g0);
        if (!(std::abs(x2) < 0.5) || std::abs(x2 - x1) < 1e-15) {
            break;
        }
        x0 = x1;
        g0 = g1;
        x1 = x2;
        g1 = slope(x1);
    }
    return keep_if_smaller(a, b, normal(x1), m, overlap);
}

/// refine_normal for a posed polyhedron a (a PosedPolyhedron or any type with `shape->vertices`,
/// `shape->face_normals` and `shape->edges` in the body frame and an orientation `q`, body ->
/// world) and a convex body b, followed by a's face normals and the edge step (edge_normal) for
/// the edges whose ends both lie near a's support along -m. The translation rounds reach a corner
/// of the overlap, where the best normal is one of a's faces' or perpendicular to one of its
/// edges, only to GJK's accuracy, and GJK's simplices are thin slivers there (an edge's ends
/// far apart, the distance small). As refine_normal, a normal is kept only when the overlap
/// along it is smaller.
template <class A, class B>
void refine_polyhedron_normal(const A& a, const B& b, Vec3& m, double& overlap) {
    refine_normal(a, b, m, overlap);
    for (const Vec3& n_body : a.shape->face_normals) {
        keep_if_smaller(a, b, Vec3(-(a.q * n_body)), m, overlap); // from b to a: a's face facing b
    }
    // Edges whose both ends lie within a band of a's support along -m (the band covers a normal
    // off by up to a few degrees: 0.05 of the bounding radius).
    const auto& v = a.shape->vertices;
    const Vec3 d = a.q.conjugate() * Vec3(-m);
    double top = -std::numeric_limits<double>::infinity();
    for (const Vec3& x : v) {
        top = std::max(top, d.dot(x));
    }
    const double bar = top - 0.05 * a.shape->radius;
    const Vec3 start = m;
    for (const auto& edge : a.shape->edges) {
        const Vec3& p0 = v[static_cast<std::size_t>(edge[0])];
        const Vec3& p1 = v[static_cast<std::size_t>(edge[1])];
        if (d.dot(p0) >= bar && d.dot(p1) >= bar) {
            Vec3 cand = start;
            double o = overlap;
            if (edge_normal(a, b, Vec3((a.q * Vec3(p1 - p0)).normalized()), cand, o)) {
                overlap = o;
                m = cand;
            }
        }
    }
}

} // namespace kiln::geometry
