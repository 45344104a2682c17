// Rows clipped by the body (fluid/deposit_body.hpp): a polyhedron's row clipped against its face
// planes and a clump's row as the union of its members' chords must pick exactly the points the
// point-by-point inside test picks, on random rows and on rows lying in a cube's face planes.

#include "fluid_helpers.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

using kiln::Vec3;
namespace f = kiln::fluid;
namespace t = kiln::test;

namespace {

/// The runs of inside points of a row, point by point (the reference).
template <class Body>
std::vector<f::RowRun> runs_by_points(const Body& body, const Vec3& p0, const Vec3& step, long n) {
    std::vector<f::RowRun> out;
    for (long k = 0; k <= n; ++k) {
        if (!body.contains(p0 + static_cast<double>(k) * step)) {
            continue;
        }
        if (!out.empty() && out.back().last == k - 1) {
            out.back().last = k;
        } else {
            out.push_back({k, k});
        }
    }
    return out;
}

bool same_runs(const std::vector<f::RowRun>& a, const std::vector<f::RowRun>& b) {
    if (a.size() != b.size()) {
        return false;
    }
    for (std::size_t k = 0; k < a.size(); ++k) {
        if (a[k].first != b[k].first || a[k].last != b[k].last) {
            return false;
        }
    }
    return true;
}

constexpr std::array<double, 4> kResolutions = {2.0, 4.5, 16.0, 47.0}; // steps per bounding radius

/// clip_row against the point tests for a posed polyhedron and a row along world x from `start`
/// (m, world) with n + 1 points; returns false if the row was left to the point tests.
bool check_row(const f::PlanesBody& body, const f::PosedPlanes& posed, const Vec3& start, long n,
               bool& same) {
    const f::RowRun r = f::clip_row(body, posed, start, n);
    if (!r.decided) {
        return false;
    }
    std::vector<f::RowRun> got;
    if (r.first <= r.last) {
        got.push_back(r);
    }
    const Vec3 p0 = posed.to_body * (start - posed.centre);
    same = same_runs(got, runs_by_points(body, p0, posed.step, n));
    return true;
}

} // namespace

TEST(Rows, PolyhedronRowsMatchTheInsideTest) {
    // Random poses of every shipped polyhedron, rows along world x at random heights through the
    // bounding sphere, 2 to 47 steps per bounding radius.
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    long rows = 0;
    long inside_rows = 0;
    f::PosedPlanes posed;
    for (const std::string name : {"cube", "icosahedron", "pyramid", "plate_10x9x2", "cylinder_16",
                                   "cylinder_8", "cuboid_6x6x5"}) {
        const auto shape = t::shape_file(name);
        const f::DepositTemplate dt = f::make_deposit_template(shape);
        const auto& body = std::get<f::PlanesBody>(dt.body);
        const double rb = dt.bounding_radius;
        for (const double res : kResolutions) {
            const double h = rb / res;
            for (int k = 0; k < 2000; ++k) {
                const Vec3 x = rb * Vec3(u(rng), u(rng), u(rng));
                f::pose_planes(body, t::random_rotation(rng).toRotationMatrix(), x, h, posed);
                const Vec3 start(x.x() - 1.3 * rb + 0.5 * h * u(rng), x.y() + rb * u(rng),
                                 x.z() + rb * u(rng));
                const auto n = static_cast<long>(2.6 * res);
                bool same = false;
                ASSERT_TRUE(check_row(body, posed, start, n, same)) << name; // not along a face
                ASSERT_TRUE(same) << name << " res " << res << " row " << k;
                ++rows;
                const f::RowRun r = f::clip_row(body, posed, start, n);
                inside_rows += r.first <= r.last ? 1 : 0;
            }
        }
    }
    std::printf("%ld rows, %ld of them through the body: all the same as the point tests\n", rows,
                inside_rows);
    EXPECT_GT(inside_rows, rows / 4); // the rows do cross the bodies
}

TEST(Rows, RowsInTheFacePlanesOfAnAlignedCubeMatchTheInsideTest) {
    // An axis-aligned cube with rows along x whose y and z are exactly on, or a round-off away
    // from, its face planes: either the planes decide the row as the point tests do, or the row
    // is left to the point tests (decided = false). Both must occur.
    const auto shape = t::shape_file("cube");
    const f::DepositTemplate dt = f::make_deposit_template(shape);
    const auto& body = std::get<f::PlanesBody>(dt.body);
    double half = 0.0;
    for (const Vec3& v : body.vertices) {
        half = std::max(half, v.x());
    }
    const double h = half / 8.0;
    const Vec3 x(1e-3, 2e-3, -1e-3);
    f::PosedPlanes posed;
    f::pose_planes(body, kiln::Mat3::Identity(), x, h, posed);
    long undecided = 0;
    long compared = 0;
    for (const double y :
         {-half, half, std::nextafter(half, 0.0), std::nextafter(half, 1.0), 0.3 * half}) {
        for (const double z : {-half, half, std::nextafter(-half, 0.0), 0.7 * half}) {
            for (const double x0 : {-half - 0.5 * h, -half, -half - 2.0 * h}) {
                bool same = false;
                if (!check_row(body, posed, x + Vec3(x0, y, z), 20, same)) {
                    ++undecided;
                    continue;
                }
                EXPECT_TRUE(same) << "y " << y << " z " << z << " x0 " << x0;
                ++compared;
            }
        }
    }
    EXPECT_GT(undecided, 0);
    EXPECT_GT(compared, 0);
}

TEST(Rows, ClumpRowsMatchTheInsideTest) {
    // Posed clumps at random positions and orientations, rows along world x at random heights:
    // the union of the members' chords picks the sub-cells whose centres lie in a member (the
    // point test in the world frame; generic positions, so no centre sits on a surface).
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    long rows = 0;
    long split_rows = 0;
    std::vector<f::RowRun> got;
    std::vector<Vec3> centres;
    for (const std::string name : {"cylinder_12", "cylinder_36", "cylinder_36_corrected", "test"}) {
        const auto shape = name == "test" ? t::clump_template() : t::shape_file(name);
        const f::DepositTemplate dt = f::make_deposit_template(shape);
        const auto& body = std::get<f::ClumpBody>(dt.body);
        const double rb = dt.bounding_radius;
        for (const double res : kResolutions) {
            const double h = rb / res;
            for (int k = 0; k < 500; ++k) {
                const Vec3 x = rb * Vec3(u(rng), u(rng), u(rng));
                const kiln::Mat3 rot = t::random_rotation(rng).toRotationMatrix();
                centres.clear();
                for (const auto& s : body.spheres) {
                    centres.push_back(x + rot * s.centre);
                }
                const double ox = -3.0 * rb + 0.1 * h * u(rng);
                const double y = x.y() + 1.1 * rb * u(rng);
                const double z = x.z() + 1.1 * rb * u(rng);
                const long lo = 1;
                const auto hi = static_cast<long>(6.0 * res) - 1;
                body.rows(centres, ox, h, y, z, lo, hi, got);
                std::vector<f::RowRun> want;
                for (long a = lo; a <= hi; ++a) {
                    const Vec3 p(ox + (static_cast<double>(a) + 0.5) * h, y, z);
                    bool in = false;
                    for (std::size_t m = 0; m < centres.size(); ++m) {
                        const double r = body.spheres[m].radius;
                        in = in || (p - centres[m]).squaredNorm() <= r * r;
                    }
                    if (!in) {
                        continue;
                    }
                    if (!want.empty() && want.back().last == a - 1) {
                        want.back().last = a;
                    } else {
                        want.push_back({a, a});
                    }
                }
                ASSERT_TRUE(same_runs(got, want)) << name << " res " << res << " row " << k;
                ++rows;
                split_rows += want.size() > 1 ? 1 : 0;
            }
        }
    }
    std::printf("%ld rows, %ld of them in two or more runs: all the same as the point tests\n",
                rows, split_rows);
    EXPECT_GT(split_rows, 0);
}
