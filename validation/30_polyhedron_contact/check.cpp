// Validation 30: polyhedron contact by three independent methods. The fast common plane
// (geometry/polyhedron_contact.hpp, Nezami et al. 2004), libccd's GJK + EPA on the vertex support
// map (geometry/ccd_adapter.cpp) and FCL (tests only: its signed distance, FCL's GJK + EPA port,
// and its collide, which runs libccd's MPR, an upper bound) must give the same overlap and normal
// over thousands of random overlapping pose pairs of each shipped polyhedron. See README.md.

#include "common/fcl_reference.hpp"
#include "geometry/polyhedron_contact.hpp"
#include "io/shape_reader.hpp"
#include "validation.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <random>

namespace kiln::validation {
namespace {

namespace g = geometry;

/// Depth agreement, relative to r_A + r_B: libccd's EPA tolerance (1e-10, compared with squared
/// lengths in part of its test) leaves ~1e-5 of the length scale; twice that.
constexpr double depth_tolerance = 2e-5;
/// A normal agrees when the overlap along it exceeds the minimum by no more than depth_tolerance
/// (relative to r_A + r_B): near ties of two candidate planes the normals may differ by a finite
/// angle while both are optimal to the methods' precision.
constexpr double normal_tolerance = 2e-5;
/// Pairs per shape with itself, and per ordered pair of different shapes.
constexpr int self_pairs = 1000;
constexpr int mixed_pairs = 50;

const char* const names[] = {"cube",        "cuboid_6x6x5", "plate_10x9x2", "pyramid",
                             "icosahedron", "cylinder_8",   "cylinder_16"};

struct Shape {
    std::string name;
    g::ConvexPolyhedron poly;
    g::PolyhedronFeatures features;
};

using test::FclPath;

/// FCL's depth and normal from B to A for the pair, handed to FCL in units of r_A + r_B.
g::ConvexContact fcl_contact(const Shape& sa, const g::PosedPolyhedron& a, const Shape& sb,
                             const g::PosedPolyhedron& b, FclPath path) {
    const double unit = sa.features.radius + sb.features.radius;
    return test::fcl_contact(test::to_fcl(sa.poly, unit), a, test::to_fcl(sb.poly, unit), b, unit,
                             path);
}

/// Overlap along a normal m from B to A: h_A(-m) + h_B(m) (m).
double overlap_along(const g::PosedPolyhedron& a, const g::PosedPolyhedron& b, const Vec3& m) {
    return b.support(m).dot(m) - a.support(-m).dot(m);
}

struct Tally {
    int pairs = 0;
    int apart = 0;                // pairs the common plane finds apart (checked against the others)
    int cp_misses = 0;            // common plane apart, but libccd or FCL finds an overlap
    int epa_failures = 0;         // libccd: no contact or not converged
    int fcl_failures = 0;         // FCL: no contact (either path)
    double worst_epa = 0.0;       // |EPA - CP| / (r_A + r_B)
    double worst_fcl = 0.0;       // |FCL signed distance - CP| / (r_A + r_B)
    double worst_mpr = 0.0;       // (FCL MPR - CP) / (r_A + r_B), >= 0
    int mpr_below = 0;            // FCL MPR shallower than CP (MPR is an upper bound)
    double worst_fcl_angle = 0.0; // largest angle between the CP and FCL (EPA) normals (rad)
    double worst_normal = 0.0;    // (overlap along the other normal - CP) / (r_A + r_B)
    double worst_angle = 0.0;     // largest angle between the CP and EPA normals (rad)
    int tilted = 0;               // pairs with an angle above 1e-3 rad
    int epa_above = 0; // EPA deeper than CP by more than round-off (EPA is a lower bound)
};

void compare(const Shape& sa, const Shape& sb, std::mt19937_64& rng, Tally& t) {
    std::normal_distribution<double> nd;
    std::uniform_real_distribution<double> ud(std::log(1e-4), std::log(5e-2));
    const double unit = sa.features.radius + sb.features.radius;
    g::PosedPolyhedron a{&sa.features, Vec3(nd(rng), nd(rng), nd(rng)) * 1e-3,
                         Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized()};
    g::PosedPolyhedron b{&sb.features, Vec3::Zero(),
                         Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized()};
    const Vec3 u = Vec3(nd(rng), nd(rng), nd(rng)).normalized();
    const double push = std::exp(ud(rng)) * std::min(sa.features.radius, sb.features.radius);
    b.x = a.support(u) - push * u - (b.support(-u) - b.x);
    ++t.pairs;
    const g::PolyhedronContact c = g::polyhedron_contact(a, b, false);
    const g::ConvexContact e = g::ccd_contact(a, b, false);
    if (!c.touching) {
        // Overlapping supports along u do not imply overlapping bodies at sharp vertices: then all
        // methods must agree that the pair is apart.
        ++t.apart;
        if (e.touching || fcl_contact(sa, a, sb, b, FclPath::kSignedDistance).touching) {
            ++t.cp_misses;
        }
        return;
    }
    // An EPA result whose overlap along its own normal is not its depth stopped early (libccd's
    // EPA can end on a polytope face through the origin); such results are counted as failures of
    // the reference, not compared.
    const bool epa_consistent =
        std::abs(overlap_along(a, b, e.normal) - e.depth) <= depth_tolerance * unit;
    if (!e.touching || !e.converged || !epa_consistent) {
        ++t.epa_failures;
    } else {
        const double d = std::abs(e.depth - c.depth) / unit;
        t.worst_epa = std::max(t.worst_epa, d);
        if (e.depth > c.depth + 1e-12 * unit) {
            ++t.epa_above;
        }
        t.worst_normal = std::max(t.worst_normal, (overlap_along(a, b, e.normal) - c.depth) / unit);
        const double angle = std::acos(std::clamp(e.normal.dot(c.normal), -1.0, 1.0));
        t.worst_angle = std::max(t.worst_angle, angle);
        t.tilted += angle > 1e-3 ? 1 : 0;
    }
    const g::ConvexContact f = fcl_contact(sa, a, sb, b, FclPath::kSignedDistance);
    const g::ConvexContact m = fcl_contact(sa, a, sb, b, FclPath::kMpr);
    if (!f.touching || !m.touching) {
        ++t.fcl_failures;
    }
    if (f.touching) {
        t.worst_fcl = std::max(t.worst_fcl, std::abs(f.depth - c.depth) / unit);
        t.worst_normal = std::max(t.worst_normal, (overlap_along(a, b, f.normal) - c.depth) / unit);
        t.worst_fcl_angle =
            std::max(t.worst_fcl_angle, std::acos(std::clamp(f.normal.dot(c.normal), -1.0, 1.0)));
    }
    if (m.touching) {
        t.worst_mpr = std::max(t.worst_mpr, (m.depth - c.depth) / unit);
        t.mpr_below += m.depth < c.depth - 1e-12 * unit ? 1 : 0;
    }
}

void report(const std::string& label, const Tally& t) {
    record(label + " pairs", t.pairs, 0, 0, "-");
    record(label + " pairs apart (all methods agree)", t.apart, 0, 0, "-");
    record(label + " apart by CP but touching by libccd or FCL", t.cp_misses, 0, 0, "-");
    record(label + " libccd failures", t.epa_failures, 0, 0, "-");
    record(label + " FCL failures", t.fcl_failures, 0, 0, "-");
    record(label + " max |EPA - CP| / (rA + rB)", t.worst_epa, 0, depth_tolerance, "-");
    record(label + " max |FCL EPA - CP| / (rA + rB)", t.worst_fcl, 0, depth_tolerance, "-");
    record(label + " max (FCL MPR - CP) / (rA + rB)", t.worst_mpr, 0, 0, "-");
    record(label + " max angle CP-FCL normal", t.worst_fcl_angle, 0, 0, "rad");
    record(label + " max excess overlap along other normals", t.worst_normal, 0, normal_tolerance,
           "-");
    record(label + " max angle CP-EPA normal", t.worst_angle, 0, 0, "rad");
    record(label + " pairs with angle > 1e-3 rad", t.tilted, 0, 0, "-");
    EXPECT_EQ(t.cp_misses, 0) << label;
    EXPECT_EQ(t.epa_above, 0) << label;
    EXPECT_LE(t.worst_epa, depth_tolerance) << label;
    EXPECT_LE(t.worst_fcl, depth_tolerance) << label;
    EXPECT_EQ(t.mpr_below, 0) << label;
    EXPECT_LE(t.worst_normal, normal_tolerance) << label;
    // Failures of the reference libraries are reported, and allowed on at most 1 % of the pairs.
    EXPECT_LE(t.epa_failures, t.pairs / 100) << label;
    EXPECT_LE(t.fcl_failures, t.pairs / 100) << label;
}

TEST(PolyhedronContact, CommonPlaneEpaAndFclAgree) {
    reset_results();
    std::vector<Shape> shapes;
    for (const char* n : names) {
        const auto t = io::read_shape_file(io::find_shape_file(n, io::default_shape_dirs()));
        Shape s{n, std::get<g::ConvexPolyhedron>(t.shape), {}};
        s.features = g::polyhedron_features(s.poly);
        shapes.push_back(std::move(s));
    }
    std::mt19937_64 rng(30);
    for (const Shape& s : shapes) {
        Tally t;
        for (int k = 0; k < self_pairs; ++k) {
            compare(s, s, rng, t);
        }
        report(s.name, t);
    }
    Tally mixed;
    for (const Shape& sa : shapes) {
        for (const Shape& sb : shapes) {
            if (&sa != &sb) {
                for (int k = 0; k < mixed_pairs; ++k) {
                    compare(sa, sb, rng, mixed);
                }
            }
        }
    }
    report("mixed", mixed);
}

} // namespace
} // namespace kiln::validation
