#pragma once
// Contact geometry of non-spherical particles (bodies) in the run loop. A particle is split into
// elements: a sphere or a clump sub-sphere is a sphere element, a superquadric is one convex
// element. Element pairs are dispatched by kind: sphere-sphere analytically, anything with a convex
// element through the support-map narrow phase (geometry/convex_contact.hpp); a convex polyhedron
// is one element of its own kind: polyhedron pairs by the fast common plane (or libccd GJK/EPA),
// a sphere against a polyhedron by the exact closest feature (geometry/polyhedron_contact.hpp),
// a polyhedron against a superquadric by libccd GJK/EPA (whatever the narrow-phase setting).
//
// Normal convention: `normal` points from element b to element a (world frame), as in
// convex_contact.hpp; moving a by overlap * normal separates the two.

#include "core/types.hpp"
#include "dynamics/scene_spec.hpp"
#include "dynamics/wall.hpp"
#include "geometry/convex_contact.hpp"
#include "geometry/polyhedron_contact.hpp"
#include "geometry/shape.hpp"

#include <cmath>
#include <compare>
#include <cstdint>
#include <vector>

namespace kiln::dynamics {

/// One element of a posed particle, world frame.
struct Element {
    enum class Kind { sphere, superquadric, polyhedron };
    Kind kind = Kind::sphere;
    Vec3 centre = Vec3::Zero();                 ///< sphere centre or body centre (m, world)
    double radius = 0.0;                        ///< sphere radius or bounding radius (m)
    const geometry::Superquadric* sq = nullptr; ///< superquadric geometry (body frame)
    Quat q = Quat::Identity();                  ///< orientation of a superquadric, body -> world
    double min_size = 0.0; ///< sphere radius, smallest half-axis or polyhedron in-radius (m)
    const geometry::PolyhedronFeatures* poly = nullptr; ///< polyhedron features (body frame)
    const geometry::ConvexPolyhedron* hull = nullptr;   ///< polyhedron triangles (body frame)
    double r_equiv = 0.0; ///< volume-equivalent sphere radius of a polyhedron (m)
};

/// Key of one element contact: particle ids a < b (b = -1 - wall index for a wall) and the element
/// indices on each side (0 for a sphere, a superquadric and a wall).
struct BodyContactKey {
    std::int64_t a = 0;  ///< id of particle a (the smaller id of a particle pair)
    std::int64_t b = 0;  ///< id of particle b, or -1 - wall index
    std::int32_t ea = 0; ///< element index in a
    std::int32_t eb = 0; ///< element index in b
    /// Ordered by (a, b, ea, eb).
    auto operator<=>(const BodyContactKey&) const = default;
};

/// One element contact involving a body, world frame: the history carried to the next step and
/// the geometry of the last evaluation (reachable for output and contact heat).
struct BodyContact {
    Vec3 shear = Vec3::Zero();   ///< tangential history (m), on a relative to b
    Vec3 normal = Vec3::UnitX(); ///< unit normal from b to a (also the Newton warm start)
    Vec3 point = Vec3::Zero();   ///< contact point (m)
    double overlap = 0.0;        ///< overlap (m)
    double r_eff = 0.0;          ///< effective radius the law used (m)
    Vec3 force = Vec3::Zero();   ///< force on a (N)
};

/// One stored element contact: its key and its record (world frame).
struct BodyContactEntry {
    BodyContactKey key;  ///< particle ids and element indices
    BodyContact contact; ///< history and last geometry
};

/// Result of one element-element or element-wall geometry query, world frame.
struct ElementContact {
    bool touching = false;  ///< overlap > 0
    bool converged = true;  ///< narrow phase converged (false: failure, contact skipped)
    bool fell_back = false; ///< the first method failed and a second answered (Newton ->
                            ///< GJK/EPA, or GJK/EPA -> MPR for a polyhedron and a superquadric)
    double overlap = 0.0;   ///< (m)
    Vec3 normal = Vec3::UnitX(); ///< unit, from b (or the wall) to a
    Vec3 point = Vec3::Zero();   ///< contact point (m)
    double r_eff = 0.0;          ///< effective radius for the law (m), clamped (see .cpp)
    bool proved_apart = false;   ///< apart by the cached or searched direction (no narrow phase)
    /// A polyhedron apart from a plane wall: the height (m, >= 0) of its deepest vertex above the
    /// wall, as computed (0 otherwise).
    double wall_gap = 0.0;
};

/// Narrow-phase counters of a run (summed over the steps).
struct NarrowPhaseCounters {
    long calls = 0;     ///< superquadric element queries
    long fallbacks = 0; ///< the first method did not converge, a second answered (see fell_back)
    long failures = 0;  ///< no method converged: the contact was skipped for that step
};

/// World centre x + R c (m) of a clump member at c (m, body frame) of a particle at x with R =
/// `rot` (body -> world). Written out, so every place that poses members gets the same bits: rows
/// 0 and 1 as R_r0 c_0, then fused R_r1 c_1 and R_r2 c_2; row 2 as R_21 c_1, then fused R_22 c_2
/// and R_20 c_0; then + x (the order GCC gave Eigen's `x + rot * c` in these loops before, so the
/// numbers did not change when it was written out).
inline Vec3 member_centre(const Vec3& x, const Mat3& rot, const Vec3& c) {
    return {x.x() + std::fma(rot(0, 2), c.z(), std::fma(rot(0, 1), c.y(), rot(0, 0) * c.x())),
            x.y() + std::fma(rot(1, 2), c.z(), std::fma(rot(1, 1), c.y(), rot(1, 0) * c.x())),
            x.z() + std::fma(rot(2, 0), c.x(), std::fma(rot(2, 2), c.z(), rot(2, 1) * c.y()))};
}

/// A clump's members by component (body frame): c[0 .. n) the x of the centres (m), then
/// c[n .. 2n) the y, the z and the radii (m). Read eight at a time into vector lanes, without
/// turning records into components at every step.
struct MemberColumns {
    std::size_t n = 0;     ///< members
    std::vector<double> c; ///< the four components, n each, one after the other
};

/// The n members `spheres` of a clump by component.
[[nodiscard]] MemberColumns member_columns(const geometry::ClumpSphere* spheres, std::size_t n);

/// World records (x, y, z, r), four doubles each, into `out`, of the members `cols` of a clump at
/// x with R = `rot` (body -> world): centre member_centre(x, rot, c) (m, world), radius r (m).
/// With AVX-512, eight members at a time: member_centre's operations lane by lane (so the same
/// bits), the results turned into records (GCC's own vector loop stored every double alone).
void pose_members(const Vec3& x, const Mat3& rot, const MemberColumns& cols, double* out);

/// Appends the elements of a particle (centre x, orientation q, radius r) of template t (nullptr:
/// a sphere) to `out`. A polyhedron template needs the overload with its features.
void append_elements(const geometry::ShapeTemplate* t, const Vec3& x, const Quat& q, double r,
                     std::vector<Element>& out);

/// As above; `features` are the template's polyhedron features (body frame; nullptr unless t is a
/// polyhedron, which then must have them).
void append_elements(const geometry::ShapeTemplate* t, const geometry::PolyhedronFeatures* features,
                     const Vec3& x, const Quat& q, double r, std::vector<Element>& out);

/// As above with the particle's rotation matrix `rot` = R(q) (body -> world) given, which poses
/// clump members (the step loop keeps one per body).
void append_elements(const geometry::ShapeTemplate* t, const geometry::PolyhedronFeatures* features,
                     const Vec3& x, const Quat& q, const Mat3& rot, double r,
                     std::vector<Element>& out);

/// Volume-equivalent sphere radius of a polyhedron template (m): the Hertz radius of its contacts
/// (docs/theory/contact.md, "Polyhedra").
[[nodiscard]] double equivalent_radius(const geometry::ShapeTemplate& t);

/// Contact of two elements; `warm` is the previous normal (b to a) or nullptr.
///
/// `separating` (optional, in and out; used by pairs of convex elements, ignored by sphere pairs):
/// in, a direction (unit, from b to a, world frame) that separated the pair at an earlier step, or
/// zero; if the gap along it still exceeds a margin (1e-10 of the two bounding radii, far above the
/// queries' round-off) the pair is apart and no other query runs. Out: a direction along which the
/// pair is apart this step (not yet checked against the margin), or zero when it touches or none
/// was found. With it, a superquadric pair also tries a portal search for a separating direction
/// (geometry/separating_axis.hpp) before its narrow phase. Either way the answer is the one
/// without it: a direction with a gap proves the pair apart. nullptr: no cache, no search (a pair
/// that touched at the last step).
///
/// `touched_last`: the pair touched at the last step. A polyhedron pair then skips the
/// line-of-centres test (two support searches that almost never prove such a pair apart) and runs
/// its exact query at once; other pairs ignore it.
///
/// `memo` (optional, in and out; read by pairs of polyhedra with the common plane, ignored by
/// others): the pair's memory of its last search (geometry::PlaneMemo), which lets a resting
/// contact skip the candidates that cannot win. The answer is the one without it, bit for bit.
///
/// `radius`: compute R* (ElementContact::r_eff). A caller that keeps the R* of the contact's first
/// step (`body_radius = "first_touch"`) passes false for a contact that has one: a superquadric's
/// R* takes two curvature tensors and an eigen-solve per query. r_eff is then 0; every other
/// field is the same, bit for bit.
[[nodiscard]] ElementContact element_contact(const Element& a, const Element& b, NarrowPhase method,
                                             const Vec3* warm, Vec3* separating = nullptr,
                                             bool touched_last = false,
                                             geometry::PlaneMemo* memo = nullptr,
                                             bool radius = true);

/// One resting pair for box_pair_contacts: two polyhedron elements whose shapes are boxes along
/// their body axes (geometry::PolyhedronFeatures::Box::aligned), with their rotation matrices
/// (body -> world, those of their orientations).
struct BoxPairQuery {
    const Element* a = nullptr;
    const Element* b = nullptr;
    const Mat3* ra = nullptr;
    const Mat3* rb = nullptr;
};

/// element_contact of n pairs of boxes with the fast common plane, as for pairs that touched at
/// the last step and have no cached direction, eight pairs at a time in vector lanes
/// (geometry::detail::box_pair_planes, then pair_point's rule by selects): the same contacts to
/// round-off (the relative pose from the rotation matrices, the depth, the near corners and the
/// point in closed form, not from vertex lists; a face-on-face pair's patch pair by pair), into
/// out[0..n).
void box_pair_contacts(const BoxPairQuery* pairs, std::size_t n, ElementContact* out);

/// Is the pair of polyhedron elements a, b apart along `sep` (unit, from b to a, world frame) by
/// more than the separation margin (1e-10 of the two bounding radii)? The test element_contact
/// runs first on a polyhedron pair's cached separating direction, for a caller that runs it
/// before assembling the query (the step loop, for a pair that was apart at its last query).
[[nodiscard]] bool polyhedra_apart_along(const Element& a, const Element& b, const Vec3& sep);

/// As polyhedra_apart_along, also returning the overlap along `sep` it compared (m).
[[nodiscard]] bool polyhedra_apart_along(const Element& a, const Element& b, const Vec3& sep,
                                         double& overlap);

/// Margin of polyhedra_apart_along (m): the overlap along the direction must lie below minus this.
[[nodiscard]] double polyhedra_separation_margin(const Element& a, const Element& b);

/// Effective radius (m) of element a against a flat wall of unit normal n (from the wall to a,
/// world frame): a sphere's radius, a polyhedron's equivalent radius, a superquadric's R* at its
/// deepest point (as element_wall_contact on a plane).
[[nodiscard]] double flat_wall_radius(const Element& a, const Vec3& n);

/// Contact of an element with a wall (normal from the wall into the element). A polyhedron's
/// contact point is its deepest vertex, or the weighted average of the almost equally deep ones.
/// `radius`: compute R* (as for element_contact; without it a superquadric's r_eff is 0).
[[nodiscard]] ElementContact element_wall_contact(const Element& a, const WallShape& w,
                                                  bool radius = true);

} // namespace kiln::dynamics
