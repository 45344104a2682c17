#pragma once
// Shape templates prepared for deposition on the transfer grid: the body-frame inside test of
// each shape kind in a form that is cheap to call once per sub-cell, and the world-frame box that
// bounds a posed body (the sub-cells scanned).

#include "core/types.hpp"
#include "geometry/clump.hpp"
#include "geometry/shape.hpp"
#include "geometry/superquadric.hpp"

#include <variant>
#include <vector>

namespace kiln::fluid {

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
