// Element geometry of bodies: see body_contact.hpp and docs/theory/contact.md ("Non-spherical
// contacts").

#include "dynamics/body_contact.hpp"

#include "geometry/depth_refinement.hpp"
#include "geometry/rotation.hpp"
#include "geometry/separating_axis.hpp"

#if defined(__AVX512F__)
#include <immintrin.h>
#endif
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <type_traits>
#include <utility>

namespace kiln::dynamics {

namespace {

// Effective radius of a contact with a convex element. From the relative principal curvatures
// k1 <= k2 (contact_curvature), R* = 1 / sqrt(k1 k2) (Johnson 1985, Sec. 4.2). A flat face gives
// k = 0 and an edge k1 = 0 (R* infinite), a tip k -> infinity (R* -> 0); either would make the
// Hertz stiffness 4/3 E* sqrt(R* delta) useless. So each curvature is raised to at least 1/L, L
// the larger bounding radius of the two elements (a face on a face: R* = L; an edge of rounding
// radius r on a face: R* = sqrt(L r)), and R* is kept at or above kRadiusFloor times the smaller
// element size (a sharp tip).
constexpr double kRadiusFloor = 0.05;

/// A sphere element as a superquadric (exponents 1: the exact sphere), for the support-map methods.
struct SphereAsSuperquadric {
    geometry::Superquadric sq;
    explicit SphereAsSuperquadric(double r) {
        sq.half_axes = Vec3::Constant(r);
        sq.e1 = 1.0;
        sq.e2 = 1.0;
    }
};

double effective_radius(double k1, double k2, const Element& a, const Element* b) {
    const double lo = kRadiusFloor * std::min(a.min_size, b ? b->min_size : a.min_size);
    const double kmin = 1.0 / std::max(a.radius, b ? b->radius : a.radius);
    const double r = 1.0 / std::sqrt(std::max(k1, kmin) * std::max(k2, kmin));
    return std::isfinite(r) ? std::max(r, lo) : lo; // infinite curvature: a tip
}

/// Eigenvalues (smaller first) of the symmetric 2x2 matrix [[k11, k12], [k12, k22]].
std::array<double, 2> eigen2(double k11, double k22, double k12) {
    const double mean = 0.5 * (k11 + k22);
    const double diff = std::sqrt(0.25 * (k11 - k22) * (k11 - k22) + k12 * k12);
    return {mean - diff, mean + diff};
}

/// Effective radius of a superquadric element touching the inside of a cylinder wall of radius
/// `wall_radius` and unit axis `axis` (world) at the body point p_body (body frame); n is the
/// contact normal (world, from the wall into the body). The wall is concave, with curvature
/// 1/R_wall around its circumference t = axis x n and none along its axis; a concave surface counts
/// negative in the relative curvature (Johnson 1985, Sec. 4.1: the gap is 1/2 x^T (K_1 + K_2) x),
/// so the relative tensor in the tangent plane is K_body - t t^T / R_wall and R* = 1/sqrt(k1 k2)
/// of its eigenvalues. The body's principal curvatures are first raised to at least 1/L, as on a
/// plane (effective_radius), so a flat face inside a cylinder gets k = 1/L along the axis and
/// about 1/L - 1/R_wall around it; relative curvatures are kept at or above 1/(2L) (a wall
/// narrower than the particle's diameter would otherwise give a conforming, infinite R*).
double concave_wall_radius(const Element& a, const Vec3& p_body, const Vec3& n, const Vec3& axis,
                           double wall_radius) {
    const Mat3 r = a.q.toRotationMatrix();
    const Mat3 k = r * a.sq->curvature_tensor(p_body) * r.transpose();
    if (!k.allFinite()) { // a tip: R* at its floor, wall or not
        const auto kp = a.sq->principal_curvatures(p_body);
        return effective_radius(kp[0], kp[1], a, nullptr);
    }
    const Vec3 e1 = n.unitOrthogonal();
    const Vec3 e2 = n.cross(e1);
    const double k11 = e1.dot(k * e1);
    const double k22 = e2.dot(k * e2);
    const double k12 = 0.5 * (e1.dot(k * e2) + e2.dot(k * e1));
    // Body tensor in the (e1, e2) basis with its eigenvalues floored at 1/L: rebuild from the
    // eigen-decomposition (the eigenvector of the smaller eigenvalue is (k12, lo - k11)).
    const double kmin = 1.0 / a.radius;
    const auto ev = eigen2(k11, k22, k12);
    Vec3 u(k12, ev[0] - k11, 0.0); // (e1, e2) coordinates; third component unused
    if (u.head<2>().squaredNorm() < 1e-30 * (k11 * k11 + k22 * k22 + 1.0)) {
        u = k11 <= k22 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
    }
    u.normalize();
    const double l0 = std::max(ev[0], kmin);
    const double l1 = std::max(ev[1], kmin);
    // K = l0 u u^T + l1 v v^T with v perpendicular to u in the plane.
    const double b11 = l0 * u.x() * u.x() + l1 * u.y() * u.y();
    const double b22 = l0 * u.y() * u.y() + l1 * u.x() * u.x();
    const double b12 = (l0 - l1) * u.x() * u.y();
    // Circumferential direction of the wall at the contact, in the same basis.
    Vec3 t = axis.cross(n);
    const double tn = t.norm();
    t = tn > 0.0 ? Vec3(t / tn) : Vec3::Zero();
    const double t1 = t.dot(e1);
    const double t2 = t.dot(e2);
    const auto rel = eigen2(b11 - t1 * t1 / wall_radius, b22 - t2 * t2 / wall_radius,
                            b12 - t1 * t2 / wall_radius);
    const double floor = 0.5 * kmin;
    const double lo = kRadiusFloor * a.min_size;
    return std::max(1.0 / std::sqrt(std::max(rel[0], floor) * std::max(rel[1], floor)), lo);
}

/// Margin of a separation proof, relative to the sum of the bounding radii (-): a cached or
/// searched direction skips the narrow phase only if the gap along it exceeds this, far above the
/// round-off of the support evaluations and of the exact queries (1e-16 relative), so a pair
/// skipped is one they would find apart too.
constexpr double kSeparationMargin = 1e-10;

/// Is the pair (posed a, b; bounding radii sum `rsum`, m) apart along the cached direction `sep`
/// (unit, from b to a, world frame; zero: none) by more than the margin?
template <class A, class B>
bool cached_apart(const A& a, const B& b, double rsum, const Vec3* sep) {
    return sep != nullptr && sep->squaredNorm() > 0.0 &&
           geometry::overlap_along(a, b, *sep) < -kSeparationMargin * rsum;
}

/// Exponent below which a superquadric counts as blocky for the separation gate (-).
constexpr double kBlocky = 0.5;

bool blocky(const Element& e) {
    return e.sq != nullptr && std::min(e.sq->e1, e.sq->e2) < kBlocky;
}

/// Overlap of a and b along the unit normal n (from b to a), from the analytic supports: the
/// distance between b's farthest point along n and a's farthest point along -n (m).
double depth_along(const geometry::PosedSuperquadric& a, const geometry::PosedSuperquadric& b,
                   const Vec3& n) {
    return n.dot(b.support(n)) - n.dot(a.support(-n));
}

ElementContact sphere_sphere(const Element& a, const Element& b) {
    ElementContact c;
    const Vec3 d = a.centre - b.centre;
    const double dist2 = d.squaredNorm();
    const double rsum = a.radius + b.radius;
    if (dist2 >= rsum * rsum || dist2 == 0.0) {
        return c;
    }
    const double dist = std::sqrt(dist2);
    c.touching = true;
    c.overlap = rsum - dist;
    c.normal = d / dist;
    c.point = b.centre + (b.radius - 0.5 * c.overlap) * c.normal;
    c.r_eff = a.radius * b.radius / rsum;
    return c;
}

/// Closest point of triangle (a, b, c) to p (Ericson 2005, Real-Time Collision Detection,
/// Sec. 5.1.5; any frame).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ab = b - a;
    const Vec3 ac = c - a;
    const Vec3 ap = p - a;
    const double d1 = ab.dot(ap);
    const double d2 = ac.dot(ap);
    if (d1 <= 0.0 && d2 <= 0.0) {
        return a;
    }
    const Vec3 bp = p - b;
    const double d3 = ab.dot(bp);
    const double d4 = ac.dot(bp);
    if (d3 >= 0.0 && d4 <= d3) {
        return b;
    }
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        return a + d1 / (d1 - d3) * ab;
    }
    const Vec3 cp = p - c;
    const double d5 = ab.dot(cp);
    const double d6 = ac.dot(cp);
    if (d6 >= 0.0 && d5 <= d6) {
        return c;
    }
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        return a + d2 / (d2 - d6) * ac;
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
        return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
    }
    const double denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

/// Sphere element s against polyhedron element p, exact: the closest point of p's surface to the
/// sphere centre (centre outside), or the nearest face plane (centre inside). Normal from p to s.
/// The polyhedron counts as flat at the contact, so R* is the sphere radius.
ElementContact sphere_polyhedron(const Element& s, const Element& p) {
    ElementContact out;
    const geometry::PolyhedronFeatures& f = *p.poly;
    const Vec3 c = p.q.conjugate() * (s.centre - p.centre); // sphere centre, body frame of p
    double smax = -std::numeric_limits<double>::infinity();
    std::size_t fmax = 0;
    for (std::size_t k = 0; k < f.face_normals.size(); ++k) {
        const double d = f.face_normals[k].dot(c) - f.face_offsets[k];
        if (d > smax) {
            smax = d;
            fmax = k;
        }
    }
    if (smax >= s.radius) {
        return out; // a face plane separates them
    }
    Vec3 n_body = Vec3::UnitZ();
    Vec3 surface = c;
    double dist = 0.0;
    if (smax <= 0.0) {
        n_body = f.face_normals[fmax];
        surface = c - smax * n_body;
        dist = smax;
    } else {
        double best = std::numeric_limits<double>::infinity();
        const auto& v = p.hull->vertices;
        for (const auto& t : p.hull->faces) {
            const Vec3 q = closest_on_triangle(c, v[static_cast<std::size_t>(t[0])],
                                               v[static_cast<std::size_t>(t[1])],
                                               v[static_cast<std::size_t>(t[2])]);
            const double d2 = (c - q).squaredNorm();
            if (d2 < best) {
                best = d2;
                surface = q;
            }
        }
        dist = std::sqrt(best);
        if (dist >= s.radius || dist <= 0.0) {
            return out;
        }
        n_body = (c - surface) / dist;
    }
    out.touching = true;
    out.overlap = s.radius - dist;
    out.normal = p.q * n_body;
    const Vec3 surface_w = p.centre + p.q * surface;
    out.point = 0.5 * (surface_w + s.centre - s.radius * out.normal);
    out.r_eff = s.radius;
    return out;
}

/// Depth band, as a fraction of the overlap, within which vertices share the contact point.
constexpr double kTieBand = 0.02;

/// Vertices of p (world) within kTieBand * overlap of its support along d, with the weights
/// w = 1 - (h_max - h_v) / band (> 0 only), appended to `out` (cleared first).
void near_support(const geometry::PosedPolyhedron& p, const Vec3& d, double overlap,
                  geometry::NearVertices& out) {
    // In the body frame (d . x = d . p.x + d_body . v): one rotation of d instead of one per
    // vertex; only the vertices in the band are turned to the world frame (band_vertices, the
    // rule the common plane's own lists follow).
    const Vec3 db = p.q.conjugate() * d;
    const std::vector<Vec3>& vs = p.shape->vertices;
    thread_local std::vector<double> h;
    h.resize(vs.size());
    double top = -std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < vs.size(); ++i) {
        h[i] = db.dot(vs[i]);
        top = std::max(top, h[i]);
    }
    geometry::band_vertices(p, h.data(), top, 1.0, kTieBand * overlap, out);
}

/// Contact point of two polyhedra with overlap delta along the unit normal m (from b to a): a
/// point of the line, along m, through the point where the gradient of the overlap
/// h_a(-m) + h_b(m) acts (Danskin), so the pair force is conservative and, being applied at one
/// point for both bodies, keeps the angular momentum. A vertex of a against a face of b: that
/// vertex; a vertex of b: that vertex; two crossing edges: the closest points of the edges. The
/// point is put half way through the overlap. An edge lying on a face: the band-weighted average
/// of its two vertices (continuous into the single vertex as it tilts). Parallel faces keep the
/// patch centroid `patch_point`: the overlap is not differentiable there.
/// `va`, `vb`: near_support of a along -m and of b along m.
Vec3 pair_point(const geometry::NearVertices& va, const geometry::NearVertices& vb, const Vec3& m,
                double delta, const Vec3& patch_point) {
    const auto average = [](const geometry::NearVertices& v) {
        Vec3 sum = Vec3::Zero();
        double wsum = 0.0;
        for (const auto& [x, w] : v) {
            sum += w * x;
            wsum += w;
        }
        return Vec3(sum / wsum);
    };
    if (va.size() == 1) {
        return va[0].first + 0.5 * delta * m;
    }
    if (vb.size() == 1) {
        return vb[0].first - 0.5 * delta * m;
    }
    if (va.size() == 2 && vb.size() == 2) {
        // Two edges: the closest points of the segments (Ericson 2005, Sec. 5.1.9, without the
        // parallel case: parallel edges keep the weighted averages).
        const Vec3 p1 = va[0].first;
        const Vec3 d1 = va[1].first - p1;
        const Vec3 p2 = vb[0].first;
        const Vec3 d2 = vb[1].first - p2;
        const Vec3 r = p1 - p2;
        const double aa = d1.squaredNorm();
        const double ee = d2.squaredNorm();
        const double bb = d1.dot(d2);
        const double denom = aa * ee - bb * bb;
        if (denom > 1e-12 * aa * ee) {
            const double c = d1.dot(r);
            const double f = d2.dot(r);
            const double s = std::clamp((bb * f - c * ee) / denom, 0.0, 1.0);
            const double t = std::clamp((bb * s + f) / ee, 0.0, 1.0);
            const double s2 = std::clamp((bb * t - c) / aa, 0.0, 1.0);
            return 0.5 * (p1 + s2 * d1 + p2 + t * d2);
        }
        return 0.5 * (average(va) + average(vb));
    }
    // An edge lying on a face: its weighted vertices, which turn continuously into the single
    // vertex when the edge tilts out of the band.
    if (va.size() == 2) {
        return average(va) + 0.5 * delta * m;
    }
    if (vb.size() == 2) {
        return average(vb) - 0.5 * delta * m;
    }
    return patch_point;
}

/// As above, the vertices near the supports found here.
Vec3 pair_point(const geometry::PosedPolyhedron& a, const geometry::PosedPolyhedron& b,
                const Vec3& m, double delta, const Vec3& patch_point) {
    thread_local geometry::NearVertices va;
    thread_local geometry::NearVertices vb;
    near_support(a, -m, delta, va);
    near_support(b, m, delta, vb);
    return pair_point(va, vb, m, delta, patch_point);
}

/// Does pair_point read the patch centroid, given its near_support lists? Only when at least
/// three vertices of each body lie within the band (two faces parallel within the band);
/// otherwise it takes vertices or edges and the patch goes unread.
bool pair_point_needs_patch(const geometry::NearVertices& va, const geometry::NearVertices& vb) {
    return va.size() >= 3 && vb.size() >= 3;
}

/// Hertz radius of two polyhedra: the volume-equivalent spheres in series.
double polyhedron_pair_radius(const Element& a, const Element& b) {
    return a.r_equiv * b.r_equiv / (a.r_equiv + b.r_equiv);
}

/// Two polyhedron elements: fast common plane (default) or libccd GJK/EPA with the common-plane
/// patch along EPA's normal (the common plane when EPA fails or its normal points the wrong
/// way). Normal from b to a; point: pair_point. `touched_last`, `memo`: see
/// element_contact.
ElementContact polyhedron_pair(const Element& a, const Element& b, NarrowPhase method, Vec3* sep,
                               bool touched_last, geometry::PlaneMemo* memo) {
    ElementContact out;
    const geometry::PosedPolyhedron pa{a.poly, a.centre, a.q};
    const geometry::PosedPolyhedron pb{b.poly, b.centre, b.q};
    // Separating-axis shortcuts: last step's separating direction, then the line of centres (two
    // support evaluations each). A pair that touched at the last step almost always touches
    // again, so it goes straight to the exact query, which finds a pair apart too.
    // The cached direction's gap from heights alone (polyhedron_overlap_along): equal to the
    // support points' form to round-off, far below the margin, so the same pairs are proved apart.
    if (sep != nullptr && sep->squaredNorm() > 0.0 && polyhedra_apart_along(a, b, *sep)) {
        out.proved_apart = true;
        return out;
    }
    const Vec3 line = a.centre - b.centre;
    if (!touched_last && line.squaredNorm() > 0.0) {
        const Vec3 m = line.normalized();
        if (m.dot(pb.support(m)) - m.dot(pa.support(-m)) < 0.0) {
            if (sep != nullptr) {
                *sep = m;
            }
            return out;
        }
    }
    if (sep != nullptr) {
        sep->setZero();
    }
    geometry::PolyhedronContact pc;
    thread_local geometry::NearVertices va;
    thread_local geometry::NearVertices vb;
    bool near_known = false;                     // va, vb hold the near supports of pc's plane
    bool exact = method != NarrowPhase::gjk_epa; // the fast common plane answers
    if (!exact) {
        const geometry::ConvexContact cc = geometry::ccd_contact(pa, pb, false);
        if (cc.converged && !cc.repaired && !cc.touching) {
            return out; // apart by GJK
        }
        // EPA's answer is kept only when it is consistent: not repaired (ccd_adapter.cpp repairs
        // libccd's reversed normals on pairs touching within its tolerance), and the overlap along
        // its normal within 1e-6 of the length scale of EPA's depth (EPA's polytope lies inside
        // the Minkowski difference, so its depth is a lower bound of the overlap along any
        // direction; kPolytopeEpaTolerance bounds the excess by about 1e-7 of the scale, more for
        // contacts shallower than ~1e-8 of it). Along a reversed normal the overlap was the size
        // of the bodies, a force that set a bed of 16-edged prisms spinning (docs/performance.md,
        // "The atlas"; test Polyhedra.GjkEpaWithItsNormalReversedFallsBackToTheCommonPlane). Any
        // other answer, and a query that did not converge, go to the exact common plane (counted
        // as a fallback).
        exact = !cc.converged || cc.repaired;
        if (!exact) {
            pc = geometry::contact_patch_along(pa, pb, cc.normal);
            exact = pc.depth > cc.depth + 1e-6 * (pa.shape->radius + pb.shape->radius);
        }
        out.fell_back = exact;
    }
    if (exact) {
        // The patch only where pair_point reads it (face on face): the same numbers as with it.
        // The near supports come from the plane's own heights (geometry::NearBand), filled before
        // the test for a touching pair. One pointer captured, so the std::function keeps the
        // test in its own storage (a capture of five references took a heap allocation per
        // query).
        const geometry::NearBand band{kTieBand, &va, &vb};
        const geometry::PatchTest need = [known =
                                              &near_known](const geometry::PolyhedronContact& c) {
            if (!c.touching) {
                return false;
            }
            *known = true;
            if (va.size() == 1) { // a vertex of a: pair_point reads neither b's list nor
                vb.clear();       // the patch
                return false;
            }
            return pair_point_needs_patch(va, vb);
        };
        // Only the point is read here: the points and the patch polygon are not built.
        pc = geometry::polyhedron_contact_point(pa, pb, need, memo, &band);
        out.converged = pc.converged;
        if (pc.converged && !pc.touching && pc.depth < 0.0 && sep != nullptr) {
            *sep = pc.normal; // the common plane of the largest gap
        }
        if (!pc.converged || !pc.touching) {
            return out;
        }
    }
    if (!(pc.depth > 0.0)) {
        return out;
    }
    out.touching = true;
    out.overlap = pc.depth;
    out.normal = pc.normal;
    out.point = near_known ? pair_point(va, vb, pc.normal, pc.depth, pc.point)
                           : pair_point(pa, pb, pc.normal, pc.depth, pc.point);
    out.r_eff = polyhedron_pair_radius(a, b);
    return out;
}

/// Deepest point (m, world) of a convex element a against an analytic wall, from its support map
/// `support` (world direction -> world point): the support point against a plane's normal, or
/// along the outward radial direction of the centre inside a cylinder (exact when the wall radius
/// is much larger than the particle). Sets out.overlap (negative when apart) and out.normal (unit,
/// from the wall into the element). Shared by superquadrics and polyhedra.
template <class Support>
Vec3 wall_deepest(const Support& support, const Element& a, const WallShape& w,
                  ElementContact& out) {
    Vec3 deepest = a.centre;
    std::visit(
        [&](const auto& s) {
            using S = std::decay_t<decltype(s)>;
            if constexpr (std::is_same_v<S, PlaneWall>) {
                deepest = support(Vec3(-s.normal));
                out.overlap = -(deepest - s.point).dot(s.normal);
                out.normal = s.normal;
            } else {
                Vec3 rho = a.centre - s.axis_point;
                rho -= rho.dot(s.axis) * s.axis;
                const Vec3 dir = rho.norm() > 1e-12 * a.radius ? Vec3(rho.normalized())
                                                               : Vec3(s.axis.unitOrthogonal());
                deepest = support(dir);
                Vec3 rp = deepest - s.axis_point;
                rp -= rp.dot(s.axis) * s.axis;
                const double dist = rp.norm();
                out.overlap = dist - s.radius;
                out.normal = dist > 0.0 ? Vec3(-rp / dist) : Vec3(-dir);
            }
        },
        w);
    return deepest;
}

/// Relative gap between the upper and the lower bound of a polyhedron-superquadric overlap (the
/// overlap along EPA's normal and EPA's depth) below which EPA's normal is kept unrefined (-):
/// the overlap is then within 0.1 % of the depth (plus 1e-9 of the size).
constexpr double kRefineGap = 1e-3;

/// The contact of polyhedron_superquadric from its normal (unit, world, from s to p) and the
/// overlap along it (m): none where the overlap is not positive (with `sep`, the normal as the
/// direction of a gap where it is negative); else the point half the overlap below the
/// superquadric's deepest point along the normal, and R* from its principal curvatures there.
/// That point, not the midpoint of the two supports: the superquadric's support is a single
/// point, the polyhedron's may be a whole face or edge, so the gradient of the overlap with
/// respect to either body's rotation is that of a force on the normal through the superquadric's
/// deepest point (Danskin). The midpoint of a face's vertex and that point was off by up to half
/// the face and made the torque non-conservative: 1 % energy error at every step size in
/// validation 14's box of cubes and superquadrics.
ElementContact polyhedron_superquadric_result(const geometry::PosedSuperquadric& ps,
                                              const Element& s, const Element& p,
                                              const Vec3& normal, double depth, Vec3* sep,
                                              bool radius, ElementContact out) {
    if (!(depth > 0.0)) {
        if (sep != nullptr && depth < 0.0) {
            *sep = normal; // a direction with a gap: apart after all
        }
        return out;
    }
    out.touching = true;
    out.overlap = depth;
    out.normal = normal;
    const Vec3 deepest_s = ps.support(normal);
    out.point = deepest_s - 0.5 * depth * normal;
    if (radius) {
        const auto k = s.sq->principal_curvatures(s.q.conjugate() * (deepest_s - s.centre));
        out.r_eff = effective_radius(k[0], k[1], s, &p);
    }
    return out;
}

/// Polyhedron element p against superquadric element s (normal from s to p): libccd GJK/EPA on
/// the two support maps. The normal is then refined (refine_polyhedron_normal,
/// depth_refinement.hpp: translation rounds, the polyhedron's faces and edges) and the overlap
/// evaluated exactly along it from the analytic supports (an upper bound of the MTD, as the
/// superquadric fallback does), so it does not carry EPA's tolerance. The polyhedron counts as
/// flat at the contact (as for a sphere), so R* is the superquadric's, from its principal
/// curvatures at its deepest point. A sphere element (a clump member) against a polyhedron never
/// comes here (sphere_polyhedron is exact). A pair that touched at the last step (`touched_last`,
/// with `warm` its last normal) skips EPA and refines from the last normal. `radius`: see
/// element_contact.
ElementContact polyhedron_superquadric(const Element& p, const Element& s, const Vec3* warm,
                                       Vec3* sep, bool touched_last, bool radius) {
    ElementContact out;
    const geometry::PosedPolyhedron pp{p.poly, p.centre, p.q};
    const geometry::PosedSuperquadric ps{s.sq, s.centre, s.q};
    const auto along = [&](const Vec3& n) { return n.dot(ps.support(n)) - n.dot(pp.support(-n)); };
    // Separating-axis shortcuts: the cached direction, the line of centres, the last normal and
    // (with a cache) the portal search.
    const double rsum = p.radius + s.radius;
    if (cached_apart(pp, ps, rsum, sep)) {
        out.proved_apart = true;
        return out;
    }
    const Vec3 line = p.centre - s.centre;
    if (line.squaredNorm() > 0.0 && along(line.normalized()) < 0.0) {
        if (sep != nullptr) {
            *sep = line.normalized();
        }
        return out;
    }
    const double warm_overlap = warm != nullptr ? along(*warm) : 0.0;
    if (warm != nullptr && warm_overlap < 0.0) {
        if (sep != nullptr) {
            *sep = *warm;
        }
        return out;
    }
    if (sep != nullptr) {
        Vec3 m;
        if (geometry::find_separating_direction(pp, ps, kSeparationMargin * rsum, m)) {
            *sep = m;
            out.proved_apart = true;
            return out;
        }
        sep->setZero();
    }
    if (touched_last && warm != nullptr) {
        // A pair that touched at the last step: its last normal (refined then) lies within the
        // step's motion of the best one, so the refinement starts there and EPA is not run (0.28
        // of the query's time; docs/performance.md, "Session 20"). GJK's distance decides whether
        // the bodies touch (a support plane with the origin outside the difference proves them
        // apart). Where a point of one body lies inside the other with room to spare, the bodies
        // overlap and GJK would say so: it is not run (geometry::overlap_proved).
        Vec3 v;
        if (!geometry::overlap_proved(pp, ps, *warm) &&
            geometry::shortest_vector(pp, ps, Vec3::Zero(), v)) {
            return out;
        }
        out.converged = true;
        Vec3 normal = *warm;
        double depth = warm_overlap;
        geometry::refine_polyhedron_normal(pp, ps, normal, depth);
        return polyhedron_superquadric_result(ps, s, p, normal, depth, sep, radius, out);
    }
    geometry::ConvexContact cc = geometry::ccd_contact(pp, ps, false);
    if (!cc.converged) {
        // libccd's EPA stopped without an answer (its support budget ran out, ccd_adapter.cpp):
        // MPR gives a penetration direction and depth that are not minimal but close to it, and
        // the depth along that direction is measured exactly below. Counted as a fallback.
        cc = geometry::ccd_contact(pp, ps, true);
        out.fell_back = cc.converged;
    }
    out.converged = cc.converged;
    if (!cc.converged || !cc.touching) {
        return out;
    }
    double depth = along(cc.normal);
    Vec3 normal = cc.normal;
    if (!(depth > 0.0)) {
        return out;
    }
    // EPA's normal is off by an angle that grows as the contact gets shallower, and the overlap
    // along it with it (up to 100 times the depth 1e-6 of the size deep; up to the bodies' size
    // on a repaired answer at GJK's boundary; docs/theory/shapes.md, "Depth along a normal"), so
    // the normal is refined (depth_refinement.hpp): the overlap along the result stays an upper
    // bound of the depth and comes within round-off of it. EPA's own depth is a lower bound (its
    // polytope lies inside the Minkowski difference), so where the two bounds already agree to
    // kRefineGap the refinement (2-3 times EPA's cost) is skipped. A repaired answer's depth and
    // MPR's (the fallback above) are not EPA's: those are always refined.
    const double scale = pp.length_scale() + ps.length_scale();
    if (cc.repaired || out.fell_back || depth - cc.depth > kRefineGap * depth + 1e-9 * scale) {
        geometry::refine_polyhedron_normal(pp, ps, normal, depth);
    }
    return polyhedron_superquadric_result(ps, s, p, normal, depth, sep, radius, out);
}

/// Contact point of a polyhedron on a wall: the deepest vertex, or, when several vertices are
/// almost equally deep (a face or an edge lying on the wall), their average weighted by
/// w = 1 - (depth_max - depth) / (kTieBand depth_max), which falls continuously to 0. The deepest
/// vertex is where the gradient of the overlap acts (Danskin), so the normal force is conservative
/// except within the band; the weighted average keeps a face at rest centred. `depth(x)` is the
/// depth of a world point below the wall (m); the point is moved half the overlap back out.
template <class Depth>
Vec3 wall_point(const geometry::PosedPolyhedron& p, double overlap, const Vec3& n, Depth depth) {
    const geometry::PolyhedronFeatures& f = *p.shape;
    const double band = kTieBand * overlap;
    Vec3 sum = Vec3::Zero();
    double wsum = 0.0;
    const Mat3 rot =
        p.q.toRotationMatrix(); // one matrix instead of a quaternion product per vertex
    for (const Vec3& v : f.vertices) {
        const Vec3 x = p.x + rot * v;
        const double w = 1.0 - (overlap - depth(x)) / band;
        if (w > 0.0) {
            sum += w * x;
            wsum += w;
        }
    }
    return (wsum > 0.0 ? Vec3(sum / wsum) : p.x) + 0.5 * overlap * n;
}

/// A box along its body axes (PolyhedronFeatures::Box::aligned, centred on the body origin, half
/// extents h) against a plane wall: polyhedron_wall's answer in closed form (the same numbers to
/// round-off). With the wall's normal n in the body frame (n_b = R^T n), the deepest corner has
/// the coordinates -sign(n_b,k) h_k and lies sum_k h_k |n_b,k| below the body's centre along n;
/// the corner with the axes of a set S flipped lies 2 sum_{k in S} h_k |n_b,k| higher, so its
/// band weight is 1 - that rise / band. The contact point is the weighted average of the corners
/// taken in the body frame and turned once, instead of eight vertices turned and measured.
ElementContact box_plane_wall(const Element& a, const geometry::PolyhedronFeatures::Box& box,
                              const PlaneWall& s) {
    ElementContact out;
    out.normal = s.normal;
    const Mat3 rot = geometry::unit_rotation_matrix(a.q);
    const Vec3 nb = rot.transpose() * s.normal;
    const Vec3 reach = box.half.cwiseProduct(nb.cwiseAbs()); // each axis's share of the depth
    const double overlap = reach.sum() - (a.centre - s.point).dot(s.normal);
    if (!(overlap > 0.0)) {
        if (overlap <= 0.0) {
            out.wall_gap = -overlap; // the deepest corner's height
        }
        return out;
    }
    out.touching = true;
    out.overlap = overlap;
    const double band = kTieBand * overlap;
    // The deepest corner, and the rise of flipping each axis as a fraction of the band.
    Vec3 deepest;
    Vec3 rise;
    for (int k = 0; k < 3; ++k) {
        deepest[k] = nb[k] > 0.0 ? -box.half[k] : box.half[k];
        rise[k] = 2.0 * reach[k] / band;
    }
    Vec3 sum = Vec3::Zero();
    double wsum = 0.0;
    for (int c = 0; c < 8; ++c) { // bit k of c: axis k flipped
        const bool fx = (c & 1) != 0;
        const bool fy = (c & 2) != 0;
        const bool fz = (c & 4) != 0;
        const double w = std::max(
            0.0, 1.0 - ((fx ? rise[0] : 0.0) + (fy ? rise[1] : 0.0) + (fz ? rise[2] : 0.0)));
        sum += w * Vec3(fx ? -deepest[0] : deepest[0], fy ? -deepest[1] : deepest[1],
                        fz ? -deepest[2] : deepest[2]);
        wsum += w;
    }
    out.point = a.centre + rot * (sum / wsum) + 0.5 * overlap * s.normal;
    out.r_eff = a.r_equiv;
    return out;
}

/// Polyhedron element against an analytic wall. Plane: the deepest vertex gives the overlap (a
/// box along its body axes: box_plane_wall). Cylinder: the support along the outward radial
/// direction, as for superquadrics. The point: wall_point.
ElementContact polyhedron_wall(const Element& a, const WallShape& w) {
    if (const auto* plane = std::get_if<PlaneWall>(&w);
        plane != nullptr && a.poly->box && a.poly->box->aligned) {
        return box_plane_wall(a, *a.poly->box, *plane);
    }
    ElementContact out;
    const geometry::PosedPolyhedron p{a.poly, a.centre, a.q};
    wall_deepest([&](const Vec3& d) { return p.support(d); }, a, w, out);
    if (!(out.overlap > 0.0)) {
        if (std::holds_alternative<PlaneWall>(w) && out.overlap <= 0.0) {
            out.wall_gap = -out.overlap; // the deepest vertex's height: exact to round-off
        }
        out.overlap = 0.0;
        return out;
    }
    out.touching = true;
    std::visit(
        [&](const auto& s) {
            using S = std::decay_t<decltype(s)>;
            if constexpr (std::is_same_v<S, PlaneWall>) {
                out.point = wall_point(p, out.overlap, out.normal,
                                       [&](const Vec3& x) { return -(x - s.point).dot(s.normal); });
            } else {
                out.point = wall_point(p, out.overlap, out.normal, [&](const Vec3& x) {
                    Vec3 rp = x - s.axis_point;
                    rp -= rp.dot(s.axis) * s.axis;
                    return rp.norm() - s.radius;
                });
            }
        },
        w);
    out.r_eff = a.r_equiv;
    return out;
}

} // namespace

bool polyhedra_apart_along(const Element& a, const Element& b, const Vec3& sep) {
    double overlap = 0.0;
    return polyhedra_apart_along(a, b, sep, overlap);
}

bool polyhedra_apart_along(const Element& a, const Element& b, const Vec3& sep, double& overlap) {
    const geometry::PosedPolyhedron pa{a.poly, a.centre, a.q};
    const geometry::PosedPolyhedron pb{b.poly, b.centre, b.q};
    overlap = geometry::polyhedron_overlap_along(pa, pb, sep);
    return overlap < -polyhedra_separation_margin(a, b);
}

double polyhedra_separation_margin(const Element& a, const Element& b) {
    return kSeparationMargin * (a.radius + b.radius);
}

double equivalent_radius(const geometry::ShapeTemplate& t) {
    return std::cbrt(3.0 * t.volume / (4.0 * std::numbers::pi));
}

void pose_members(const Vec3& x, const Mat3& rot, const MemberColumns& cols, double* out) {
    const std::size_t n = cols.n;
    std::size_t j = 0;
#if defined(__AVX512F__)
    const __m512i lo = _mm512_setr_epi64(0, 4, 8, 12, 1, 5, 9, 13);
    const __m512i hi = _mm512_setr_epi64(2, 6, 10, 14, 3, 7, 11, 15);
    const __m512i first = _mm512_setr_epi64(0, 1, 2, 3, 8, 9, 10, 11);
    const __m512i second = _mm512_setr_epi64(4, 5, 6, 7, 12, 13, 14, 15);
    const __m512d r00 = _mm512_set1_pd(rot(0, 0)), r01 = _mm512_set1_pd(rot(0, 1)),
                  r02 = _mm512_set1_pd(rot(0, 2)), r10 = _mm512_set1_pd(rot(1, 0)),
                  r11 = _mm512_set1_pd(rot(1, 1)), r12 = _mm512_set1_pd(rot(1, 2)),
                  r20 = _mm512_set1_pd(rot(2, 0)), r21 = _mm512_set1_pd(rot(2, 1)),
                  r22 = _mm512_set1_pd(rot(2, 2));
    const __m512d bx = _mm512_set1_pd(x.x()), by = _mm512_set1_pd(x.y()),
                  bz = _mm512_set1_pd(x.z());
    const double* cxs = cols.c.data();
    const double* cys = cxs + n;
    const double* czs = cys + n;
    const double* crs = czs + n;
    for (; j + 8 <= n; j += 8) {
        const __m512d cx = _mm512_loadu_pd(cxs + j);
        const __m512d cy = _mm512_loadu_pd(cys + j);
        const __m512d cz = _mm512_loadu_pd(czs + j);
        const __m512d cr = _mm512_loadu_pd(crs + j);
        // member_centre's operations, in its order
        const __m512d ox = _mm512_add_pd(
            bx, _mm512_fmadd_pd(r02, cz, _mm512_fmadd_pd(r01, cy, _mm512_mul_pd(r00, cx))));
        const __m512d oy = _mm512_add_pd(
            by, _mm512_fmadd_pd(r12, cz, _mm512_fmadd_pd(r11, cy, _mm512_mul_pd(r10, cx))));
        const __m512d oz = _mm512_add_pd(
            bz, _mm512_fmadd_pd(r20, cx, _mm512_fmadd_pd(r22, cz, _mm512_mul_pd(r21, cy))));
        const __m512d oxy03 = _mm512_permutex2var_pd(ox, first, oy); // x0..x3 y0..y3
        const __m512d oxy47 = _mm512_permutex2var_pd(ox, second, oy);
        const __m512d ozr03 = _mm512_permutex2var_pd(oz, first, cr); // z0..z3 r0..r3
        const __m512d ozr47 = _mm512_permutex2var_pd(oz, second, cr);
        double* q = out + 4 * j;
        _mm512_storeu_pd(q, _mm512_permutex2var_pd(oxy03, lo, ozr03));
        _mm512_storeu_pd(q + 8, _mm512_permutex2var_pd(oxy03, hi, ozr03));
        _mm512_storeu_pd(q + 16, _mm512_permutex2var_pd(oxy47, lo, ozr47));
        _mm512_storeu_pd(q + 24, _mm512_permutex2var_pd(oxy47, hi, ozr47));
    }
#endif
    for (; j < n; ++j) {
        const Vec3 c = member_centre(x, rot, Vec3(cols.c[j], cols.c[n + j], cols.c[2 * n + j]));
        out[4 * j] = c.x();
        out[4 * j + 1] = c.y();
        out[4 * j + 2] = c.z();
        out[4 * j + 3] = cols.c[3 * n + j];
    }
}

MemberColumns member_columns(const geometry::ClumpSphere* spheres, std::size_t n) {
    MemberColumns m;
    m.n = n;
    m.c.resize(4 * n);
    for (std::size_t j = 0; j < n; ++j) {
        m.c[j] = spheres[j].centre.x();
        m.c[n + j] = spheres[j].centre.y();
        m.c[2 * n + j] = spheres[j].centre.z();
        m.c[3 * n + j] = spheres[j].radius;
    }
    return m;
}

void append_elements(const geometry::ShapeTemplate* t, const Vec3& x, const Quat& q, double r,
                     std::vector<Element>& out) {
    append_elements(t, nullptr, x, q, r, out);
}

void append_elements(const geometry::ShapeTemplate* t, const geometry::PolyhedronFeatures* features,
                     const Vec3& x, const Quat& q, double r, std::vector<Element>& out) {
    const bool clump = t != nullptr && std::holds_alternative<geometry::Clump>(t->shape);
    append_elements(t, features, x, q, clump ? q.toRotationMatrix() : Mat3::Identity(), r, out);
}

void append_elements(const geometry::ShapeTemplate* t, const geometry::PolyhedronFeatures* features,
                     const Vec3& x, const Quat& q, const Mat3& rot, double r,
                     std::vector<Element>& out) {
    if (t == nullptr) {
        out.push_back({Element::Kind::sphere, x, r, nullptr, Quat::Identity(), r});
        return;
    }
    if (const auto* c = std::get_if<geometry::Clump>(&t->shape)) {
        for (const geometry::ClumpSphere& s : c->spheres) {
            out.push_back({Element::Kind::sphere, member_centre(x, rot, s.centre), s.radius,
                           nullptr, Quat::Identity(), s.radius});
        }
        return;
    }
    if (const auto* s = std::get_if<geometry::Superquadric>(&t->shape)) {
        out.push_back({Element::Kind::superquadric, x, r, s, q, s->half_axes.minCoeff()});
        return;
    }
    if (const auto* s = std::get_if<geometry::Sphere>(&t->shape)) {
        out.push_back({Element::Kind::sphere, x, s->radius, nullptr, Quat::Identity(), s->radius});
        return;
    }
    const auto& hull = std::get<geometry::ConvexPolyhedron>(t->shape);
    if (features == nullptr) {
        throw std::logic_error("append_elements: polyhedron template without its features");
    }
    Element e{Element::Kind::polyhedron, x, r, nullptr, q, features->inradius};
    e.poly = features;
    e.hull = &hull;
    e.r_equiv = features->r_equiv;
    out.push_back(e);
}

void box_pair_contacts(const BoxPairQuery* pairs, std::size_t n, ElementContact* out) {
    // pair_point's rule in the lanes. A box's corners near its support plane are the extreme
    // corner and those turned from it along the axes whose turn (ea[k]) stays within the band:
    // no such axis, the corner alone; one, the extreme corner (weight 1) and its neighbour
    // (weight 1 - ea[k] / band): an edge; two or more, at least three corners: a face, whose
    // contact point is the patch's centroid (computed per pair only where both bodies have one).
    constexpr std::size_t w = geometry::detail::BoxPairLanes::kWidth;
    geometry::detail::BoxPairLanes lanes;
    alignas(64) double point[3][w];
    alignas(64) int patch[w];
    for (std::size_t p0 = 0; p0 < n; p0 += w) {
        const std::size_t count = std::min(w, n - p0);
        for (std::size_t q = 0; q < count; ++q) {
            const BoxPairQuery& s = pairs[p0 + q];
            geometry::detail::box_pair_lane(lanes, q, *s.a->poly, s.a->centre, *s.ra, *s.b->poly,
                                            s.b->centre, *s.rb);
        }
        geometry::detail::box_pair_planes(lanes, count);
        const auto& ra = lanes.ra;
        const auto& rb = lanes.rb;
#pragma omp simd
        for (std::size_t q = 0; q < w; ++q) {
            const double depth = lanes.depth[q];
            const double band = kTieBand * depth;
            // Per body: the axes within the band, and for one such axis the neighbour's offset
            // from the extreme corner (world; -2 c_k along the body's axis k) and its weight.
            int low_a = 0;
            int low_b = 0;
            double off_a[3] = {0.0, 0.0, 0.0};
            double off_b[3] = {0.0, 0.0, 0.0};
            // The turn of the last axis within the band gives the weight (one division per
            // body, taken after the loop).
            double ta = 0.0;
            double tb = 0.0;
            for (int k = 0; k < 3; ++k) {
                const bool in_a = lanes.ea[k][q] < band;
                const bool in_b = lanes.eb[k][q] < band;
                low_a += in_a ? 1 : 0;
                low_b += in_b ? 1 : 0;
                ta = in_a ? lanes.ea[k][q] : ta;
                tb = in_b ? lanes.eb[k][q] : tb;
                for (int i = 0; i < 3; ++i) {
                    off_a[i] = in_a ? -2.0 * lanes.corner_a[k][q] * ra[3 * i + k][q] : off_a[i];
                    off_b[i] = in_b ? -2.0 * lanes.corner_b[k][q] * rb[3 * i + k][q] : off_b[i];
                }
            }
            const double wa = low_a > 0 ? 1.0 - ta / band : 0.0;
            const double wb = low_b > 0 ? 1.0 - tb / band : 0.0;
            double pa[3];
            double pb[3];
            double nw[3];
            double avg_a[3];
            double avg_b[3];
            for (int i = 0; i < 3; ++i) {
                pa[i] = lanes.point_a[i][q];
                pb[i] = lanes.point_b[i][q];
                nw[i] = lanes.normal[i][q];
                // The two corners' weighted average: (p + w (p + off)) / (1 + w).
                avg_a[i] = pa[i] + wa / (1.0 + wa) * off_a[i];
                avg_b[i] = pb[i] + wb / (1.0 + wb) * off_b[i];
            }
            // Two edges: the closest points of the segments (pair_point's form).
            const double r[3] = {pa[0] - pb[0], pa[1] - pb[1], pa[2] - pb[2]};
            const double aa = off_a[0] * off_a[0] + off_a[1] * off_a[1] + off_a[2] * off_a[2];
            const double ee = off_b[0] * off_b[0] + off_b[1] * off_b[1] + off_b[2] * off_b[2];
            const double bb = off_a[0] * off_b[0] + off_a[1] * off_b[1] + off_a[2] * off_b[2];
            const double cc = off_a[0] * r[0] + off_a[1] * r[1] + off_a[2] * r[2];
            const double ff = off_b[0] * r[0] + off_b[1] * r[1] + off_b[2] * r[2];
            const double denom = aa * ee - bb * bb;
            const bool crossing = low_a == 1 && low_b == 1 && denom > 1e-12 * aa * ee;
            // Divisors kept finite in lanes that do not use them.
            const double den = crossing ? denom : 1.0;
            const double aa1 = crossing ? aa : 1.0;
            const double ee1 = crossing ? ee : 1.0;
            const double ss = std::clamp((bb * ff - cc * ee) / den, 0.0, 1.0);
            const double tt = std::clamp((bb * ss + ff) / ee1, 0.0, 1.0);
            const double s2 = std::clamp((bb * tt - cc) / aa1, 0.0, 1.0);
            const double half = 0.5 * depth;
            for (int i = 0; i < 3; ++i) {
                const double edges = crossing
                                         ? 0.5 * (pa[i] + s2 * off_a[i] + pb[i] + tt * off_b[i])
                                         : 0.5 * (avg_a[i] + avg_b[i]);
                point[i][q] = low_a == 0                 ? pa[i] + half * nw[i]
                              : low_b == 0               ? pb[i] - half * nw[i]
                              : low_a == 1 && low_b == 1 ? edges
                              : low_a == 1               ? avg_a[i] + half * nw[i]
                              : low_b == 1               ? avg_b[i] - half * nw[i]
                                                         : 0.0;
            }
            patch[q] = low_a >= 2 && low_b >= 2 ? 1 : 0;
        }
        for (std::size_t q = 0; q < count; ++q) {
            const BoxPairQuery& s = pairs[p0 + q];
            ElementContact& ec = out[p0 + q];
            ec = ElementContact{};
            if (lanes.touching[q] == 0) {
                continue;
            }
            ec.touching = true;
            ec.overlap = lanes.depth[q];
            ec.normal = Vec3(lanes.normal[0][q], lanes.normal[1][q], lanes.normal[2][q]);
            ec.point = Vec3(point[0][q], point[1][q], point[2][q]);
            // Face on face: the patch's centroid (with the general code's area tolerance).
            if (patch[q] != 0) {
                const double scale = s.a->poly->radius + s.b->poly->radius;
                if (!geometry::detail::box_pair_patch(lanes, q, 1e-24 * scale * scale, ec.point)) {
                    ec.point = geometry::detail::patch_point(
                        {s.a->poly, s.a->centre, s.a->q}, {s.b->poly, s.b->centre, s.b->q},
                        Vec3(lanes.normal_a[0][q], lanes.normal_a[1][q], lanes.normal_a[2][q]));
                }
            }
            ec.r_eff = polyhedron_pair_radius(*s.a, *s.b);
        }
    }
}

ElementContact element_contact(const Element& a, const Element& b, NarrowPhase method,
                               const Vec3* warm, Vec3* separating, bool touched_last,
                               geometry::PlaneMemo* memo, bool radius) {
    // Bounding spheres first: most candidate pairs are apart.
    const double rsum = a.radius + b.radius;
    if ((a.centre - b.centre).squaredNorm() >= rsum * rsum) {
        return {};
    }
    if (a.kind == Element::Kind::sphere && b.kind == Element::Kind::sphere) {
        return sphere_sphere(a, b);
    }
    const bool poly_a = a.kind == Element::Kind::polyhedron;
    const bool poly_b = b.kind == Element::Kind::polyhedron;
    if (poly_a && poly_b) {
        return polyhedron_pair(a, b, method, separating, touched_last, memo);
    }
    if (poly_b && a.kind == Element::Kind::sphere) {
        return sphere_polyhedron(a, b);
    }
    if (poly_a && b.kind == Element::Kind::sphere) {
        ElementContact c = sphere_polyhedron(b, a);
        c.normal = -c.normal;
        return c;
    }
    if (poly_a) {
        return polyhedron_superquadric(a, b, warm, separating, touched_last, radius);
    }
    if (poly_b) { // the same with the roles swapped: directions from a to b
        const Vec3 back = warm != nullptr ? Vec3(-*warm) : Vec3::Zero();
        Vec3 sep_back = separating != nullptr ? Vec3(-*separating) : Vec3::Zero();
        ElementContact c = polyhedron_superquadric(b, a, warm != nullptr ? &back : nullptr,
                                                   separating != nullptr ? &sep_back : nullptr,
                                                   touched_last, radius);
        if (separating != nullptr) {
            *separating = -sep_back;
        }
        c.normal = -c.normal;
        return c;
    }
    const SphereAsSuperquadric sa(a.radius);
    const SphereAsSuperquadric sb(b.radius);
    const geometry::PosedSuperquadric pa{a.sq ? a.sq : &sa.sq, a.centre, a.q};
    const geometry::PosedSuperquadric pb{b.sq ? b.sq : &sb.sq, b.centre, b.q};
    // Separating-axis shortcut: the overlap along any direction bounds the MTD from above, so a
    // gap along the line of centres or along the last normal proves the bodies apart (two
    // support evaluations instead of a narrow-phase search).
    // A cached direction of an earlier step comes first, and with a cache a portal search for a
    // separating direction runs before the narrow phase (near misses dominate blocky scenes).
    ElementContact apart;
    apart.proved_apart = true;
    if (cached_apart(pa, pb, rsum, separating)) {
        return apart;
    }
    const Vec3 line = a.centre - b.centre;
    if (line.squaredNorm() > 0.0 && depth_along(pa, pb, line.normalized()) < 0.0) {
        if (separating != nullptr) {
            *separating = line.normalized();
        }
        return {};
    }
    // Along the warm normal: the same two supports are Newton's first evaluation, handed on.
    std::array<Vec3, 2> warm_supports;
    if (warm != nullptr) {
        warm_supports = {pa.support(-*warm), pb.support(*warm)};
        if (warm->dot(warm_supports[1]) - warm->dot(warm_supports[0]) < 0.0) {
            if (separating != nullptr) {
                *separating = *warm;
            }
            return {};
        }
    }
    if (separating != nullptr) {
        Vec3 m;
        if (geometry::find_separating_direction(pa, pb, kSeparationMargin * rsum, m)) {
            *separating = m;
            return apart;
        }
        separating->setZero();
    }
    geometry::ConvexContact cc;
    ElementContact out;
    if (method == NarrowPhase::newton) {
        // Near misses (bounding spheres overlap, bodies apart) make Newton search for the largest
        // gap, which is slow for blocky shapes (exponent below kBlocky: 3x faster whole scene at
        // e = 0.3, bench_bodies); MPR proves separation cheaply there. Smooth shapes converge
        // faster in Newton than MPR takes (2.5x slower whole scene at e = 0.8 with the gate).
        if (blocky(a) || blocky(b)) {
            const geometry::ConvexContact mpr = geometry::ccd_contact(pa, pb, true);
            if (mpr.converged && !mpr.touching) {
                return out;
            }
        }
        // A pair that touched at the last step starts from its last normal; where that run
        // stalls, its direction is finished below instead of by the cold start (four runs of up
        // to 100 iterations: for superballs a third of Newton's iterations, a quarter of them
        // failing too; docs/performance.md, "Session 20").
        geometry::NewtonSettings settings;
        settings.cold_after_warm = !(touched_last && warm != nullptr);
        cc = geometry::support_newton_contact(pa, pb, warm, settings,
                                              warm != nullptr ? &warm_supports : nullptr);
        if (!cc.converged && !settings.cold_after_warm) {
            // The stalled warm run: GJK's distance decides whether the bodies touch, and the
            // translation rounds of depth_refinement.hpp finish its direction (the overlap along
            // the result, an upper bound of the MTD, never above that along the stalled one).
            out.fell_back = true;
            Vec3 v;
            if (geometry::shortest_vector(pa, pb, Vec3::Zero(), v)) {
                out.converged = true;
                return out;
            }
            double depth = depth_along(pa, pb, cc.normal);
            geometry::refine_normal(pa, pb, cc.normal, depth);
            cc.converged = true;
            cc.depth = depth;
            cc.touching = depth > 0.0;
            cc.set_deepest(pa.support(-cc.normal), pb.support(cc.normal));
        } else if (!cc.converged) {
            // Newton stalled (near flat faces the support map is ill-conditioned and its gradient
            // test may not be met). Its last direction and GJK/EPA's normal both give an exact
            // upper bound of the MTD when f is evaluated there with the analytic supports; the
            // smaller one is kept. Using EPA's own depth instead would switch between two depth
            // definitions and leave an energy error that does not shrink with dt (validation 14).
            out.fell_back = true;
            const geometry::ConvexContact epa = geometry::ccd_contact(pa, pb, false);
            // Any direction overestimates the MTD, so a stalled direction could invent a contact:
            // EPA decides whether the bodies touch, and a failure of both is counted and skipped.
            if (!epa.converged || !epa.touching) {
                cc = epa;
            } else {
                const double f_newton = depth_along(pa, pb, cc.normal);
                const double f_epa = depth_along(pa, pb, epa.normal);
                cc.converged = true;
                cc.depth = std::min(f_newton, f_epa);
                cc.normal = f_epa < f_newton ? epa.normal : cc.normal;
            }
            cc.touching = cc.converged && cc.depth > 0.0;
            cc.set_deepest(pa.support(-cc.normal), pb.support(cc.normal));
        }
    } else {
        cc = geometry::ccd_contact(pa, pb, false);
    }
    out.converged = cc.converged;
    if (separating != nullptr && cc.converged && cc.depth < 0.0 && method == NarrowPhase::newton) {
        *separating = cc.normal; // Newton's direction of the largest gap
    }
    if (!cc.converged || !cc.touching || cc.depth <= 0.0) {
        return out;
    }
    out.touching = true;
    out.overlap = cc.depth;
    out.normal = cc.normal;
    out.point = cc.point;
    if (radius) {
        const geometry::ContactCurvature k = geometry::contact_curvature(pa, pb, cc);
        out.r_eff = effective_radius(k.k_min, k.k_max, a, &b);
    }
    return out;
}

double flat_wall_radius(const Element& a, const Vec3& n) {
    if (a.kind == Element::Kind::polyhedron) {
        return a.r_equiv;
    }
    if (a.kind == Element::Kind::sphere) {
        return a.radius;
    }
    const geometry::PosedSuperquadric p{a.sq, a.centre, a.q};
    const auto k = a.sq->principal_curvatures(a.q.conjugate() * (p.support(-n) - a.centre));
    return effective_radius(k[0], k[1], a, nullptr);
}

ElementContact element_wall_contact(const Element& a, const WallShape& w, bool radius) {
    ElementContact out;
    if (a.kind == Element::Kind::sphere) {
        const WallContact g =
            std::visit([&](const auto& s) { return wall_contact(s, a.centre, a.radius); }, w);
        if (g.overlap > 0.0) {
            out.touching = true;
            out.overlap = g.overlap;
            out.normal = g.n;
            out.point = a.centre - (a.radius - 0.5 * g.overlap) * g.n;
            out.r_eff = g.r_eff;
        }
        return out;
    }
    if (a.kind == Element::Kind::polyhedron) {
        return polyhedron_wall(a, w);
    }
    // Convex element: the deepest point is the support point against the wall normal (plane), or
    // along the outward radial direction of the centre (cylinder; exact in the limit of a wall
    // radius much larger than the particle). R*: a plane is flat; a cylinder is concave around
    // its circumference (concave_wall_radius).
    const geometry::PosedSuperquadric p{a.sq, a.centre, a.q};
    const Vec3 deepest = wall_deepest([&](const Vec3& d) { return p.support(d); }, a, w, out);
    if (!(out.overlap > 0.0)) {
        out.overlap = 0.0;
        return out;
    }
    out.touching = true;
    out.point = deepest + 0.5 * out.overlap * out.normal;
    if (!radius) {
        return out;
    }
    const Vec3 p_body = a.q.conjugate() * (deepest - a.centre);
    if (const auto* cyl = std::get_if<CylinderWall>(&w)) {
        out.r_eff = concave_wall_radius(a, p_body, out.normal, cyl->axis, cyl->radius);
    } else {
        const auto k = a.sq->principal_curvatures(p_body);
        out.r_eff = effective_radius(k[0], k[1], a, nullptr);
    }
    return out;
}

} // namespace kiln::dynamics
