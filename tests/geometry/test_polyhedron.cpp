// Convex polyhedra: exact mass properties of boxes and the tetrahedron, invariance under rotation,
// translation and extra interior points, support map against brute force, refused degenerate input.

#include "core/error.hpp"
#include "geometry/hull.hpp"
#include "geometry/polyhedron.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <gtest/gtest.h>
#include <memory>
#include <random>
#include <vector>

namespace g = kiln::geometry;
using kiln::Mat3;
using kiln::Vec3;

namespace {

constexpr double kExact = 1e-13; // relative: sums of a few dozen products of O(1) numbers
constexpr double kCloud = 1e-11; // relative: hull of hundreds of rotated points, then eigen-solve

g::ConvexPolyhedron from_points(const std::vector<Vec3>& pts) {
    const g::Hull h = g::convex_hull(pts, "test");
    return g::make_polyhedron(h.vertices, h.faces, "test");
}

std::vector<Vec3> box_corners(const Vec3& e) {
    std::vector<Vec3> p;
    for (int i = 0; i < 8; ++i) {
        p.emplace_back((i & 1 ? 0.5 : -0.5) * e.x(), (i & 2 ? 0.5 : -0.5) * e.y(),
                       (i & 4 ? 0.5 : -0.5) * e.z());
    }
    return p;
}

/// Closed-form principal moments per unit density of a box with edges e, ascending.
Vec3 box_moments(const Vec3& e) {
    const double v = e.prod();
    Vec3 m(v / 12.0 * (e.y() * e.y() + e.z() * e.z()), v / 12.0 * (e.x() * e.x() + e.z() * e.z()),
           v / 12.0 * (e.x() * e.x() + e.y() * e.y()));
    std::sort(m.begin(), m.end());
    return m;
}

/// Integral of x^a y^b z^c over the unit simplex: a! b! c! / (a + b + c + 3)! (Dirichlet).
double simplex_moment(int a, int b, int c) {
    const auto fact = [](int n) {
        double f = 1.0;
        for (int k = 2; k <= n; ++k) {
            f *= k;
        }
        return f;
    };
    return fact(a) * fact(b) * fact(c) / fact(a + b + c + 3);
}

Mat3 random_rotation(std::mt19937& rng) {
    std::normal_distribution<double> n(0.0, 1.0);
    return kiln::Quat(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
}

} // namespace

TEST(Polyhedron, UnitCubeIsExact) {
    const g::ConvexPolyhedron p = from_points(box_corners(Vec3::Ones()));
    EXPECT_NEAR(p.volume, 1.0, kExact);
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(p.inertia_unit_density[k], 1.0 / 6.0, kExact);
    }
    EXPECT_EQ(p.vertices.size(), 8U);
    EXPECT_EQ(p.faces.size(), 12U); // the seed's "12 triangles, 8 vertices and 18 edges"
    EXPECT_EQ(p.edges.size(), 18U);
    EXPECT_NEAR(p.surface_area(), 6.0, kExact);
    EXPECT_NEAR(p.bounding_radius(), std::sqrt(3.0) / 2.0, kExact);
}

TEST(Polyhedron, CuboidIsExactAndPrincipal) {
    const Vec3 e(6.0, 5.0, 2.0);
    const g::ConvexPolyhedron p = from_points(box_corners(e));
    EXPECT_NEAR(p.volume, e.prod(), kExact * e.prod());
    const Vec3 m = box_moments(e);
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(p.inertia_unit_density[k], m[k], kExact * m[k]);
    }
    // The body frame is principal: the inertia tensor of the moved vertices is diagonal.
    const g::MassProperties b = g::polyhedron_mass_properties(p.vertices, p.faces);
    EXPECT_LT(b.centroid.norm(), kExact * e.norm());
    EXPECT_LT((b.inertia_centroid - Mat3(p.inertia_unit_density.asDiagonal())).norm(),
              kExact * m.norm());
    EXPECT_NEAR(p.surface_area(), 2.0 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x()),
                kExact * 100.0);
    // Shadows along the principal axes: the largest moment is about the axis normal to 6 x 5.
    EXPECT_NEAR(p.projected_area(Vec3::UnitZ()), e.x() * e.y(), kExact * 30.0);
    EXPECT_NEAR(p.projected_area(Vec3::UnitX()), e.y() * e.z(), kExact * 30.0);
}

TEST(Polyhedron, UnitTetrahedronMatchesDirichletMoments) {
    const std::vector<Vec3> v{Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
    const std::vector<std::array<int, 3>> f{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    const g::MassProperties m = g::polyhedron_mass_properties(v, f);
    const double vol = simplex_moment(0, 0, 0);
    const double c = simplex_moment(1, 0, 0) / vol;
    EXPECT_NEAR(m.volume, vol, kExact);
    EXPECT_LT((m.centroid - Vec3::Constant(c)).norm(), kExact);
    const double cov_xx = simplex_moment(2, 0, 0) - vol * c * c;
    const double cov_xy = simplex_moment(1, 1, 0) - vol * c * c;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            const double expected = i == j ? 2.0 * cov_xx : -cov_xy;
            EXPECT_NEAR(m.inertia_centroid(i, j), expected, kExact) << i << j;
        }
    }
    // The same tetrahedron through the hull: principal moments are the eigenvalues of that tensor.
    const g::ConvexPolyhedron p = from_points(v);
    EXPECT_NEAR(p.volume, vol, kExact);
    const g::PrincipalFrame pf = g::principal_frame(m.inertia_centroid);
    EXPECT_LT((p.inertia_unit_density - pf.moments).norm(), kExact);
}

TEST(Polyhedron, RotatedTranslatedCloudsGiveTheSameProperties) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    // A hull of random points on an ellipsoid, plus points strictly inside it.
    std::vector<Vec3> base;
    for (int i = 0; i < 300; ++i) {
        Vec3 d(u(rng), u(rng), u(rng));
        d.normalize();
        base.emplace_back(3.0 * d.x(), 2.0 * d.y(), 1.0 * d.z());
    }
    const g::ConvexPolyhedron ref = from_points(base);
    for (int i = 0; i < 200; ++i) {
        base.push_back(0.5 * Vec3(u(rng), u(rng), u(rng)));
    }
    for (int trial = 0; trial < 5; ++trial) {
        const Mat3 r = random_rotation(rng);
        const Vec3 t = 100.0 * Vec3(u(rng), u(rng), u(rng));
        std::vector<Vec3> moved;
        for (const Vec3& p : base) {
            moved.push_back(r * p + t);
        }
        std::shuffle(moved.begin(), moved.end(), rng);
        const g::ConvexPolyhedron p = from_points(moved);
        EXPECT_EQ(p.vertices.size(), ref.vertices.size());
        EXPECT_NEAR(p.volume, ref.volume, kCloud * ref.volume);
        for (int k = 0; k < 3; ++k) {
            EXPECT_NEAR(p.inertia_unit_density[k], ref.inertia_unit_density[k],
                        kCloud * ref.inertia_unit_density[k]);
        }
        EXPECT_LT((p.template_centroid - (r * ref.template_centroid + t)).norm(), kCloud * 100.0);
        EXPECT_NEAR(p.surface_area(), ref.surface_area(), kCloud * ref.surface_area());
    }
}

TEST(Polyhedron, SupportMatchesBruteForceOverTheInputPoints) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<Vec3> pts;
    for (int i = 0; i < 400; ++i) {
        pts.emplace_back(2.0 * u(rng), u(rng), 0.5 * u(rng));
    }
    const g::ConvexPolyhedron p = from_points(pts);
    for (int trial = 0; trial < 1000; ++trial) {
        const Vec3 d = Vec3(u(rng), u(rng), u(rng)).normalized();
        double best = -1e300;
        for (const Vec3& q : pts) {
            best = std::max(best, d.dot(p.template_axes.transpose() * (q - p.template_centroid)));
        }
        EXPECT_NEAR(p.support(d).dot(d), best, kExact * 10.0);
    }
}

TEST(Polyhedron, DegenerateInputIsRefused) {
    const auto message = [](const std::vector<Vec3>& pts) {
        try {
            (void)g::convex_hull(pts, "bad.obj");
        } catch (const kiln::InputError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_NE(message({Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY()}).find("at least 4 points"),
              std::string::npos);
    EXPECT_NE(message(std::vector<Vec3>(5, Vec3::Ones())).find("coincide"), std::string::npos);
    std::vector<Vec3> line;
    std::vector<Vec3> flat;
    for (int i = 0; i < 10; ++i) {
        line.push_back(Vec3(1.0, 2.0, 3.0) * i);
        flat.emplace_back(std::cos(i), std::sin(i), 0.3 * std::cos(i));
    }
    EXPECT_NE(message(line).find("collinear"), std::string::npos);
    const std::string m = message(flat);
    EXPECT_NE(m.find("coplanar"), std::string::npos) << m;
    EXPECT_EQ(m.rfind("bad.obj", 0), 0U) << m;
    // An open surface (a cube without its top two triangles) is refused by make_polyhedron.
    const g::Hull h = g::convex_hull(box_corners(Vec3::Ones()), "cube");
    std::vector<std::array<int, 3>> open;
    for (const auto& f : h.faces) {
        bool top = true;
        for (int k : f) {
            top = top && h.vertices[static_cast<std::size_t>(k)].z() > 0.0;
        }
        if (!top) {
            open.push_back(f);
        }
    }
    ASSERT_EQ(open.size(), 10U);
    EXPECT_THROW((void)g::make_polyhedron(h.vertices, open, "open"), kiln::InputError);
    // A vertex on no face is refused too (it would enter the support map but not the volume).
    std::vector<Vec3> stray = h.vertices;
    stray.push_back(Vec3(5.0, 0.0, 0.0));
    EXPECT_THROW((void)g::make_polyhedron(stray, h.faces, "stray"), kiln::InputError);
}

TEST(Polyhedron, HullOfAPointSetThatTripsCgalQuickhull) {
    // Vertices of a random polyhedron of Yade 2023 (polyhedra_utils.polyhedra, 8 mm, seed 13; m),
    // in Yade's order. Its first three points span a hull face with a fourth point within 1e-18 m
    // of it: CGAL 5.5's quickhull, started from them, erased one list node twice (CGAL issues
    // 6543, 8625, 8761; a heap use after free that valgrind reports, docs/performance.md).
    // convex_hull starts CGAL from a wide triangle through the body instead.
    const std::vector<std::array<double, 3>> raw = {
        {-0.0037925338691577153, 0.0024623643710816648, 0.0041230810810475851},
        {0.0027564161407388071, -0.0035542779847415728, 0.0026204724562411525},
        {-0.0025542833513977096, -0.0021756666300861306, 0.0036216055063861517},
        {-0.0033714743054181896, -0.0044042511619974264, -0.00049629992795993845},
        {0.0050861578851706096, 0.0012575115311620449, 0.002517643003821058},
        {-0.0014844048609994941, -0.0030062254392800121, -0.0034908138220036689},
        {0.0049688854100693736, -0.0012457920729634178, 0.002382410797702007},
        {0.0049498363566863202, -0.001360872174298347, 0.0023146993088795473},
        {0.0031225705159359666, -0.0039637810254559442, 0.0020010661835871942},
        {0.0028131701909979061, -0.0045199146694135228, 0.00094542083539498646},
        {0.0030579057687336424, 0.004050837502987098, -0.0028039092746570881},
        {-0.0019115704140087062, 0.0038539519112033272, 0.0038852313588663596},
        {0.0041912537794731846, 0.0031987719561861641, -0.0018162651753710879},
        {-0.0055589815797045944, 0.00049896286549538688, -0.002377851208302314},
        {0.0041574446153093431, -0.0028576016246253237, -0.0010181994480252341},
        {-0.0024347166376168703, -0.0048578523914548869, -0.0010411978263840985},
        {0.0036963282757556362, -0.0015440193454149633, -0.0033004888645731911},
        {0.0039072069650425015, 0.0022910540248760594, -0.0029527592146450341},
        {-0.005012640393465672, 0.00083107784802747154, -0.0031852172056214094},
        {0.00061149314341376985, 0.0051051954357097988, -0.0027366640723887714},
    };
    std::vector<Vec3> pts;
    for (const auto& p : raw) {
        pts.emplace_back(p[0], p[1], p[2]);
    }
    const g::Hull h = g::convex_hull(pts, "seed 13");
    const g::ConvexPolyhedron poly = g::make_polyhedron(h.vertices, h.faces, "seed 13");
    EXPECT_GT(poly.volume, 0.0);
    // Every input point lies inside or on the hull (to round-off of the 8 mm size).
    for (const Vec3& p : pts) {
        for (const auto& f : h.faces) {
            const Vec3& a = h.vertices[static_cast<std::size_t>(f[0])];
            const Vec3 n = (h.vertices[static_cast<std::size_t>(f[1])] - a)
                               .cross(h.vertices[static_cast<std::size_t>(f[2])] - a);
            EXPECT_LE(n.normalized().dot(p - a), 1e-15);
        }
    }
}

TEST(Polyhedron, EqualMomentsGiveAFrameIndependentOfTheVertexOrder) {
    // A cube (three equal moments) and a square prism rotated off the input axes (two equal
    // moments): the order of the input points changes the round-off of the inertia tensor, which
    // used to choose the axes of the degenerate moments. The body-frame vertex set must be the
    // same for every order: the input frame for the cube; for the prism its distinct axis and the
    // input axis least aligned with it.
    std::mt19937 rng(3);
    const Mat3 turn = random_rotation(rng);
    const std::vector<std::pair<std::string, std::vector<Vec3>>> shapes{
        {"cube", box_corners(Vec3::Ones())}, {"prism", [&] {
                                                  std::vector<Vec3> p =
                                                      box_corners(Vec3(1.0, 1.0, 2.5));
                                                  for (Vec3& v : p) {
                                                      v = turn * v;
                                                  }
                                                  return p;
                                              }()}};
    for (const auto& [name, pts] : shapes) {
        const g::ConvexPolyhedron ref = from_points(pts);
        if (name == "cube") {
            EXPECT_LT((ref.template_axes - Mat3::Identity()).norm(), kExact);
        }
        std::vector<Vec3> shuffled = pts;
        for (int trial = 0; trial < 6; ++trial) {
            std::shuffle(shuffled.begin(), shuffled.end(), rng);
            const g::ConvexPolyhedron p = from_points(shuffled);
            EXPECT_LT((p.template_axes - ref.template_axes).norm(), kExact) << name << trial;
            for (const Vec3& v : p.vertices) {
                double nearest = 1.0;
                for (const Vec3& w : ref.vertices) {
                    nearest = std::min(nearest, (v - w).norm());
                }
                EXPECT_LT(nearest, kExact) << name << trial;
            }
        }
    }
}

TEST(Polyhedron, HullOrderDependsOnThePointSetOnly) {
    // Vertices of Yade 2023's random polyhedron 22 (polyhedra_utils.polyhedra, 8 mm, seed 22; m),
    // in Yade's order: CGAL returned its hull vertices in an order that followed the heap layout
    // (another working directory gave another trajectory of bench/yade's drop).
    const std::vector<std::array<double, 3>> raw = {
        {-0.00014082306300607517, 7.9376945460676689e-05, 0.004674592399219476},
        {0.002350194606717447, 0.0031861791517318492, 0.0030128935838600948},
        {-0.00045094426223009527, 0.0052496872294662657, -0.00032108673475005414},
        {-0.00050889286282595732, -0.0054115955061159356, -0.0013524161581774255},
        {0.00121000243267859, 0.0055624881511199716, -0.00062771858458763111},
        {-0.0030548735259602307, -0.0013230351355694179, -0.0038273280675373534},
        {0.0010074399041168089, 0.0054923192333864047, 0.00018176214977073252},
        {-0.0059736915213836773, 0.0015789869279322763, -0.0010258839138378439},
        {-0.0058038165434610642, 0.0025303192642928563, -0.00045461880826961568},
        {0.003626897618786689, 0.0022311324380537641, -0.0035559676106321613},
        {0.0044104060216557731, -0.0029780748727060544, 0.0014880058213829137},
        {0.0041555667236150761, 0.0019824345677026171, -0.0031448359240179601},
        {0.0011322756432069186, 0.0055190407242284283, 8.1279037946559163e-05},
        {0.0012968973924286794, 0.0051716698914441063, 0.00062684349765132312},
        {-0.0062343508566038326, 0.0014990407521615623, 0.00029535855997380334},
        {-0.0022937465738002804, -0.0022373765832509399, -0.004060086396816107},
        {0.0050656190863847339, 0.0004199092486127454, -0.0017958770470623629},
        {0.0041867940415383862, -0.0031582912271387467, -0.00022302796690099914},
        {0.0051420835892530322, -0.00029367225427202274, 0.0010304677436271739},
        {-0.00068112761577241278, -0.0054552827205876682, -0.00050824830757624073},
        {0.0034336176456747887, -0.0034072010911796358, 0.0021532026889368346},
        {-0.0051437402564570786, -0.00075877179951378774, 0.0029550338238984218},
        {-0.0021472392177044131, -0.0016466151979206136, -0.0043190407583237143},
        {0.0033608012811859253, 0.0030496552140935177, -0.0029374533477799711},
    };
    // CGAL's output order followed the heap: with the other half of 64 blocks of one size freed
    // in random order before each call, 11 of 40 calls returned another order. convex_hull now
    // sorts its output, so every call, and every input order, gives the same bits.
    std::vector<Vec3> pts;
    for (const auto& p : raw) {
        pts.emplace_back(p[0], p[1], p[2]);
    }
    const g::Hull ref = g::convex_hull(pts, "seed 22");
    std::mt19937 rng(1);
    std::vector<std::unique_ptr<char[]>> held;
    for (int trial = 0; trial < 40; ++trial) {
        std::vector<std::unique_ptr<char[]>> blocks;
        const std::size_t size = std::size_t{16} << (trial % 9);
        for (int k = 0; k < 64; ++k) {
            blocks.emplace_back(new char[size]);
        }
        std::shuffle(blocks.begin(), blocks.end(), rng);
        for (std::size_t k = 0; k < 32; ++k) {
            held.push_back(std::move(blocks[k]));
        }
        blocks.clear();
        const g::Hull h = g::convex_hull(pts, "seed 22");
        EXPECT_TRUE(h.vertices == ref.vertices && h.faces == ref.faces) << "heap trial " << trial;
    }
    std::vector<Vec3> shuffled = pts;
    for (int trial = 0; trial < 10; ++trial) {
        std::shuffle(shuffled.begin(), shuffled.end(), rng);
        const g::Hull h = g::convex_hull(shuffled, "seed 22");
        EXPECT_TRUE(h.vertices == ref.vertices && h.faces == ref.faces) << "order trial " << trial;
    }
    // Sorted vertices, triangles starting at their smallest index, sorted triangles.
    EXPECT_TRUE(std::is_sorted(ref.faces.begin(), ref.faces.end()));
    for (const auto& f : ref.faces) {
        EXPECT_LT(f[0], std::min(f[1], f[2]));
    }
}
