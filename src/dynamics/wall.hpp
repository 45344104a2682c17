#pragma once
// Analytic walls. A wall is a geometric shape plus a material; sphere-wall contacts use the same
// contact laws as sphere-sphere contacts with the wall as body j (infinite mass, at rest).

#include "core/types.hpp"
#include "geometry/mesh_wall.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <variant>

namespace kiln::dynamics {

/// Infinite plane; particles live on the side the normal points to.
struct PlaneWall {
    Vec3 point = Vec3::Zero();   ///< a point on the plane (m, world)
    Vec3 normal = Vec3::UnitZ(); ///< unit normal pointing into the domain (world)
};

/// Infinite circular cylinder; particles live inside it.
struct CylinderWall {
    Vec3 axis_point = Vec3::Zero(); ///< a point on the axis (m, world)
    Vec3 axis = Vec3::UnitZ();      ///< unit axis direction (world)
    double radius = 0;              ///< inner radius (m)
};

using WallShape = std::variant<PlaneWall, CylinderWall>;

/// A wall of the scene.
struct Wall {
    std::string name; ///< label used in output and messages
    WallShape shape;  ///< geometry
    int material = 0; ///< material index
};

/// A triangle-mesh wall of the scene (world frame). Its contacts with every particle go through
/// the body path (System::body_forces), with tangential history keyed by the mesh feature.
struct MeshWallSpec {
    std::string name;                               ///< label used in output and messages
    std::shared_ptr<const geometry::MeshWall> mesh; ///< triangles, world frame
    int material = 0;                               ///< material index
};

/// Sphere-wall contact geometry, world frame.
struct WallContact {
    Vec3 n;         ///< unit normal from the wall to the sphere centre
    double overlap; ///< delta (m), > 0 when touching
    double r_eff;   ///< effective radius of curvature R* (m)
};

/// Contact of a sphere (centre x, radius r) with a plane. Returns overlap <= 0 when apart.
inline WallContact wall_contact(const PlaneWall& w, const Vec3& x, double r) {
    const double d = (x - w.point).dot(w.normal);
    return {w.normal, r - d, r};
}

/// Contact of a sphere inside a cylinder. R*: the Hertz equivalent radius of the relative
/// curvatures 1/r along the axis and 1/r - 1/R_cyl around it (the wall is concave around only),
/// R* = 1/sqrt(k1 k2) = r / sqrt(1 - r/R_cyl) (Johnson 1985, Contact Mechanics, Sec. 4.2: R_e =
/// sqrt(R' R'')); the smaller relative curvature is kept at or above 1/(2r), as the body rule
/// does for a superquadric (docs/theory/contact.md, "Walls").
inline WallContact wall_contact(const CylinderWall& w, const Vec3& x, double r) {
    Vec3 rho = x - w.axis_point;
    rho -= rho.dot(w.axis) * w.axis;
    const double dist = rho.norm();
    if (dist < 1e-300) {
        return {Vec3::UnitX(), -1.0, r};
    }
    const double gap = w.radius - dist;
    const double r_eff = r / std::sqrt(std::max(1.0 - r / w.radius, 0.5));
    return {-rho / dist, r - gap, r_eff};
}

} // namespace kiln::dynamics
