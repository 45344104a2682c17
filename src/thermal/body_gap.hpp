#pragma once
// The gap between two particles that need not touch (gas-gap conduction and radiation between
// bodies): the distance of their surfaces and the nearest points, from the shapes alone (the
// mechanics' narrow phase only reports overlapping pairs). Theory: docs/theory/heat.md, "Gaps
// between bodies".
//
// Every particle is split into convex cores with a margin: a sphere is its centre with margin R,
// a clump its member spheres (centre, margin r_m), a superquadric or polyhedron itself (support
// map, margin 0). The distance of two cores is found by GJK on their support maps (Gilbert,
// Johnson & Keerthi 1988, IEEE J. Robot. Autom. 4, 193; van den Bergen 2003, Collision Detection
// in Interactive 3D Environments, Sec. 4.3), the distance of the particles is the smallest core
// distance minus both margins.

#include "dynamics/system.hpp"
#include "geometry/polyhedron.hpp"
#include "geometry/superquadric.hpp"

#include <cstddef>
#include <limits>
#include <vector>

namespace kiln::thermal {

/// The nearest points of two particles.
struct BodyGap {
    double gap = 0;              ///< surface distance (m); < 0 = overlap of sphere elements, 0 when
                                 ///< two convex cores overlap (depth not measured)
    Vec3 point_i = Vec3::Zero(); ///< nearest point on i's surface (m, world)
    Vec3 point_j = Vec3::Zero(); ///< nearest point on j's surface (m, world)
    Vec3 normal = Vec3::UnitX(); ///< unit direction from i towards j at the gap (world)
    double member_radius_i = 0;  ///< radius of i's nearest sphere element (m); 0 for a convex body
    double member_radius_j = 0;  ///< the same for j (m)
    bool converged = true;       ///< false: GJK hit its iteration cap (gap is then an upper bound)
};

/// Gap and nearest points of every pair of elements (cores) of particles index `i` and `j` of
/// `sys`: one for two convex bodies or spheres, one per member (pair) for clumps; in element
/// order (i's elements outer). Overlapping convex cores as in body_gap.
///
/// `cutoff` (-, default: none) leaves out the element pairs whose gap is proved larger than
/// 2 cutoff R, R = 2 R_i R_j / (R_i + R_j), with R_i a sphere element's radius or a convex body's
/// bounding radius: the gas-gap reach (heat/gas_conduction.hpp) of the largest spheres an element
/// can stand for, so no pair within the reach of its equivalent spheres is left out. Their GJK
/// stops as soon as its lower bound of the distance passes that reach; the pairs kept are the same
/// numbers either way.
[[nodiscard]] std::vector<BodyGap>
element_gaps(const dynamics::System& sys, std::size_t i, std::size_t j,
             double cutoff = std::numeric_limits<double>::infinity());

/// Gap and nearest points of particles index `i` and `j` of `sys` (any shapes): the element pair
/// of smallest gap. Cores that
/// overlap give gap 0 with the normal along the line of centres and the points where each body's
/// support along it lies. The GJK distance is accurate to 1e-9 times the larger bounding radius.
[[nodiscard]] BodyGap body_gap(const dynamics::System& sys, std::size_t i, std::size_t j);

/// The gap of one element (core) of a particle to a plane (a wall or a wall's tangent plane).
struct PlaneGap {
    double gap = 0; ///< distance of the element's surface from the plane (m); < 0 =
                    ///< overlap (depth of a sphere element, or of a convex body's support)
    Vec3 point = Vec3::Zero(); ///< the element's point nearest the plane (m, world)
    double member_radius = 0;  ///< radius of a sphere element (m); 0 for a convex body
};

/// Gap of every element of particle index `i` of `sys` to the plane through `point` (m, world)
/// with unit normal `normal` (world, pointing to the particle's side): one for a sphere or a convex
/// body (its support point along -normal, exact), one per member for a clump; in element order.
[[nodiscard]] std::vector<PlaneGap> plane_gaps(const dynamics::System& sys, std::size_t i,
                                               const Vec3& point, const Vec3& normal);

/// A convex core placed in the world: a point (sphere centre, clump member centre) or a convex
/// body with a support map (superquadric, polyhedron).
struct Core {
    Vec3 x = Vec3::Zero();                                  ///< centre (m, world)
    Quat q = Quat::Identity();                              ///< body -> world rotation
    const geometry::Superquadric* superquadric = nullptr;   ///< set for a superquadric
    const geometry::ConvexPolyhedron* polyhedron = nullptr; ///< set for a polyhedron

    /// Point of the core farthest along the world direction `d` (m, world).
    [[nodiscard]] Vec3 support(const Vec3& d) const;
};

/// GJK distance of two cores.
struct CoreDistance {
    double distance = 0;   ///< |a - b| (m); 0 when the cores overlap
    Vec3 a = Vec3::Zero(); ///< nearest point of core A (m, world)
    Vec3 b = Vec3::Zero(); ///< nearest point of core B (m, world)
    bool overlap = false;  ///< the cores overlap (a, b then undefined)
    bool converged = true; ///< false: the iteration cap was hit
    bool beyond = false;   ///< stopped when the distance was proved larger than `beyond` (then
                           ///< `distance` is that lower bound and a, b are undefined)
    int iterations = 0;    ///< GJK iterations (-)
};

/// Distance and nearest points of cores `a` and `b` by GJK, to the absolute tolerance
/// `tolerance` (m) on the distance. With `beyond` (m) finite, GJK stops as soon as its lower
/// bound of the distance exceeds `beyond` (for callers that drop such pairs); otherwise the
/// iterations and the answer are the same.
[[nodiscard]] CoreDistance core_distance(const Core& a, const Core& b, double tolerance,
                                         double beyond = std::numeric_limits<double>::infinity());

} // namespace kiln::thermal
