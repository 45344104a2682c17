// Adapter to libccd (GJK + EPA and MPR on support maps); the only kiln file including libccd.
// Coordinates are shifted to an origin near the contact and scaled by a length of the bodies, so
// libccd's absolute tolerances become relative ones. One template serves every pair of posed
// shapes with a world-frame `support(d)` and a centre `x`.

#include "geometry/convex_contact.hpp"
#include "geometry/polyhedron_contact.hpp"
#include "geometry/separating_axis.hpp"

#include <ccd/ccd.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace kiln::geometry {

namespace {

/// Support calls of one query, shared by both bodies' callbacks.
struct SupportBudget {
    long calls = 0; ///< support points asked for so far (both bodies)
    bool spent() const;
};

/// What libccd's callbacks see: one body, the shift and scaling of the query and its budget.
template <class Body> struct CcdBody {
    const Body* body;
    Vec3 origin;
    double scale;
    SupportBudget* budget;
};

/// Most support points one query may ask for. libccd 2.x's EPA expands its polytope in a loop
/// without an iteration limit (danfis/libccd issue #7), and for some touching pairs (a cube and an
/// ellipsoid in cases/hot_shapes, kept as a test) it cycles for ever without meeting
/// epa_tolerance, each turn slower as the polytope grows. The converging queries of the unit tests
/// (thousands of random pairs of every kind) all stay below this budget. Past it both bodies
/// answer the origin, so the Minkowski support has no extent along any direction: EPA's next step
/// cannot expand (nextSupport sees no progress) and it stops, as MPR stops refining. The query
/// then reports not converged (the caller falls back to MPR or counts a failure).
constexpr long kSupportBudget = 2500;

bool SupportBudget::spent() const {
    return calls > kSupportBudget;
}

template <class Body> void ccd_support(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
    const auto* b = static_cast<const CcdBody<Body>*>(obj);
    if (++b->budget->calls > kSupportBudget) {
        out->v[0] = out->v[1] = out->v[2] = 0.0;
        return;
    }
    const Vec3 d(dir->v[0], dir->v[1], dir->v[2]);
    const Vec3 s = (b->body->support(d) - b->origin) / b->scale;
    out->v[0] = s.x();
    out->v[1] = s.y();
    out->v[2] = s.z();
}

template <class Body> void ccd_centre(const void* obj, ccd_vec3_t* c) {
    const auto* b = static_cast<const CcdBody<Body>*>(obj);
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
constexpr double kTolerance = 1e-10; // relative to the length scale of the query

/// GJK + EPA (use_mpr = false) or MPR of bodies a and b in coordinates (x - origin) / scale.
/// Normal from b to a, world frame; the point is the midpoint of the deepest points along it.
template <class A, class B>
ConvexContact query(const A& a, const B& b, const Vec3& origin, double scale, bool use_mpr,
                    double epa_tolerance = kEpaTolerance) {
    SupportBudget budget;
    const CcdBody<A> ca{&a, origin, scale, &budget};
    const CcdBody<B> cb{&b, origin, scale, &budget};
    ccd_t ccd;
    CCD_INIT(&ccd);
    ccd.support1 = ccd_support<A>;
    ccd.support2 = ccd_support<B>;
    ccd.center1 = ccd_centre<A>;
    ccd.center2 = ccd_centre<B>;
    ccd.max_iterations = kMaxIterations;
    ccd.epa_tolerance = epa_tolerance;
    ccd.mpr_tolerance = kTolerance;
    ccd.dist_tolerance = kTolerance;
    ccd_real_t depth = 0;
    ccd_vec3_t dir;
    ccd_vec3_t pos;
    const int rc = use_mpr ? ccdMPRPenetration(&ca, &cb, &ccd, &depth, &dir, &pos)
                           : ccdGJKPenetration(&ca, &cb, &ccd, &depth, &dir, &pos);
    ConvexContact c;
    if (budget.spent()) {
        c.converged = false; // stopped by the support budget: the answer is not trusted
        return c;
    }
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
    // The normal's orientation is checked. On a pair that touches only to within libccd's
    // tolerance (the origin on the boundary of the Minkowski difference) EPA returns, with a depth
    // of the tolerance's size, a normal that need not be the contact's: on pairs placed at GJK's
    // boundary it was reversed in 65-84 % of pairs of polyhedra and 18-66 % of pairs with a
    // superquadric. Along a reversed normal the overlap is the size of the bodies, and a caller
    // that measures the overlap along it (the polyhedron-superquadric contact, the patch of two
    // polyhedra) got a force that set a bed spinning (docs/performance.md, "The atlas"). The true
    // normal makes the overlap along it the smallest over all directions (the depth), so an
    // answer with a smaller overlap along its reverse is repaired: MPR decides whether the bodies
    // touch, and the normal is the one of EPA's reverse, MPR's normal and its reverse with the
    // smallest overlap along it, measured exactly (the depth reported, an upper bound of the true
    // depth, where EPA's own is a lower bound). On the grazing prisms of the atlas MPR's normal
    // was the contact's. Two polyhedra take the exact common plane instead (body_contact.cpp).
    const double plus = overlap_along(a, b, c.normal);
    const double minus = overlap_along(a, b, Vec3(-c.normal));
    // (Also when either is not a number: at GJK's very boundary libccd's direction can be NaN,
    // seen in a sanitizer build; that answer is repaired the same way or reported as failed.)
    if (!(plus <= minus)) {
        c.repaired = true;
        const auto not_touching = [&c](bool converged) {
            c.converged = converged;
            c.touching = false;
            c.depth = 0.0;
            return c;
        };
        const ConvexContact m = use_mpr ? c : query(a, b, origin, scale, true, epa_tolerance);
        if (!m.converged || !m.touching) {
            return not_touching(m.converged);
        }
        Vec3 best = -c.normal;
        c.depth = std::isfinite(minus) ? minus : std::numeric_limits<double>::infinity();
        for (const Vec3& n : {m.normal, Vec3(-m.normal)}) {
            const double along = overlap_along(a, b, n);
            if (along < c.depth) {
                c.depth = along;
                best = n;
            }
        }
        if (!std::isfinite(c.depth)) {
            return not_touching(false); // no direction with a finite overlap
        }
        c.normal = best;
        if (!(c.depth > 0.0)) {
            return not_touching(true); // the direction kept separates them
        }
    }
    c.point = 0.5 * (a.support(-c.normal) + b.support(c.normal));
    return c;
}

/// Shift to the midpoint of the centres, scale by the sum of the length scales.
template <class A, class B>
ConvexContact centred_query(const A& a, const B& b, bool use_mpr,
                            double epa_tolerance = kEpaTolerance) {
    return query(a, b, 0.5 * (a.x + b.x), a.length_scale() + b.length_scale(), use_mpr,
                 epa_tolerance);
}

} // namespace

ConvexContact ccd_contact(const PosedSuperquadric& a, const PosedSuperquadric& b, bool use_mpr) {
    return centred_query(a, b, use_mpr);
}

ConvexContact ccd_contact(const PosedPolyhedron& a, const PosedPolyhedron& b, bool use_mpr) {
    return centred_query(a, b, use_mpr, kPolytopeEpaTolerance);
}

ConvexContact ccd_contact(const PosedPolyhedron& a, const PosedSuperquadric& b, bool use_mpr) {
    return centred_query(a, b, use_mpr);
}

ConvexContact ccd_contact(const PosedSuperquadric& a, const SupportTriangle& b, bool use_mpr) {
    // A wall triangle may be much larger than the particle: the particle sets origin and scale.
    return query(a, b, a.x, 2.0 * a.length_scale(), use_mpr);
}

} // namespace kiln::geometry
