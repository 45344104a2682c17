// Element geometry of bodies: see body_contact.hpp and docs/theory/contact.md ("Non-spherical
// contacts").

#include "dynamics/body_contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

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

} // namespace

void append_elements(const geometry::ShapeTemplate* t, const Vec3& x, const Quat& q, double r,
                     std::vector<Element>& out) {
    if (t == nullptr) {
        out.push_back({Element::Kind::sphere, x, r, nullptr, Quat::Identity(), r});
        return;
    }
    if (const auto* c = std::get_if<geometry::Clump>(&t->shape)) {
        for (const geometry::ClumpSphere& s : c->spheres) {
            out.push_back({Element::Kind::sphere, x + q * s.centre, s.radius, nullptr,
                           Quat::Identity(), s.radius});
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
    // Polyhedra are refused when the scene is built (System); reaching here is a programming error.
    out.push_back({Element::Kind::sphere, x, r, nullptr, Quat::Identity(), r});
}

ElementContact element_contact(const Element& a, const Element& b, NarrowPhase method,
                               const Vec3* warm) {
    // Bounding spheres first: most candidate pairs are apart.
    const double rsum = a.radius + b.radius;
    if ((a.centre - b.centre).squaredNorm() >= rsum * rsum) {
        return {};
    }
    if (a.kind == Element::Kind::sphere && b.kind == Element::Kind::sphere) {
        return sphere_sphere(a, b);
    }
    const SphereAsSuperquadric sa(a.radius);
    const SphereAsSuperquadric sb(b.radius);
    const geometry::PosedSuperquadric pa{a.sq ? a.sq : &sa.sq, a.centre, a.q};
    const geometry::PosedSuperquadric pb{b.sq ? b.sq : &sb.sq, b.centre, b.q};
    // Separating-axis shortcut: the overlap along any direction bounds the MTD from above, so a
    // gap along the line of centres or along the last normal proves the bodies apart (two
    // support evaluations instead of a narrow-phase search).
    const Vec3 line = a.centre - b.centre;
    if (line.squaredNorm() > 0.0 && depth_along(pa, pb, line.normalized()) < 0.0) {
        return {};
    }
    if (warm != nullptr && depth_along(pa, pb, *warm) < 0.0) {
        return {};
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
        cc = geometry::support_newton_contact(pa, pb, warm);
        if (!cc.converged) {
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
            cc.point = 0.5 * (pa.support(-cc.normal) + pb.support(cc.normal));
        }
    } else {
        cc = geometry::ccd_contact(pa, pb, false);
    }
    out.converged = cc.converged;
    if (!cc.converged || !cc.touching || cc.depth <= 0.0) {
        return out;
    }
    out.touching = true;
    out.overlap = cc.depth;
    out.normal = cc.normal;
    out.point = cc.point;
    const geometry::ContactCurvature k = geometry::contact_curvature(pa, pb, cc);
    out.r_eff = effective_radius(k.k_min, k.k_max, a, &b);
    return out;
}

ElementContact element_wall_contact(const Element& a, const WallShape& w) {
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
    // Convex element: the deepest point is the support point against the wall normal (plane), or
    // along the outward radial direction of the centre (cylinder; exact in the limit of a wall
    // radius much larger than the particle). The wall is flat for the effective radius.
    const geometry::PosedSuperquadric p{a.sq, a.centre, a.q};
    Vec3 deepest;
    std::visit(
        [&](const auto& s) {
            using S = std::decay_t<decltype(s)>;
            if constexpr (std::is_same_v<S, PlaneWall>) {
                deepest = p.support(-s.normal);
                out.overlap = -(deepest - s.point).dot(s.normal);
                out.normal = s.normal;
            } else {
                Vec3 rho = a.centre - s.axis_point;
                rho -= rho.dot(s.axis) * s.axis;
                const Vec3 dir = rho.norm() > 1e-12 * a.radius ? Vec3(rho.normalized())
                                                               : Vec3(s.axis.unitOrthogonal());
                deepest = p.support(dir);
                Vec3 rp = deepest - s.axis_point;
                rp -= rp.dot(s.axis) * s.axis;
                const double dist = rp.norm();
                out.overlap = dist - s.radius;
                out.normal = dist > 0.0 ? Vec3(-rp / dist) : Vec3(-dir);
            }
        },
        w);
    if (!(out.overlap > 0.0)) {
        out.overlap = 0.0;
        return out;
    }
    out.touching = true;
    out.point = deepest + 0.5 * out.overlap * out.normal;
    const auto k = a.sq->principal_curvatures(a.q.conjugate() * (deepest - a.centre));
    out.r_eff = effective_radius(k[0], k[1], a, nullptr);
    return out;
}

} // namespace kiln::dynamics
