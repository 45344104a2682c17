#pragma once
// Shape templates prepared for deposition on the transfer grid: the body-frame inside test of
// each shape kind in a form that is cheap to call once per sub-cell, and the world-frame box that
// bounds a posed body (the sub-cells scanned).

#include "core/types.hpp"
#include "geometry/clump.hpp"
#include "geometry/shape.hpp"
#include "geometry/superquadric.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <variant>
#include <vector>

namespace kiln::fluid {

/// The points of one row that lie inside a body: first..last, as step numbers along the row
/// (clip_row) or as sub-cell indices (chord_run, ClumpBody::rows). Empty when first > last. When
/// `decided` is false the row runs along one of a polyhedron's face planes (within round-off) and
/// the caller tests every point with the body's inside test instead.
struct RowRun {
    long first = 0;
    long last = -1;
    bool decided = true;
};

/// Width (in steps) of the band around each end of a row's exact interval where the inside test
/// decides instead of the interval: the interval's round-off is below 1e-8 steps for bodies up to
/// 100 sub-cells across (docs/theory/fluid.md, "Convex polyhedra: rows clipped by the faces"), so
/// points outside the bands get the same answer from both.
inline constexpr double kRowTie = 1e-6;

/// The sub-cells a in [lo, hi] of a row along world x (sub-cell size h, grid origin ox, m) whose
/// centres ox + (a + 1/2) h lie on the chord [cx - w, cx + w] (m): the rule of a sphere's rows,
/// also each clump member's.
inline RowRun chord_run(double cx, double w, double ox, double h, long lo, long hi) {
    const double a0 = std::ceil((cx - w - ox) / h - 0.5);
    const double a1 = std::floor((cx + w - ox) / h - 0.5);
    return {static_cast<long>(std::max(a0, static_cast<double>(lo))),
            static_cast<long>(std::min(a1, static_cast<double>(hi)))};
}

namespace detail {
/// The integer points of the exact interval [lo, hi] (within [0, n]) that `inside` accepts: the
/// interval decides the points farther than kRowTie from its ends, the inside test the others.
template <class Inside> RowRun settle_row(double lo, double hi, long n, const Inside& inside) {
    const auto len = static_cast<double>(n);
    RowRun r;
    r.first = std::max(0L, static_cast<long>(std::ceil(std::max(lo, -1.0) - kRowTie)));
    r.last = std::min(n, static_cast<long>(std::floor(std::min(hi, len + 1.0) + kRowTie)));
    if (r.first > r.last) {
        return r;
    }
    if (static_cast<double>(r.first) <= lo + kRowTie && !inside(r.first)) {
        ++r.first;
    }
    if (r.first <= r.last && static_cast<double>(r.last) >= hi - kRowTie && !inside(r.last)) {
        --r.last;
    }
    return r;
}
} // namespace detail

/// Sphere centred at the body origin; deposited by exact chord intervals, no per-sub-cell test.
struct SphereBody {
    double radius = 0.0; ///< radius (m)
};

/// Convex polyhedron as the intersection of half-spaces n . p <= d (body frame).
struct PlanesBody {
    std::vector<Vec3> normals;   ///< outward unit normals of the distinct face planes, body frame
    std::vector<double> offsets; ///< plane offsets d = n . (point on the face) (m)
    std::vector<Vec3> vertices;  ///< vertices (m, body frame), for the world bounding box
    /// True when the body-frame point p (m) lies inside or on the polyhedron.
    [[nodiscard]] bool contains(const Vec3& p) const {
        for (std::size_t f = 0; f < normals.size(); ++f) {
            if (normals[f].dot(p) > offsets[f]) {
                return false;
            }
        }
        return true;
    }
};

/// A polyhedron's face planes posed in the world for rows along world x with step h
/// (pose_planes): face f holds the world points p with n_f . p <= e_f.
struct PosedPlanes {
    std::vector<Vec3> normal;        ///< outward unit normals (world frame)
    std::vector<double> offset;      ///< e_f = n_f . x + d_f (m)
    std::vector<double> inv_rate;    ///< 1 / (h n_f,x) (1/m), 0 for a face parallel to the rows
    Mat3 to_body = Mat3::Identity(); ///< world -> body rotation (R^T)
    Vec3 centre = Vec3::Zero();      ///< body position x (m, world frame)
    Vec3 step = Vec3::Zero();        ///< one step along world x, in the body frame (m)
    double h = 0.0;                  ///< step (m)
};

/// Poses the polyhedron at x (m, world) with rotation matrix rot (body -> world) for rows along
/// world x with step h (m); `out`'s storage is reused.
void pose_planes(const PlanesBody& body, const Mat3& rot, const Vec3& x, double h,
                 PosedPlanes& out);

/// The row's world points start + t h e_x (t = 0..n) inside the posed polyhedron: the interval
/// that every face's half-space leaves, O(faces). Points within kRowTie steps of the interval's
/// ends are decided by `body.contains` at p0 + t step (p0 = R^T (start - x), body frame), so the
/// points are those `contains` accepts at p0 + t step. Not decided when the row lies along a face.
[[nodiscard]] RowRun clip_row(const PlanesBody& body, const PosedPlanes& posed, const Vec3& start,
                              long n);

/// Superquadric tested by its inside-outside function F < 0 (body frame).
struct SuperquadricBody {
    geometry::Superquadric shape; ///< half-axes and exponents, body frame
    /// True when the body-frame point p (m) lies inside the superquadric.
    [[nodiscard]] bool contains(const Vec3& p) const {
        const Vec3& a = shape.half_axes;
        if (std::abs(p.x()) > a.x() || std::abs(p.y()) > a.y() || std::abs(p.z()) > a.z()) {
            return false; // outside the box [-a, a]: skips the powers of F
        }
        return shape.inside_outside(p) < 0.0;
    }
};

/// Union of spheres (a clump), body frame.
struct ClumpBody {
    std::vector<geometry::ClumpSphere> spheres; ///< member spheres, body frame
    /// True when the body-frame point p (m) lies in at least one member sphere.
    [[nodiscard]] bool contains(const Vec3& p) const {
        for (const auto& s : spheres) {
            if ((p - s.centre).squaredNorm() <= s.radius * s.radius) {
                return true;
            }
        }
        return false;
    }
    /// The sub-cells of one grid row (along world x, at height y, z) inside the posed clump: the
    /// sub-cells a in [lo, hi] whose centres ox + (a + 1/2) h lie on a member's chord, the rule of
    /// the sphere path applied to each member; `centres` are the members' centres (m, world
    /// frame) in the order of `spheres`. Runs in increasing order, overlapping and adjacent ones
    /// merged; `out` is cleared first.
    void rows(std::span<const Vec3> centres, double ox, double h, double y, double z, long lo,
              long hi, std::vector<RowRun>& out) const;
};

/// A body as the deposition kernel sees it.
using DepositBody = std::variant<SphereBody, PlanesBody, SuperquadricBody, ClumpBody>;

/// A shape template prepared for deposition.
struct DepositTemplate {
    DepositBody body;    ///< inside test, body frame
    double volume = 0.0; ///< the template's true volume (m^3): deposited when no sub-cell fits
    double bounding_radius = 0.0; ///< radius of a centred sphere enclosing the body (m)
};

/// Prepares a template (any shape of geometry::Shape) for deposition; the volume is the
/// template's own (geometry::ShapeTemplate::volume).
[[nodiscard]] DepositTemplate make_deposit_template(const geometry::ShapeTemplate& t);

/// World-frame box [lo, hi] (m) bounding body `b` at position x (m, world) with rotation matrix
/// r (body -> world).
[[nodiscard]] Aabb world_box(const DepositBody& b, const Vec3& x, const Mat3& r);

} // namespace kiln::fluid
