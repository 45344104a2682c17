// A polyhedron pair's memory of its last common-plane search between steps (geometry::PlaneMemo,
// polyhedron_contact.hpp; docs/architecture.md, "Memory of a polyhedron pair's common plane"):
// the refill after a full search and the search from the memory's bounds. Its stages evaluate the
// candidates by the full search's own expressions (polyhedron_search.hpp), so its answers are the
// full search's, bit for bit.

#include "geometry/polyhedron_search.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace kiln::geometry {

namespace {

using namespace search;

/// Tolerance of the memory's bounds and tests, relative to the sum of the bounding radii (-):
/// far above the round-off of the distances (1e-16 relative) and of the stored values, far below
/// any overlap the law acts on. Bounds are widened by it, ties within it and overlaps or
/// certificates thinner than it go to the full search.
constexpr double kMemoTolerance = 1e-9;

/// Relative motion (relative to the sum of the bounding radii) beyond which the memory is not
/// read and the full search refills it: the bounds widen with the motion, so a memory far from
/// the pose rules out little. A choice of speed only; the answer does not depend on it (0.1 since
/// session 27, against 0.01 before: 1-3 % faster for icosahedra and `cylinder_16`, 0.3 slower).
constexpr double kMemoDrift = 0.1;

/// 1 / sqrt(2): the spectral norm of the difference of two rotation matrices over its Frobenius
/// norm.
constexpr double kSpectralOverFrobenius = 0.70710678118654752;

thread_local PlaneMemoCounters memo_counters;

/// The largest over k < n of min(d0[k], d1[k]), in four running maxima (the largest of a set does
/// not depend on the order it is taken in; one chain of dependent maxima was the refill's critical
/// path). -infinity for n = 0.
double largest_of_pair_minima(const double* d0, const double* d1, std::size_t n) {
    constexpr double lowest = -std::numeric_limits<double>::infinity();
    double h0 = lowest;
    double h1 = lowest;
    double h2 = lowest;
    double h3 = lowest;
    std::size_t k = 0;
    for (; k + 4 <= n; k += 4) {
        h0 = std::max(h0, std::min(d0[k], d1[k]));
        h1 = std::max(h1, std::min(d0[k + 1], d1[k + 1]));
        h2 = std::max(h2, std::min(d0[k + 2], d1[k + 2]));
        h3 = std::max(h3, std::min(d0[k + 3], d1[k + 3]));
    }
    for (; k < n; ++k) {
        h0 = std::max(h0, std::min(d0[k], d1[k]));
    }
    return std::max(std::max(h0, h1), std::max(h2, h3));
}

/// The faces of the largest stored separations `stored` (nf of them), largest first, equal
/// values by index, into `top` (-1 past nf), and the largest of the rest into `rest`
/// (-infinity: none); see PlaneMemo::top_a.
void rank_faces(const double* stored, std::size_t nf, std::array<int, PlaneMemo::kTopFaces>& top,
                double& rest) {
    thread_local std::vector<int> order;
    order.resize(nf);
    for (std::size_t k = 0; k < nf; ++k) {
        order[k] = static_cast<int>(k);
    }
    const auto length = static_cast<std::size_t>(
        std::clamp(detail::memo_listed_faces(), 1, static_cast<int>(PlaneMemo::kTopFaces)));
    const std::size_t sorted = std::min(nf, length + 1);
    std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(sorted),
                      order.end(), [stored](int i, int j) {
                          const double si = stored[static_cast<std::size_t>(i)];
                          const double sj = stored[static_cast<std::size_t>(j)];
                          return si > sj || (si == sj && i < j);
                      });
    top.fill(-1);
    for (std::size_t i = 0; i < std::min(nf, length); ++i) {
        top[i] = order[i];
    }
    rest = nf > length ? stored[static_cast<std::size_t>(order[length])]
                       : -std::numeric_limits<double>::infinity();
}

/// Bit e set for each of the n <= 64 stored values not above bar (NaN included): the edges the
/// prune keeps. With AVX-512, eight comparisons at a time into a mask register: the loop of one
/// comparison and shift per edge was 3 % of a settled icosahedron step (docs/performance.md,
/// "Session 36").
std::uint64_t kept_mask(const double* stored, std::size_t n, double bar) {
#if defined(__AVX512F__)
    const __m512d b = _mm512_set1_pd(bar);
    std::uint64_t mask = 0;
    std::size_t e = 0;
    for (; e + 8 <= n; e += 8) {
        const __mmask8 m = _mm512_cmp_pd_mask(_mm512_loadu_pd(stored + e), b, _CMP_NGT_UQ);
        mask |= static_cast<std::uint64_t>(m) << e;
    }
    if (e < n) {
        const auto tail = static_cast<__mmask8>((1U << (n - e)) - 1U);
        const __mmask8 m =
            _mm512_mask_cmp_pd_mask(tail, _mm512_maskz_loadu_pd(tail, stored + e), b, _CMP_NGT_UQ);
        mask |= static_cast<std::uint64_t>(m) << e;
    }
    return mask;
#else
    std::uint64_t mask = 0;
    for (std::size_t e = 0; e < n; ++e) {
        mask |= static_cast<std::uint64_t>(!(stored[e] > bar)) << e;
    }
    return mask;
#endif
}

/// Separation (m) along the face plane (n, o) of one body: the smallest n . v - o over the
/// vertices v of the other (PlaneDistances::separation's expression, no table kept).
double plane_separation(const Vec3& n, double o, const std::vector<Vec3>& v) {
    double s = std::numeric_limits<double>::infinity();
    for (const Vec3& x : v) {
        s = std::min(s, n.dot(x) - o);
    }
    return s;
}

/// One face stage of the memory's search: the separations (m) of the faces of one body that can
/// be the largest, as face_separations gives them, into `met` as (face, separation) in the order
/// evaluated. The faces go in the memory's order (top, then the rest by index when rest's bound
/// reaches the bar); the first always, every other one unless its bound (stored value + drift +
/// 2 tol) lies below the bar, the largest of `floor` (m, a value the answer reaches) and the
/// separations met. Listed by their stored values, the first one ruled out ends the list (the
/// bounds keep the order). `separation(k)` evaluates face k.
template <class Separation>
void memo_faces(const std::array<int, PlaneMemo::kTopFaces>& top, double rest, const double* stored,
                std::size_t nf, double drift, double tol, double floor, Separation&& separation,
                std::vector<std::pair<int, double>>& met) {
    met.clear();
    double bar = floor;
    for (std::size_t i = 0; i < top.size(); ++i) {
        const int k = top[i];
        if (k < 0) {
            break; // past the list (rest: the faces not listed, -infinity when none)
        }
        if (i > 0 && stored[static_cast<std::size_t>(k)] + drift + 2.0 * tol < bar) {
            return;
        }
        const double s = separation(static_cast<std::size_t>(k));
        met.emplace_back(k, s);
        bar = std::max(bar, s);
    }
    if (rest + drift + 2.0 * tol < bar) {
        return;
    }
    for (std::size_t k = 0; k < nf; ++k) {
        const bool listed = std::find(top.begin(), top.end(), static_cast<int>(k)) != top.end();
        if (!listed && !(stored[k] + drift + 2.0 * tol < bar)) {
            const double s = separation(k);
            met.emplace_back(static_cast<int>(k), s);
            bar = std::max(bar, s);
        }
    }
}

/// Raises top (m) to the largest separation in `met` and face to its face + base, and second to
/// the largest of the other values met (top's old value among them when raised). A value equal
/// to top does not raise it but becomes second: a tie, which the search declines (the full
/// search then decides between the faces), so the order the faces were met in does not matter.
void take_faces(const std::vector<std::pair<int, double>>& met, int base, double& top, int& face,
                double& second) {
    std::size_t win = met.size();
    double value = top;
    for (std::size_t i = 0; i < met.size(); ++i) {
        if (met[i].second > value) {
            win = i;
            value = met[i].second;
        }
    }
    for (std::size_t i = 0; i < met.size(); ++i) {
        if (i != win) {
            second = std::max(second, met[i].second);
        }
    }
    if (win < met.size()) {
        second = std::max(second, top);
        top = value;
        face = base + met[win].first;
    }
}

/// Is the memory's certificate vertex still inside the other body by more than tol (m)? (-1: no
/// vertex.)
bool memo_inside(const PolyhedronFeatures& fa, const PolyhedronFeatures& fb, Relative& r,
                 int vertex, double tol) {
    const auto nvb = static_cast<int>(r.vb.size());
    if (vertex < 0) {
        return false;
    }
    if (vertex < nvb) {
        const Vec3 x = r.vb[static_cast<std::size_t>(vertex)];
        for (std::size_t k = 0; k < fa.face_normals.size(); ++k) {
            if (!(fa.face_normals[k].dot(x) - fa.face_offsets[k] < -tol)) {
                return false;
            }
        }
        return true;
    }
    relative_faces(fb, r);
    const Vec3 x = fa.vertices[static_cast<std::size_t>(vertex - nvb)];
    for (std::size_t k = 0; k < r.nb.size(); ++k) {
        if (!(r.nb[k].dot(x) - r.ob[k] < -tol)) {
            return false;
        }
    }
    return true;
}

/// Does an edge cross the other body (the full search's second certificate)? B's edges first
/// (the one that did at the last query, then the kept ones in r), then A's likewise; the one found
/// is kept in memo.cross (A's edge e as e, B's as the count of A's edges + e).
bool memo_crossing(const PolyhedronFeatures& fa, const PolyhedronFeatures& fb, Relative& r,
                   PlaneMemo& memo) {
    // B's edges are tested against A's own planes, A's against all of B's planes turned into A's
    // frame: B's first, so that a query certified by one of them turns no more of B's planes.
    thread_local std::vector<int> one(1);
    const auto nea = static_cast<int>(fa.edges.size());
    if (memo.cross >= nea) {
        one[0] = memo.cross - nea;
        if (edge_crosses(fb.edges, one, r.vb, fa.face_normals, fa.face_offsets) >= 0) {
            return true;
        }
    }
    int e = edge_crosses(fb.edges, r.edges_b, r.vb, fa.face_normals, fa.face_offsets);
    if (e >= 0) {
        memo.cross = nea + e;
        return true;
    }
    relative_faces(fb, r);
    if (memo.cross >= 0 && memo.cross < nea) {
        one[0] = memo.cross;
        if (edge_crosses(fa.edges, one, fa.vertices, r.nb, r.ob) >= 0) {
            return true;
        }
    }
    e = edge_crosses(fa.edges, r.edges_a, fa.vertices, r.nb, r.ob);
    memo.cross = e;
    return e >= 0;
}
} // namespace

namespace search {

/// Refills the memory at the pose of r (make_relative and relative_faces done) from complete
/// tables of distances, for a touching answer `best` (m, < 0), with the vertex deepest inside the
/// other body as the certificate to try first (none: -1).
void refill_memo(const PolyhedronFeatures& fa, const PolyhedronFeatures& fb, const Relative& r,
                 double best, PlaneMemo& memo) {
    ++memo_counters.refills;
    // The full search's tables where it filled them all (the values are bounds: any exact
    // evaluation serves), else tables of their own.
    thread_local std::vector<double> own_b; // B's vertices beyond A's planes
    thread_local std::vector<double> own_a; // A's vertices beyond B's planes
    thread_local std::vector<double> sep;
    const std::size_t nfa = fa.face_normals.size();
    const std::size_t nfb = fb.face_normals.size();
    memo.values.resize(nfa + nfb + fa.edges.size() + fb.edges.size());
    if (!r.full_tables) {
        face_distances(fa.face_normals, fa.face_offsets, r.vb, own_b, sep);
        face_distances(r.nb, r.ob, fa.vertices, own_a, sep);
    }
    const std::vector<double>& dist_b = r.full_tables ? r.dist_b.dist : own_b;
    const std::vector<double>& dist_a = r.full_tables ? r.dist_a.dist : own_a;
    // Separation along each face: the smallest distance in its column.
    // (Row by row: an index modulo nf per entry was an integer division per distance.)
    const auto columns = [](const std::vector<double>& dist, std::size_t nf, double* out) {
        std::fill(out, out + nf, std::numeric_limits<double>::infinity());
        const std::size_t rows = dist.size() / nf;
        for (std::size_t i = 0; i < rows; ++i) {
            const double* d = dist.data() + i * nf;
            for (std::size_t k = 0; k < nf; ++k) {
                out[k] = std::min(out[k], d[k]);
            }
        }
    };
    columns(dist_b, nfa, memo.values.data());
    columns(dist_a, nfb, memo.values.data() + nfa);
    rank_faces(memo.values.data(), nfa, memo.top_a, memo.rest_a);
    rank_faces(memo.values.data() + nfa, nfb, memo.top_b, memo.rest_b);
    // Per edge, the larger of the prune's two distances: beyond one face plane of the other body
    // (the larger over the planes of the nearer end's distance), and beyond its bounding sphere.
    const auto edge_reach = [](const std::vector<std::array<int, 4>>& edges,
                               const std::vector<Vec3>& v, const std::vector<double>& dist,
                               std::size_t nf, const Vec3& centre, double radius, double* out) {
        for (std::size_t e = 0; e < edges.size(); ++e) {
            const auto i0 = static_cast<std::size_t>(edges[e][0]);
            const auto i1 = static_cast<std::size_t>(edges[e][1]);
            const double* d0 = dist.data() + i0 * nf;
            const double* d1 = dist.data() + i1 * nf;
            const double m = std::sqrt(segment_point_distance2(v[i0], v[i1], centre)) - radius;
            out[e] = std::max(m, largest_of_pair_minima(d0, d1, nf));
        }
    };
    double* stored_edges = memo.values.data() + nfa + nfb;
    edge_reach(fa.edges, fa.vertices, dist_a, nfb, r.shift, fb.radius, stored_edges);
    edge_reach(fb.edges, r.vb, dist_b, nfa, Vec3::Zero(), fa.radius,
               stored_edges + fa.edges.size());
    // The vertex deepest inside the other body (smallest largest distance): B's if one of B's is
    // inside (tested later against A's own planes), else A's (against B's planes turned).
    const double tol = kMemoTolerance * (fa.radius + fb.radius);
    double deepest = -tol;
    memo.inside = -1;
    memo.cross = -1;
    const auto scan = [&](const std::vector<double>& dist, std::size_t nf, std::size_t nv,
                          int base) {
        for (std::size_t i = 0; i < nv; ++i) {
            const double* d = dist.data() + i * nf;
            const double top = largest_of_pair_minima(d, d, nf);
            if (top < deepest) {
                deepest = top;
                memo.inside = base + static_cast<int>(i);
            }
        }
    };
    scan(dist_b, nfa, r.vb.size(), 0);
    if (memo.inside < 0) {
        scan(dist_a, nfb, fa.vertices.size(), static_cast<int>(r.vb.size()));
    }
    memo.valid = true;
    memo.fa = &fa;
    memo.fb = &fb;
    memo.rot = r.rot;
    memo.shift = r.shift;
    memo.shift_in_b = r.rot.transpose() * r.shift;
    memo.answer = best;
    memo.last_rot = memo.rot;
    memo.last_shift = memo.shift;
    memo.last_shift_in_b = memo.shift_in_b;
    memo.last_answer = best;
}

/// The common plane from the memory (see PlaneMemo), after make_relative: true with best, best_m
/// (A's frame), c.feature and the prune's lists in r set as the full search sets them, when the
/// bounds single out the answer; false (c and r to be reset) when the full search must run.
///
/// Why it is the full search's answer: a vertex of one body moves relative to the other by at
/// most drift = |dR| r + |ds| (the change of the relative rotation in the Frobenius norm, which
/// bounds the spectral one, times the bounding radius, plus the change of the centre's position),
/// so every separation along a face and every distance beyond a plane moves by at most the drift,
/// and the largest separation of all (the answer) too. A face whose stored separation plus the
/// drift lies below a lower bound of the answer cannot win nor tie and is not evaluated; an edge
/// whose stored distance beyond one plane minus the drift exceeds the prune's reach is one the full
/// prune drops as well (the reach here is at least the full search's: its best face is at most
/// the full search's). So the candidates evaluated include all the full search evaluates that can
/// come near the answer, by the same expressions; the answer is kept only when it beats every
/// other value met by the tolerance and a vertex lies inside the other body (then the full search
/// has its certificate of overlap and takes no other path).
bool memo_search(const PolyhedronFeatures& fa, const PolyhedronFeatures& fb, Relative& r,
                 PlaneMemo& memo, double& best, Vec3& best_m, PolyhedronContact& c) {
    if (!memo.valid || memo.fa != &fa || memo.fb != &fb) {
        return false;
    }
    ++memo_counters.tried;
    const double scale = fa.radius + fb.radius;
    const double tol = kMemoTolerance * scale;
    const Vec3 shift_in_b = r.rot.transpose() * r.shift;
    // Bounds of the motion since the pose (rot0, shift0, shift_in_b0): of A's vertices in B's
    // frame (first) and of B's in A's (second), the rotation's change by its Frobenius norm times
    // `norm_factor` (at least its spectral norm) times the other body's bounding radius, plus the
    // centre's shift.
    const auto motion = [&](const Mat3& rot0, const Vec3& shift0, const Vec3& shift_in_b0,
                            double norm_factor) {
        const double turn = (r.rot - rot0).norm() * norm_factor;
        return std::pair{turn * fa.radius + (shift_in_b - shift_in_b0).norm(),
                         turn * fb.radius + (r.shift - shift0).norm()};
    };
    const auto drift = motion(memo.rot, memo.shift, memo.shift_in_b, 1.0);
    const double drift_a = drift.first;
    const double drift_b = drift.second;
    if (!(std::max(drift_a, drift_b) <= kMemoDrift * scale)) {
        return false;
    }
    const double floor = memo.answer - std::min(drift_a, drift_b) - tol; // <= the answer
    thread_local std::vector<std::pair<int, double>> met;
    double second = -std::numeric_limits<double>::infinity();
    const std::size_t nfa = fa.face_normals.size();
    const std::size_t nfb = fb.face_normals.size();
    c.iterations += static_cast<int>(nfa + nfb);
    int face = -1; // the face that raised the best last (A's k as k, B's as nfa + k)
    double top = best;
    // Faces of A: evaluated unless their bound (stored value, drift, round-off of the stored
    // value, and the tie margin) lies below the running lower bound of the answer.
    // (The separations by the full search's expression, without its table of distances: the
    // memory's route reads none of it.)
    memo_faces(
        memo.top_a, memo.rest_a, memo.values.data(), nfa, drift_b, tol, floor,
        [&](std::size_t k) {
            return plane_separation(fa.face_normals[k], fa.face_offsets[k], r.vb);
        },
        met);
    take_faces(met, 0, top, face, second);
    if (!(top < -tol)) {
        return false;
    }
    // Faces of B: only the planes evaluated are turned into A's frame (make_relative sized them).
    memo_faces(
        memo.top_b, memo.rest_b, memo.values.data() + nfa, nfb, drift_a, tol, std::max(floor, top),
        [&](std::size_t k) {
            need_face(fb, r, k);
            return plane_separation(r.nb[k], r.ob[k], fa.vertices);
        },
        met);
    take_faces(met, static_cast<int>(nfa), top, face, second);
    best = top;
    if (face >= 0 && static_cast<std::size_t>(face) < nfa) {
        best_m = -fa.face_normals[static_cast<std::size_t>(face)];
        c.feature = CommonPlaneFeature::kFaceOfA;
    } else if (face >= 0) {
        best_m = r.nb[static_cast<std::size_t>(face) - nfa];
        c.feature = CommonPlaneFeature::kFaceOfB;
    }
    if (!(best < -tol)) {
        return false;
    }
    // The prune from the stored distances (the full search's reach expression).
    const double reach = -best + 1e-9 * (fa.radius + fb.radius);
    // An edge is dropped when its stored distance, less the drift and the tolerance, exceeds the
    // reach; written without a branch (most edges are dropped, the rest in no pattern). Up to 64
    // edges, one bit per kept edge first (comparisons independent of each other), then the kept
    // ones listed in order: appending at a running count made every comparison wait for the last.
    const auto keep = [](const double* stored, std::size_t n, double bar, std::vector<int>& kept) {
        if (n <= 64) {
            std::uint64_t mask = kept_mask(stored, n, bar);
            kept.clear();
            for (; mask != 0; mask &= mask - 1) {
                kept.push_back(std::countr_zero(mask));
            }
            return;
        }
        kept.resize(n);
        int* out = kept.data();
        std::size_t m = 0;
        for (std::size_t e = 0; e < n; ++e) {
            out[m] = static_cast<int>(e);
            m += stored[e] > bar ? 0U : 1U;
        }
        kept.resize(m);
    };
    const double* stored_edges = memo.values.data() + nfa + nfb;
    keep(stored_edges, fa.edges.size(), reach + drift_a + tol, r.edges_a);
    keep(stored_edges + fa.edges.size(), fb.edges.size(), reach + drift_b + tol, r.edges_b);
    r.pruned = true;
    relative_arcs(fb, r);
    edge_stage(fa, fb, r, best, best_m, c, second);
    if (!(best < -tol) || !(second < best - tol)) {
        return false;
    }
    // The certificate of overlap. First the overlap held since the last query: the largest
    // separation over all directions (the answer, < 0 when the bodies overlap) moves by at most
    // the largest motion of a vertex relative to the other body, as every separation along a
    // fixed direction does. So last_answer + motion < -tol means the bodies overlap now by more
    // than tol, and then the full search finds its certificate (the intersection's vertices are
    // vertices inside the other body or edges crossing it) and takes the same path. The motion as
    // drift_a and drift_b, with the rotation's spectral norm: for two rotation matrices
    // ||R1 - R0||_2 = ||R1 - R0||_F / sqrt(2) (2 sin(theta / 2) against 2 sqrt(2) sin(theta / 2)),
    // to the round-off of R's orthogonality (1e-16), which tol covers. Otherwise the stored
    // vertex inside the other body, else a kept edge crossing it (edge_crosses as the full search
    // calls it: a crossing edge passes within the reach of the other body, so the full prune
    // keeps it too, and the same expression gives the same answer).
    const auto moved =
        motion(memo.last_rot, memo.last_shift, memo.last_shift_in_b, kSpectralOverFrobenius);
    const bool held = memo.last_answer + std::min(moved.first, moved.second) < -tol;
    if (!held && !memo_inside(fa, fb, r, memo.inside, tol) && !memo_crossing(fa, fb, r, memo)) {
        return false;
    }
    memo.last_rot = r.rot;
    memo.last_shift = r.shift;
    memo.last_shift_in_b = shift_in_b;
    memo.last_answer = best;
    ++memo_counters.answered;
    memo_counters.held += held ? 1 : 0;
    if (c.feature != CommonPlaneFeature::kEdgeEdge && face >= 0) {
        const bool of_a = static_cast<std::size_t>(face) < nfa;
        const auto& top_list = of_a ? memo.top_a : memo.top_b;
        const int k = of_a ? face : face - static_cast<int>(nfa);
        if (std::find(top_list.begin(), top_list.end(), k) == top_list.end()) {
            ++memo_counters.unlisted;
        }
    }
    return true;
}

} // namespace search

PlaneMemoCounters& plane_memo_counters() {
    return memo_counters;
}

namespace detail {
int& memo_listed_faces() {
    thread_local int length = static_cast<int>(PlaneMemo::kTopFaces);
    return length;
}
} // namespace detail

} // namespace kiln::geometry
