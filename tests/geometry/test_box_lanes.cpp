// Two boxes' closed-form common plane in vector lanes (geometry::detail::box_planes,
// src/geometry/box_plane.cpp) against the one-pair closed form (detail::box_plane), and that
// against polyhedron_contact, which runs it: the lanes give the same separation, normal, feature
// and candidate count, bit for bit, lane by lane, for pairs of the shipped boxes (and a box whose
// axes are not its body frame's) in random, near, stacked and edge-on-edge poses, with the lanes
// mixing shapes and poses. The face-on-face patch of the resting pairs' route
// (detail::box_pair_patch) against polyhedron_contact's patch code.

#include "geometry/polyhedron.hpp"
#include "geometry/polyhedron_contact.hpp"
#include "geometry/polyhedron_search.hpp"
#include "geometry/rotation.hpp"
#include "io/shape_reader.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <gtest/gtest.h>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace g = kiln::geometry;
using kiln::Mat3;
using kiln::Quat;
using kiln::Vec3;

namespace {

g::PolyhedronFeatures load(const std::string& name, bool turned = false) {
    const auto t =
        kiln::io::read_shape_file(kiln::io::find_shape_file(name, kiln::io::default_shape_dirs()));
    g::ConvexPolyhedron p = std::get<g::ConvexPolyhedron>(t.shape);
    if (turned) {
        // The same solid with its faces off the body frame's axes (Box::aligned false).
        const Mat3 turn = Quat(0.9, 0.3, -0.2, 0.25).normalized().toRotationMatrix();
        for (Vec3& v : p.vertices) {
            v = turn * v;
        }
    }
    return g::polyhedron_features(p);
}

Quat about(const Vec3& axis, double angle) {
    return Quat(Eigen::AngleAxisd(angle, axis.normalized()));
}

/// One posed pair and what polyhedron_contact (the scalar closed form) found for it.
struct Case {
    g::PosedPolyhedron a;
    g::PosedPolyhedron b;
    g::PolyhedronContact scalar;
};

} // namespace

TEST(BoxLanes, EveryLaneIsTheScalarClosedForm) {
    std::vector<g::PolyhedronFeatures> shapes;
    for (const std::string name : {"cube", "cuboid_6x6x5", "plate_10x9x2"}) {
        shapes.push_back(load(name));
    }
    shapes.push_back(load("cuboid_6x6x5", true));
    for (const g::PolyhedronFeatures& s : shapes) {
        ASSERT_TRUE(s.box.has_value());
    }
    ASSERT_FALSE(shapes.back().box->aligned);

    std::mt19937_64 rng(28);
    std::normal_distribution<double> nd;
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::uniform_real_distribution<double> log_turn(std::log(1e-14), std::log(1e-2));
    const auto random_q = [&] { return Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized(); };
    std::vector<Case> cases;
    int kinds[4] = {};
    for (int n = 0; n < 4000; ++n) {
        const g::PolyhedronFeatures& fa = shapes[static_cast<std::size_t>(n) % shapes.size()];
        const g::PolyhedronFeatures& fb =
            shapes[(static_cast<std::size_t>(n) / shapes.size()) % shapes.size()];
        const g::PolyhedronFeatures::Box& ba = *fa.box;
        const g::PolyhedronFeatures::Box& bb = *fb.box;
        Case c{{&fa, Vec3(nd(rng), nd(rng), nd(rng)) * 1e-3, random_q()},
               {&fb, Vec3::Zero(), random_q()},
               {}};
        const double reach = fa.radius + fb.radius;
        const int kind = n % 4;
        if (kind == 0) {
            // Random orientations, centres 0.3 to 1.0 of the radii's sum apart.
            c.b.x = c.a.x + (0.3 + 0.7 * std::abs(unit(rng))) * reach *
                                Vec3(nd(rng), nd(rng), nd(rng)).normalized();
        } else if (kind == 1) {
            // Supports along a random direction overlapping by 1e-6 to 1e-1 of the smaller
            // radius, or apart by as much.
            const Vec3 u = Vec3(nd(rng), nd(rng), nd(rng)).normalized();
            const double gap = (unit(rng) > 0.0 ? 1.0 : -1.0) * std::exp(unit(rng) * 7.0 - 9.0) *
                               std::min(fa.radius, fb.radius);
            c.b.x = c.a.support(u) + gap * u - (c.b.support(-u) - c.b.x);
        } else if (kind == 2) {
            // B on A, the boxes' axes together up to a turn of 1e-14 to 1e-2 rad or none (every
            // edge pair parallel: the closed form's cut at 1e-12; faces of A and B tie).
            const double angle = n % 8 == 2 ? 0.0 : std::exp(log_turn(rng));
            const Mat3 turn = about(Vec3(nd(rng), nd(rng), nd(rng)), angle).toRotationMatrix();
            c.b.q =
                Quat(c.a.q.toRotationMatrix() * ba.axes * turn * bb.axes.transpose()).normalized();
            const Vec3 up = c.a.q * Vec3(ba.axes.col(2));
            const double gap = unit(rng) * 1e-3 * (ba.half.z() + bb.half.z());
            c.b.x = c.a.x + (ba.half.z() + bb.half.z() + gap) * up +
                    c.a.q * (ba.axes * Vec3(unit(rng), unit(rng), 0.0) * 0.3 *
                             std::min(ba.half.x(), bb.half.x()));
        } else {
            // Edge on edge, the edges 1e-14 to 1e-2 rad from parallel (crossing edges decide).
            const double angle = std::exp(log_turn(rng));
            c.a.q = Quat(about(Vec3::UnitX(), 0.25 * std::numbers::pi).toRotationMatrix() *
                         ba.axes.transpose())
                        .normalized();
            c.b.q =
                Quat((about(Vec3::UnitZ(), angle) * about(Vec3::UnitX(), 0.25 * std::numbers::pi))
                         .toRotationMatrix() *
                     bb.axes.transpose())
                    .normalized();
            c.a.x = Vec3::Zero();
            c.b.x = Vec3::Zero();
            const double top_a = c.a.support(Vec3::UnitZ()).z();
            const double low_b = c.b.support(-Vec3::UnitZ()).z();
            c.b.x =
                Vec3(0.0, 0.5 * unit(rng) * std::min(ba.half.x(), bb.half.x()) * std::tan(angle),
                     top_a - low_b + 1e-3 * unit(rng) * reach);
        }
        c.scalar = g::polyhedron_contact(c.a, c.b, false);
        if (c.scalar.feature == g::CommonPlaneFeature::kNone) {
            continue; // bounding spheres apart: no plane searched
        }
        ++kinds[kind];
        cases.push_back(c);
    }
    for (const int k : kinds) {
        EXPECT_GT(k, 500);
    }

    // Batches of eight and a last partial one (lanes past n are left as the last batch's).
    constexpr std::size_t w = g::detail::BoxLanes::kWidth;
    g::detail::BoxLanes lanes;
    std::vector<Mat3> rot(w);
    std::vector<g::detail::BoxPlane> one(w);
    std::vector<g::detail::BoxPlane> out(w);
    int features[4] = {};
    int touching = 0;
    std::size_t checked = 0;
    for (std::size_t k0 = 0; k0 < cases.size(); k0 += w) {
        const std::size_t n = std::min(w, cases.size() - k0);
        for (std::size_t q = 0; q < n; ++q) {
            const Case& c = cases[k0 + q];
            // The relative pose as polyhedron_contact computes it (the same function).
            g::search::Relative r;
            g::search::make_relative(c.a, c.b, r);
            rot[q] = r.rot;
            one[q] = g::detail::box_plane(*c.a.shape, *c.b.shape, rot[q], r.shift);
            g::detail::box_lane(lanes, q, *c.a.shape, *c.b.shape, rot[q], r.shift);
        }
        g::detail::box_planes(lanes, n, out.data());
        for (std::size_t q = 0; q < n; ++q) {
            const Case& c = cases[k0 + q];
            const g::detail::BoxPlane& o = out[q];
            SCOPED_TRACE("case " + std::to_string(k0 + q));
            // The one-pair form is polyhedron_contact's plane: its depth is -best (a negation),
            // its world normal A's turn of the normal (here turned in another file, which GCC
            // may fuse otherwise: to round-off).
            ASSERT_EQ(one[q].feature, c.scalar.feature);
            ASSERT_EQ(-one[q].best, c.scalar.depth);
            ASSERT_EQ(one[q].candidates, c.scalar.iterations);
            ASSERT_LE((c.a.q * one[q].normal - c.scalar.normal).norm(), 1e-15);
            // The lanes are the one-pair form, bit for bit (A's frame).
            ASSERT_EQ(o.feature, one[q].feature);
            ASSERT_EQ(o.best, one[q].best);
            ASSERT_EQ(o.candidates, one[q].candidates);
            ASSERT_EQ(o.normal.x(), one[q].normal.x());
            ASSERT_EQ(o.normal.y(), one[q].normal.y());
            ASSERT_EQ(o.normal.z(), one[q].normal.z());
            ++features[static_cast<int>(o.feature)];
            touching += c.scalar.touching ? 1 : 0;
            ++checked;
        }
    }
    EXPECT_EQ(checked, cases.size());
    // Every kind of plane and both verdicts met often.
    EXPECT_GT(features[static_cast<int>(g::CommonPlaneFeature::kFaceOfA)], 300);
    EXPECT_GT(features[static_cast<int>(g::CommonPlaneFeature::kFaceOfB)], 300);
    EXPECT_GT(features[static_cast<int>(g::CommonPlaneFeature::kEdgeEdge)], 300);
    EXPECT_GT(touching, 1000);
    EXPECT_GT(static_cast<int>(checked) - touching, 1000);
}

TEST(BoxLanes, FaceOnFacePatchIsThePolyhedronPatch) {
    // detail::box_pair_patch (the section of each box by the mid-plane as the quadrilateral of
    // the four edges across its face, the two clipped) against polyhedron_contact's patch code
    // (detail::patch_point: sections from the vertex and edge lists, hulls, clip), for two boxes
    // face on face: B under A with any of its faces up, twisted about the normal, shifted
    // sideways so that the faces overlap partly or wholly, tilted by up to 2e-5 rad (the corners
    // across a face up to ~1e-7 m apart along the normal: the function takes any tilt that
    // leaves the other four corners past the plane), pressed by 0.1-1 % of A's size, the pair
    // then turned and moved anywhere. Both give the patch's
    // centroid; to round-off of the coordinates (1e-12 of the size; a misplaced corner moves it
    // by ~1e-4 of the size and more).
    std::vector<g::PolyhedronFeatures> shapes;
    for (const std::string name : {"cube", "cuboid_6x6x5", "plate_10x9x2"}) {
        shapes.push_back(load(name));
    }
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::uniform_int_distribution<int> pick(0, 2);
    std::uniform_int_distribution<int> axis(0, 5);
    const auto random_turn = [&] {
        return Quat(unit(rng), unit(rng), unit(rng), unit(rng)).normalized();
    };
    constexpr std::size_t w = g::detail::BoxPairLanes::kWidth;
    g::detail::BoxPairLanes lanes;
    int answered = 0;
    double worst = 0.0;
    for (int batch = 0; batch < 250; ++batch) {
        std::array<g::PosedPolyhedron, w> pa;
        std::array<g::PosedPolyhedron, w> pb;
        for (std::size_t q = 0; q < w; ++q) {
            const g::PolyhedronFeatures& fa = shapes[static_cast<std::size_t>(pick(rng))];
            const g::PolyhedronFeatures& fb = shapes[static_cast<std::size_t>(pick(rng))];
            // In A's frame: B's face l (sign s) up against A's bottom face.
            const int up = axis(rng);
            const int l = up % 3;
            const double sign = up < 3 ? 1.0 : -1.0;
            constexpr double quarter = 0.5 * std::numbers::pi;
            const Quat lay = l == 0   ? about(Vec3::UnitY(), -sign * quarter)
                             : l == 1 ? about(Vec3::UnitX(), sign * quarter)
                                      : about(Vec3::UnitX(), sign > 0.0 ? 0.0 : 2.0 * quarter);
            ASSERT_LE((lay * (sign * Vec3::Unit(l)) - Vec3::UnitZ()).norm(), 1e-15);
            const Quat twist = about(Vec3::UnitZ(), std::numbers::pi * unit(rng));
            const Quat tilt = about(Vec3(unit(rng), unit(rng), 0.0), 2e-5 * unit(rng));
            const Quat qb_rel = tilt * twist * lay;
            const double size = fa.box->half.minCoeff();
            const double press = size * (0.001 + 0.009 * (0.5 + 0.5 * unit(rng)));
            const Vec3 shift(0.8 * fa.box->half.x() * unit(rng), 0.8 * fa.box->half.y() * unit(rng),
                             -(fa.box->half.z() + fb.box->half[l]) + press);
            const Quat g0 = random_turn();
            const Vec3 x0(0.1 * unit(rng), 0.1 * unit(rng), 0.1 * unit(rng));
            pa[q] = {&fa, x0, g0};
            pb[q] = {&fb, x0 + g0 * shift, (g0 * qb_rel).normalized()};
            g::detail::box_pair_lane(lanes, q, fa, pa[q].x, g::unit_rotation_matrix(pa[q].q), fb,
                                     pb[q].x, g::unit_rotation_matrix(pb[q].q));
        }
        g::detail::box_pair_planes(lanes, w);
        for (std::size_t q = 0; q < w; ++q) {
            SCOPED_TRACE("batch " + std::to_string(batch) + " lane " + std::to_string(q));
            ASSERT_EQ(lanes.touching[q], 1);
            const double scale = pa[q].shape->radius + pb[q].shape->radius;
            Vec3 point;
            ASSERT_TRUE(g::detail::box_pair_patch(lanes, q, 1e-24 * scale * scale, point));
            const Vec3 m(lanes.normal_a[0][q], lanes.normal_a[1][q], lanes.normal_a[2][q]);
            const Vec3 general = g::detail::patch_point(pa[q], pb[q], m);
            const double size = pa[q].shape->box->half.minCoeff();
            worst = std::max(worst, (point - general).norm() / size);
            EXPECT_LE((point - general).norm(), 1e-12 * size);
            ++answered;
        }
    }
    EXPECT_EQ(answered, 2000);
    std::printf("%d face-on-face patches; largest difference %.2g of the size\n", answered, worst);
}
