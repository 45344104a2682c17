// Adapter to libccd (GJK + EPA and MPR on support maps); the only kiln file including libccd.
// Coordinates are shifted to the midpoint of the centres and scaled by the sum of the largest
// half-axes, so libccd's absolute tolerances become relative ones.

#include "geometry/convex_contact.hpp"
#include "geometry/polyhedron_contact.hpp"

#include <ccd/ccd.h>

namespace kiln::geometry {

namespace {

/// What libccd's callbacks see: one body and the scaling of the query.
struct CcdBody {
    const PosedSuperquadric* body;
    Vec3 origin;
    double scale;
};

void ccd_support(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
    const auto* b = static_cast<const CcdBody*>(obj);
    const Vec3 d(dir->v[0], dir->v[1], dir->v[2]);
    const Vec3 s = (b->body->support(d) - b->origin) / b->scale;
    out->v[0] = s.x();
    out->v[1] = s.y();
    out->v[2] = s.z();
}

void ccd_centre(const void* obj, ccd_vec3_t* c) {
    const auto* b = static_cast<const CcdBody*>(obj);
    const Vec3 s = (b->body->x - b->origin) / b->scale;
    c->v[0] = s.x();
    c->v[1] = s.y();
    c->v[2] = s.z();
}

constexpr unsigned long kMaxIterations = 1000; // GJK and MPR iterations before giving up
// libccd compares the EPA tolerance with squared distances in part of its test (nextSupport in
// ccd.c 2.x), so 1e-10 means about 1e-5 of the length scale. Smaller values made libccd's EPA
// loop forever on some superquadric pairs (it has no iteration limit); 1e-10 ran 2000 random
// pairs in 0.3 s. MPR and GJK use lengths.
constexpr double kEpaTolerance = 1e-10;
constexpr double kTolerance = 1e-10; // relative to the sum of the largest half-axes

} // namespace

ConvexContact ccd_contact(const PosedSuperquadric& a, const PosedSuperquadric& b, bool use_mpr) {
    const double scale = a.length_scale() + b.length_scale();
    const Vec3 origin = 0.5 * (a.x + b.x);
    const CcdBody ca{&a, origin, scale};
    const CcdBody cb{&b, origin, scale};
    ccd_t ccd;
    CCD_INIT(&ccd);
    ccd.support1 = ccd_support;
    ccd.support2 = ccd_support;
    ccd.center1 = ccd_centre;
    ccd.center2 = ccd_centre;
    ccd.max_iterations = kMaxIterations;
    ccd.epa_tolerance = kEpaTolerance;
    ccd.mpr_tolerance = kTolerance;
    ccd.dist_tolerance = kTolerance;
    ccd_real_t depth = 0;
    ccd_vec3_t dir;
    ccd_vec3_t pos;
    const int rc = use_mpr ? ccdMPRPenetration(&ca, &cb, &ccd, &depth, &dir, &pos)
                           : ccdGJKPenetration(&ca, &cb, &ccd, &depth, &dir, &pos);
    ConvexContact c;
    if (rc == -1) {
        c.touching = false;
        return c;
    }
    if (rc != 0) {
        c.converged = false;
        return c;
    }
    c.touching = true;
    c.depth = depth * scale;
    // libccd's dir moves B out of A, i.e. points from A to B.
    c.normal = -Vec3(dir.v[0], dir.v[1], dir.v[2]).normalized();
    c.point = 0.5 * (a.support(-c.normal) + b.support(c.normal));
    return c;
}

// Convex polyhedra: the same queries on the vertex support maps, shifted to the midpoint of the
// centres and scaled by the sum of the bounding radii.
namespace {

struct CcdPolyhedron {
    const PosedPolyhedron* body;
    Vec3 origin;
    double scale;
};

void ccd_poly_support(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
    const auto* b = static_cast<const CcdPolyhedron*>(obj);
    const Vec3 d(dir->v[0], dir->v[1], dir->v[2]);
    const Vec3 s = (b->body->support(d) - b->origin) / b->scale;
    out->v[0] = s.x();
    out->v[1] = s.y();
    out->v[2] = s.z();
}

void ccd_poly_centre(const void* obj, ccd_vec3_t* c) {
    const auto* b = static_cast<const CcdPolyhedron*>(obj);
    const Vec3 s = (b->body->x - b->origin) / b->scale;
    c->v[0] = s.x();
    c->v[1] = s.y();
    c->v[2] = s.z();
}

} // namespace

ConvexContact ccd_contact(const PosedPolyhedron& a, const PosedPolyhedron& b, bool use_mpr) {
    const double scale = a.length_scale() + b.length_scale();
    const Vec3 origin = 0.5 * (a.x + b.x);
    const CcdPolyhedron ca{&a, origin, scale};
    const CcdPolyhedron cb{&b, origin, scale};
    ccd_t ccd;
    CCD_INIT(&ccd);
    ccd.support1 = ccd_poly_support;
    ccd.support2 = ccd_poly_support;
    ccd.center1 = ccd_poly_centre;
    ccd.center2 = ccd_poly_centre;
    ccd.max_iterations = kMaxIterations;
    ccd.epa_tolerance = kEpaTolerance;
    ccd.mpr_tolerance = kTolerance;
    ccd.dist_tolerance = kTolerance;
    ccd_real_t depth = 0;
    ccd_vec3_t dir;
    ccd_vec3_t pos;
    const int rc = use_mpr ? ccdMPRPenetration(&ca, &cb, &ccd, &depth, &dir, &pos)
                           : ccdGJKPenetration(&ca, &cb, &ccd, &depth, &dir, &pos);
    ConvexContact c;
    if (rc == -1) {
        return c;
    }
    if (rc != 0) {
        c.converged = false;
        return c;
    }
    c.touching = true;
    c.depth = depth * scale;
    c.normal = -Vec3(dir.v[0], dir.v[1], dir.v[2]).normalized(); // libccd's dir points from A to B
    c.point = 0.5 * (a.support(-c.normal) + b.support(c.normal));
    return c;
}

} // namespace kiln::geometry
