// Common-plane contact of convex polyhedra (geometry/polyhedron_contact.hpp): analytic face-face,
// edge-face and edge-edge cases with their patches, continuity from edge-on to face-on, optimality
// of the plane against sampled directions and against libccd's EPA, pair-order symmetry.

#include "common/fcl_reference.hpp"
#include "geometry/hull.hpp"
#include "geometry/polyhedron.hpp"
#include "geometry/polyhedron_contact.hpp"
#include "geometry/separating_axis.hpp"
#include "io/shape_reader.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <gtest/gtest.h>
#include <numbers>
#include <random>
#include <string>

namespace g = kiln::geometry;
using kiln::Quat;
using kiln::Vec3;

namespace {

constexpr double kPi = std::numbers::pi;
/// Relative tolerance of exact geometry: a few products and one division of O(1) numbers.
constexpr double kExact = 1e-12;
/// EPA's precision: libccd's tolerance of 1e-10 on squared lengths is ~1e-5 of the length scale.
constexpr double kEpa = 2e-5;

g::ConvexPolyhedron load_polyhedron(const std::string& name) {
    const auto t =
        kiln::io::read_shape_file(kiln::io::find_shape_file(name, kiln::io::default_shape_dirs()));
    return std::get<g::ConvexPolyhedron>(t.shape);
}

g::PolyhedronFeatures load(const std::string& name) {
    return g::polyhedron_features(load_polyhedron(name));
}

/// Features in the axes of the template's input file (the cube's faces normal to x, y, z): the
/// body frame of a cube is any principal frame, so its axes are arbitrary.
g::PolyhedronFeatures load_aligned(const std::string& name) {
    g::ConvexPolyhedron p = load_polyhedron(name);
    for (Vec3& v : p.vertices) {
        v = p.template_axes * v;
    }
    return g::polyhedron_features(p);
}

/// Edge length of an axis-aligned cube (m).
double edge_of_cube(const g::PolyhedronFeatures& f) {
    return 2.0 * f.vertices[0].cwiseAbs().maxCoeff();
}

/// Overlap along a normal m from B to A: h_A(-m) + h_B(m) (m).
double overlap_along(const g::PosedPolyhedron& a, const g::PosedPolyhedron& b, const Vec3& m) {
    return b.support(m).dot(m) - a.support(-m).dot(m);
}

/// Largest violation of the face planes of a posed body by a world point (m; <= 0 inside).
double outside(const g::PosedPolyhedron& p, const Vec3& x) {
    const Vec3 xb = p.q.conjugate() * (x - p.x);
    double worst = -std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < p.shape->face_normals.size(); ++k) {
        worst = std::max(worst, p.shape->face_normals[k].dot(xb) - p.shape->face_offsets[k]);
    }
    return worst;
}

Quat about(const Vec3& axis, double angle) {
    return Quat(Eigen::AngleAxisd(angle, axis.normalized()));
}

TEST(PolyhedronContact, FeaturesOfTheShippedShapes) {
    // Cube: 6 planar faces and 12 feature edges (the 6 triangle diagonals dropped).
    const g::PolyhedronFeatures cube = load("cube");
    EXPECT_EQ(cube.face_normals.size(), 6U);
    EXPECT_EQ(cube.edges.size(), 12U);
    const g::PolyhedronFeatures cyl = load("cylinder_16");
    EXPECT_EQ(cyl.face_normals.size(), 18U);
    EXPECT_EQ(cyl.edges.size(), 48U);
    const g::PolyhedronFeatures ico = load("icosahedron");
    EXPECT_EQ(ico.face_normals.size(), 20U);
    EXPECT_EQ(ico.edges.size(), 30U);
}

TEST(PolyhedronContact, FaceOnFaceGivesTheOverlapRectangle) {
    const g::PolyhedronFeatures cube = load_aligned("cube");
    const double l = edge_of_cube(cube);
    const double delta = 0.01 * l;
    const Vec3 shift(0.3 * l, -0.2 * l, l - delta);
    const g::PosedPolyhedron b{&cube, Vec3::Zero(), Quat::Identity()};
    const g::PosedPolyhedron a{&cube, shift, Quat::Identity()};
    const g::PolyhedronContact c = g::polyhedron_contact(a, b);
    ASSERT_TRUE(c.touching);
    EXPECT_NEAR(c.depth, delta, kExact * l);
    EXPECT_NEAR(c.normal.z(), 1.0, kExact);
    const double area = (l - 0.3 * l) * (l - 0.2 * l);
    EXPECT_NEAR(c.patch_area / area, 1.0, kExact);
    // Centroid of the overlap rectangle, on the plane half way through the overlap.
    EXPECT_NEAR(c.point.x(), 0.15 * l, kExact * l);
    EXPECT_NEAR(c.point.y(), -0.1 * l, kExact * l);
    EXPECT_NEAR(c.point.z(), 0.5 * l - 0.5 * delta, kExact * l);
    // A n B is a box: 8 vertices.
    EXPECT_EQ(c.points.size(), 8U);
    EXPECT_EQ(c.patch.size(), 4U);
}

TEST(PolyhedronContact, EdgeOnEdgeGivesTheSquarePatch) {
    // A's edge along x pointing down, B's edge along y pointing up: two 90-degree wedges crossing.
    // Their sections half way through the overlap are strips of half-width delta/2, so the patch
    // is a square of area delta^2.
    const g::PolyhedronFeatures cube = load_aligned("cube");
    const double l = edge_of_cube(cube);
    const double delta = 0.02 * l;
    const g::PosedPolyhedron b{&cube, Vec3::Zero(), about(Vec3::UnitY(), kPi / 4)};
    const g::PosedPolyhedron a{&cube, Vec3(0, 0, std::sqrt(2.0) * l - delta),
                               about(Vec3::UnitX(), kPi / 4)};
    const g::PolyhedronContact c = g::polyhedron_contact(a, b);
    ASSERT_TRUE(c.touching);
    EXPECT_EQ(c.feature, g::CommonPlaneFeature::kEdgeEdge);
    EXPECT_NEAR(c.depth, delta, kExact * l);
    EXPECT_NEAR(c.normal.z(), 1.0, kExact);
    EXPECT_NEAR(c.patch_area / (delta * delta), 1.0, 1e-9);
    EXPECT_NEAR(c.point.norm(), std::abs(c.point.z()), kExact * l);
}

/// What a sweep of cube A from theta = 45 degrees (edge down) to 0 (face down) about x measured.
struct Sweep {
    double worst_point = 0.0;  // largest step of the contact point (m)
    double worst_area = 0.0;   // largest step of the patch area (m^2)
    double worst_normal = 0.0; // largest step of the normal (-)
    double worst_depth = 0.0;  // largest deviation of the overlap from delta (m)
    double worst_width = 0.0;  // largest relative deviation of the strip area (see below)
    double first_area = 0.0;   // patch area at 45 degrees (m^2)
    double last_area = 0.0;    // patch area at 0 (m^2)
    Vec3 last_point = Vec3::Zero();
    bool all_touching = true;
};

/// Turns A in `steps` steps with its lowest point kept delta below `top` (B's highest point).
Sweep sweep(const g::PolyhedronFeatures& cube, const g::PosedPolyhedron& b, double top,
            double delta, int steps) {
    const double l = edge_of_cube(cube);
    const double dtheta = (kPi / 4) / steps;
    Sweep w;
    Vec3 last_normal = Vec3::Zero();
    for (int i = steps; i >= 0; --i) {
        const double th = i * dtheta;
        const double lowest = 0.5 * l * (std::cos(th) + std::sin(th));
        const g::PosedPolyhedron a{&cube, Vec3(0.0, 0.0, top + lowest - delta),
                                   about(Vec3::UnitX(), th)};
        const g::PolyhedronContact c = g::polyhedron_contact(a, b);
        w.all_touching = w.all_touching && c.touching;
        w.worst_depth = std::max(w.worst_depth, std::abs(c.depth - delta));
        if (i < steps) {
            w.worst_point = std::max(w.worst_point, (c.point - w.last_point).norm());
            w.worst_area = std::max(w.worst_area, std::abs(c.patch_area - w.last_area));
            w.worst_normal = std::max(w.worst_normal, (c.normal - last_normal).norm());
        } else {
            w.first_area = c.patch_area;
        }
        // Against a face: the patch is the section of A's wedge at height delta/2 above its edge,
        // a strip of width (delta/2)/(sin theta cos theta), while the plane cuts only the two faces
        // next to the edge.
        const double h = 0.5 * delta;
        if (i > 0 && h < l * std::sin(th)) {
            const double strip = l * h / (std::sin(th) * std::cos(th));
            w.worst_width = std::max(w.worst_width, std::abs(c.patch_area / strip - 1.0));
        }
        w.last_point = c.point;
        w.last_area = c.patch_area;
        last_normal = c.normal;
    }
    return w;
}

TEST(PolyhedronContact, EdgeOnToFaceOnIsContinuous) {
    // Cube A turned by theta about x, from 45 degrees (edge down) to 0 (face down), on cube B,
    // with its lowest point kept delta below B's top face: the overlap must stay delta and the
    // normal +z, and the contact point and patch area must move continuously: their largest step
    // must shrink in proportion when the angular step is halved (a jump would not shrink).
    const g::PolyhedronFeatures cube = load_aligned("cube");
    const double l = edge_of_cube(cube);
    const double delta = 0.01 * l;
    const g::PosedPolyhedron b{&cube, Vec3::Zero(), Quat::Identity()};
    const Sweep coarse = sweep(cube, b, 0.5 * l, delta, 2000);
    const Sweep fine = sweep(cube, b, 0.5 * l, delta, 4000);
    EXPECT_TRUE(fine.all_touching);
    EXPECT_LT(fine.worst_depth, kExact * l);
    EXPECT_LT(fine.worst_normal, kExact);
    EXPECT_LT(fine.worst_width, 1e-9);
    EXPECT_NEAR(fine.last_area / (l * l), 1.0, kExact);
    EXPECT_NEAR(fine.last_point.y(), 0.0, kExact * l);
    // Halving the step must at least nearly halve the largest steps (0.6: first-order margin).
    EXPECT_LT(fine.worst_point, 0.6 * coarse.worst_point);
    EXPECT_LT(fine.worst_area, 0.6 * coarse.worst_area);
    std::printf("edge->face: largest point step %.3g l and %.3g l, area step %.3g l^2 and %.3g "
                "l^2 at 2000 and 4000 steps\n",
                coarse.worst_point / l, fine.worst_point / l, coarse.worst_area / (l * l),
                fine.worst_area / (l * l));
}

TEST(PolyhedronContact, EdgeEdgeToFaceEdgeIsContinuous) {
    // As above, but against B's upward edge (B turned 45 degrees about y): from an edge-edge
    // contact (square patch delta^2) to A's face on B's edge (strip delta x l). The winning
    // candidate changes from an edge pair to A's face at theta = 0 with the same normal.
    const g::PolyhedronFeatures cube = load_aligned("cube");
    const double l = edge_of_cube(cube);
    const double delta = 0.01 * l;
    const g::PosedPolyhedron b{&cube, Vec3::Zero(), about(Vec3::UnitY(), kPi / 4)};
    const Sweep coarse = sweep(cube, b, l / std::sqrt(2.0), delta, 2000);
    const Sweep fine = sweep(cube, b, l / std::sqrt(2.0), delta, 4000);
    EXPECT_TRUE(fine.all_touching);
    EXPECT_LT(fine.worst_depth, kExact * l);
    EXPECT_LT(fine.worst_normal, kExact);
    EXPECT_NEAR(fine.first_area / (delta * delta), 1.0, 1e-9);
    EXPECT_NEAR(fine.last_area / (delta * l), 1.0, 1e-9);
    EXPECT_LT(fine.worst_point, 0.6 * coarse.worst_point);
    EXPECT_LT(fine.worst_area, 0.6 * coarse.worst_area);
}

TEST(PolyhedronContact, SeparatedBodiesAreNotTouching) {
    const g::PolyhedronFeatures cube = load_aligned("cube");
    const double l = edge_of_cube(cube);
    const g::PosedPolyhedron b{&cube, Vec3::Zero(), Quat::Identity()};
    const g::PosedPolyhedron a{&cube, Vec3(0.1 * l, 0.0, 1.05 * l), Quat::Identity()};
    const g::PolyhedronContact c = g::polyhedron_contact(a, b);
    EXPECT_FALSE(c.touching);
    EXPECT_NEAR(c.depth, -0.05 * l, kExact * l); // face-face: the separation is the gap
    const g::PosedPolyhedron far{&cube, Vec3(0.0, 0.0, 3.0 * l), Quat::Identity()};
    EXPECT_FALSE(g::polyhedron_contact(far, b).touching);
}

struct RandomPair {
    g::PosedPolyhedron a;
    g::PosedPolyhedron b;
};

/// Random orientations; B placed so that the supports along a random direction overlap by
/// 1e-4 to 5e-2 of the bounding radius (the MTD is at most that).
RandomPair random_pair(const g::PolyhedronFeatures& fa, const g::PolyhedronFeatures& fb,
                       std::mt19937_64& rng) {
    std::normal_distribution<double> nd;
    std::uniform_real_distribution<double> ud(std::log(1e-4), std::log(5e-2));
    RandomPair p{{&fa, Vec3(nd(rng), nd(rng), nd(rng)) * 1e-3,
                  Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized()},
                 {&fb, Vec3::Zero(), Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized()}};
    const Vec3 u = Vec3(nd(rng), nd(rng), nd(rng)).normalized();
    const double overlap = std::exp(ud(rng)) * std::min(fa.radius, fb.radius);
    p.b.x = p.a.support(u) - overlap * u - (p.b.support(-u) - p.b.x);
    return p;
}

/// 500 directions spread over the sphere (Fibonacci lattice) for a sampled minimum.
std::vector<Vec3> fibonacci_directions() {
    std::vector<Vec3> dirs;
    for (int k = 0; k < 500; ++k) {
        const double z = 1.0 - (2.0 * k + 1.0) / 500.0;
        const double phi = k * kPi * (3.0 - std::sqrt(5.0));
        dirs.emplace_back(std::sqrt(1 - z * z) * std::cos(phi),
                          std::sqrt(1 - z * z) * std::sin(phi), z);
    }
    return dirs;
}

/// The common plane of a touching pair is optimal: its overlap is the overlap along its normal,
/// and neither a sampled direction nor any cross product of two edges (every separating-axis
/// candidate, here without the Gauss-map and distance pruning of polyhedron_contact) has a smaller
/// one.
void expect_optimal(const RandomPair& p, const g::PolyhedronFeatures& fa,
                    const g::PolyhedronFeatures& fb, const std::vector<Vec3>& dirs) {
    const double scale = fa.radius + fb.radius;
    const g::PolyhedronContact c = g::polyhedron_contact(p.a, p.b);
    ASSERT_TRUE(c.touching);
    EXPECT_NEAR(overlap_along(p.a, p.b, c.normal), c.depth, kExact * scale);
    for (const Vec3& d : dirs) {
        ASSERT_GE(overlap_along(p.a, p.b, d), c.depth - kExact * scale);
    }
    for (const auto& ea : fa.edges) {
        const Vec3 da = p.a.q * (fa.vertices[static_cast<std::size_t>(ea[1])] -
                                 fa.vertices[static_cast<std::size_t>(ea[0])]);
        for (const auto& eb : fb.edges) {
            const Vec3 db = p.b.q * (fb.vertices[static_cast<std::size_t>(eb[1])] -
                                     fb.vertices[static_cast<std::size_t>(eb[0])]);
            const Vec3 axis = da.cross(db);
            if (axis.norm() > 1e-9 * da.norm() * db.norm()) {
                ASSERT_GE(overlap_along(p.a, p.b, axis.normalized()), c.depth - kExact * scale);
                ASSERT_GE(overlap_along(p.a, p.b, -axis.normalized()), c.depth - kExact * scale);
            }
        }
    }
}

TEST(PolyhedronContact, PlaneIsOptimalAndAgreesWithEpa) {
    const char* names[] = {"cube",        "cuboid_6x6x5", "plate_10x9x2", "pyramid",
                           "icosahedron", "cylinder_8",   "cylinder_16"};
    std::vector<g::PolyhedronFeatures> shapes;
    for (const char* n : names) {
        shapes.push_back(load(n));
    }
    const std::vector<Vec3> dirs = fibonacci_directions();
    std::mt19937_64 rng(7);
    double worst_epa = 0.0;
    int pairs = 0;
    for (std::size_t i = 0; i < shapes.size(); ++i) {
        for (std::size_t j = 0; j < shapes.size(); ++j) {
            for (int n = 0; n < 10; ++n) {
                const RandomPair p = random_pair(shapes[i], shapes[j], rng);
                const double scale = shapes[i].radius + shapes[j].radius;
                const g::PolyhedronContact c = g::polyhedron_contact(p.a, p.b);
                if (!c.touching) {
                    // Overlapping supports along u need not overlap the bodies at a sharp vertex:
                    // then libccd must find them apart too.
                    EXPECT_FALSE(g::ccd_contact(p.a, p.b, false).touching);
                    continue;
                }
                ++pairs;
                SCOPED_TRACE(std::string(names[i]) + " on " + names[j]);
                expect_optimal(p, shapes[i], shapes[j], dirs);
                // Every contact point and patch corner lies in both bodies.
                for (const Vec3& x : c.points) {
                    EXPECT_LT(outside(p.a, x), 1e-10 * scale);
                    EXPECT_LT(outside(p.b, x), 1e-10 * scale);
                }
                for (const Vec3& x : c.patch) {
                    EXPECT_LT(outside(p.a, x), 1e-10 * scale);
                    EXPECT_LT(outside(p.b, x), 1e-10 * scale);
                }
                // The patch along EPA's (or any given) normal: the same as the plane's own.
                const g::PolyhedronContact along = g::contact_patch_along(p.a, p.b, c.normal);
                EXPECT_NEAR(along.depth, c.depth, kExact * scale);
                EXPECT_NEAR(along.patch_area, c.patch_area, 1e-9 * c.patch_area + 1e-20);
                // (The normal's round trip through the world frame changes it by 1e-16; a plane
                // cutting faces at grazing angles amplifies that: 3.5e-9 of the size was seen.)
                EXPECT_NEAR((along.point - c.point).norm(), 0.0, 1e-7 * scale);
                // Pair order: same overlap, opposite normal.
                const g::PolyhedronContact r = g::polyhedron_contact(p.b, p.a);
                EXPECT_NEAR(r.depth, c.depth, kExact * scale);
                EXPECT_NEAR((r.normal + c.normal).norm(), 0.0, 1e-9);
                EXPECT_NEAR(r.patch_area, c.patch_area, 1e-9 * c.patch_area + 1e-20);
                // EPA approaches the same minimum from below.
                const g::ConvexContact e = g::ccd_contact(p.a, p.b, false);
                if (e.touching && e.converged) {
                    EXPECT_LE(e.depth, c.depth + kExact * scale);
                    EXPECT_NEAR(e.depth, c.depth, kEpa * scale) << names[i] << " " << names[j];
                    worst_epa = std::max(worst_epa, std::abs(e.depth - c.depth) / scale);
                }
            }
        }
    }
    std::printf("%d pairs: largest |EPA - common plane| = %.3g of r_A + r_B\n", pairs, worst_epa);
}

using kiln::test::fcl_contact;
using kiln::test::FclPath;
using kiln::test::to_fcl;

TEST(PolyhedronContact, AgreesWithFcl) {
    // FCL's signed distance (GJK + EPA) must agree to EPA precision and never exceed the common
    // plane's MTD; FCL's collide (MPR) must never be shallower than it (MPR is an upper bound).
    const char* names[] = {"cube", "pyramid", "icosahedron", "cylinder_16"};
    std::mt19937_64 rng(11);
    int compared = 0;
    double worst_indep = 0.0;
    double worst_mpr = 0.0;
    int missed = 0;
    for (const char* na : names) {
        for (const char* nb : names) {
            const g::ConvexPolyhedron pa = load_polyhedron(na);
            const g::ConvexPolyhedron pb = load_polyhedron(nb);
            const g::PolyhedronFeatures fa = g::polyhedron_features(pa);
            const g::PolyhedronFeatures fb = g::polyhedron_features(pb);
            const double unit = fa.radius + fb.radius;
            const auto sa = to_fcl(pa, unit);
            const auto sb = to_fcl(pb, unit);
            for (int n = 0; n < 10; ++n) {
                const RandomPair p = random_pair(fa, fb, rng);
                const g::PolyhedronContact c = g::polyhedron_contact(p.a, p.b, false);
                if (!c.touching) {
                    continue; // apart (sharp vertex); compared in PlaneIsOptimalAndAgreesWithEpa
                }
                const g::ConvexContact f =
                    fcl_contact(sa, p.a, sb, p.b, unit, FclPath::kSignedDistance);
                ++compared;
                if (!f.touching) {
                    ++missed; // FCL's GJK missed the overlap (counted, see below)
                } else {
                    EXPECT_NEAR(f.depth, c.depth, kEpa * unit) << na << " " << nb;
                    EXPECT_LE(f.depth, c.depth + kExact * unit) << na << " " << nb;
                    worst_indep = std::max(worst_indep, std::abs(f.depth - c.depth) / unit);
                }
                const g::ConvexContact m = fcl_contact(sa, p.a, sb, p.b, unit, FclPath::kMpr);
                if (!m.touching) {
                    ++missed;
                } else {
                    EXPECT_GE(m.depth, c.depth - kExact * unit) << na << " " << nb;
                    worst_mpr = std::max(worst_mpr, (m.depth - c.depth) / unit);
                }
            }
        }
    }
    std::printf("%d pairs: largest |FCL EPA - CP| %.3g, FCL MPR deeper by up to %.3g, of r_A + "
                "r_B; FCL missed %d overlaps\n",
                compared, worst_indep, worst_mpr, missed);
    // A reference that misses overlaps is reported, not trusted: at most 5 % of the queries (two
    // per pair).
    EXPECT_LE(missed, compared / 10);
}

TEST(PolyhedronContact, ManyEdgedRandomHullsStayOptimal) {
    // Hulls of 26 random points (as Yade's random polyhedra, bench/yade): ~70 feature edges each,
    // where the edge stage drops most edges by their distance from the other body. The plane
    // must stay the optimum over all edge pairs, unpruned, and over sampled directions.
    std::mt19937_64 rng(19);
    std::normal_distribution<double> nd;
    std::vector<g::PolyhedronFeatures> shapes;
    for (int k = 0; k < 4; ++k) {
        std::vector<Vec3> pts;
        for (int i = 0; i < 26; ++i) {
            pts.push_back(Vec3(nd(rng), nd(rng), nd(rng)).normalized() * 4e-3 *
                          (0.6 + 0.4 * std::abs(nd(rng)) / (1.0 + std::abs(nd(rng)))));
        }
        const g::Hull h = g::convex_hull(pts, "random hull");
        shapes.push_back(g::polyhedron_features(g::make_polyhedron(h.vertices, h.faces, "hull")));
        EXPECT_GT(shapes.back().edges.size(), 30U);
    }
    const std::vector<Vec3> dirs = fibonacci_directions();
    int pairs = 0;
    int edge_edge = 0;
    for (std::size_t i = 0; i < shapes.size(); ++i) {
        for (std::size_t j = 0; j < shapes.size(); ++j) {
            for (int n = 0; n < 25; ++n) {
                const RandomPair p = random_pair(shapes[i], shapes[j], rng);
                const g::PolyhedronContact c = g::polyhedron_contact(p.a, p.b);
                if (!c.touching) {
                    continue;
                }
                ++pairs;
                edge_edge += c.feature == g::CommonPlaneFeature::kEdgeEdge ? 1 : 0;
                SCOPED_TRACE("hull " + std::to_string(i) + " on hull " + std::to_string(j));
                expect_optimal(p, shapes[i], shapes[j], dirs);
            }
        }
    }
    std::printf("%d touching pairs, %d with an edge-edge plane\n", pairs, edge_edge);
    EXPECT_GT(pairs, 200); // most of the 400 placements overlap
}

/// Margin of the separation proofs, relative to the sum of the bounding radii (as body_contact).
constexpr double kProofMargin = 1e-10;
/// A gap the portal search must find: 1e-3 of the size, far from the round-off and the margin.
constexpr double kClearGap = 1e-3;

/// Pose pairs near contact: random orientations, B's centre at 0.5 to 1.05 times the sum of the
/// bounding radii from A's in a random direction (overlapping, near misses and clear gaps).
template <class Body> std::pair<Body, Body> near_pair(Body a, Body b, std::mt19937_64& rng) {
    std::normal_distribution<double> nd;
    std::uniform_real_distribution<double> ud(0.5, 1.05);
    a.q = Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized();
    b.q = Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized();
    a.x = Vec3(nd(rng), nd(rng), nd(rng)) * 1e-3;
    b.x = a.x + ud(rng) * (a.length_scale() + b.length_scale()) *
                    Vec3(nd(rng), nd(rng), nd(rng)).normalized();
    return {a, b};
}

TEST(PolyhedronContact, PatchOnDemandGivesTheSameNumbers) {
    // The overload with a patch test gives the depth, normal and feature of the full query bit for
    // bit, whatever the test answers, and the full result when it asks for the patch.
    std::mt19937_64 rng(31);
    for (const std::string name : {"cube", "icosahedron", "cylinder_16"}) {
        SCOPED_TRACE(name);
        const g::PolyhedronFeatures f = load(name);
        int touching = 0;
        for (int n = 0; n < 300; ++n) {
            const RandomPair p = random_pair(f, f, rng);
            const g::PolyhedronContact full = g::polyhedron_contact(p.a, p.b, true);
            for (const bool want : {false, true}) {
                const g::PolyhedronContact lazy = g::polyhedron_contact(
                    p.a, p.b, [&](const g::PolyhedronContact&) { return want; });
                ASSERT_EQ(lazy.touching, full.touching);
                ASSERT_EQ(lazy.depth, full.depth); // exact equality is the point
                ASSERT_EQ(lazy.normal, full.normal);
                ASSERT_EQ(lazy.feature, full.feature);
                if (want) {
                    ASSERT_EQ(lazy.point, full.point);
                    ASSERT_EQ(lazy.patch_area, full.patch_area);
                    ASSERT_EQ(lazy.patch.size(), full.patch.size());
                }
            }
            touching += full.touching ? 1 : 0;
        }
        EXPECT_GT(touching, 250); // random_pair overlaps along a direction: most pairs touch
    }
}

/// Expects two results of the common plane to be the same numbers, bit for bit.
void expect_same_bits(const g::PolyhedronContact& x, const g::PolyhedronContact& y) {
    ASSERT_EQ(x.touching, y.touching);
    ASSERT_EQ(x.converged, y.converged);
    ASSERT_EQ(x.depth, y.depth); // exact equality is the point
    ASSERT_EQ(x.normal, y.normal);
    ASSERT_EQ(x.feature, y.feature);
    ASSERT_EQ(x.iterations, y.iterations);
    ASSERT_EQ(x.point, y.point);
    ASSERT_EQ(x.patch_area, y.patch_area);
    ASSERT_EQ(x.points, y.points);
    ASSERT_EQ(x.patch, y.patch);
}

TEST(PolyhedronContact, FaceBoundsChangeNoBit) {
    // The bounded face stages skip the faces whose upper bound (inscribed ball of the other body)
    // cannot beat the largest separation found; the prune and the certificates read the
    // distances on demand. Against the full tables: the same result, bit for bit, for every
    // shipped polyhedron pair near contact (overlapping, near misses and clear gaps) and for
    // random hulls of many faces.
    std::mt19937_64 rng(47);
    std::vector<g::PolyhedronFeatures> shapes;
    for (const std::string name :
         {"cube", "icosahedron", "cylinder_16", "cylinder_8", "pyramid", "plate_10x9x2"}) {
        shapes.push_back(load(name));
    }
    std::normal_distribution<double> nd;
    for (int k = 0; k < 2; ++k) {
        std::vector<Vec3> pts;
        for (int i = 0; i < 40; ++i) {
            pts.push_back(Vec3(nd(rng), nd(rng), nd(rng)).normalized() * 4e-3);
        }
        const g::Hull h = g::convex_hull(pts, "random hull");
        shapes.push_back(g::polyhedron_features(g::make_polyhedron(h.vertices, h.faces, "hull")));
    }
    int touching = 0;
    int apart = 0;
    for (std::size_t i = 0; i < shapes.size(); ++i) {
        for (std::size_t j = 0; j < shapes.size(); ++j) {
            SCOPED_TRACE(std::to_string(i) + " on " + std::to_string(j));
            for (int n = 0; n < 60; ++n) {
                const RandomPair p = n % 2 == 0 ? random_pair(shapes[i], shapes[j], rng) : [&] {
                    const auto q = near_pair(g::PosedPolyhedron{&shapes[i]},
                                             g::PosedPolyhedron{&shapes[j]}, rng);
                    return RandomPair{q.first, q.second};
                }();
                const g::PolyhedronContact fast =
                    g::detail::polyhedron_contact_with(p.a, p.b, g::detail::FaceScan::bounded);
                const g::PolyhedronContact full =
                    g::detail::polyhedron_contact_with(p.a, p.b, g::detail::FaceScan::full);
                expect_same_bits(fast, full);
                if (!shapes[i].box || !shapes[j].box) { // (two boxes: a closed form instead)
                    expect_same_bits(g::polyhedron_contact(p.a, p.b, true), full);
                }
                touching += full.touching ? 1 : 0;
                apart += full.touching ? 0 : 1;
            }
        }
    }
    std::printf("%d touching pairs, %d apart\n", touching, apart);
    EXPECT_GT(touching, 1000);
    EXPECT_GT(apart, 300);
}

/// Expects the memory's result to be the full search's, bit for bit (all but the count of
/// candidates, which is what the memory saves).
void expect_same_answer(const g::PolyhedronContact& x, const g::PolyhedronContact& y) {
    g::PolyhedronContact z = x;
    z.iterations = y.iterations;
    expect_same_bits(z, y);
}

/// A random rotation by an angle of at most `angle` (rad).
Quat small_turn(double angle, std::mt19937_64& rng) {
    std::normal_distribution<double> nd;
    std::uniform_real_distribution<double> ud(0.0, angle);
    return Quat(Eigen::AngleAxisd(ud(rng), Vec3(nd(rng), nd(rng), nd(rng)).normalized()));
}

/// A shipped polyhedron with its vertices turned by a fixed rotation (the same solid, its faces
/// no longer along the body frame's axes).
g::ConvexPolyhedron turned_polyhedron(const std::string& name) {
    g::ConvexPolyhedron p = load_polyhedron(name);
    const kiln::Mat3 turn = Quat(0.9, 0.3, -0.2, 0.25).normalized().toRotationMatrix();
    for (Vec3& v : p.vertices) {
        v = turn * v;
    }
    return p;
}

TEST(PolyhedronContact, BoxesAreFoundAndOnlyBoxes) {
    // The closed form for two boxes (box_plane) is taken only for boxes: the cube, the cuboid
    // and the plate are found (with their half extents) with their axes as the body frame's
    // (`aligned`: their meshes are drawn axis-aligned), the cuboid turned by a rotation is found
    // with its own axes, the other shipped polyhedra and a box sheared by 1e-6 are not.
    std::vector<std::pair<g::PolyhedronFeatures, bool>> boxes;
    for (const std::string name : {"cube", "cuboid_6x6x5", "plate_10x9x2"}) {
        boxes.emplace_back(load(name), true);
    }
    boxes.emplace_back(g::polyhedron_features(turned_polyhedron("cuboid_6x6x5")), false);
    for (const auto& [f, aligned] : boxes) {
        ASSERT_TRUE(f.box.has_value());
        EXPECT_EQ(f.box->aligned, aligned);
        if (aligned) {
            EXPECT_EQ(f.box->axes, kiln::Mat3::Identity());
        }
        // Every vertex is a corner: its heights along the axes are the half extents.
        for (const Vec3& v : f.vertices) {
            EXPECT_NEAR((f.box->axes.transpose() * v).cwiseAbs().maxCoeff() -
                            (f.box->axes.transpose() * v).cwiseAbs().minCoeff(),
                        f.box->half.maxCoeff() - f.box->half.minCoeff(), 1e-12 * f.radius);
        }
        for (int i = 0; i < 3; ++i) {
            EXPECT_NEAR(
                (f.face_normals[static_cast<std::size_t>(f.box->plus[i])] - f.box->axes.col(i))
                    .norm(),
                0.0, 1e-12);
            EXPECT_NEAR(
                (f.face_normals[static_cast<std::size_t>(f.box->minus[i])] + f.box->axes.col(i))
                    .norm(),
                0.0, 1e-12);
        }
    }
    // The cuboid's half extents along e_x, e_y, e_z in its mesh: 3, 3 and 2.5 mm.
    EXPECT_NEAR((boxes[1].first.box->half - Vec3(3e-3, 3e-3, 2.5e-3)).norm(), 0.0, 1e-15);
    for (const std::string name : {"pyramid", "icosahedron", "cylinder_8", "cylinder_16"}) {
        EXPECT_FALSE(load(name).box.has_value()) << name;
    }
    g::ConvexPolyhedron sheared = load_polyhedron("cube");
    for (Vec3& v : sheared.vertices) {
        v.x() += 1e-6 * v.z();
    }
    EXPECT_FALSE(g::polyhedron_features(sheared).box.has_value());
}

TEST(PolyhedronContact, BoxPairsAgreeWithTheGeneralSearch) {
    // Two boxes take the closed-form separating-axis test (box_plane) instead of the general
    // search (Gauss-map pruned edge pairs): the same optimum by another expression, so the same
    // number to round-off. Against the general search (FaceScan::full) on random pairs, pairs
    // near contact, and stacks of aligned boxes turned by 1e-12 to 1e-3 rad (nearly parallel
    // edges, where the edge directions come from differences of nearly equal numbers): the same
    // touching/apart verdict, the same overlap to 1e-12 of the size (kExact), and a normal
    // along which the overlap is that overlap (where two planes tie, either serves).
    std::mt19937_64 rng(61);
    std::vector<g::PolyhedronFeatures> shapes;
    for (const std::string name : {"cube", "cuboid_6x6x5", "plate_10x9x2"}) {
        shapes.push_back(load(name));
    }
    // A box whose axes are not its body frame's (turned before box_plane), alone and against the
    // aligned ones.
    shapes.push_back(g::polyhedron_features(turned_polyhedron("cuboid_6x6x5")));
    std::normal_distribution<double> nd;
    std::uniform_real_distribution<double> log_turn(std::log(1e-12), std::log(1e-3));
    int touching = 0;
    int apart = 0;
    int edge_planes = 0;
    int stacked = 0;
    double worst = 0.0;
    for (std::size_t i = 0; i < shapes.size(); ++i) {
        for (std::size_t j = 0; j < shapes.size(); ++j) {
            SCOPED_TRACE(std::to_string(i) + " on " + std::to_string(j));
            for (int n = 0; n < 300; ++n) {
                RandomPair p = n % 3 == 0 ? random_pair(shapes[i], shapes[j], rng) : [&] {
                    const auto q = near_pair(g::PosedPolyhedron{&shapes[i]},
                                             g::PosedPolyhedron{&shapes[j]}, rng);
                    return RandomPair{q.first, q.second};
                }();
                if (n % 3 == 2) {
                    // B on top of A, both boxes' axes along A's up to a small turn.
                    const g::PolyhedronFeatures::Box& ba = *shapes[i].box;
                    const g::PolyhedronFeatures::Box& bb = *shapes[j].box;
                    p.a.q = Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized();
                    const kiln::Mat3 turn =
                        small_turn(std::exp(log_turn(rng)), rng).toRotationMatrix();
                    const kiln::Mat3 rot_b =
                        p.a.q.toRotationMatrix() * ba.axes * turn * bb.axes.transpose();
                    p.b.q = Quat(rot_b).normalized();
                    const Vec3 up = p.a.q * Vec3(ba.axes.col(2));
                    const double gap = (n % 2 == 0 ? -1.0 : 1.0) * 1e-3 * std::exp(nd(rng)) *
                                       (ba.half.z() + bb.half.z());
                    p.b.x = p.a.x + (ba.half.z() + bb.half.z() + gap) * up +
                            p.a.q * (ba.axes * Vec3(nd(rng), nd(rng), 0.0) * 0.3 *
                                     std::min(ba.half.x(), bb.half.x()));
                    ++stacked;
                }
                const double scale = shapes[i].radius + shapes[j].radius;
                const g::PolyhedronContact fast = g::polyhedron_contact(p.a, p.b, false);
                const g::PolyhedronContact full =
                    g::detail::polyhedron_contact_with(p.a, p.b, g::detail::FaceScan::full, false);
                const double margin = kExact * scale;
                if (std::abs(full.depth) > margin) {
                    ASSERT_EQ(fast.touching, full.touching) << n;
                }
                if (!full.touching) {
                    // Apart: a separating direction where a plane was searched (not where the
                    // bounding spheres are apart), and depth minus a lower bound of the gap.
                    if (fast.feature != g::CommonPlaneFeature::kNone) {
                        EXPECT_NEAR(g::polyhedron_overlap_along(p.a, p.b, fast.normal), fast.depth,
                                    margin)
                            << n;
                    }
                    EXPECT_LT(fast.depth, margin) << n;
                    ++apart;
                    continue;
                }
                ++touching;
                edge_planes += fast.feature == g::CommonPlaneFeature::kEdgeEdge ? 1 : 0;
                EXPECT_NEAR(fast.depth, full.depth, margin) << n;
                EXPECT_NEAR(g::polyhedron_overlap_along(p.a, p.b, fast.normal), full.depth, margin)
                    << n;
                worst = std::max(worst, std::abs(fast.depth - full.depth) / scale);
            }
        }
    }
    // Edge on edge, nearly parallel: A with an edge up (turned 45 deg about its x axis), B with an
    // edge down (likewise), turned about the vertical by 1e-10 to 1e-2 rad and shifted sideways
    // within the crossing. The two 45 deg faces of each side nearly tie, and the thin face of the
    // Minkowski difference spanned by the two edges (its width of the order of the angle) is the
    // optimum in many of these poses: where the closed form's parallel-edge cut matters.
    int crossing = 0;
    int reference_off = 0; // poses where the general search's own value is off (see below)
    std::uniform_real_distribution<double> log_angle(std::log(1e-10), std::log(1e-2));
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (int n = 0; n < 2000; ++n) {
        const g::PolyhedronFeatures& fa = shapes[static_cast<std::size_t>(n) % shapes.size()];
        const g::PolyhedronFeatures& fb =
            shapes[(static_cast<std::size_t>(n) / shapes.size()) % shapes.size()];
        const g::PolyhedronFeatures::Box& ba = *fa.box;
        const g::PolyhedronFeatures::Box& bb = *fb.box;
        const double angle = std::exp(log_angle(rng));
        const kiln::Mat3 ra = about(Vec3::UnitX(), 0.25 * kPi).toRotationMatrix();
        const kiln::Mat3 rb =
            (about(Vec3::UnitZ(), angle) * about(Vec3::UnitX(), 0.25 * kPi)).toRotationMatrix();
        RandomPair p{{&fa, Vec3::Zero(), Quat(ra * ba.axes.transpose()).normalized()},
                     {&fb, Vec3::Zero(), Quat(rb * bb.axes.transpose()).normalized()}};
        // Heights of A's top edge and B's bottom edge from the supports along z.
        const double top_a = p.a.support(Vec3::UnitZ()).z();
        const double low_b = p.b.support(-Vec3::UnitZ()).z();
        const double reach = std::min(ba.half.x(), bb.half.x());
        p.b.x = Vec3(0.0, 0.5 * unit(rng) * reach * std::tan(angle),
                     top_a - low_b - 1e-3 * std::exp(nd(rng)) * reach);
        const double scale = fa.radius + fb.radius;
        const g::PolyhedronContact fast = g::polyhedron_contact(p.a, p.b, false);
        const g::PolyhedronContact full =
            g::detail::polyhedron_contact_with(p.a, p.b, g::detail::FaceScan::full, false);
        ASSERT_EQ(fast.touching, full.touching) << n;
        if (!full.touching) {
            continue;
        }
        crossing += full.feature == g::CommonPlaneFeature::kEdgeEdge ? 1 : 0;
        const double margin = kExact * scale;
        // The closed form's overlap is the overlap along its own normal (a vertex scan, exact to
        // round-off of the size) and no larger than along the general search's normal.
        const double along_fast = g::polyhedron_overlap_along(p.a, p.b, fast.normal);
        EXPECT_NEAR(fast.depth, along_fast, margin) << n << " angle " << angle;
        EXPECT_LE(fast.depth, g::polyhedron_overlap_along(p.a, p.b, full.normal) + margin) << n;
        if (std::abs(fast.depth - full.depth) > margin) {
            // The general search's edge-edge value comes from cross products of edge vectors
            // (differences of vertex positions): for edges 1e-8 rad from parallel its direction
            // carries a relative error of ~1e-16 / 1e-8, and its depth an error of ~1e-12 of the
            // size. Where the two differ, it is the general search's value that disagrees with
            // the overlap along its own normal.
            EXPECT_GT(std::abs(full.depth - g::polyhedron_overlap_along(p.a, p.b, full.normal)),
                      margin)
                << n << " angle " << angle;
            EXPECT_EQ(full.feature, g::CommonPlaneFeature::kEdgeEdge) << n;
            ++reference_off;
            continue;
        }
        worst = std::max(worst, std::abs(fast.depth - full.depth) / scale);
    }
    std::printf("%d touching (%d on an edge-edge plane), %d apart, %d stacked, %d crossing on an "
                "edge-edge plane (%d where the general search's value is off its own normal's "
                "overlap); largest |depth - general| = %.3g of r_A + r_B elsewhere\n",
                touching, edge_planes, apart, stacked, crossing, reference_off, worst);
    // How often the general search is off depends on how the compiler rounds its cross
    // products (6 of 158 crossing poses in the Release build, 40 of 176 in the sanitizer build);
    // the direct comparison must still cover many crossing poses.
    EXPECT_GT(crossing - reference_off, 100);
    EXPECT_GT(crossing, 100);
    EXPECT_GT(touching, 1000);
    EXPECT_GT(apart, 300);
    EXPECT_GT(edge_planes, 100);
}

TEST(PolyhedronContact, NearBandListsTheVerticesNearEachSupport) {
    // The lists of NearBand (the vertices within a band of each body's support plane, from the
    // plane's own heights in A's frame) against the same lists from world-frame heights, for the
    // shipped polyhedra and random touching pairs, with the band at 2 % of the depth (the run's)
    // and at 50 % (many vertices): the same vertices in the same order at the same positions (to
    // 1e-14 of the size: the same expression, which GCC may fuse differently in another
    // function), the weights within 1e-13 of the size over the band (the heights differ by
    // round-off, far below 1e-13 of the size; the bands of the shallowest pairs are 1e-9 of it).
    // A vertex within 1e-12 of the size of the band's edge may be in one list and not the other.
    std::mt19937_64 rng(67);
    std::vector<g::PolyhedronFeatures> shapes;
    for (const std::string name :
         {"cube", "icosahedron", "cylinder_16", "pyramid", "plate_10x9x2"}) {
        shapes.push_back(load(name));
    }
    const auto reference = [](const g::PosedPolyhedron& p, const Vec3& d, double band, double scale,
                              g::NearVertices& out, int& edge) {
        out.clear();
        double top = -std::numeric_limits<double>::infinity();
        for (const Vec3& v : p.shape->vertices) {
            top = std::max(top, d.dot(p.x + p.q * v));
        }
        for (const Vec3& v : p.shape->vertices) {
            const Vec3 x = p.x + p.q * v;
            const double below = top - d.dot(x);
            if (std::abs(below - band) < 1e-12 * scale) {
                ++edge; // too near the band's edge to compare
            }
            if (below < band) {
                out.emplace_back(x, 1.0 - below / band);
            }
        }
    };
    int compared = 0;
    int many = 0;
    int edge = 0;
    for (const double fraction : {0.02, 0.5}) {
        for (std::size_t i = 0; i < shapes.size(); ++i) {
            for (std::size_t j = 0; j < shapes.size(); ++j) {
                SCOPED_TRACE(std::to_string(i) + " on " + std::to_string(j));
                for (int n = 0; n < 60; ++n) {
                    const RandomPair p = random_pair(shapes[i], shapes[j], rng);
                    g::NearVertices va;
                    g::NearVertices vb;
                    const g::NearBand near{fraction, &va, &vb};
                    bool called = false;
                    const g::PatchTest need = [&](const g::PolyhedronContact& c) {
                        called = c.touching;
                        return false;
                    };
                    const g::PolyhedronContact c =
                        g::polyhedron_contact_point(p.a, p.b, need, nullptr, &near);
                    if (!c.touching) {
                        continue;
                    }
                    ASSERT_TRUE(called);
                    const double scale = shapes[i].radius + shapes[j].radius;
                    const double band = fraction * c.depth;
                    int at_edge = 0;
                    g::NearVertices ra;
                    g::NearVertices rb;
                    reference(p.a, -c.normal, band, scale, ra, at_edge);
                    reference(p.b, c.normal, band, scale, rb, at_edge);
                    if (at_edge > 0) {
                        edge += at_edge;
                        continue;
                    }
                    for (const auto& [got, want] : {std::pair{&va, &ra}, std::pair{&vb, &rb}}) {
                        ASSERT_EQ(got->size(), want->size()) << n;
                        for (std::size_t k = 0; k < got->size(); ++k) {
                            EXPECT_NEAR(((*got)[k].first - (*want)[k].first).norm(), 0.0,
                                        1e-14 * scale)
                                << n;
                            EXPECT_NEAR((*got)[k].second, (*want)[k].second, 1e-13 * scale / band)
                                << n;
                        }
                    }
                    ++compared;
                    many += va.size() + vb.size() > 4 ? 1 : 0;
                }
            }
        }
    }
    std::printf("%d touching pairs compared (%d with more than four vertices in the bands), %d "
                "vertices at a band's edge\n",
                compared, many, edge);
    EXPECT_GT(compared, 1000);
    EXPECT_GT(many, 100);
}

/// The trajectories of MemoryChangesNoBit with the memory listing `listed` faces of each body
/// (detail::memo_listed_faces), each memory query after one of the pair the other way round when
/// `scramble`; returns the counters' change over them and the number of touching queries.
struct MemoryRun {
    g::PlaneMemoCounters n; // the counters' change
    int touching = 0;       // queries whose pair touched
};
MemoryRun memory_trajectories(int listed, bool scramble) {
    // A pair's memory of its last search (PlaneMemo) along random trajectories of touching pairs:
    // steps of 1e-8 to 3e-3 of the size, translation and rotation, so that the memory is read
    // with tight and loose bounds, refilled when the pair has moved too far, and meets pairs that
    // come apart. Every answer equals the full search's bit for bit (normal, depth, feature,
    // point, points, patch), with the patch asked for and not; the aligned cube stacks give
    // face-on-face contacts with near ties. The same through polyhedron_contact_point (its own
    // memory), which leaves the points and the patch polygon empty.
    const int listed_before = g::detail::memo_listed_faces();
    g::detail::memo_listed_faces() = listed;
    std::mt19937_64 rng(53);
    std::vector<g::PolyhedronFeatures> shapes;
    for (const std::string name :
         {"cube", "icosahedron", "cylinder_16", "cylinder_8", "pyramid", "plate_10x9x2"}) {
        shapes.push_back(load(name));
    }
    std::normal_distribution<double> nd;
    std::uniform_real_distribution<double> step(std::log(1e-8), std::log(3e-3));
    const g::PlaneMemoCounters before = g::plane_memo_counters();
    int touching = 0;
    for (std::size_t i = 0; i < shapes.size(); ++i) {
        for (std::size_t j = 0; j < shapes.size(); ++j) {
            SCOPED_TRACE(std::to_string(i) + " on " + std::to_string(j));
            for (int n = 0; n < 16; ++n) {
                RandomPair p = random_pair(shapes[i], shapes[j], rng);
                if (i == 0 && j == 0 && n < 4) { // aligned cubes, B on A's top face, shifted
                    p.a.q = Quat::Identity();
                    p.b.q = small_turn(1e-9, rng);
                    p.b.x = p.a.x + Vec3(1e-3 * nd(rng), 1e-3 * nd(rng),
                                         2.0 * shapes[0].inradius - 1e-6 * (n + 1));
                }
                g::PlaneMemo memo;
                g::PlaneMemo memo_point; // the same trajectory through polyhedron_contact_point
                for (int t = 0; t < 40; ++t) {
                    const double size = shapes[i].radius + shapes[j].radius;
                    const double s = std::exp(step(rng));
                    p.b.x += s * size * Vec3(nd(rng), nd(rng), nd(rng)).normalized();
                    p.a.q = (small_turn(s, rng) * p.a.q).normalized();
                    p.b.q = (small_turn(s, rng) * p.b.q).normalized();
                    const bool want = t % 3 != 0;
                    const g::PatchTest need = [want](const g::PolyhedronContact&) { return want; };
                    const g::PolyhedronContact full = g::polyhedron_contact(p.a, p.b, need);
                    // With `scramble`, each memory query after a query of the pair the other way
                    // round, which leaves the search's scratch (per thread) holding the other
                    // body's planes: the memory turns only the planes it reads, and must not read
                    // stale ones.
                    if (scramble) {
                        static_cast<void>(g::polyhedron_contact(p.b, p.a, need));
                    }
                    expect_same_answer(g::polyhedron_contact(p.a, p.b, need, memo), full);
                    // Without the points and the patch polygon: the rest the same bits.
                    if (scramble) {
                        static_cast<void>(g::polyhedron_contact(p.b, p.a, need));
                    }
                    g::PolyhedronContact point =
                        g::polyhedron_contact_point(p.a, p.b, need, &memo_point);
                    EXPECT_TRUE(point.points.empty() && point.patch.empty());
                    point.points = full.points;
                    point.patch = full.patch;
                    expect_same_answer(point, full);
                    touching += full.touching ? 1 : 0;
                }
            }
        }
    }
    g::detail::memo_listed_faces() = listed_before;
    const g::PlaneMemoCounters& after = g::plane_memo_counters();
    std::printf("%d faces listed: %d touching, memory tried %ld, answered %ld (%ld on a face "
                "beyond its list, %ld certified by the overlap held), refilled %ld\n",
                listed, touching, after.tried - before.tried, after.answered - before.answered,
                after.unlisted - before.unlisted, after.held - before.held,
                after.refills - before.refills);
    EXPECT_GT(touching, 10000);
    return {{after.tried - before.tried, after.answered - before.answered,
             after.refills - before.refills, after.unlisted - before.unlisted,
             after.held - before.held},
            touching};
}

TEST(PolyhedronContact, MemoryChangesNoBit) {
    const MemoryRun run = memory_trajectories(g::PlaneMemo::kTopFaces, true);
    const g::PlaneMemoCounters& n = run.n;
    // The memory's route is exercised, not only the fallback; and both of its certificates of
    // overlap: the overlap held since the last query, and a vertex or an edge tested.
    EXPECT_GT(n.answered, run.touching / 2);
    EXPECT_GT(n.held, n.answered / 10);
    EXPECT_GT(n.answered - n.held, 500);
    // Whether the memory answers or hands over to the full search (its certificates of overlap
    // read B's planes too) does not depend on what the scratch held before either.
    const g::PlaneMemoCounters fresh = memory_trajectories(g::PlaneMemo::kTopFaces, false).n;
    EXPECT_EQ(n.tried, fresh.tried);
    EXPECT_EQ(n.answered, fresh.answered);
    EXPECT_EQ(n.refills, fresh.refills);
    EXPECT_EQ(n.held, fresh.held);
}

TEST(PolyhedronContact, MemoryFollowsPairsPullingApart) {
    // Resting pairs pulled apart along their normal in steps of a tenth of the starting overlap,
    // with a small turn each step, until they part: every answer of the memory is the full
    // search's bit for bit, most of them certified by the overlap held since the last one
    // (PlaneMemo::last_answer), and none has the pair touching once the full search has it apart.
    // (Pulled along the normal, a face plane separates the parted pairs, which the memory's face
    // stage sees before any certificate; a certificate that held too long is caught by the random
    // trajectories of MemoryChangesNoBit, where it fails.)
    std::mt19937_64 rng(61);
    std::vector<g::PolyhedronFeatures> shapes;
    for (const std::string name : {"icosahedron", "cylinder_16", "pyramid"}) {
        shapes.push_back(load(name));
    }
    const g::PlaneMemoCounters before = g::plane_memo_counters();
    int parted = 0;
    for (const g::PolyhedronFeatures& fa : shapes) {
        for (const g::PolyhedronFeatures& fb : shapes) {
            for (int n = 0; n < 8; ++n) {
                RandomPair p = random_pair(fa, fb, rng);
                const g::PatchTest need = [](const g::PolyhedronContact&) { return false; };
                const g::PolyhedronContact start = g::polyhedron_contact(p.a, p.b, need);
                ASSERT_TRUE(start.touching);
                const double step = 0.1 * start.depth;
                g::PlaneMemo memo;
                static_cast<void>(g::polyhedron_contact(p.a, p.b, need, memo)); // fills it
                for (int t = 0; t < 40; ++t) {
                    p.b.x -= step * start.normal; // along the normal from B to A: apart
                    p.b.q = (small_turn(1e-3 * step / fb.radius, rng) * p.b.q).normalized();
                    const g::PolyhedronContact full = g::polyhedron_contact(p.a, p.b, need);
                    const g::PolyhedronContact mem = g::polyhedron_contact(p.a, p.b, need, memo);
                    expect_same_answer(mem, full);
                    if (!full.touching) {
                        EXPECT_FALSE(mem.touching);
                        ++parted;
                        break;
                    }
                }
            }
        }
    }
    const g::PlaneMemoCounters& after = g::plane_memo_counters();
    std::printf("%d pairs parted; memory answered %ld, %ld certified by the overlap held\n", parted,
                after.answered - before.answered, after.held - before.held);
    EXPECT_EQ(parted, 72);
    EXPECT_GT(after.held - before.held, 72 * 4);
}

TEST(PolyhedronContact, MemoryWithAShortListChangesNoBit) {
    // The memory lists the faces of the largest stored separations first and searches the others
    // only when their bound reaches the answer; with the default list the plane is almost always
    // a listed face (the faces' separations move by at most the drift since the refill). With one
    // face listed the faces beyond decide often, and the answers stay the full search's.
    const MemoryRun run = memory_trajectories(1, true);
    EXPECT_GT(run.n.answered, run.touching / 2);
    EXPECT_GT(run.n.unlisted, 100);
}

TEST(SeparatingAxis, BoxSupportIsTheScansVertex) {
    // A box's support from the signs of the direction along its axes: the vertex the scan of
    // every vertex (farthest_vertex) returns, for random directions and for directions near a
    // face or an edge (components of 0, 1e-15 and 1e-9), where the closed form hands over to
    // the scan. Boxes in the principal frame (axes turned) and in the file's (aligned).
    std::mt19937_64 rng(43);
    std::normal_distribution<double> nd;
    std::uniform_int_distribution<int> pick(0, 3);
    const std::array<double, 4> small = {0.0, 1e-15, 1e-9, 1.0};
    for (const std::string name : {"cube", "plate_10x9x2", "cuboid_6x6x5"}) {
        for (const bool aligned : {false, true}) {
            SCOPED_TRACE(name + (aligned ? " aligned" : " principal"));
            const g::PolyhedronFeatures f = aligned ? load_aligned(name) : load(name);
            ASSERT_TRUE(f.box.has_value());
            int closed = 0; // directions the closed form answered (not near a face or an edge)
            for (int n = 0; n < 4000; ++n) {
                Vec3 g(nd(rng), nd(rng), nd(rng));
                if (n % 2 == 1) { // near a face or an edge: scale components along the axes
                    for (int k = 0; k < 3; ++k) {
                        g[k] *= small[static_cast<std::size_t>(pick(rng))];
                    }
                    if (g.isZero()) {
                        continue;
                    }
                }
                const Vec3 d = f.box->axes * g;
                EXPECT_EQ(f.support(d), g::farthest_vertex(f.vertices, d)) << n;
                const Vec3 lead = 2.0 * f.box->half.cwiseProduct(g.cwiseAbs());
                closed += lead.minCoeff() > 1e-9 * f.radius * d.norm() ? 1 : 0;
            }
            EXPECT_GT(closed, 1900);
        }
    }
}

TEST(SeparatingAxis, PolyhedronOverlapFromHeightsAgreesWithTheSupportForm) {
    // polyhedron_overlap_along (heights in the body frames) against overlap_along (support points
    // turned to the world) over near-contact poses and random directions: the same number to
    // round-off, far inside the separation margin, so a cached direction proves the same pairs.
    /// Round-off of two rotations and a few dot products of O(size) numbers, relative to the size.
    constexpr double kRoundOff = 1e-14;
    static_assert(kRoundOff < 1e-3 * kProofMargin, "the margin must dwarf the difference");
    std::mt19937_64 rng(41);
    std::normal_distribution<double> nd;
    // (The boxes, cube and plates, take the closed form of a box's highest corner.)
    for (const std::string name :
         {"cube", "plate_10x9x2", "plate_inv4", "icosahedron", "cylinder_16"}) {
        SCOPED_TRACE(name);
        const g::PolyhedronFeatures f = load(name);
        EXPECT_EQ(f.box.has_value(),
                  name == "cube" || name == "plate_10x9x2" || name == "plate_inv4");
        const double scale = 2.0 * f.radius;
        double worst = 0.0;
        for (int n = 0; n < 2000; ++n) {
            const auto [a, b] = near_pair(g::PosedPolyhedron{&f}, g::PosedPolyhedron{&f}, rng);
            const Vec3 m = Vec3(nd(rng), nd(rng), nd(rng)).normalized();
            worst = std::max(
                worst, std::abs(g::polyhedron_overlap_along(a, b, m) - g::overlap_along(a, b, m)));
        }
        EXPECT_LE(worst, kRoundOff * scale);
    }
}

TEST(SeparatingAxis, PortalSearchProvesOnlyTrueGapsAndFindsClearOnes) {
    // find_separating_direction answers only with a proof: each direction it returns leaves a gap
    // larger than the margin, and the exact common plane finds the pair apart too. A pair that the
    // common plane finds apart by more than kClearGap of the size (its gap is a lower bound) must
    // get a direction: the portal search converges on convex bodies. (Before the common plane
    // certified the overlap of a pruned search, it reported contacts for some pairs apart by an
    // edge-edge plane: the cube's pose 32 here, apart by 5 % of the size, came out touching.)
    std::mt19937_64 rng(23);
    for (const std::string name : {"cube", "icosahedron", "cylinder_16"}) {
        SCOPED_TRACE(name);
        const g::PolyhedronFeatures f = load(name);
        const double scale = 2.0 * f.radius;
        int found = 0;
        int apart = 0;
        for (int n = 0; n < 2000; ++n) {
            const auto [a, b] = near_pair(g::PosedPolyhedron{&f}, g::PosedPolyhedron{&f}, rng);
            const g::PolyhedronContact c = g::polyhedron_contact(a, b, false);
            Vec3 m = Vec3::Zero();
            const bool proof = g::find_separating_direction(a, b, kProofMargin * scale, m);
            apart += c.touching ? 0 : 1;
            if (proof) {
                ++found;
                ASSERT_FALSE(c.touching)
                    << "pose " << n << " depth " << c.depth << " feature "
                    << static_cast<int>(c.feature) << " along m " << g::overlap_along(a, b, m)
                    << " along c.normal " << g::overlap_along(a, b, c.normal) << " scale " << scale;
                ASSERT_LT(g::overlap_along(a, b, m), -kProofMargin * scale);
                ASSERT_NEAR(m.norm(), 1.0, kExact);
            } else if (!c.touching) {
                ASSERT_LE(-c.depth, kClearGap * scale) << "a clear gap without a proof, pose " << n;
            }
        }
        EXPECT_GT(found, 500);                // the placements give many gaps
        EXPECT_GE(found, apart - apart / 50); // and nearly all of them get a proof
    }
}

TEST(SeparatingAxis, PortalSearchOnSuperquadricsAgreesWithTheNarrowPhase) {
    // As above for superquadrics (blocky e = 0.3 and smooth e = 0.8, 1 x 2 x 3 mm). Whether a pair
    // touches: libccd's GJK (no proof may be found for a pair it finds intersecting). The gap of a
    // pair apart: Newton's cold start (27 + 1 directions, 4 starts) where it converges (its depth
    // is minus the largest gap); a clear gap must get a proof.
    std::mt19937_64 rng(29);
    for (const double e : {0.3, 0.8}) {
        SCOPED_TRACE(e);
        g::Superquadric sq;
        sq.half_axes = Vec3(1e-3, 2e-3, 3e-3);
        sq.e1 = sq.e2 = e;
        const double scale = 2.0 * sq.half_axes.maxCoeff();
        int found = 0;
        int apart = 0;
        for (int n = 0; n < 500; ++n) {
            const auto [a, b] =
                near_pair(g::PosedSuperquadric{&sq}, g::PosedSuperquadric{&sq}, rng);
            const g::ConvexContact gjk = g::ccd_contact(a, b, false);
            ASSERT_TRUE(gjk.converged);
            Vec3 m = Vec3::Zero();
            const bool proof = g::find_separating_direction(a, b, kProofMargin * scale, m);
            apart += gjk.touching ? 0 : 1;
            if (proof) {
                ++found;
                ASSERT_FALSE(gjk.touching) << "pose " << n;
                ASSERT_LT(g::overlap_along(a, b, m), -kProofMargin * scale);
                continue;
            }
            const g::ConvexContact newton = g::support_newton_contact(a, b);
            if (newton.converged) {
                ASSERT_LE(-newton.depth, kClearGap * scale) << "a clear gap without a proof " << n;
            }
        }
        EXPECT_GT(found, 100);
        EXPECT_GE(found, apart - apart / 50);
    }
}

} // namespace

namespace {

/// Pairs of a and b placed at GJK's boundary (b moved along a random direction, 80 bisections of
/// the adapter's touching answer): the pairs on which libccd's EPA returns its normal reversed.
/// An answer that fails must say so (not touching; at most 10), and every touching one have the
/// smaller overlap along its normal than along the reverse and report the overlap along it as its
/// depth (to round-off); returns how many answers were repaired.
template <class A, class B> int grazing_pairs(A a, B b, std::mt19937_64& rng) {
    std::normal_distribution<double> nd;
    const double scale = a.length_scale() + b.length_scale();
    int repaired = 0;
    int failed = 0; // libccd found no direction with a finite overlap (NaN at the boundary)
    for (int n = 0; n < 200; ++n) {
        a.q = Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized();
        b.q = Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized();
        a.x = Vec3::Zero();
        const Vec3 u = Vec3(nd(rng), nd(rng), nd(rng)).normalized();
        double lo = 0.0;
        double hi = 2.0 * scale;
        for (int k = 0; k < 80; ++k) {
            const double t = 0.5 * (lo + hi);
            b.x = t * u;
            (g::ccd_contact(a, b, false).touching ? lo : hi) = t;
        }
        b.x = lo * u;
        const g::ConvexContact c = g::ccd_contact(a, b, false);
        if (!c.converged) { // a failure is reported, never a touching answer
            EXPECT_FALSE(c.touching) << "pair " << n;
            ++failed;
            continue;
        }
        repaired += c.repaired ? 1 : 0;
        if (c.touching) {
            const double along = g::overlap_along(a, b, c.normal);
            EXPECT_LE(along, g::overlap_along(a, b, Vec3(-c.normal))) << "pair " << n;
            if (c.repaired) {
                EXPECT_NEAR(c.depth, along, 1e-12 * scale) << "pair " << n; // (contraction)
            }
        }
    }
    EXPECT_LE(failed, 10); // rare (NaN directions were first seen in a sanitizer build)
    return repaired;
}

TEST(CcdContact, ANormalReversedAtGjksBoundaryIsRepaired) {
    // libccd's EPA on pairs touching only to within its tolerance returned the normal reversed in
    // 65-84 % of pairs of polyhedra and 18-66 % of pairs with a superquadric (16-edged prisms,
    // cubes, a cube and an ellipsoid, a prism and a blocky superquadric, two ellipsoids, two blocky
    // superquadrics: 400 pairs each, bisected on libccd's own answer). The adapter's answers must
    // be oriented (repaired).
    std::mt19937_64 rng(41);
    const g::PolyhedronFeatures cube = load("cube");
    const g::PolyhedronFeatures prism = load("cylinder_16");
    g::Superquadric ell;
    ell.half_axes = Vec3(1e-3, 2e-3, 3e-3);
    ell.e1 = ell.e2 = 1.0;
    g::Superquadric blocky;
    blocky.half_axes = Vec3::Constant(3e-3);
    blocky.e1 = 0.2;
    blocky.e2 = 1.0;
    const int pp = grazing_pairs(g::PosedPolyhedron{&prism}, g::PosedPolyhedron{&cube}, rng);
    const int ps = grazing_pairs(g::PosedPolyhedron{&cube}, g::PosedSuperquadric{&ell}, rng);
    const int ss = grazing_pairs(g::PosedSuperquadric{&blocky}, g::PosedSuperquadric{&ell}, rng);
    std::printf("  repaired: polyhedra %d, polyhedron-superquadric %d, superquadrics %d of 200\n",
                pp, ps, ss);
    EXPECT_GT(pp, 0); // the poses still meet the reversed normal
    EXPECT_GT(ps, 0);
    EXPECT_GT(ss, 0);
}

TEST(CcdContact, EpaThatWouldCycleStopsAndMprAnswers) {
    // A cube and a 1:2:3 ellipsoid of cases/hot_shapes at the step where libccd's EPA cycled for
    // ever before the support budget (ccd_adapter.cpp; danfis/libccd issue #7): poses as recorded
    // in that run (hex floats). GJK/EPA must now return, flagged as not converged, and MPR (the
    // fallback of the polyhedron-superquadric contact) must give a touching contact whose depth
    // along its normal is positive and close to its own.
    const g::PolyhedronFeatures cube = load("cube");
    g::Superquadric ell;
    ell.half_axes = Vec3(0x1.0624dd2f1a9fcp-10, 0x1.0624dd2f1a9fcp-9, 0x1.89374bc6a7efap-9);
    ell.e1 = ell.e2 = 1.0;
    const g::PosedPolyhedron a{
        &cube, Vec3(-0x1.10edbc65958c3p-8, 0x1.9a7a89ba1070cp-7, 0x1.2724b60aecacap-10),
        Quat(-0x1.f6890899daa41p-1, 0x1.5f2558bf2684fp-24, -0x1.08b91d53681c6p-17,
             -0x1.87f709e2434bbp-3)};
    const g::PosedSuperquadric b{
        &ell, Vec3(-0x1.fc9e6946e4ec1p-8, 0x1.5589800c84051p-7, 0x1.a1de5b7c483cp-10),
        Quat(-0x1.ac282ef99da12p-2, 0x1.60b2b25439d6ap-1, -0x1.034529d699981p-3,
             0x1.282bbe5bec728p-1)};
    const g::ConvexContact epa = g::ccd_contact(a, b, false);
    EXPECT_FALSE(epa.converged);
    const g::ConvexContact mpr = g::ccd_contact(a, b, true);
    ASSERT_TRUE(mpr.converged);
    ASSERT_TRUE(mpr.touching);
    const double along =
        b.support(mpr.normal).dot(mpr.normal) - a.support(-mpr.normal).dot(mpr.normal);
    EXPECT_GT(along, 0.0);
    EXPECT_NEAR(along, mpr.depth, 1e-3 * edge_of_cube(cube)); // MPR's depth: not minimal, close
    std::printf("  MPR depth %.4e m (along its normal %.4e m)\n", mpr.depth, along);
}

} // namespace
