// Two boxes' closed-form common plane in vector lanes (geometry::detail::box_planes,
// src/geometry/box_plane.cpp) against the one-pair closed form (detail::box_plane), and that
// against polyhedron_contact, which runs it: the lanes give the same separation, normal, feature
// and candidate count, bit for bit, lane by lane, for pairs of the shipped boxes (and a box whose
// axes are not its body frame's) in random, near, stacked and edge-on-edge poses, with the lanes
// mixing shapes and poses.

#include "geometry/polyhedron.hpp"
#include "geometry/polyhedron_contact.hpp"
#include "geometry/polyhedron_search.hpp"
#include "io/shape_reader.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <cstddef>
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
