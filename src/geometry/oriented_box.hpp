#pragma once
// A box around a body, in its body frame, and the separating-axis test of two such boxes posed in
// the world. The broad phase uses it to drop list entries of bodies whose boxes are apart though
// their bounding spheres overlap (a flat plate's bounding sphere holds 7 times its volume).

#include "core/types.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace kiln::geometry {

/// A box holding a body: centre (m) and half extents (m) along the body axes, body frame.
struct BodyBox {
    Vec3 centre = Vec3::Zero();
    Vec3 half = Vec3::Zero();
};

/// The smallest box along the body axes holding the points (m, body frame); of a convex body, its
/// vertices. An empty list gives a box of zero size at the origin.
[[nodiscard]] inline BodyBox body_box(const std::vector<Vec3>& points) {
    if (points.empty()) {
        return {};
    }
    Vec3 lo = points.front();
    Vec3 hi = points.front();
    for (const Vec3& v : points) {
        lo = lo.cwiseMin(v);
        hi = hi.cwiseMax(v);
    }
    return {0.5 * (lo + hi), 0.5 * (hi - lo)};
}

/// True when two boxes are proved apart by more than `gap` (m, >= 0): box a of centre ca (m,
/// world), axes the columns of ra (body -> world rotation) and half extents ha (m), box b likewise.
/// The test of the 15 axes (three faces of each box, nine cross products of their edges) as in
/// Gottschalk, Lin and Manocha, "OBBTree", SIGGRAPH 1996, with the gap added to every radius:
/// "apart" means that on one axis the two projections are more than `gap` apart, so that the
/// distance between the boxes exceeds `gap` and two bodies inside them stay apart while neither
/// moves any of its points by gap / 2 or more (turns included). The absolute values of the relative
/// rotation are widened by 1e-9 and the radii by 1e-9 of the box sizes, so that round-off
/// (rotation matrices orthogonal to ~1e-16) can only answer "not apart": a false "apart" would
/// lose a contact, a false "not apart" only keeps a pair that the narrow phase then rules out.
[[nodiscard]] inline bool boxes_apart(const Vec3& ca, const Mat3& ra, const Vec3& ha,
                                      const Vec3& cb, const Mat3& rb, const Vec3& hb, double gap) {
    const Mat3 c = ra.transpose() * rb; // b's axes in a's frame
    const Mat3 abs_c = (c.cwiseAbs().array() + 1e-9).matrix();
    const Vec3 t = ra.transpose() * (cb - ca); // b's centre in a's frame
    // (A negative gap is taken as 0: on a cross axis of nearly parallel edges, whose length
    // tends to 0, it would prove overlapping boxes apart.)
    const double widen = std::max(gap, 0.0) + 1e-9 * (ha.sum() + hb.sum());
    for (int i = 0; i < 3; ++i) { // a's faces
        if (std::abs(t[i]) > ha[i] + abs_c.row(i).dot(hb) + widen) {
            return true;
        }
    }
    for (int j = 0; j < 3; ++j) { // b's faces
        if (std::abs(t.dot(c.col(j))) > hb[j] + abs_c.col(j).dot(ha) + widen) {
            return true;
        }
    }
    for (int i = 0; i < 3; ++i) { // a's edge i across b's edge j
        const int i1 = (i + 1) % 3;
        const int i2 = (i + 2) % 3;
        for (int j = 0; j < 3; ++j) {
            const int j1 = (j + 1) % 3;
            const int j2 = (j + 2) % 3;
            const double r_a = ha[i1] * abs_c(i2, j) + ha[i2] * abs_c(i1, j);
            const double r_b = hb[j1] * abs_c(i, j2) + hb[j2] * abs_c(i, j1);
            // The axis a_i x b_j is not unit: its length |sin| <= 1 scales the projections and
            // the radii alike, but not the gap, which is therefore taken at full length (the
            // test is only weaker for it).
            if (std::abs(t[i2] * c(i1, j) - t[i1] * c(i2, j)) > r_a + r_b + widen) {
                return true;
            }
        }
    }
    return false;
}

} // namespace kiln::geometry
