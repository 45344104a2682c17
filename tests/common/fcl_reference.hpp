#pragma once
// FCL 0.7 as an independent reference for polyhedron contact (tests and validation 30): the
// polyhedron handed to FCL as a Convex shape, and FCL's penetration depth and normal by either of
// its two paths that report one.

#include "geometry/convex_contact.hpp"
#include "geometry/polyhedron.hpp"
#include "geometry/polyhedron_contact.hpp"

#include <fcl/geometry/shape/convex.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>
#include <fcl/narrowphase/distance.h>

#include <memory>
#include <vector>

namespace kiln::test {

/// FCL's convex shape of a polyhedron (body frame), lengths divided by `unit`: FCL's GJK/EPA
/// tolerances are absolute (1e-6), so a pair is handed to FCL in units of its size.
inline std::shared_ptr<fcl::Convexd> to_fcl(const geometry::ConvexPolyhedron& p, double unit) {
    auto v = std::make_shared<std::vector<fcl::Vector3d>>();
    for (const Vec3& x : p.vertices) {
        v->push_back(x / unit);
    }
    auto f = std::make_shared<std::vector<int>>();
    for (const auto& t : p.faces) {
        f->insert(f->end(), {3, t[0], t[1], t[2]});
    }
    return std::make_shared<fcl::Convexd>(v, static_cast<int>(p.faces.size()), f);
}

/// The two FCL paths that report a penetration depth for two Convex shapes.
enum class FclPath {
    kMpr,           ///< fcl::collide with GST_LIBCCD: libccd's MPR, an upper bound of the MTD
    kSignedDistance ///< fcl::distance with signed distance: FCL's GJK + EPA port, the MTD
};

/// FCL's penetration depth (m) and unit normal from B to A (world frame) for the posed
/// polyhedra a and b, whose FCL shapes sa and sb were built by to_fcl with the same `unit`;
/// `touching` is false when FCL finds no overlap. Only depth, normal and touching are set.
inline geometry::ConvexContact fcl_contact(const std::shared_ptr<fcl::Convexd>& sa,
                                           const geometry::PosedPolyhedron& a,
                                           const std::shared_ptr<fcl::Convexd>& sb,
                                           const geometry::PosedPolyhedron& b, double unit,
                                           FclPath path) {
    fcl::Transform3d ta = fcl::Transform3d::Identity();
    ta.linear() = a.q.toRotationMatrix();
    fcl::Transform3d tb = fcl::Transform3d::Identity();
    tb.linear() = b.q.toRotationMatrix();
    tb.translation() = (b.x - a.x) / unit;
    geometry::ConvexContact c;
    const fcl::CollisionObjectd oa(sa, ta);
    const fcl::CollisionObjectd ob(sb, tb);
    if (path == FclPath::kSignedDistance) {
        fcl::DistanceRequestd req(true);
        req.enable_signed_distance = true;
        req.gjk_solver_type = fcl::GST_LIBCCD;
        fcl::DistanceResultd res;
        fcl::distance(&oa, &ob, req, res);
        if (!(res.min_distance < 0.0)) {
            return c;
        }
        c.touching = true;
        c.depth = -res.min_distance * unit;
        c.normal = (res.nearest_points[1] - res.nearest_points[0]).normalized();
        return c;
    }
    fcl::CollisionRequestd req(1, true);
    req.gjk_solver_type = fcl::GST_LIBCCD;
    fcl::CollisionResultd res;
    fcl::collide(&oa, &ob, req, res);
    if (res.numContacts() == 0) {
        return c;
    }
    c.touching = true;
    c.depth = res.getContact(0).penetration_depth * unit;
    c.normal = -res.getContact(0).normal.normalized(); // FCL's normal points from A to B
    return c;
}

} // namespace kiln::test
