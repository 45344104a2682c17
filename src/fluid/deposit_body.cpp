#include "fluid/deposit_body.hpp"

#include "geometry/polyhedron_contact.hpp"

#include <cmath>
#include <limits>
#include <utility>

namespace kiln::fluid {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The polyhedron's planar faces (coplanar triangles merged, as the contact's features have
// them), so the inside test makes one comparison per face.
PlanesBody planes_of(const geometry::ConvexPolyhedron& p) {
    geometry::PolyhedronFeatures f = geometry::polyhedron_features(p);
    return PlanesBody{std::move(f.face_normals), std::move(f.face_offsets), std::move(f.vertices)};
}

struct BodyOf {
    DepositBody operator()(const geometry::Sphere& s) const { return SphereBody{s.radius}; }
    DepositBody operator()(const geometry::ConvexPolyhedron& p) const { return planes_of(p); }
    DepositBody operator()(const geometry::Superquadric& q) const { return SuperquadricBody{q}; }
    DepositBody operator()(const geometry::Clump& c) const { return ClumpBody{c.spheres}; }
};

} // namespace

DepositTemplate make_deposit_template(const geometry::ShapeTemplate& t) {
    return {std::visit(BodyOf{}, t.shape), t.volume, t.bounding_radius()};
}

Aabb world_box(const DepositBody& b, const Vec3& x, const Mat3& r) {
    struct Box {
        const Vec3& x;
        const Mat3& r;
        Aabb operator()(const SphereBody& s) const {
            return {x.array() - s.radius, x.array() + s.radius};
        }
        Aabb operator()(const SuperquadricBody& s) const {
            // The body box [-a, a] turned into the world: half extents |R| a.
            const Vec3 e = r.cwiseAbs() * s.shape.half_axes;
            return {x - e, x + e};
        }
        Aabb operator()(const PlanesBody& p) const {
            Aabb out{Vec3::Constant(kInf), Vec3::Constant(-kInf)};
            for (const Vec3& v : p.vertices) {
                const Vec3 w = r * v;
                out.lo = out.lo.cwiseMin(w);
                out.hi = out.hi.cwiseMax(w);
            }
            return {x + out.lo, x + out.hi};
        }
        Aabb operator()(const ClumpBody& c) const {
            Aabb out{Vec3::Constant(kInf), Vec3::Constant(-kInf)};
            for (const auto& s : c.spheres) {
                const Vec3 w = r * s.centre;
                out.lo = out.lo.cwiseMin(w - Vec3::Constant(s.radius));
                out.hi = out.hi.cwiseMax(w + Vec3::Constant(s.radius));
            }
            return {x + out.lo, x + out.hi};
        }
    };
    return std::visit(Box{x, r}, b);
}

} // namespace kiln::fluid
