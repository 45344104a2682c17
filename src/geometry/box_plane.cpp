// The common plane of two boxes in closed form (geometry::detail::box_plane, one pair, as
// polyhedron_contact runs it) and the same for several pairs at once in vector lanes
// (detail::box_planes; the first piece of the resting pairs' narrow phase across pairs,
// docs/performance.md "Session 18" and "Session 28").
//
// The candidates of the separating-axis test for boxes (Gottschalk, Lin and Manocha 1996,
// SIGGRAPH, "OBBTree", Sec. 4): the three face normals of each box and the nine cross products of
// their edge directions, each direction n rated by the support functions, separation =
// |n . t| - h_A(n) - h_B(n) (t B's centre relative to A's; a box's support function is even).
// Why it is the general search's answer: the faces of the Minkowski difference have normals among
// these directions, and along any direction the overlap of two overlapping bodies is at least the
// penetration depth, so the largest separation over a set of directions holding every face normal
// is the largest over the faces (the general search's value, to round-off). Apart, the largest is
// positive (a separating axis), as the general search's first separating plane is. Everything in
// A's box frame: C = A's axes^T B's axes, t likewise, so each support is a sum of three products;
// the cross products' components are entries of C, and the separation along one is divided by
// its length only at the end, so it keeps full relative precision for nearly parallel edges.
// Exactly parallel edges (length <= 1e-12) give no direction: their planes are face planes.
//
// Both forms write every product that meets a sum as an explicit fused multiply-add (std::fma),
// in the same order, and leave the compiler no product to fuse on its own: so the lanes give the
// one-pair form's answer bit for bit however GCC inlines or vectorises either
// (tests/geometry/test_box_lanes.cpp). The winner's normal is built by one function for both.

#include "geometry/polyhedron_contact.hpp"

#include "geometry/convex_polygon.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

namespace kiln::geometry::detail {

namespace {

/// B's axes (cm) and centre (t) in A's box frame, from the relative pose (rot: B body -> A body,
/// shift: B's centre in A's frame): for two boxes along their bodies' axes the pose as it is.
[[gnu::noinline]] void box_frame(const PolyhedronFeatures::Box& ba,
                                 const PolyhedronFeatures::Box& bb, const Mat3& rot,
                                 const Vec3& shift, Mat3& cm, Vec3& t) {
    const bool turned = !ba.aligned || !bb.aligned;
    cm = turned ? Mat3(ba.axes.transpose() * (rot * bb.axes)) : rot;
    t = turned ? Vec3(ba.axes.transpose() * shift) : shift;
}

/// a0 b0 + a1 b1 + a2 b2, fused in that order.
inline double dot3(double a0, double a1, double a2, double b0, double b1, double b2) {
    return std::fma(a2, b2, std::fma(a1, b1, a0 * b0));
}

/// Separation along face i of A (faces of B: the same with the roles swapped): |t_i| - ha_i -
/// |C_i0| hb_0 - |C_i1| hb_1 - |C_i2| hb_2 (the support of B along the axis).
inline double face_separation(double ti, double hi, double ac0, double ac1, double ac2, double h0,
                              double h1, double h2) {
    return std::abs(ti) - hi - dot3(ac0, ac1, ac2, h0, h1, h2);
}

/// Edge i of A with edge j of B: n = e_i x C_j has components n1 = -C(i2, j) (i1) and
/// n2 = C(i1, j) (i2), and 0 along i. Its numerator |n . t| - h_A(n) - h_B(n) (B's support along n
/// from n . C_l; l = j gives 0, a triple product with C_j twice) and its length.
inline void edge_candidate(double n1, double n2, double t1, double t2, double ha1, double ha2,
                           double c1j1, double c2j1, double c1j2, double c2j2, double hb1,
                           double hb2, double& num, double& len) {
    len = std::sqrt(std::fma(n1, n1, n2 * n2));
    const double c1 = std::fma(n1, c1j1, n2 * c2j1);
    const double c2 = std::fma(n1, c1j2, n2 * c2j2);
    num = std::fma(
        -hb2, std::abs(c2),
        std::fma(-hb1, std::abs(c1),
                 std::fma(-ha2, std::abs(n2),
                          std::fma(-ha1, std::abs(n1), std::abs(std::fma(n1, t1, n2 * t2))))));
}

constexpr int next(int i) {
    return i == 2 ? 0 : i + 1;
}
constexpr int prev(int i) {
    return i == 0 ? 2 : i - 1;
}

/// The answer from the winning candidate `win` (0-2: face i of A, 3-5: face j of B, 6 + 3 i + j:
/// edge i of A with edge j of B, of length w_len): the normal from B to A in A's body frame and
/// the feature. cm, t, tc: B's axes, B's centre and tc = cm^T t in A's box frame.
[[gnu::noinline]] void box_plane_end(const PolyhedronFeatures& fa, const PolyhedronFeatures& fb,
                                     const Mat3& rot, const Mat3& cm, const Vec3& t, const Vec3& tc,
                                     int win, double w_len, BoxPlane& out) {
    const PolyhedronFeatures::Box& ba = *fa.box;
    const PolyhedronFeatures::Box& bb = *fb.box;
    if (win < 3) {
        const auto i = static_cast<std::size_t>(win);
        const auto k = static_cast<std::size_t>(t[win] < 0.0 ? ba.minus[i] : ba.plus[i]);
        out.normal = -fa.face_normals[k];
        out.feature = CommonPlaneFeature::kFaceOfA;
    } else if (win < 6) {
        // B's face towards A: its normal points against t.
        const auto j = static_cast<std::size_t>(win - 3);
        const auto k = static_cast<std::size_t>(tc[win - 3] > 0.0 ? bb.minus[j] : bb.plus[j]);
        out.normal = rot * fb.face_normals[k];
        out.feature = CommonPlaneFeature::kFaceOfB;
    } else {
        // From B to A: against t.
        const int wi = (win - 6) / 3;
        const int wj = (win - 6) % 3;
        Vec3 n = Vec3::Zero();
        n[next(wi)] = -cm(prev(wi), wj);
        n[prev(wi)] = cm(next(wi), wj);
        const Vec3 m = ba.axes * (n / w_len);
        out.normal = t.dot(n) > 0.0 ? Vec3(-m) : m;
        out.feature = CommonPlaneFeature::kEdgeEdge;
    }
}

} // namespace

BoxPlane box_plane(const PolyhedronFeatures& fa, const PolyhedronFeatures& fb, const Mat3& rot,
                   const Vec3& shift) {
    const PolyhedronFeatures::Box& ba = *fa.box;
    const PolyhedronFeatures::Box& bb = *fb.box;
    Mat3 cm;
    Vec3 t;
    box_frame(ba, bb, rot, shift, cm, t);
    const Mat3 ac = cm.cwiseAbs();
    const Vec3& ha = ba.half;
    const Vec3& hb = bb.half;
    int win = -1;
    double top = -std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i) {
        const double sep =
            face_separation(t[i], ha[i], ac(i, 0), ac(i, 1), ac(i, 2), hb[0], hb[1], hb[2]);
        if (sep > top) {
            top = sep;
            win = i;
        }
    }
    Vec3 tc;
    for (int j = 0; j < 3; ++j) {
        tc[j] = dot3(cm(0, j), cm(1, j), cm(2, j), t[0], t[1], t[2]); // t along B's axes
        const double sep =
            face_separation(tc[j], hb[j], ac(0, j), ac(1, j), ac(2, j), ha[0], ha[1], ha[2]);
        if (sep > top) {
            top = sep;
            win = 3 + j;
        }
    }
    // Compared as numerators against top * len (len > 0), the one division is the winner's.
    double w_len = 1.0;
    int count = 6;
    for (int i = 0; i < 3; ++i) {
        const int i1 = next(i);
        const int i2 = prev(i);
        for (int j = 0; j < 3; ++j) {
            const int j1 = next(j);
            const int j2 = prev(j);
            double num;
            double len;
            edge_candidate(-cm(i2, j), cm(i1, j), t[i1], t[i2], ha[i1], ha[i2], cm(i1, j1),
                           cm(i2, j1), cm(i1, j2), cm(i2, j2), hb[j1], hb[j2], num, len);
            if (len <= 1e-12) {
                continue;
            }
            ++count;
            if (num > top * len) {
                top = num / len;
                win = 6 + 3 * i + j;
                w_len = len;
            }
        }
    }
    BoxPlane out;
    out.best = top;
    out.candidates = count;
    box_plane_end(fa, fb, rot, cm, t, tc, win, w_len, out);
    return out;
}

void box_lane(BoxLanes& lanes, std::size_t q, const PolyhedronFeatures& fa,
              const PolyhedronFeatures& fb, const Mat3& rot, const Vec3& shift) {
    Mat3 cm;
    Vec3 t;
    box_frame(*fa.box, *fb.box, rot, shift, cm, t);
    lanes.fa[q] = &fa;
    lanes.fb[q] = &fb;
    lanes.rot[q] = &rot;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            lanes.c[3 * i + j][q] = cm(i, j);
        }
        lanes.t[i][q] = t[i];
        lanes.ha[i][q] = fa.box->half[i];
        lanes.hb[i][q] = fb.box->half[i];
    }
}

namespace {

constexpr std::size_t kW = BoxLanes::kWidth;

/// The running winner of the closed form in lanes (box_planes): the largest separation (top), the
/// candidate (win, as box_plane_end reads it), the winning edge direction's length, B's centre
/// along B's axes (tc) and the number of candidates.
struct PlaneRun {
    alignas(64) double top[kW];
    alignas(64) double w_len[kW];
    alignas(64) double tc[3][kW];
    alignas(64) int win[kW];
    alignas(64) int count[kW];
};

/// The edge candidates of plane_candidates as box_plane runs them: a candidate wins where its
/// numerator exceeds the running best times its length, and the best becomes the quotient.
void edges_divided(const double (&c)[9][kW], const double (&t)[3][kW], const double (&ha)[3][kW],
                   const double (&hb)[3][kW], PlaneRun& r) {
    for (int i = 0; i < 3; ++i) {
        const int i1 = next(i);
        const int i2 = prev(i);
        for (int j = 0; j < 3; ++j) {
            const int j1 = next(j);
            const int j2 = prev(j);
            const int id = 6 + 3 * i + j;
            // The division only where a lane's candidate wins (rare in a resting pile, where
            // face planes win): first the tests, then the quotients if any lane needs one.
            alignas(64) double num[kW];
            alignas(64) double len[kW];
            alignas(64) int g[kW];
            int wins = 0;
#pragma omp simd reduction(+ : wins)
            for (std::size_t q = 0; q < kW; ++q) {
                edge_candidate(-c[3 * i2 + j][q], c[3 * i1 + j][q], t[i1][q], t[i2][q], ha[i1][q],
                               ha[i2][q], c[3 * i1 + j1][q], c[3 * i2 + j1][q], c[3 * i1 + j2][q],
                               c[3 * i2 + j2][q], hb[j1][q], hb[j2][q], num[q], len[q]);
                const bool valid = !(len[q] <= 1e-12);
                r.count[q] += valid ? 1 : 0;
                g[q] = valid && num[q] > r.top[q] * len[q] ? 1 : 0;
                wins += g[q];
            }
            if (wins == 0) {
                continue;
            }
#pragma omp simd
            for (std::size_t q = 0; q < kW; ++q) {
                const bool gq = g[q] != 0;
                r.top[q] = gq ? num[q] / len[q] : r.top[q];
                r.win[q] = gq ? id : r.win[q];
                r.w_len[q] = gq ? len[q] : r.w_len[q];
            }
        }
    }
}

/// box_plane's candidates and comparisons in its order, candidate by candidate across the lanes;
/// a candidate replaces a lane's running best where the one-pair form's test holds (no branch).
/// Lanes past the pairs in use hold whatever their inputs are; their results are not read.
void plane_candidates(const double (&c)[9][kW], const double (&t)[3][kW], const double (&ha)[3][kW],
                      const double (&hb)[3][kW], PlaneRun& r) {
#pragma omp simd
    for (std::size_t q = 0; q < kW; ++q) {
        r.top[q] = -std::numeric_limits<double>::infinity();
        r.win[q] = -1;
        r.w_len[q] = 1.0;
        r.count[q] = 6;
    }
    for (int i = 0; i < 3; ++i) {
#pragma omp simd
        for (std::size_t q = 0; q < kW; ++q) {
            const double sep =
                face_separation(t[i][q], ha[i][q], std::abs(c[3 * i][q]), std::abs(c[3 * i + 1][q]),
                                std::abs(c[3 * i + 2][q]), hb[0][q], hb[1][q], hb[2][q]);
            const bool g = sep > r.top[q];
            r.top[q] = g ? sep : r.top[q];
            r.win[q] = g ? i : r.win[q];
        }
    }
    for (int j = 0; j < 3; ++j) {
#pragma omp simd
        for (std::size_t q = 0; q < kW; ++q) {
            r.tc[j][q] = dot3(c[j][q], c[3 + j][q], c[6 + j][q], t[0][q], t[1][q], t[2][q]);
            const double sep =
                face_separation(r.tc[j][q], hb[j][q], std::abs(c[j][q]), std::abs(c[3 + j][q]),
                                std::abs(c[6 + j][q]), ha[0][q], ha[1][q], ha[2][q]);
            const bool g = sep > r.top[q];
            r.top[q] = g ? sep : r.top[q];
            r.win[q] = g ? 3 + j : r.win[q];
        }
    }
    edges_divided(c, t, ha, hb, r);
}

} // namespace

void box_planes(const BoxLanes& lanes, std::size_t n, BoxPlane* out) {
    PlaneRun r;
    plane_candidates(lanes.c, lanes.t, lanes.ha, lanes.hb, r);
    const auto& c = lanes.c;
    const auto& t = lanes.t;
    for (std::size_t q = 0; q < n; ++q) {
        Mat3 cm;
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) {
                cm(i, j) = c[3 * i + j][q];
            }
        }
        BoxPlane& o = out[q];
        o.best = r.top[q];
        o.candidates = r.count[q];
        box_plane_end(*lanes.fa[q], *lanes.fb[q], *lanes.rot[q], cm,
                      Vec3(t[0][q], t[1][q], t[2][q]), Vec3(r.tc[0][q], r.tc[1][q], r.tc[2][q]),
                      r.win[q], r.w_len[q], o);
    }
}

void box_pair_lane(BoxPairLanes& lanes, std::size_t q, const PolyhedronFeatures& fa, const Vec3& xa,
                   const Mat3& ra, const PolyhedronFeatures& fb, const Vec3& xb, const Mat3& rb) {
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            lanes.ra[3 * i + j][q] = ra(i, j);
            lanes.rb[3 * i + j][q] = rb(i, j);
        }
        lanes.xa[i][q] = xa[i];
        lanes.d[i][q] = xb[i] - xa[i];
        lanes.ha[i][q] = fa.box->half[i];
        lanes.hb[i][q] = fb.box->half[i];
    }
}

void box_pair_planes(BoxPairLanes& lanes, std::size_t n) {
    constexpr std::size_t w = BoxPairLanes::kWidth;
    for (std::size_t q = n; q < w; ++q) { // every lane runs the same code: copies of lane 0
        for (int k = 0; k < 9; ++k) {
            lanes.ra[k][q] = lanes.ra[k][0];
            lanes.rb[k][q] = lanes.rb[k][0];
        }
        for (int k = 0; k < 3; ++k) {
            lanes.xa[k][q] = lanes.xa[k][0];
            lanes.d[k][q] = lanes.d[k][0];
            lanes.ha[k][q] = lanes.ha[k][0];
            lanes.hb[k][q] = lanes.hb[k][0];
        }
    }
    const auto& ra = lanes.ra;
    const auto& rb = lanes.rb;
    const auto& ha = lanes.ha;
    const auto& hb = lanes.hb;
    // One pass over the lanes with every candidate unrolled in it, so that each lane's running
    // winner stays in registers (candidate by candidate across the lanes, as box_planes runs, it
    // went through memory at every candidate: -9 % of a cube step, docs/performance.md "Session
    // 31"). The inner loops are unrolled (GCC unroll) before the vectoriser sees the lane loop,
    // which it takes only without loops inside. The faces as box_plane rates them, in its order
    // and with its fused products; the edge pairs keep the running best as a fraction
    // top / top_len (a face: its separation over 1) compared cross-multiplied,
    // num top_len > top len (both lengths > 0), so no lane divides until the end: the winner is
    // box_plane's but in near-ties (two products round otherwise than one quotient and one
    // product); its separation and direction are the same quotients.
#pragma omp simd
    for (std::size_t q = 0; q < w; ++q) {
        // The relative pose in A's frame (for aligned boxes A's box frame): C = Ra^T Rb, B's
        // axes, and t = Ra^T (x_b - x_a), B's centre.
        double c[9];
        double t[3];
#pragma GCC unroll 3
        for (int i = 0; i < 3; ++i) {
#pragma GCC unroll 3
            for (int j = 0; j < 3; ++j) {
                c[3 * i + j] = dot3(ra[i][q], ra[3 + i][q], ra[6 + i][q], rb[j][q], rb[3 + j][q],
                                    rb[6 + j][q]);
            }
            t[i] = dot3(ra[i][q], ra[3 + i][q], ra[6 + i][q], lanes.d[0][q], lanes.d[1][q],
                        lanes.d[2][q]);
        }
        // The faces of A, then of B: the winner's unit direction u (A's frame) and whether the
        // normal from B to A is -u (flip), by box_plane_end's rules.
        double top = -std::numeric_limits<double>::infinity();
        double u[3] = {1.0, 0.0, 0.0};
        int flip = 0;
#pragma GCC unroll 3
        for (int i = 0; i < 3; ++i) {
            const double sep =
                face_separation(t[i], ha[i][q], std::abs(c[3 * i]), std::abs(c[3 * i + 1]),
                                std::abs(c[3 * i + 2]), hb[0][q], hb[1][q], hb[2][q]);
            const bool g = sep > top;
            top = g ? sep : top;
#pragma GCC unroll 3
            for (int k = 0; k < 3; ++k) { // e_i
                u[k] = g ? (k == i ? 1.0 : 0.0) : u[k];
            }
            flip = g ? (t[i] >= 0.0 ? 1 : 0) : flip;
        }
#pragma GCC unroll 3
        for (int j = 0; j < 3; ++j) {
            const double tc = dot3(c[j], c[3 + j], c[6 + j], t[0], t[1], t[2]);
            const double sep = face_separation(tc, hb[j][q], std::abs(c[j]), std::abs(c[3 + j]),
                                               std::abs(c[6 + j]), ha[0][q], ha[1][q], ha[2][q]);
            const bool g = sep > top;
            top = g ? sep : top;
#pragma GCC unroll 3
            for (int k = 0; k < 3; ++k) { // B's axis j: column j of C
                u[k] = g ? c[3 * k + j] : u[k];
            }
            flip = g ? (tc > 0.0 ? 1 : 0) : flip;
        }
        // The edge pairs (raw: the winner's direction times its length).
        double top_len = 1.0;
        double raw[3] = {u[0], u[1], u[2]};
#pragma GCC unroll 3
        for (int i = 0; i < 3; ++i) {
            const int i1 = next(i);
            const int i2 = prev(i);
#pragma GCC unroll 3
            for (int j = 0; j < 3; ++j) {
                const int j1 = next(j);
                const int j2 = prev(j);
                const double n1 = -c[3 * i2 + j];
                const double n2 = c[3 * i1 + j];
                double num;
                double len;
                edge_candidate(n1, n2, t[i1], t[i2], ha[i1][q], ha[i2][q], c[3 * i1 + j1],
                               c[3 * i2 + j1], c[3 * i1 + j2], c[3 * i2 + j2], hb[j1][q], hb[j2][q],
                               num, len);
                const bool g = !(len <= 1e-12) && num * top_len > top * len;
                top = g ? num : top;
                top_len = g ? len : top_len;
                raw[i] = g ? 0.0 : raw[i];
                raw[i1] = g ? n1 : raw[i1];
                raw[i2] = g ? n2 : raw[i2];
                flip = g ? (std::fma(n1, t[i1], n2 * t[i2]) > 0.0 ? 1 : 0) : flip;
            }
        }
        top = top / top_len;
        // Along the normal m (A's frame): A's corner s h (s_k = +-1) is at height
        // sum_k s_k h_k m_k, lowest where s_k = -sign(m_k), at d_a = -sum_k h_k |m_k|; B's corner
        // t + C (s h) at m . t + sum_j s_j h_j g_j with g = C^T m, highest at
        // d_b = m . t + sum_j h_j |g_j|. Turning axis k away from the extreme corner moves a
        // corner by e_k = 2 h_k |m_k| (B: 2 h_j |g_j|).
        double m[3];
#pragma GCC unroll 3
        for (int k = 0; k < 3; ++k) {
            const double uk = raw[k] / top_len;
            m[k] = flip != 0 ? -uk : uk;
            lanes.normal_a[k][q] = m[k];
        }
        double g[3];
#pragma GCC unroll 3
        for (int j = 0; j < 3; ++j) {
            g[j] = dot3(c[j], c[3 + j], c[6 + j], m[0], m[1], m[2]);
            lanes.ea[j][q] = 2.0 * (ha[j][q] * std::abs(m[j]));
            lanes.eb[j][q] = 2.0 * (hb[j][q] * std::abs(g[j]));
            lanes.normal[j][q] =
                dot3(ra[3 * j][q], ra[3 * j + 1][q], ra[3 * j + 2][q], m[0], m[1], m[2]);
            lanes.corner_a[j][q] = m[j] < 0.0 ? ha[j][q] : -ha[j][q];
            lanes.corner_b[j][q] = g[j] > 0.0 ? hb[j][q] : -hb[j][q];
        }
        const double d_a =
            -dot3(ha[0][q], ha[1][q], ha[2][q], std::abs(m[0]), std::abs(m[1]), std::abs(m[2]));
        const double d_b = std::fma(
            hb[2][q], std::abs(g[2]),
            std::fma(hb[1][q], std::abs(g[1]),
                     std::fma(hb[0][q], std::abs(g[0]), dot3(m[0], m[1], m[2], t[0], t[1], t[2]))));
        lanes.depth[q] = d_b - d_a;
        lanes.touching[q] = !(top > 0.0) && lanes.depth[q] > 0.0 ? 1 : 0;
        // The extreme corners in the world: x_a + Ra c_a, x_b + Rb c_b (x_b = x_a + d).
        const auto& ca = lanes.corner_a;
        const auto& cb = lanes.corner_b;
#pragma GCC unroll 3
        for (int k = 0; k < 3; ++k) {
            lanes.point_a[k][q] =
                lanes.xa[k][q] + dot3(ra[3 * k][q], ra[3 * k + 1][q], ra[3 * k + 2][q], ca[0][q],
                                      ca[1][q], ca[2][q]);
            lanes.point_b[k][q] = (lanes.xa[k][q] + lanes.d[k][q]) +
                                  dot3(rb[3 * k][q], rb[3 * k + 1][q], rb[3 * k + 2][q], cb[0][q],
                                       cb[1][q], cb[2][q]);
        }
    }
}

bool box_pair_patch(const BoxPairLanes& lanes, std::size_t q, double area_tol, Vec3& point) {
    const double half = 0.5 * lanes.depth[q];
    const Vec3 n(lanes.normal[0][q], lanes.normal[1][q], lanes.normal[2][q]);
    // The section of one box by the mid-plane, in 2D about o = (A's lowest corner) + half n: the
    // corners across the face of the two axes other than `k` (heights from the extreme corner
    // sums of e, all within half of it) carried along axis k to the plane. Only when the other
    // four corners (e_k and beyond) lie past it: then these four edges are the ones the plane
    // crosses, and the section is this quadrilateral.
    const Vec3 o = Vec3(lanes.point_a[0][q], lanes.point_a[1][q], lanes.point_a[2][q]) + half * n;
    const Vec3 u = n.unitOrthogonal();
    const Vec3 v = n.cross(u);
    const auto quad = [&](const double(&corner)[3][BoxPairLanes::kWidth],
                          const double(&rot)[9][BoxPairLanes::kWidth],
                          const double(&e)[3][BoxPairLanes::kWidth], const Vec3& extreme,
                          std::array<Vec2, 4>& out) {
        int k = 0;
        for (int j = 1; j < 3; ++j) {
            k = e[j][q] > e[k][q] ? j : k;
        }
        const int i = next(k);
        const int j = prev(k);
        if (!(e[k][q] > half) || !(e[i][q] + e[j][q] < half)) {
            return false;
        }
        // Turning axis l away from the extreme corner: -2 corner_l along the body's axis l.
        const auto offset = [&](int l) {
            const double f = -2.0 * corner[l][q];
            return Vec3(f * rot[l][q], f * rot[3 + l][q], f * rot[6 + l][q]);
        };
        const Vec3 oi = offset(i);
        const Vec3 oj = offset(j);
        const Vec3 ok = offset(k);
        const std::array<double, 4> h = {0.0, e[i][q], e[i][q] + e[j][q], e[j][q]};
        const std::array<Vec3, 4> c = {extreme, extreme + oi, extreme + oi + oj, extreme + oj};
        for (std::size_t s = 0; s < 4; ++s) {
            const Vec3 x = c[s] + ((half - h[s]) / e[k][q]) * ok - o;
            out[s] = Vec2(u.dot(x), v.dot(x));
        }
        if (cross2(out[1] - out[0], out[2] - out[0]) < 0.0) { // counter-clockwise
            std::swap(out[1], out[3]);
        }
        return true;
    };
    std::array<Vec2, 4> qa;
    std::array<Vec2, 4> qb;
    if (!quad(lanes.corner_a, lanes.ra, lanes.ea,
              Vec3(lanes.point_a[0][q], lanes.point_a[1][q], lanes.point_a[2][q]), qa) ||
        !quad(lanes.corner_b, lanes.rb, lanes.eb,
              Vec3(lanes.point_b[0][q], lanes.point_b[1][q], lanes.point_b[2][q]), qb)) {
        return false;
    }
    // A's quadrilateral clipped by B's (Sutherland-Hodgman, as clip_convex_into): at most eight
    // corners.
    std::array<Vec2, 8> buffer_0;
    std::array<Vec2, 8> buffer_1;
    Vec2* poly = buffer_0.data();
    Vec2* next_poly = buffer_1.data();
    std::size_t size = 4;
    std::copy(qa.begin(), qa.end(), poly);
    for (std::size_t c = 0; c < 4 && size > 0; ++c) {
        const Vec2& c0 = qb[c];
        const Vec2 edge = qb[(c + 1) % 4] - c0;
        std::array<double, 8> side; // > 0: inside, left of the edge
        for (std::size_t k = 0; k < size; ++k) {
            side[k] = cross2(edge, poly[k] - c0);
        }
        std::size_t kept = 0;
        for (std::size_t k = 0; k < size; ++k) {
            const std::size_t k1 = k + 1 == size ? 0 : k + 1;
            const double sp = side[k];
            const double sr = side[k1];
            if (sp >= 0.0) {
                next_poly[kept++] = poly[k];
            }
            if ((sp >= 0.0) != (sr >= 0.0)) {
                next_poly[kept++] = poly[k] + (poly[k1] - poly[k]) * (sp / (sp - sr));
            }
        }
        size = kept;
        std::swap(poly, next_poly);
    }
    double area2 = 0.0;
    Vec2 moment = Vec2::Zero();
    for (std::size_t k = 0; k < size; ++k) {
        const Vec2& p = poly[k];
        const Vec2& r = poly[k + 1 == size ? 0 : k + 1];
        const double w = cross2(p, r);
        area2 += w;
        moment += w * (p + r);
    }
    if (!(area2 > 2.0 * area_tol)) {
        return false;
    }
    const Vec2 cen = moment / (3.0 * area2);
    point = o + cen.x() * u + cen.y() * v;
    return true;
}

} // namespace kiln::geometry::detail
