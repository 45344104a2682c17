// The box test of two bodies (geometry/oriented_box.hpp): its answer "apart" against an
// independent separating-axis test from the boxes' corners, and the promise the broad phase
// relies on: boxes proved more than `gap` apart do not meet after each moves every point by less
// than gap / 2.

#include "geometry/oriented_box.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <gtest/gtest.h>
#include <random>
#include <vector>

namespace g = kiln::geometry;
using kiln::Mat3;
using kiln::Quat;
using kiln::Vec3;

namespace {

struct Box {
    Vec3 c;
    Mat3 r;
    Vec3 h;
};

std::array<Vec3, 8> corners(const Box& b) {
    std::array<Vec3, 8> out;
    for (int s = 0; s < 8; ++s) {
        const Vec3 sign((s & 1) != 0 ? 1.0 : -1.0, (s & 2) != 0 ? 1.0 : -1.0,
                        (s & 4) != 0 ? 1.0 : -1.0);
        out[static_cast<std::size_t>(s)] = b.c + b.r * sign.cwiseProduct(b.h);
    }
    return out;
}

/// The gap (m) between the two boxes' shadows on the unit axis u, from their corners (negative:
/// the shadows overlap).
double shadow_gap(const Box& a, const Box& b, const Vec3& u) {
    double lo_a = 1e300, hi_a = -1e300, lo_b = 1e300, hi_b = -1e300;
    for (const Vec3& c : corners(a)) {
        lo_a = std::min(lo_a, u.dot(c));
        hi_a = std::max(hi_a, u.dot(c));
    }
    for (const Vec3& c : corners(b)) {
        lo_b = std::min(lo_b, u.dot(c));
        hi_b = std::max(hi_b, u.dot(c));
    }
    return std::max(lo_b - hi_a, lo_a - hi_b);
}

/// The largest gap (m) between the two boxes' shadows on the 15 unit axes (faces of each, cross
/// products of their edges), from their corners: negative when no axis separates them, which for
/// two boxes means that they overlap. Independent of boxes_apart's algebra.
double largest_shadow_gap(const Box& a, const Box& b) {
    std::vector<Vec3> axes;
    for (int i = 0; i < 3; ++i) {
        axes.push_back(a.r.col(i));
        axes.push_back(b.r.col(i));
        for (int j = 0; j < 3; ++j) {
            const Vec3 n = a.r.col(i).cross(b.r.col(j));
            if (n.norm() > 1e-6) {
                axes.push_back(n.normalized());
            }
        }
    }
    double best = -1e300;
    for (const Vec3& u : axes) {
        best = std::max(best, shadow_gap(a, b, u));
    }
    return best;
}

Quat random_rotation(std::mt19937& rng) {
    std::normal_distribution<double> n(0.0, 1.0);
    return Quat(n(rng), n(rng), n(rng), n(rng)).normalized();
}

bool apart(const Box& a, const Box& b, double gap) {
    return g::boxes_apart(a.c, a.r, a.h, b.c, b.r, b.h, gap);
}

/// Box b moved rigidly so that none of its points moves more than `reach` (m): a turn about its
/// centre by an angle theta and a shift, |shift| + 2 sin(theta / 2) |h| = reach.
Box moved(const Box& b, double reach, std::mt19937& rng) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double share = u(rng); // of the reach taken by the turn
    const double arm = b.h.norm();
    const double theta = 2.0 * std::asin(std::min(1.0, share * reach / (2.0 * arm)));
    std::normal_distribution<double> n(0.0, 1.0);
    const Vec3 axis = Vec3(n(rng), n(rng), n(rng)).normalized();
    const Vec3 shift = Vec3(n(rng), n(rng), n(rng)).normalized() * (1.0 - share) * reach;
    Box out = b;
    out.r = Eigen::AngleAxisd(theta, axis).toRotationMatrix() * b.r;
    out.c = b.c + shift;
    return out;
}

} // namespace

TEST(OrientedBox, BodyBoxHoldsThePoints) {
    const std::vector<Vec3> pts{Vec3(1, -2, 0.5), Vec3(-3, 4, 0.25), Vec3(0, 0, -1)};
    const g::BodyBox b = g::body_box(pts);
    EXPECT_EQ(b.centre, Vec3(-1, 1, -0.25));
    EXPECT_EQ(b.half, Vec3(2, 3, 0.75));
}

TEST(OrientedBox, FaceToFaceAtTheGap) {
    // Two unit cubes side by side along x with a gap d between their faces: apart by more than
    // `gap` exactly when d > gap (to the test's widening of 1e-9 of the sizes).
    const Box a{Vec3::Zero(), Mat3::Identity(), Vec3::Constant(0.5)};
    for (const double d : {0.0, 0.05, 0.1, 0.2}) {
        const Box b{Vec3(1.0 + d, 0.3, -0.2), Mat3::Identity(), Vec3::Constant(0.5)};
        EXPECT_EQ(apart(a, b, 0.1), d > 0.1 + 1e-6) << d;
        EXPECT_FALSE(apart(a, b, d + 1e-6)) << d;
        if (d > 0.0) {
            EXPECT_TRUE(apart(a, b, d - 1e-6)) << d;
        }
    }
    // Overlapping boxes are never apart; a negative gap counts as 0 (parallel edges' cross axes
    // have length 0, on which it would prove them apart).
    const Box c{Vec3(0.9, 0.1, 0.0), Mat3::Identity(), Vec3::Constant(0.5)};
    EXPECT_FALSE(apart(a, c, 0.0));
    EXPECT_FALSE(apart(a, c, -0.05));
    EXPECT_FALSE(apart(a, c, -1.0));
}

TEST(OrientedBox, EdgeAcrossEdgeIsSeparatedByTheirCrossAxis) {
    // A cube and a second one turned 45 degrees about z and then about x: they face each other
    // edge on edge, so only a cross-product axis separates them.
    const Box a{Vec3::Zero(), Mat3::Identity(), Vec3::Constant(0.5)};
    const Mat3 r =
        (Eigen::AngleAxisd(M_PI / 4, Vec3::UnitX()) * Eigen::AngleAxisd(M_PI / 4, Vec3::UnitY()))
            .toRotationMatrix();
    Box b{Vec3::Zero(), r, Vec3::Constant(0.5)};
    // Along the direction between the two edges' nearest points, slide b out until the shadows'
    // gap from the corners is 0.05.
    const Vec3 dir = Vec3(1, 1, 1).normalized();
    double lo = 0.0, hi = 4.0;
    for (int it = 0; it < 200; ++it) {
        const double mid = 0.5 * (lo + hi);
        b.c = mid * dir;
        (largest_shadow_gap(a, b) < 0.05 ? lo : hi) = mid;
    }
    b.c = hi * dir;
    EXPECT_NEAR(largest_shadow_gap(a, b), 0.05, 1e-12);
    EXPECT_TRUE(apart(a, b, 0.04));
    EXPECT_FALSE(apart(a, b, 0.06));
}

TEST(OrientedBox, AgreesWithTheCornersShadows) {
    // Random boxes and poses: "apart" only where the corners' shadows have a gap above `gap` on
    // some axis, and always where a face axis has one (the cross axes may answer "not apart" a
    // little early: their gap is taken at full length, see boxes_apart).
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> size(0.1, 2.0);
    std::uniform_real_distribution<double> pos(-3.0, 3.0);
    int apart_count = 0;
    int overlap_count = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        const Box a{Vec3(pos(rng), pos(rng), pos(rng)), random_rotation(rng).toRotationMatrix(),
                    Vec3(size(rng), size(rng), 0.1 * size(rng))};
        const Box b{Vec3(pos(rng), pos(rng), pos(rng)), random_rotation(rng).toRotationMatrix(),
                    Vec3(size(rng), 0.2 * size(rng), size(rng))};
        const double gap = 0.25;
        const double shadow = largest_shadow_gap(a, b);
        const bool said = apart(a, b, gap);
        if (said) {
            ++apart_count;
            EXPECT_GT(shadow, gap) << trial;
        } else {
            ++overlap_count;
        }
        // A face axis with a clear gap must be found.
        double face_gap = -1e300;
        for (int i = 0; i < 3; ++i) {
            face_gap =
                std::max({face_gap, shadow_gap(a, b, a.r.col(i)), shadow_gap(a, b, b.r.col(i))});
        }
        if (face_gap > gap + 1e-6) {
            EXPECT_TRUE(said) << trial;
        }
    }
    EXPECT_GT(apart_count, 2000);
    EXPECT_GT(overlap_count, 2000);
}

TEST(OrientedBox, ApartBoxesDoNotMeetWithinHalfTheGapOfMotion) {
    // The broad phase's promise: boxes more than `gap` apart stay apart while each moves every
    // point by less than gap / 2 (turns included). Pairs near the limit: b placed just beyond
    // the gap along a random direction, then both moved by 0.999 of gap / 2.
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> size(0.2, 1.5);
    std::normal_distribution<double> n(0.0, 1.0);
    const double gap = 0.3;
    int tested = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        const Box a{Vec3::Zero(), random_rotation(rng).toRotationMatrix(),
                    Vec3(size(rng), size(rng), 0.2 * size(rng))};
        Box b{Vec3::Zero(), random_rotation(rng).toRotationMatrix(),
              Vec3(size(rng), 0.3 * size(rng), size(rng))};
        const Vec3 dir = Vec3(n(rng), n(rng), n(rng)).normalized();
        // The nearest placement along dir that boxes_apart accepts (bisection).
        double lo = 0.0, hi = 10.0;
        for (int it = 0; it < 60; ++it) {
            const double mid = 0.5 * (lo + hi);
            b.c = mid * dir;
            (apart(a, b, gap) ? hi : lo) = mid;
        }
        b.c = hi * dir;
        if (!apart(a, b, gap)) {
            continue;
        }
        ++tested;
        for (int m = 0; m < 5; ++m) {
            const Box a2 = moved(a, 0.999 * 0.5 * gap, rng);
            const Box b2 = moved(b, 0.999 * 0.5 * gap, rng);
            EXPECT_GT(largest_shadow_gap(a2, b2), 0.0) << trial << " " << m;
        }
    }
    EXPECT_GT(tested, 19000);
}
