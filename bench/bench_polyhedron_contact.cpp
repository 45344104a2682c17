// Cost per pair of the polyhedron contact methods on random overlapping poses of each shipped
// polyhedron with itself (overlap 1e-4 to 5e-2 of the bounding radius), by feature-edge count:
// fast common plane with and without the points and patch, libccd GJK + EPA and MPR; a
// sphere-sphere overlap for comparison; mesh-wall queries of a sphere and a cube; a polyhedron
// against a superquadric by libccd's EPA alone and with the normal's refinement
// (depth_refinement.hpp, as the contact of such a pair runs it); two cubes whose box axes are
// not their body frame's (`cube_turned_plane`, beside `cube_plane`); the closed form of two cubes
// alone, one pair or eight at a time in vector lanes (`run_box_lanes`); from two cubes' poses to
// their plane, as the run does it and in lanes (`run_box_route`, an estimate for a batched route).
// Run:
// build/bench/kiln_bench_polyhedra

#include "geometry/convex_contact.hpp"
#include "geometry/depth_refinement.hpp"
#include "geometry/mesh_wall.hpp"
#include "geometry/polyhedron_contact.hpp"
#include "geometry/polyhedron_search.hpp"
#include "io/shape_reader.hpp"

#include <algorithm>
#include <benchmark/benchmark.h>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

namespace {

using kiln::Quat;
using kiln::Vec3;
namespace g = kiln::geometry;

/// A shipped polyhedron by name; "NAME_turned": its vertices turned by a fixed rotation (the same
/// solid, a box no longer along its body frame's axes: PolyhedronFeatures::Box::aligned false).
const g::PolyhedronFeatures& shape(const std::string& name) {
    static std::map<std::string, g::PolyhedronFeatures> cache;
    auto it = cache.find(name);
    if (it == cache.end()) {
        const std::string suffix = "_turned";
        const bool turned = name.size() > suffix.size() && name.ends_with(suffix);
        const auto t = kiln::io::read_shape_file(
            kiln::io::find_shape_file(turned ? name.substr(0, name.size() - suffix.size()) : name,
                                      kiln::io::default_shape_dirs()));
        g::ConvexPolyhedron p = std::get<g::ConvexPolyhedron>(t.shape);
        if (turned) {
            const kiln::Mat3 turn = Quat(0.9, 0.3, -0.2, 0.25).normalized().toRotationMatrix();
            for (Vec3& v : p.vertices) {
                v = turn * v;
            }
        }
        it = cache.emplace(name, g::polyhedron_features(p)).first;
    }
    return it->second;
}

struct Pair {
    g::PosedPolyhedron a;
    g::PosedPolyhedron b;
};

std::vector<Pair> poses(const g::PolyhedronFeatures& s) {
    std::mt19937_64 rng(1);
    std::normal_distribution<double> nd;
    std::uniform_real_distribution<double> ud(std::log(1e-4), std::log(5e-2));
    std::vector<Pair> out;
    for (int i = 0; i < 256; ++i) {
        Pair p{{&s, Vec3::Zero(), Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized()},
               {&s, Vec3::Zero(), Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized()}};
        const Vec3 u = Vec3(nd(rng), nd(rng), nd(rng)).normalized();
        p.b.x = p.a.support(u) - std::exp(ud(rng)) * s.radius * u - p.b.support(-u);
        out.push_back(p);
    }
    return out;
}

/// kPlaneGeneral: the general common-plane search with full tables (FaceScan::full, the search
/// two cubes took before session 25) even for two boxes, which otherwise take the closed form of
/// the separating-axis test: the two side by side.
enum class Method { kPlane, kPlanePatch, kPlaneGeneral, kEpa, kMpr };

void run(benchmark::State& state, const std::string& name, Method m) {
    const g::PolyhedronFeatures& s = shape(name);
    const std::vector<Pair> pairs = poses(s);
    std::size_t i = 0;
    for (auto _ : state) {
        const Pair& p = pairs[i++ % pairs.size()];
        switch (m) {
        case Method::kPlane:
            benchmark::DoNotOptimize(g::polyhedron_contact(p.a, p.b, false));
            break;
        case Method::kPlanePatch:
            benchmark::DoNotOptimize(g::polyhedron_contact(p.a, p.b, true));
            break;
        case Method::kPlaneGeneral:
            benchmark::DoNotOptimize(
                g::detail::polyhedron_contact_with(p.a, p.b, g::detail::FaceScan::full, false));
            break;
        case Method::kEpa:
            benchmark::DoNotOptimize(g::ccd_contact(p.a, p.b, false));
            break;
        case Method::kMpr:
            benchmark::DoNotOptimize(g::ccd_contact(p.a, p.b, true));
            break;
        }
    }
    state.counters["edges"] = static_cast<double>(s.edges.size());
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

/// The closed form of two boxes alone (no posing, depth or patch) at the relative poses of the
/// cube poses above: one pair at a time as polyhedron_contact runs it (detail::box_plane,
/// `lanes` false), or eight pairs at a time in vector lanes (detail::box_planes, the same bits),
/// the filling of the lanes included. Per pair (items).
void run_box_lanes(benchmark::State& state, const std::string& name, bool lanes) {
    const g::PolyhedronFeatures& s = shape(name);
    const std::vector<Pair> pairs = poses(s);
    std::vector<kiln::Mat3> rot;
    std::vector<Vec3> shift;
    for (const Pair& p : pairs) {
        rot.push_back((p.a.q.conjugate() * p.b.q).toRotationMatrix());
        shift.push_back(p.a.q.conjugate() * (p.b.x - p.a.x));
    }
    constexpr std::size_t w = g::detail::BoxLanes::kWidth;
    g::detail::BoxLanes box_lanes;
    std::vector<g::detail::BoxPlane> out(w);
    std::size_t i = 0;
    for (auto _ : state) {
        if (lanes) {
            for (std::size_t q = 0; q < w; ++q) {
                const std::size_t k = (i + q) % pairs.size();
                g::detail::box_lane(box_lanes, q, s, s, rot[k], shift[k]);
            }
            g::detail::box_planes(box_lanes, w, out.data());
        } else {
            for (std::size_t q = 0; q < w; ++q) {
                const std::size_t k = (i + q) % pairs.size();
                out[q] = g::detail::box_plane(s, s, rot[k], shift[k]);
            }
        }
        benchmark::DoNotOptimize(out.data());
        i += w;
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * w));
}

/// What the resting box pairs' route in lanes could give (session 28's estimate; not the run's
/// code): per pair, from the two bodies' poses (x, q; world) to the plane (separation and world
/// normal). `lanes` false: as the run does it, B placed in A's frame (search::make_relative, B's
/// vertices included: the depth reads them), the one-pair closed form and A's turn of the normal.
/// `lanes` true: the relative pose for eight pairs in lanes (the quaternion product, its rotation
/// matrix and B's centre in A's frame, by the same formulas as unit_rotation_matrix, not the same
/// bits), the closed form in lanes, and the normal turned by A's rotation matrix, for eight pairs
/// at a time. Per pair (items).
void run_box_route(benchmark::State& state, bool lanes) {
    const g::PolyhedronFeatures& s = shape("cube");
    const std::vector<Pair> pairs = poses(s);
    constexpr std::size_t w = g::detail::BoxLanes::kWidth;
    const std::size_t nb = pairs.size() / w;
    // The poses in structure-of-arrays form per block of eight (as a batched route would keep
    // them).
    struct Block {
        alignas(64) double qa[4][w];
        alignas(64) double qb[4][w];
        alignas(64) double d[3][w];
    };
    std::vector<Block> blocks(nb);
    for (std::size_t k = 0; k < nb * w; ++k) {
        Block& b = blocks[k / w];
        const std::size_t q = k % w;
        const Pair& p = pairs[k];
        for (int c = 0; c < 4; ++c) {
            b.qa[c][q] = p.a.q.coeffs()[c];
            b.qb[c][q] = p.b.q.coeffs()[c];
        }
        for (int c = 0; c < 3; ++c) {
            b.d[c][q] = p.b.x[c] - p.a.x[c];
        }
    }
    g::detail::BoxLanes box_lanes;
    std::vector<kiln::Mat3> rot(w);
    std::vector<g::detail::BoxPlane> out(w);
    alignas(64) double ra[9][w];
    alignas(64) double normal[3][w];
    thread_local g::search::Relative r;
    std::size_t i = 0;
    for (auto _ : state) {
        if (!lanes) {
            for (std::size_t q = 0; q < w; ++q) {
                const Pair& p = pairs[(i * w + q) % (nb * w)];
                g::search::make_relative(p.a, p.b, r);
                out[q] = g::detail::box_plane(s, s, r.rot, r.shift);
                const Vec3 n = p.a.q * out[q].normal;
                for (int c = 0; c < 3; ++c) {
                    normal[c][q] = n[c];
                }
            }
        } else {
            const Block& b = blocks[i % nb];
#pragma omp simd
            for (std::size_t q = 0; q < w; ++q) {
                // qab = conj(qa) qb (Eigen's coefficient order x, y, z, w).
                const double ax = -b.qa[0][q];
                const double ay = -b.qa[1][q];
                const double az = -b.qa[2][q];
                const double aw = b.qa[3][q];
                const double bx = b.qb[0][q];
                const double by = b.qb[1][q];
                const double bz = b.qb[2][q];
                const double bw = b.qb[3][q];
                const double x = aw * bx + ax * bw + ay * bz - az * by;
                const double y = aw * by - ax * bz + ay * bw + az * bx;
                const double z = aw * bz + ax * by - ay * bx + az * bw;
                const double qw = aw * bw - ax * bx - ay * by - az * bz;
                double* c = &box_lanes.c[0][0];
                c[0 * w + q] = 1 - 2 * (y * y + z * z);
                c[1 * w + q] = 2 * (x * y - qw * z);
                c[2 * w + q] = 2 * (x * z + qw * y);
                c[3 * w + q] = 2 * (x * y + qw * z);
                c[4 * w + q] = 1 - 2 * (x * x + z * z);
                c[5 * w + q] = 2 * (y * z - qw * x);
                c[6 * w + q] = 2 * (x * z - qw * y);
                c[7 * w + q] = 2 * (y * z + qw * x);
                c[8 * w + q] = 1 - 2 * (x * x + y * y);
                // A's rotation matrix (A body -> world); B's centre in A's frame is R_A^T d.
                const double ux = -ax;
                const double uy = -ay;
                const double uz = -az;
                ra[0][q] = 1 - 2 * (uy * uy + uz * uz);
                ra[1][q] = 2 * (ux * uy - aw * uz);
                ra[2][q] = 2 * (ux * uz + aw * uy);
                ra[3][q] = 2 * (ux * uy + aw * uz);
                ra[4][q] = 1 - 2 * (ux * ux + uz * uz);
                ra[5][q] = 2 * (uy * uz - aw * ux);
                ra[6][q] = 2 * (ux * uz - aw * uy);
                ra[7][q] = 2 * (uy * uz + aw * ux);
                ra[8][q] = 1 - 2 * (ux * ux + uy * uy);
                for (int k = 0; k < 3; ++k) {
                    box_lanes.t[k][q] =
                        ra[k][q] * b.d[0][q] + ra[3 + k][q] * b.d[1][q] + ra[6 + k][q] * b.d[2][q];
                    box_lanes.ha[k][q] = s.box->half[k];
                    box_lanes.hb[k][q] = s.box->half[k];
                }
            }
            for (std::size_t q = 0; q < w; ++q) {
                box_lanes.fa[q] = &s;
                box_lanes.fb[q] = &s;
                for (int k = 0; k < 9; ++k) {
                    rot[q](k / 3, k % 3) = box_lanes.c[k][q];
                }
                box_lanes.rot[q] = &rot[q];
            }
            g::detail::box_planes(box_lanes, w, out.data());
            for (std::size_t q = 0; q < w; ++q) {
                for (int c = 0; c < 3; ++c) {
                    normal[c][q] = ra[3 * c][q] * out[q].normal[0] +
                                   ra[3 * c + 1][q] * out[q].normal[1] +
                                   ra[3 * c + 2][q] * out[q].normal[2];
                }
            }
        }
        benchmark::DoNotOptimize(normal);
        benchmark::DoNotOptimize(out.data());
        ++i;
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * w));
}

/// Sphere-sphere overlap, normal and contact point (the spherical narrow phase), for comparison.
void BM_SphereSphere(benchmark::State& state) {
    std::mt19937_64 rng(1);
    std::normal_distribution<double> nd;
    std::vector<Vec3> d;
    for (int i = 0; i < 256; ++i) {
        d.push_back(Vec3(nd(rng), nd(rng), nd(rng)).normalized() * 1.99e-3);
    }
    const double r = 1e-3;
    std::size_t i = 0;
    for (auto _ : state) {
        const Vec3& x = d[i++ % d.size()];
        const double dist = x.norm();
        const Vec3 n = x / dist;
        const double overlap = 2.0 * r - dist;
        benchmark::DoNotOptimize(overlap);
        benchmark::DoNotOptimize(n);
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

/// Mesh wall: a sphere or a cube pressed into a 20 x 20 flat grid of 800 triangles at random spots.
void run_wall(benchmark::State& state, bool cube) {
    const int n = 20;
    const double s = 1e-3;
    std::vector<Vec3> v;
    for (int j = 0; j <= n; ++j) {
        for (int k = 0; k <= n; ++k) {
            v.emplace_back(k * s, j * s, 0.0);
        }
    }
    std::vector<std::array<int, 3>> t;
    for (int j = 0; j < n; ++j) {
        for (int k = 0; k < n; ++k) {
            const int a = j * (n + 1) + k;
            t.push_back({a, a + 1, a + n + 2});
            t.push_back({a, a + n + 2, a + n + 1});
        }
    }
    const g::MeshWall w(v, t, "bench");
    const g::PolyhedronFeatures& c = shape("cube");
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> ud(3e-3, 17e-3);
    std::normal_distribution<double> nd;
    std::vector<g::PosedPolyhedron> bodies;
    for (int i = 0; i < 256; ++i) {
        g::PosedPolyhedron p{&c, Vec3(ud(rng), ud(rng), 0.0),
                             Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized()};
        p.x.z() = -p.support(-Vec3::UnitZ()).z() - 1e-5;
        bodies.push_back(p);
    }
    std::vector<g::MeshContact> out;
    std::size_t i = 0;
    for (auto _ : state) {
        const g::PosedPolyhedron& p = bodies[i++ % bodies.size()];
        if (cube) {
            w.polyhedron_contacts(p, out);
        } else {
            w.sphere_contacts(Vec3(p.x.x(), p.x.y(), 0.99e-3), 1e-3, out);
        }
        benchmark::DoNotOptimize(out.data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

/// A polyhedron and a superquadric (a 1:2:3 ellipsoid, or a blocky one of e = 0.3), 256 random
/// overlapping poses (overlap 1e-4 to 5e-2 of the polyhedron's bounding radius): libccd's EPA
/// and the overlap along its normal (Refine::no), then the refinement of the normal always
/// (Refine::always) or, as the contact runs it (body_contact.cpp), only where the overlap along
/// EPA's normal exceeds EPA's depth by more than 1e-3 of itself plus 1e-9 of the length scale
/// (Refine::gated; the counter `refined` is the share of pairs refined).
enum class Refine { no, always, gated };
void run_mixed(benchmark::State& state, const std::string& name, double e, Refine refine) {
    const g::PolyhedronFeatures& s = shape(name);
    g::Superquadric q;
    q.half_axes = Vec3(1e-3, 2e-3, 3e-3);
    q.e1 = q.e2 = e;
    std::mt19937_64 rng(2);
    std::normal_distribution<double> nd;
    std::uniform_real_distribution<double> ud(std::log(1e-4), std::log(5e-2));
    std::vector<std::pair<g::PosedPolyhedron, g::PosedSuperquadric>> pairs;
    for (int i = 0; i < 256; ++i) {
        g::PosedPolyhedron a{&s, Vec3::Zero(),
                             Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized()};
        g::PosedSuperquadric b{&q, Vec3::Zero(),
                               Quat(nd(rng), nd(rng), nd(rng), nd(rng)).normalized()};
        const Vec3 u = Vec3(nd(rng), nd(rng), nd(rng)).normalized();
        b.x = a.support(u) - std::exp(ud(rng)) * s.radius * u - b.support(-u);
        pairs.emplace_back(a, b);
    }
    std::size_t i = 0;
    std::int64_t refined = 0;
    for (auto _ : state) {
        const auto& [a, b] = pairs[i++ % pairs.size()];
        const g::ConvexContact c = g::ccd_contact(a, b, false);
        Vec3 m = c.normal;
        double overlap = g::overlap_along(a, b, m);
        const double scale = a.length_scale() + b.length_scale();
        const bool wide = c.repaired || overlap - c.depth > 1e-3 * overlap + 1e-9 * scale;
        if (c.touching && (refine == Refine::always || (refine == Refine::gated && wide))) {
            g::refine_polyhedron_normal(a, b, m, overlap);
            ++refined;
        }
        benchmark::DoNotOptimize(overlap);
        benchmark::DoNotOptimize(m);
    }
    state.counters["refined"] = static_cast<double>(refined) /
                                static_cast<double>(std::max<std::int64_t>(1, state.iterations()));
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

} // namespace

BENCHMARK_CAPTURE(run_mixed, cube_ellipsoid_epa, std::string("cube"), 1.0, Refine::no);
BENCHMARK_CAPTURE(run_mixed, cube_ellipsoid_epa_refined, std::string("cube"), 1.0, Refine::always);
BENCHMARK_CAPTURE(run_mixed, cube_ellipsoid_epa_gated, std::string("cube"), 1.0, Refine::gated);
BENCHMARK_CAPTURE(run_mixed, cube_blocky_epa, std::string("cube"), 0.3, Refine::no);
BENCHMARK_CAPTURE(run_mixed, cube_blocky_epa_refined, std::string("cube"), 0.3, Refine::always);
BENCHMARK_CAPTURE(run_mixed, cube_blocky_epa_gated, std::string("cube"), 0.3, Refine::gated);
BENCHMARK_CAPTURE(run_mixed, cylinder16_ellipsoid_epa, std::string("cylinder_16"), 1.0, Refine::no);
BENCHMARK_CAPTURE(run_mixed, cylinder16_ellipsoid_epa_refined, std::string("cylinder_16"), 1.0,
                  Refine::always);
BENCHMARK_CAPTURE(run_mixed, cylinder16_ellipsoid_epa_gated, std::string("cylinder_16"), 1.0,
                  Refine::gated);
BENCHMARK(BM_SphereSphere);
BENCHMARK_CAPTURE(run, pyramid_plane, std::string("pyramid"), Method::kPlane);
BENCHMARK_CAPTURE(run, pyramid_plane_patch, std::string("pyramid"), Method::kPlanePatch);
BENCHMARK_CAPTURE(run, pyramid_epa, std::string("pyramid"), Method::kEpa);
BENCHMARK_CAPTURE(run, pyramid_mpr, std::string("pyramid"), Method::kMpr);
BENCHMARK_CAPTURE(run, cube_plane, std::string("cube"), Method::kPlane);
BENCHMARK_CAPTURE(run, cube_plane_patch, std::string("cube"), Method::kPlanePatch);
BENCHMARK_CAPTURE(run, cube_plane_general, std::string("cube"), Method::kPlaneGeneral);
BENCHMARK_CAPTURE(run, cube_turned_plane, std::string("cube_turned"), Method::kPlane);
BENCHMARK_CAPTURE(run_box_lanes, cube_closed_form, std::string("cube"), false);
BENCHMARK_CAPTURE(run_box_lanes, cube_closed_form_lanes, std::string("cube"), true);
BENCHMARK_CAPTURE(run_box_route, cube_pose_to_plane, false);
BENCHMARK_CAPTURE(run_box_route, cube_pose_to_plane_lanes, true);
BENCHMARK_CAPTURE(run, cube_epa, std::string("cube"), Method::kEpa);
BENCHMARK_CAPTURE(run, cube_mpr, std::string("cube"), Method::kMpr);
BENCHMARK_CAPTURE(run, plate_plane, std::string("plate_10x9x2"), Method::kPlane);
BENCHMARK_CAPTURE(run, plate_plane_patch, std::string("plate_10x9x2"), Method::kPlanePatch);
BENCHMARK_CAPTURE(run, plate_plane_general, std::string("plate_10x9x2"), Method::kPlaneGeneral);
BENCHMARK_CAPTURE(run, plate_epa, std::string("plate_10x9x2"), Method::kEpa);
BENCHMARK_CAPTURE(run, cylinder8_plane, std::string("cylinder_8"), Method::kPlane);
BENCHMARK_CAPTURE(run, cylinder8_plane_patch, std::string("cylinder_8"), Method::kPlanePatch);
BENCHMARK_CAPTURE(run, cylinder8_epa, std::string("cylinder_8"), Method::kEpa);
BENCHMARK_CAPTURE(run, cylinder8_mpr, std::string("cylinder_8"), Method::kMpr);
BENCHMARK_CAPTURE(run, icosahedron_plane, std::string("icosahedron"), Method::kPlane);
BENCHMARK_CAPTURE(run, icosahedron_plane_patch, std::string("icosahedron"), Method::kPlanePatch);
BENCHMARK_CAPTURE(run, icosahedron_epa, std::string("icosahedron"), Method::kEpa);
BENCHMARK_CAPTURE(run, icosahedron_mpr, std::string("icosahedron"), Method::kMpr);
BENCHMARK_CAPTURE(run, cylinder16_plane, std::string("cylinder_16"), Method::kPlane);
BENCHMARK_CAPTURE(run, cylinder16_plane_patch, std::string("cylinder_16"), Method::kPlanePatch);
BENCHMARK_CAPTURE(run, cylinder16_epa, std::string("cylinder_16"), Method::kEpa);
BENCHMARK_CAPTURE(run, cylinder16_mpr, std::string("cylinder_16"), Method::kMpr);
BENCHMARK_CAPTURE(run_wall, sphere_on_mesh, false);
BENCHMARK_CAPTURE(run_wall, cube_on_mesh, true);
