#pragma once
// Proof that two convex bodies are apart: a direction along which their support planes leave a
// gap (the separating-axis theorem; any direction with a gap proves the bodies disjoint, so a
// caller may skip its contact query). Written once against the support maps, so it serves
// superquadrics and polyhedra alike (any type with a world-frame `support(d)` and a centre `x`).
//
// The search is the discovery and refinement of Minkowski portal refinement (Snethen 2008, "Xeno-
// Collide: complex collision made simple", Game Programming Gems 7, Sec. 2.5; the steps as in
// libccd's mpr.c) on the Minkowski difference M = A - B, with one change: it answers only when it
// holds a proof. It returns a direction when the support of M along it lies below the origin by
// more than a margin; when the portal holds the origin, the refinement stalls or the iteration
// limit is reached it returns nothing, which proves nothing (the caller then runs its own query).
//
// Normal convention as in convex_contact.hpp: m points from B towards A (world frame), and the
// overlap along m is h_B(m) + h_A(-m) = m . s_B(m) - m . s_A(-m), h the support function.

#include "core/types.hpp"

#include <utility>

namespace kiln::geometry {

/// Overlap (m) of posed convex bodies a and b along the unit world direction m (from b towards a):
/// m . s_b(m) - m . s_a(-m). Negative: m separates them (a gap of that size along m).
template <class A, class B>
[[nodiscard]] double overlap_along(const A& a, const B& b, const Vec3& m) {
    return m.dot(b.support(m)) - m.dot(a.support(-m));
}

/// Searches a unit direction m (world frame, from b towards a) with overlap_along(a, b, m) <
/// -margin (margin in m, >= 0). Returns true and sets m when it finds one (a proof that a and b are
/// apart by more than the margin); false when it finds none (no proof of contact either).
/// `max_iterations` bounds each of the two phases of the portal search.
template <class A, class B>
[[nodiscard]] bool find_separating_direction(const A& a, const B& b, double margin, Vec3& m,
                                             int max_iterations = 40) {
    // Support of M = A - B along d (any length), world frame.
    const auto support = [&](const Vec3& d) { return Vec3(a.support(d) - b.support(-d)); };
    // d separates when M's support along the unit d lies below -margin: then m = -d, and the
    // overlap along m is checked again with the callers' formula (round-off of the two forms).
    const auto proves = [&](const Vec3& d) {
        const double len = d.norm();
        if (!(len > 0.0)) {
            return false;
        }
        const Vec3 cand = -d / len;
        if (overlap_along(a, b, cand) < -margin) {
            m = cand;
            return true;
        }
        return false;
    };
    const Vec3 v0 = a.x - b.x; // a point inside M
    if (!(v0.squaredNorm() > 0.0)) {
        return false; // centres coincide: the bodies overlap
    }
    // Discovery: a portal (v1, v2, v3) that the ray from v0 towards the origin passes through.
    Vec3 dir = -v0;
    Vec3 v1 = support(dir);
    if (v1.dot(dir) < 0.0) {
        return proves(dir);
    }
    dir = v0.cross(v1);
    if (!(dir.squaredNorm() > 0.0)) {
        return false; // the origin lies on the segment v0-v1: inside M
    }
    Vec3 v2 = support(dir);
    if (v2.dot(dir) < 0.0) {
        return proves(dir);
    }
    dir = (v1 - v0).cross(v2 - v0);
    if (dir.dot(v0) > 0.0) {
        std::swap(v1, v2);
        dir = -dir;
    }
    Vec3 v3;
    for (int it = 0;; ++it) {
        if (it == max_iterations || !(dir.squaredNorm() > 0.0)) {
            return false;
        }
        v3 = support(dir);
        if (v3.dot(dir) < 0.0) {
            return proves(dir);
        }
        if (v1.cross(v3).dot(v0) < 0.0) { // origin outside (v1, v0, v3): replace v2
            v2 = v3;
            dir = (v1 - v0).cross(v3 - v0);
            continue;
        }
        if (v3.cross(v2).dot(v0) < 0.0) { // origin outside (v3, v0, v2): replace v1
            v1 = v3;
            dir = (v3 - v0).cross(v2 - v0);
            continue;
        }
        break;
    }
    // Refinement: move the portal outwards until it holds the origin (contact: no proof) or a
    // support plane leaves the origin outside (a separating direction).
    for (int it = 0; it < max_iterations; ++it) {
        dir = (v2 - v1).cross(v3 - v1);
        if (!(dir.squaredNorm() > 0.0) || dir.dot(v1) >= 0.0) {
            return false; // degenerate portal, or the origin lies inside it: no separation
        }
        const Vec3 v4 = support(dir);
        if (v4.dot(dir) < 0.0) {
            return proves(dir);
        }
        // The portal's planes cannot move further out: the origin lies within round-off of M's
        // boundary, or M's boundary is reached. No proof.
        if (v4.dot(dir) - v1.dot(dir) <= 1e-14 * dir.norm() * (v4 - v0).norm()) {
            return false;
        }
        const Vec3 v4v0 = v4.cross(v0);
        if (v1.dot(v4v0) > 0.0) {
            if (v2.dot(v4v0) > 0.0) {
                v1 = v4;
            } else {
                v3 = v4;
            }
        } else if (v3.dot(v4v0) > 0.0) {
            v2 = v4;
        } else {
            v1 = v4;
        }
    }
    return false;
}

} // namespace kiln::geometry
