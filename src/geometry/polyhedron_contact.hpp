#pragma once
// Contact between two convex polyhedra by the common-plane method (Cundall 1988, Int. J. Rock
// Mech. 25, 107) in the fast form of Nezami et al. (2004, Int. J. Numer. Anal. Meth. Geomech. 28,
// 783; 2006, Comput. Geotech. 33, 145), as used by the seed (Hoehner 2014 via Oschmann 2019,
// Sec. 3.3.2; notes/seed001_shape.md Sec. 4.3).
//
// The common plane (CP) with normal m (from B to A) and the vertex distances d_A = min over A of
// m.x, d_B = max over B of m.x has the gap d_A - d_B; the CP is the plane of largest gap (Cundall's
// condition 3), and the overlap is -gap = h_A(-m) + h_B(m) with h the support function. Nezami's
// fast CP evaluates only the candidate orientations that can be optimal: planes parallel to a face
// of A or of B and planes parallel to one edge of A and one edge of B. For convex polyhedra the
// best of these is the exact optimum (the faces of the Minkowski difference A - B have exactly
// these normals; an edge pair counts only if its Gauss-map arcs cross, Gregorius 2013, GDC talk
// "The separating axis test between convex polyhedra"), so no iteration is needed and the overlap
// equals the minimum translation distance that EPA approximates. Hoehner's first FCP step
// (separating the particles before the search) is not done, as in the seed (L462).
//
// Multi-point contact and patch: the contact points are the vertices of the intersection A n B
// (vertices of each body inside the other and intersections of the edges of each body with the
// faces of the other, found by clipping every edge against the other body's face planes). The
// patch is the section of A n B by the common plane, placed half way between d_A and d_B: the
// intersection of the two convex polygons in which the CP cuts A and B. The contact point is the
// patch centroid, so it moves continuously when a contact turns from an edge into a face (see
// docs/theory/shapes.md, "Common plane").
//
// Conventions as in convex_contact.hpp: the normal points from B to A, world frame; failures are
// reported in the result, never thrown.

#include "core/types.hpp"
#include "geometry/convex_contact.hpp"
#include "geometry/polyhedron.hpp"

#include <array>
#include <functional>
#include <optional>
#include <utility>
#include <vector>

namespace kiln::geometry {

/// Contact features of a convex polyhedron (body frame): planar faces with coplanar triangles
/// merged, and the edges between faces of different planes (the triangles' diagonals dropped).
struct PolyhedronFeatures {
    std::vector<Vec3> vertices;            ///< vertex positions (m), body frame
    std::vector<Vec3> face_normals;        ///< outward unit normal of each planar face, body frame
    std::vector<double> face_offsets;      ///< n . x on each face plane (m), body frame
    std::vector<std::array<int, 4>> edges; ///< feature edges: vertices v0, v1, faces f0, f1
    /// Per feature edge, its Gauss-map arc's n1 x n0 (the normals of faces f1 and f0) and its
    /// vector v1 - v0 (m), body frame: the edge-edge stage reads them for A's edges at every query.
    std::vector<std::array<Vec3, 2>> edge_arcs;
    double radius = 0.0;   ///< distance of the farthest vertex from the origin (m)
    double inradius = 0.0; ///< smallest face offset (m): the inscribed radius
    /// Volume-equivalent sphere radius (m), kept so the step loop does not take a cube root per
    /// body and step.
    double r_equiv = 0.0;

    /// A rectangular box (cuboid) centred on the body origin, given by its faces: two boxes meet
    /// in the closed form of the separating-axis test (box_plane.cpp, detail::box_plane) instead
    /// of the general search and its memory.
    struct Box {
        Mat3 axes; ///< columns: unit normals of three faces, one per pair (body frame)
        Vec3 half; ///< half extents along the columns of axes (m)
        std::array<int, 3> plus;  ///< face index whose normal is axes.col(i) (to 1e-12)
        std::array<int, 3> minus; ///< face index whose normal is -axes.col(i) (to 1e-12)
        /// The faces' normals are the body frame's axes (each within 1e-12 of +-e_k): axes is
        /// then exactly the identity (column k along e_k, plus[k] the face along +e_k), and B's
        /// pose needs no turning into the box frames.
        bool aligned = false;
        /// The vertex on each corner: corner[s] for the corner on the + side of axes.col(k)
        /// where bit k of s is set.
        std::array<int, 8> corner{};
        /// A body-frame vector along the axes: axes^T d (d itself where aligned).
        [[nodiscard]] Vec3 along(const Vec3& d) const {
            return aligned ? d : Vec3(axes.transpose() * d);
        }
        /// The index into `corner` of the corner on the + side of each axis where g (a vector
        /// along the axes) is positive.
        [[nodiscard]] static std::size_t corner_of(const Vec3& g) {
            return static_cast<std::size_t>((g[0] > 0.0 ? 1 : 0) | (g[1] > 0.0 ? 2 : 0) |
                                            (g[2] > 0.0 ? 4 : 0));
        }
    };
    /// Set by polyhedron_features when the polyhedron is a box to 1e-12 of its radius (face
    /// normals opposite and orthogonal, every vertex on a corner); empty for other shapes.
    std::optional<Box> box;

    /// Support point (m, body frame): the vertex maximising d . x for a body-frame direction d
    /// (the first in the list where several do, to round-off). A box picks its corner from the
    /// signs of d along its axes where no other corner comes near (the same vertex).
    [[nodiscard]] Vec3 support(const Vec3& d_body) const;
};

/// Features of a polyhedron (faces whose normals differ by less than 1e-9 rad are merged).
[[nodiscard]] PolyhedronFeatures polyhedron_features(const ConvexPolyhedron& p);

/// A polyhedron placed in the world: centre of mass x (m) and orientation q (body -> world).
struct PosedPolyhedron {
    const PolyhedronFeatures* shape = nullptr; ///< geometry, body frame
    Vec3 x = Vec3::Zero();                     ///< centre of mass (m), world frame
    Quat q = Quat::Identity();                 ///< orientation, body -> world

    /// Support point (m, world frame) for a world-frame direction d.
    [[nodiscard]] Vec3 support(const Vec3& d_world) const {
        return x + q * shape->support(q.conjugate() * d_world);
    }
    /// Length scale for relative tolerances: the bounding radius (m).
    [[nodiscard]] double length_scale() const { return shape->radius; }
};

/// Overlap (m) of posed polyhedra a and b along the unit world direction m (from b towards a),
/// h_b(m) + h_a(-m) with h the support function: the value of overlap_along
/// (separating_axis.hpp) to round-off, from heights alone: m . (x_b - x_a) plus the largest
/// heights of b's vertices along m and of a's along -m in the body frames (one rotation of m per
/// body, no support point turned back to the world). Negative: m separates them.
[[nodiscard]] double polyhedron_overlap_along(const PosedPolyhedron& a, const PosedPolyhedron& b,
                                              const Vec3& m);

/// Which candidate plane of the fast common plane won.
enum class CommonPlaneFeature {
    kNone,     ///< no candidate (bounding spheres apart)
    kFaceOfA,  ///< plane parallel to a face of A
    kFaceOfB,  ///< plane parallel to a face of B
    kEdgeEdge, ///< plane parallel to an edge of A and an edge of B
};

/// Result of a polyhedron contact query. Failures are reported, never thrown.
struct PolyhedronContact {
    bool touching = false;       ///< bodies overlap (depth > 0)
    bool converged = true;       ///< false: degenerate input (e.g. non-finite pose)
    double depth = 0.0;          ///< overlap (m); when apart: minus a lower bound of the gap
    Vec3 normal = Vec3::UnitX(); ///< unit common-plane normal from B towards A, world frame
    Vec3 point = Vec3::Zero();   ///< contact point (m), world frame: centroid of the patch (or of
                                 ///< the points when the patch is degenerate), on the CP
    std::vector<Vec3> points;    ///< vertices of A n B (m), world frame
    std::vector<Vec3> patch;     ///< patch polygon on the CP (m), world frame, counter-clockwise
                                 ///< seen from A (about `normal`)
    double patch_area = 0.0;     ///< area of the patch (m^2)
    CommonPlaneFeature feature = CommonPlaneFeature::kNone; ///< winning candidate
    int iterations = 0; ///< candidate planes evaluated (faces plus edge pairs passing the test)
};

/// Overlap, common-plane normal, contact points and patch of two posed polyhedra (fast common
/// plane). `with_patch = false` skips the points and the patch (point = midpoint of the deepest
/// points of A and B along the normal).
[[nodiscard]] PolyhedronContact
polyhedron_contact(const PosedPolyhedron& a, const PosedPolyhedron& b, bool with_patch = true);

/// Decides, for the plane of a touching pair, whether its points and patch are built (see the
/// overload below). Its argument has touching, depth, normal and feature as the full result would
/// have them, and point = midpoint of the deepest points of A and B along the normal.
using PatchTest = std::function<bool(const PolyhedronContact&)>;

/// As polyhedron_contact with the patch, but the points and the patch are built only when
/// `need_patch` returns true for the plane found (a caller that reads the patch only for some
/// configurations, e.g. face on face, saves it for the others). Depth, normal and feature are the
/// same numbers either way; without the patch, point = midpoint of the deepest points.
[[nodiscard]] PolyhedronContact
polyhedron_contact(const PosedPolyhedron& a, const PosedPolyhedron& b, const PatchTest& need_patch);

namespace detail {
/// How the common plane's face stages scan (the answer is the same bits either way).
enum class FaceScan {
    automatic, ///< bounded for bodies with more vertices than faces (polyhedron_contact.cpp)
    full,      ///< every vertex against every face plane, the prune from the full tables
    bounded,   ///< only the faces whose upper bound can be the largest; the rest on demand
};
/// polyhedron_contact (without a patch test) with the face stages chosen: for tests.
[[nodiscard]] PolyhedronContact polyhedron_contact_with(const PosedPolyhedron& a,
                                                        const PosedPolyhedron& b, FaceScan scan,
                                                        bool with_patch = true);
/// How many faces of each body a memory refilled in this thread lists (PlaneMemo::top_a), at
/// most PlaneMemo::kTopFaces (the default): tests shorten the list so that the faces beyond it
/// decide often. The answers are the same bits for any length.
int& memo_listed_faces();

/// The closed-form common plane of two boxes (PolyhedronFeatures::box) at one relative pose: the
/// largest separation (m, < 0: overlap), the normal from B to A (A's body frame), the plane's
/// feature and the number of candidate planes (box_plane.cpp).
struct BoxPlane {
    double best = 0.0;
    Vec3 normal = Vec3::UnitX();
    CommonPlaneFeature feature = CommonPlaneFeature::kNone;
    int candidates = 0;
};
/// One pair, as polyhedron_contact runs it (rot: B body -> A body, shift: B's centre in A's
/// frame, m; both bodies boxes).
[[nodiscard]] BoxPlane box_plane(const PolyhedronFeatures& fa, const PolyhedronFeatures& fb,
                                 const Mat3& rot, const Vec3& shift);
/// Pairs of boxes in lanes: the inputs of the closed form per lane in structure-of-arrays form,
/// evaluated lane-parallel without branches (the winner chosen by box_plane's comparisons, in its
/// order), then each lane finished by box_plane's own code: box_plane's answer, bit for bit.
struct BoxLanes {
    static constexpr std::size_t kWidth = 8;
    const PolyhedronFeatures* fa[kWidth] = {};
    const PolyhedronFeatures* fb[kWidth] = {};
    const Mat3* rot[kWidth] = {};     ///< B body -> A body (the caller's storage)
    alignas(64) double c[9][kWidth];  ///< B's box axes in A's box frame, entry (i, j) at 3 i + j
    alignas(64) double t[3][kWidth];  ///< B's centre in A's box frame (m)
    alignas(64) double ha[3][kWidth]; ///< A's half extents (m)
    alignas(64) double hb[3][kWidth]; ///< B's half extents (m)
};
/// Fills lane q of `lanes` for the pair (fa, fb) at the relative pose (rot, shift); both boxes.
void box_lane(BoxLanes& lanes, std::size_t q, const PolyhedronFeatures& fa,
              const PolyhedronFeatures& fb, const Mat3& rot, const Vec3& shift);
/// The first n lanes' common planes into out[0..n).
void box_planes(const BoxLanes& lanes, std::size_t n, BoxPlane* out);

/// Pairs of boxes whose faces lie along their bodies' axes (Box::aligned, every shipped box),
/// posed in the world by rotation matrices, in lanes: the common plane (box_plane's closed form,
/// the winner's normal by its rules, picked in the lanes), the depth, the extreme corners and how
/// far their neighbours lie from each body's support plane, from the poses to the end without
/// vertex lists and without branches (box_plane.cpp, box_pair_planes). The route of resting box
/// pairs (dynamics::box_pair_contacts). A corner of a box is given by its body-frame coordinates,
/// +-half[k] along body axis k.
struct BoxPairLanes {
    static constexpr std::size_t kWidth = BoxLanes::kWidth;
    // Inputs (box_pair_lane).
    alignas(64) double ra[9][kWidth]; ///< A's rotation, body -> world, entry (i, j) at 3 i + j
    alignas(64) double rb[9][kWidth]; ///< B's rotation, body -> world
    alignas(64) double xa[3][kWidth]; ///< A's centre (m, world frame)
    alignas(64) double d[3][kWidth];  ///< B's centre minus A's (m, world frame)
    alignas(64) double ha[3][kWidth]; ///< A's half extents (m, along A's body axes)
    alignas(64) double hb[3][kWidth]; ///< B's half extents (m)
    // Outputs (box_pair_planes).
    alignas(64) int touching[kWidth]; ///< 1 where the closed form finds no separation and depth > 0
    alignas(64) double depth[kWidth]; ///< distance of the extreme corners along the normal (m)
    alignas(64) double normal[3][kWidth];   ///< unit normal from B to A, world frame
    alignas(64) double normal_a[3][kWidth]; ///< the same, A's body frame
    alignas(64) double corner_a[3][kWidth]; ///< A's corner lowest along the normal (A's frame)
    alignas(64) double corner_b[3][kWidth]; ///< B's corner highest along the normal (B's frame)
    alignas(64) double point_a[3][kWidth];  ///< A's lowest corner, world frame (m)
    alignas(64) double point_b[3][kWidth];  ///< B's highest corner, world frame (m)
    /// A's neighbour of the lowest corner along body axis k lies ea[k] above it along the normal
    /// (2 half[k] |m_k|; B's: eb[k] below B's highest); the corners across faces, sums of these.
    alignas(64) double ea[3][kWidth];
    alignas(64) double eb[3][kWidth];
};
/// Fills lane q's inputs for the boxes fa at (xa, ra) and fb at (xb, rb) (body -> world); both
/// aligned.
void box_pair_lane(BoxPairLanes& lanes, std::size_t q, const PolyhedronFeatures& fa, const Vec3& xa,
                   const Mat3& ra, const PolyhedronFeatures& fb, const Vec3& xb, const Mat3& rb);
/// The outputs of the first n (1 to kWidth) lanes; lanes n and beyond are overwritten with
/// copies of lane 0 (every lane runs the same code).
void box_pair_planes(BoxPairLanes& lanes, std::size_t n);
/// Lane q of box_pair_planes' outputs, touching face on face: the centroid of the patch (the
/// section of the two boxes by the plane half way through the depth, as polyhedron_contact's
/// patch), world frame, into `point`. Where each box's section is the quadrilateral of the four
/// edges across its face (the other corners past the plane: every resting pair) the two are
/// clipped here; otherwise, or where the patch's doubled area is not above 2 area_tol (m^2), it
/// returns false and the general patch code has to answer.
[[nodiscard]] bool box_pair_patch(const BoxPairLanes& lanes, std::size_t q, double area_tol,
                                  Vec3& point);

/// The contact point of the patch of a and b for the normal m (unit, from B to A, A's body
/// frame), world frame: polyhedron_contact's point for a face-on-face contact along m.
[[nodiscard]] Vec3 patch_point(const PosedPolyhedron& a, const PosedPolyhedron& b, const Vec3& m);
} // namespace detail

/// Memory of one pair's common plane between steps (temporal coherence of a resting contact).
/// Filled by the full search at a stored relative pose; at a later pose the separation of every
/// candidate has moved by at most the distance a vertex has moved relative to the other body
/// (translation plus rotation times the bounding radius), so the stored separations become upper
/// bounds and the edges' stored distances beyond the other body's planes lower bounds. The search
/// then evaluates only the faces and edges these bounds cannot rule out, and keeps its answer only
/// when it is clear (no near tie, a certificate of overlap): otherwise the full search runs and
/// refills the memory. The answer is the full search's, bit for bit (the same expressions
/// for the candidates evaluated; those ruled out lie below it by a margin).
struct PlaneMemo {
    bool valid = false;                     ///< filled for the shapes below
    const PolyhedronFeatures* fa = nullptr; ///< A's features when filled
    const PolyhedronFeatures* fb = nullptr; ///< B's features when filled
    Mat3 rot = Mat3::Identity();            ///< B body -> A body at the stored pose
    Vec3 shift = Vec3::Zero();              ///< B's centre in A's frame (m), stored pose
    Vec3 shift_in_b = Vec3::Zero();         ///< rot^T shift (m): A's centre is -this in B's frame
    double answer = 0.0;                    ///< largest separation (m, < 0: overlap), stored pose
    /// The pose and answer of the last query the memory or the full search answered (the stored
    /// pose after a refill): the overlap held since then certifies overlap while the relative
    /// motion since stays below it (polyhedron_memo.cpp, memo_search).
    Mat3 last_rot = Mat3::Identity();
    Vec3 last_shift = Vec3::Zero();
    Vec3 last_shift_in_b = Vec3::Zero();
    double last_answer = 0.0;
    /// Stored values (m), one block: the separation along each face of A, then of B; then per
    /// feature edge of A, then of B, a lower bound of its distance from the other body (the larger
    /// of its distance beyond one of the other's face planes, both ends, and beyond the other's
    /// bounding sphere).
    std::vector<double> values;
    int inside = -1; ///< a vertex strictly inside the other body: B's j as j, A's i as nv_B + i
    int cross = -1;  ///< an edge found crossing the other body: A's e as e, B's as ne_A + e
    /// Faces listed by their stored separations, so that the search meets the faces that can
    /// win first and stops at the first one ruled out: top_a holds the kTopFaces faces of A with
    /// the largest stored separations (fewer with detail::memo_listed_faces), largest first
    /// (equal values: lower index first), -1 past them; rest_a is the largest stored separation
    /// of A's other faces (m; -infinity: none). top_b and rest_b the same for B.
    static constexpr std::size_t kTopFaces = 4;
    std::array<int, kTopFaces> top_a{};
    std::array<int, kTopFaces> top_b{};
    double rest_a = 0.0;
    double rest_b = 0.0;
};

/// As polyhedron_contact with `need_patch`, with the pair's memory `memo` (read and written; see
/// PlaneMemo). The same answer as without it, bit for bit.
[[nodiscard]] PolyhedronContact polyhedron_contact(const PosedPolyhedron& a,
                                                   const PosedPolyhedron& b,
                                                   const PatchTest& need_patch, PlaneMemo& memo);

/// Vertices of a body near its support plane: world position (m) and weight (-), see NearBand.
using NearVertices = std::vector<std::pair<Vec3, double>>;

/// The band rule of NearBand for one body p: its vertices whose heights h (m, one per vertex of
/// p's shape, in its order, along some direction from any common origin) lie within `band`
/// (m, > 0) of the extreme `top` (sign = +1: the highest, below = top - h; -1: the lowest,
/// below = h - top), appended to `out` (cleared first) in the order of the vertices, each at its
/// world position (m) with the weight 1 - below / band (> 0).
void band_vertices(const PosedPolyhedron& p, const double* h, double top, double sign, double band,
                   NearVertices& out);

/// The vertices of each body within a band of its support plane along the common plane's normal,
/// filled by polyhedron_contact_point before it calls the patch test of a touching pair: `a` gets
/// A's vertices whose height along -normal lies within fraction * depth of A's largest, `b`
/// B's along +normal, each in the order of the body's vertices, with the weight
/// 1 - (largest - height) / (fraction * depth) (> 0). The heights are those of the plane's own
/// depth (A's body frame), so no body is searched twice.
struct NearBand {
    double fraction = 0.0;     ///< band as a fraction of the depth (> 0)
    NearVertices* a = nullptr; ///< A's vertices (cleared first)
    NearVertices* b = nullptr; ///< B's vertices (cleared first)
};

/// As polyhedron_contact with `need_patch` and the memory (nullptr: none), for a caller that reads
/// only touching, converged, depth, normal, point, patch_area and feature: those are the same
/// numbers, while `points` and `patch` are left empty (not turned to the world frame). With
/// `near`, its lists are filled for a touching pair before `need_patch` is called (and left as
/// they were otherwise).
[[nodiscard]] PolyhedronContact polyhedron_contact_point(const PosedPolyhedron& a,
                                                         const PosedPolyhedron& b,
                                                         const PatchTest& need_patch,
                                                         PlaneMemo* memo,
                                                         const NearBand* near = nullptr);

/// Counters of the memory route in this thread (for tests and benchmarks): queries that tried it,
/// and those it answered.
struct PlaneMemoCounters {
    long tried = 0;    ///< queries with a valid memory
    long answered = 0; ///< of which the memory's route gave the answer
    long refills = 0;  ///< full searches that refilled a memory
    /// Of the answered, those whose plane is a face the memory did not list among its first
    /// (PlaneMemo::top_a, top_b): found among the rest.
    long unlisted = 0;
    /// Of the answered, those whose overlap the overlap held since the last query certified
    /// (PlaneMemo::last_answer), with no vertex or edge tested.
    long held = 0;
};
/// This thread's counters (mutable, for resetting).
PlaneMemoCounters& plane_memo_counters();

/// Points and patch for a given normal m (unit, from B to A, world frame), as polyhedron_contact
/// computes them after finding its plane; fills depth (h_A(-m) + h_B(m)), normal, point, points,
/// patch and patch_area. Gives a patch to a normal found otherwise (e.g. by EPA).
[[nodiscard]] PolyhedronContact contact_patch_along(const PosedPolyhedron& a,
                                                    const PosedPolyhedron& b, const Vec3& m);

/// libccd's EPA tolerance for two polyhedra, in the query's scaled coordinates (lengths divided
/// by the sum of the bounding radii). libccd stops EPA when the new support point lies within
/// sqrt(tolerance) of the nearest face, or when |w| (h - |w|) < tolerance (|w| the face's
/// distance from the origin, h the support height along its normal). The overlap along the
/// returned normal therefore exceeds the true depth by at most max(sqrt(tol), tol / |w|) scaled
/// lengths. The Minkowski difference of two polyhedra has finitely many vertices, so EPA ends
/// when a support point adds nothing: round-off level is safe (at 1e-17 some queries of a bed of
/// cubes no longer converged), 1e-14 leaves three decades. The 1e-10 used for curved
/// shapes left a shallow cube contact 2.7 times too deep (tests/dynamics/test_polyhedra.cpp).
inline constexpr double kPolytopeEpaTolerance = 1e-14;

/// libccd adapter (ccd_adapter.cpp): GJK + EPA (use_mpr = false) or MPR on the support maps.
/// Two polyhedra use kPolytopeEpaTolerance.
[[nodiscard]] ConvexContact ccd_contact(const PosedPolyhedron& a, const PosedPolyhedron& b,
                                        bool use_mpr);

/// libccd GJK + EPA or MPR of a polyhedron a and a superquadric b (normal from b to a, world
/// frame).
[[nodiscard]] ConvexContact ccd_contact(const PosedPolyhedron& a, const PosedSuperquadric& b,
                                        bool use_mpr);

} // namespace kiln::geometry
