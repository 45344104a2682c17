#pragma once
// Narrow phase between two convex bodies given by support maps (superquadrics today; any convex
// shape with a support map later). Two independent methods compute the same quantity, the
// minimum translation distance (MTD): the overlap delta = min over unit n of h_A(n) + h_B(-n),
// h the support function (distance of the supporting plane), i.e. the distance from the origin to
// the boundary of the Minkowski difference A - B (van den Bergen 2003, Collision Detection in
// Interactive 3D Environments, Sec. 4.3.4):
//  - kCcdEpa: GJK + EPA of libccd (Gilbert, Johnson & Keerthi 1988; van den Bergen 2001);
//  - kSupportNewton: Newton's method on the unit sphere for min h_A(n) + h_B(-n) with the analytic
//    support maps (gradient = s_A(n) - s_B(-n) by Danskin's theorem), started from 15 directions.
// kCcdMpr (Minkowski portal refinement, Snethen 2008, via libccd) is also offered: it is faster
// but its depth is the distance to a boundary point found along the portal, an upper bound of the
// MTD, not the MTD itself.
//
// Normal convention (as in docs/theory/contact.md): `normal` is the unit vector from B towards A
// (world frame); moving A by depth * normal separates the bodies.

#include "core/types.hpp"
#include "geometry/superquadric.hpp"

#include <algorithm>
#include <array>

namespace kiln::geometry {

/// A superquadric placed in the world: centre x (m) and orientation q (body -> world).
struct PosedSuperquadric {
    const Superquadric* shape = nullptr; ///< geometry, body frame
    Vec3 x = Vec3::Zero();               ///< centre (m), world frame
    Quat q = Quat::Identity();           ///< orientation, body -> world

    /// Support point (m, world frame) for a world-frame direction d.
    [[nodiscard]] Vec3 support(const Vec3& d_world) const {
        return x + q * shape->support(q.conjugate() * d_world);
    }
    /// Length scale of the body for relative tolerances: the largest half-axis (m).
    [[nodiscard]] double length_scale() const { return shape->half_axes.maxCoeff(); }
};

/// Narrow-phase methods.
enum class ConvexMethod {
    kCcdEpa,       ///< libccd GJK + EPA: the MTD
    kCcdMpr,       ///< libccd MPR: penetration along the portal (upper bound of the MTD)
    kSupportNewton ///< Newton on the sphere of directions, analytic support maps: the MTD
};

/// Result of a narrow-phase query. Failures are reported, never thrown.
struct ConvexContact {
    bool touching = false;         ///< bodies overlap (depth > 0)
    bool converged = true;         ///< false: the method hit its iteration limit or failed
    double depth = 0.0;            ///< overlap (m); kSupportNewton: negative = gap when apart
    Vec3 normal = Vec3::UnitX();   ///< unit normal from B towards A, world frame
    Vec3 point = Vec3::Zero();     ///< contact point (m), world frame: midpoint of the deepest
                                   ///< points of A and B along the normal
    int iterations = 0;            ///< iterations used (Newton: summed over the starts)
    bool deepest_known = false;    ///< deepest_a and deepest_b hold the supports along `normal`
    Vec3 deepest_a = Vec3::Zero(); ///< A's deepest point s_A(-normal) (m), world frame
    Vec3 deepest_b = Vec3::Zero(); ///< B's deepest point s_B(normal) (m), world frame
    /// libccd only (ccd_adapter.cpp): its normal pointed the wrong way (the overlap along its
    /// reverse was the smaller) and the answer was repaired from MPR and that reverse.
    bool repaired = false;

    /// Sets the deepest points (world frame) and the contact point, their midpoint.
    void set_deepest(const Vec3& sa, const Vec3& sb) {
        deepest_known = true;
        deepest_a = sa;
        deepest_b = sb;
        point = 0.5 * (sa + sb);
    }
};

/// Local geometry of a contact for the contact laws and heat: relative principal curvatures in the
/// common tangent plane (sum of both bodies' curvature tensors at their deepest points).
struct ContactCurvature {
    double k_min = 0.0;            ///< smaller relative principal curvature (1/m)
    double k_max = 0.0;            ///< larger relative principal curvature (1/m)
    double effective_radius = 0.0; ///< 1/sqrt(k_min k_max) (m), Johnson 1985 Sec. 4.2; infinite
                                   ///< when a relative curvature is 0 (flat on flat)
    double hertz_area = 0.0;       ///< contact area estimate pi R_e delta (m^2) (Hertz, circular
                                   ///< contact of the equivalent radius); infinite with R_e
};

/// Relative curvature of a contact found by convex_contact (needs touching and a valid normal).
[[nodiscard]] ContactCurvature
contact_curvature(const PosedSuperquadric& a, const PosedSuperquadric& b, const ConvexContact& c);

/// Overlap, normal and contact point of two posed superquadrics by the chosen method.
[[nodiscard]] ConvexContact convex_contact(const PosedSuperquadric& a, const PosedSuperquadric& b,
                                           ConvexMethod method);

/// libccd adapter (ccd_adapter.cpp, the only file that includes libccd): kCcdEpa or kCcdMpr.
[[nodiscard]] ConvexContact ccd_contact(const PosedSuperquadric& a, const PosedSuperquadric& b,
                                        bool use_mpr);

/// A triangle (world frame) as a support map, for a particle against one triangle of a mesh wall.
struct SupportTriangle {
    std::array<Vec3, 3> v; ///< corners (m), world frame
    Vec3 x;                ///< centroid (m), world frame

    /// Support point (m, world frame): the corner maximising d . x for a world direction d.
    [[nodiscard]] Vec3 support(const Vec3& d) const {
        const double a = d.dot(v[0]);
        const double b = d.dot(v[1]);
        const double c = d.dot(v[2]);
        return a >= b ? (a >= c ? v[0] : v[2]) : (b >= c ? v[1] : v[2]);
    }
    /// Length scale for relative tolerances: the farthest corner from the centroid (m).
    [[nodiscard]] double length_scale() const {
        return std::max({(v[0] - x).norm(), (v[1] - x).norm(), (v[2] - x).norm()});
    }
};

/// libccd GJK + EPA (use_mpr = false) or MPR of a superquadric a and a triangle b; normal from the
/// triangle to a (world frame). Origin and scale are a's, so a large triangle does not coarsen the
/// tolerance.
[[nodiscard]] ConvexContact ccd_contact(const PosedSuperquadric& a, const SupportTriangle& b,
                                        bool use_mpr);

/// How Newton's method on the sphere of directions estimates its Hessian and judges its steps.
/// Every setting converges to the same test (tangential gradient below 1e-9 of the summed largest
/// half-axes); the defaults are the cheapest that keep validation 14 (docs/performance.md, "Cost
/// per contact of superquadrics (session 11)"); fd_step = 1e-6 with roundoff_steps and
/// secant_updates off gives the method of 2026-11-24, the reference of the tests.
struct NewtonSettings {
    /// Finite-difference step (rad) of the Hessian. Near a flat face the support map moves as
    /// |d_t|^(1/(2/e - 1)) with the tangential direction d_t, so the Hessian changes within far
    /// less than 1e-6 rad; 1e-8 rad resolves it and keeps the round-off of the difference (the
    /// support map's 1.6e-13 relative over the step) near 1e-5 of the curvature radius.
    double fd_step = 1e-8;
    /// Central differences (4 evaluations); forward ones (2) are cheaper and converge as well,
    /// but their one-sided Hessian shifted where the runs stop within the tolerance in a way that
    /// did not cancel over steps: validation 14 (superquadrics, linear law) fell from order 1.73
    /// to 1.52 with them.
    bool central_differences = true;
    /// Where the decrease a step promises is below the round-off of f, accept a step that keeps
    /// f within its round-off and shrinks the gradient (instead of 20 halvings and a stop).
    bool roundoff_steps = true;
    /// After a full Newton step, update dp/dn by Broyden's secant formula (no evaluations)
    /// instead of new differences; after a shortened step, differences again.
    bool secant_updates = true;
    /// The first Hessian of a run from the two bodies' curvature tensors at the current supports
    /// (their inverses, the curvature radii, summed) instead of differences; differences where a
    /// point is nearly flat or a tip, and for pairs with an exponent below 0.5 (blocky).
    bool analytic_hessian = true;
    /// When the run from a warm normal fails, run the cold start (27 directions, Newton from the
    /// best 4, up to 100 iterations each). false: return the failed run's last direction and f,
    /// unconverged, for the caller to finish (element_contact does so for a pair that touched at
    /// the last step: its stalled direction is near the best one).
    bool cold_after_warm = true;
};

/// Newton's method on the sphere of directions (convex_contact.cpp). Without `warm_normal` it
/// samples 27 directions and runs Newton from the best 4 (robust, slow: a reference). With the
/// previous step's normal (unit, from B to A, world frame) it runs one Newton from there (the DEM
/// use: the pose changes little per step) and falls back to the cold start when that fails.
/// `warm_supports`, with `warm_normal` only: the caller's s_A(-warm_normal) and s_B(warm_normal)
/// (m, world frame), e.g. from its own separation test along the warm normal, so that Newton's
/// first evaluation is not repeated.
[[nodiscard]] ConvexContact
support_newton_contact(const PosedSuperquadric& a, const PosedSuperquadric& b,
                       const Vec3* warm_normal = nullptr, const NewtonSettings& settings = {},
                       const std::array<Vec3, 2>* warm_supports = nullptr);

} // namespace kiln::geometry
