#pragma once
// Internals of the fast common plane (not part of kiln_geometry's interface), shared by
// polyhedron_contact.cpp (the full search, the patch) and polyhedron_memo.cpp (a pair's memory of
// its last search, geometry::PlaneMemo): B placed in A's frame, the tables of vertex-plane
// distances, the face and edge stages and the certificates of overlap.

#include "geometry/polyhedron_contact.hpp"

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace kiln::geometry::search {

/// Storage of PlaneDistances, kept between queries (per thread) to reuse its memory.
struct DistanceTable {
    std::vector<double> dist;            // vertex-major distances (m)
    std::vector<unsigned char> row_done; // per vertex: its row is filled
    std::vector<unsigned char> col_done; // per face: its column is filled
    std::vector<std::uint64_t> beyond;   // per vertex with a row: bit k set when dist > reach
    std::vector<std::size_t> cols;       // the filled columns, in the order filled
};

/// B expressed in A's body frame: vertices and face planes.
struct Relative {
    Mat3 rot;               // B body -> A body
    Vec3 shift;             // B's centre in A's frame (m)
    std::vector<Vec3> vb;   // B's vertices in A's frame (m)
    std::vector<Vec3> nb;   // B's face normals in A's frame
    std::vector<double> ob; // B's face offsets in A's frame (m)
    // Per feature edge of B, in A's frame: the negated normals c, d of its two faces and d x c,
    // the Gauss-map arc of the edge of -B.
    std::vector<std::array<Vec3, 3>> arcs;
    // Signed distances of the vertices of one body beyond the face planes of the other,
    // vertex-major: dist_b[j * nfa + k] = n_a,k . vb_j - o_a,k and dist_a[i * nfb + k] =
    // n_b,k . va_i - o_b,k (m), filled by columns (a face's separation) and rows (a vertex's
    // distances, for the prune and the certificates) where they are first read.
    DistanceTable dist_b, dist_a;
    std::vector<int> edges_a, edges_b; // feature edges kept for the edge-edge stage
    bool pruned = false;               // edges_a/edges_b are valid for this pose
    bool faces = false;                // nb/ob are valid for this pose (relative_faces)
    // The pose's number (make_relative counts them; 0 is never one), and per face of B the
    // number of the pose its entries of nb/ob were turned for (relative_face): a search that
    // reads a few of B's planes turns only those.
    std::uint32_t pose = 0;
    std::vector<std::uint32_t> face_pose;
    bool full_tables = false; // dist_b and dist_a hold every distance (full search)
};

/// Signed distances (m) of the vertices `v` of one body beyond the face planes (n, o) of the
/// other, vertex-major (entry i * nf + k = n_k . v_i - o_k), filled by whole columns (one face
/// against every vertex: its separation) or whole rows (one vertex against every face: the prune
/// and the certificates) where first read. An entry may be computed in both; it is the one
/// expression `n_k . v_i - o_k` either way, so the numbers do not depend on which are read.
class PlaneDistances {
  public:
    PlaneDistances(const std::vector<Vec3>& n, const std::vector<double>& o,
                   const std::vector<Vec3>& v, DistanceTable& t)
        : n_(n), o_(o), v_(v), t_(t), nf_(n.size()) {
        t_.dist.resize(nf_ * v.size());
        t_.row_done.assign(v.size(), 0);
        t_.col_done.assign(nf_, 0);
        t_.beyond.resize(v.size());
        t_.cols.clear();
    }
    /// Separation (m) along face k: the smallest distance of the vertices beyond its plane.
    double separation(std::size_t k) {
        const Vec3 n = n_[k];
        const double o = o_[k];
        const Vec3* v = v_.data();
        const std::size_t nv = v_.size();
        const std::size_t nf = nf_;
        double* col = t_.dist.data() + k;
        double s = std::numeric_limits<double>::infinity();
        for (std::size_t i = 0; i < nv; ++i) {
            const double d = n.dot(v[i]) - o;
            col[i * nf] = d;
            s = std::min(s, d);
        }
        if (t_.col_done[k] == 0) {
            t_.col_done[k] = 1;
            t_.cols.push_back(k);
        }
        return s;
    }
    /// The prune's distance (m): the masks of the rows mark the planes a vertex lies beyond by
    /// more than `reach`. Set before the first row.
    void set_reach(double reach) { reach_ = reach; }
    /// Do both vertices i0 and i1 lie beyond one face plane by more than the reach? Reads the
    /// filled columns first, then the two rows.
    bool both_beyond(std::size_t i0, std::size_t i1) {
        const double reach = reach_;
        for (const std::size_t k : t_.cols) {
            if (t_.dist[i0 * nf_ + k] > reach && t_.dist[i1 * nf_ + k] > reach) {
                return true;
            }
        }
        if (t_.row_done[i1] != 0 && t_.row_done[i0] == 0) {
            std::swap(i0, i1); // start from a row already filled
        }
        fill_row(i0);
        if (nf_ <= 64) {
            if (t_.row_done[i1] != 0) {
                return (t_.beyond[i0] & t_.beyond[i1]) != 0;
            }
            // The other end only against the planes the first lies beyond (often none: an
            // end inside the other body keeps the edge without the second row).
            const Vec3 x = v_[i1];
            for (std::uint64_t m = t_.beyond[i0]; m != 0; m &= m - 1) {
                const auto k = static_cast<std::size_t>(std::countr_zero(m));
                if (n_[k].dot(x) - o_[k] > reach) {
                    return true;
                }
            }
            return false;
        }
        fill_row(i1);
        const double* d0 = t_.dist.data() + i0 * nf_;
        const double* d1 = t_.dist.data() + i1 * nf_;
        for (std::size_t k = 0; k < nf_; ++k) {
            if (d0[k] > reach && d1[k] > reach) {
                return true;
            }
        }
        return false;
    }
    /// Does a vertex lie strictly inside the other body (all its distances negative)? A filled
    /// column with a distance >= 0 answers no for that vertex without its row; a vertex without
    /// a row stops at its first distance >= 0.
    bool any_inside() {
        for (std::size_t i = 0; i < v_.size(); ++i) {
            bool out = false;
            for (const std::size_t k : t_.cols) {
                out = out || t_.dist[i * nf_ + k] >= 0.0;
            }
            if (out) {
                continue;
            }
            std::size_t k = 0;
            if (t_.row_done[i] != 0) {
                const double* d = t_.dist.data() + i * nf_;
                while (k < nf_ && !(d[k] >= 0.0)) {
                    ++k;
                }
            } else {
                const Vec3 x = v_[i];
                while (k < nf_ && !(n_[k].dot(x) - o_[k] >= 0.0)) {
                    ++k;
                }
            }
            if (k == nf_) {
                return true;
            }
        }
        return false;
    }
    [[nodiscard]] const std::vector<Vec3>& vertices() const { return v_; }
    [[nodiscard]] std::size_t faces() const { return nf_; }

  private:
    void fill_row(std::size_t i) {
        if (t_.row_done[i] != 0) {
            return;
        }
        t_.row_done[i] = 1;
        // Locals, so that the stores into the row (doubles) cannot alias them for the compiler.
        const Vec3* n = n_.data();
        const double* o = o_.data();
        const Vec3 x = v_[i];
        const double reach = reach_;
        const std::size_t nf = nf_;
        double* row = t_.dist.data() + i * nf;
        std::uint64_t mask = 0;
        for (std::size_t k = 0; k < nf; ++k) {
            const double d = n[k].dot(x) - o[k];
            row[k] = d;
            mask |= static_cast<std::uint64_t>(d > reach) << (k & 63U);
        }
        t_.beyond[i] = mask;
    }

    const std::vector<Vec3>& n_;
    const std::vector<double>& o_;
    const std::vector<Vec3>& v_;
    DistanceTable& t_;
    std::size_t nf_;
    double reach_ = std::numeric_limits<double>::infinity();
};

/// B's pose and vertices in A's frame (enough for A's face stage, which rejects most near misses).
void make_relative(const PosedPolyhedron& a, const PosedPolyhedron& b, Relative& r);

/// B's face plane k in A's frame (after make_relative): r.nb[k] and r.ob[k]. One function for
/// every caller (not inlined), so that a plane turned alone has the bits of one turned with all.
void relative_face(const PolyhedronFeatures& fb, Relative& r, std::size_t k);

/// B's face plane k in A's frame unless it is turned for this pose already.
inline void need_face(const PolyhedronFeatures& fb, Relative& r, std::size_t k) {
    if (r.face_pose[k] != r.pose) {
        relative_face(fb, r, k);
    }
}

/// B's face planes in A's frame (after make_relative): all of them.
void relative_faces(const PolyhedronFeatures& fb, Relative& r);

/// The Gauss-map arcs of B's kept edges (after the prune; turns the planes they read).
void relative_arcs(const PolyhedronFeatures& fb, Relative& r);

/// Squared distance (m^2) from the segment p0-p1 to the point c.
[[nodiscard]] double segment_point_distance2(const Vec3& p0, const Vec3& p1, const Vec3& c);

/// The edge-edge stage over the kept edges r.edges_a x r.edges_b (arcs set): raises best and
/// sets best_m and c.feature when an edge pair gives a larger separation; raises `second` to the
/// largest of the other values met (polyhedron_contact.cpp).
void edge_stage(const PolyhedronFeatures& fa, const PolyhedronFeatures& fb, const Relative& r,
                double& best, Vec3& best_m, PolyhedronContact& c, double& second);

/// Separations along the face planes of `t`'s other body that can be the largest, the others
/// -infinity (polyhedron_contact.cpp); with `bound` empty every face is computed.
void face_separations(PlaneDistances& t, const std::vector<double>& bound, double floor,
                      std::vector<double>& sep);

/// Every distance of the vertices `v` beyond the face planes (n, o), vertex-major, and the
/// separation along each face; true when a vertex lies strictly inside (polyhedron_contact.cpp).
bool face_distances(const std::vector<Vec3>& n, const std::vector<double>& o,
                    const std::vector<Vec3>& v, std::vector<double>& dist,
                    std::vector<double>& sep);

/// The first kept edge (vertices `v`) that crosses the body of face planes (n, o); -1: none.
[[nodiscard]] int edge_crosses(const std::vector<std::array<int, 4>>& edges,
                               const std::vector<int>& kept, const std::vector<Vec3>& v,
                               const std::vector<Vec3>& n, const std::vector<double>& o);

/// Refills the memory at the pose of r (make_relative and relative_faces done) after a full
/// search with the touching answer `best` (m, < 0) (polyhedron_memo.cpp).
void refill_memo(const PolyhedronFeatures& fa, const PolyhedronFeatures& fb, const Relative& r,
                 double best, PlaneMemo& memo);

/// The common plane from the memory, after make_relative: true with best, best_m (A's frame),
/// c.feature and the prune's lists in r set as the full search sets them; false when the full
/// search must run (polyhedron_memo.cpp).
[[nodiscard]] bool memo_search(const PolyhedronFeatures& fa, const PolyhedronFeatures& fb,
                               Relative& r, PlaneMemo& memo, double& best, Vec3& best_m,
                               PolyhedronContact& c);

} // namespace kiln::geometry::search
