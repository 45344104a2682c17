// Non-spherical particles in the step loop: clumps and superquadrics, their contacts with spheres,
// each other and walls, and the invariants the loop must keep.

#include "body_scene.hpp"
#include "core/error.hpp"
#include "dynamics/system.hpp"
#include "geometry/clump.hpp"
#include "geometry/rotation.hpp"
#include "io/shape_reader.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <gtest/gtest.h>
#include <map>
#include <numbers>
#include <variant>
#include <vector>

namespace kiln::dynamics {
namespace {

using test::angular_momentum;
using test::base_scene;
using test::body;
using test::momentum;
using test::shape;
using test::superquadric;

// The members posed in vector lanes are member_centre's numbers, bit for bit, for any count
// (whole groups of eight and the rest) and any pose.
TEST(Bodies, PosedMembersAreMemberCentreBitForBit) {
    std::vector<geometry::ClumpSphere> spheres;
    for (int j = 0; j < 21; ++j) {
        const double t = 0.37 * j;
        spheres.push_back({Vec3(1e-3 * std::cos(t), 2e-3 * std::sin(1.3 * t), 0.5e-3 * j - 4e-3),
                           (1.0 + 0.01 * j) * 1e-3});
    }
    const Quat q = Quat(0.3, -0.5, 0.7, 0.2).normalized();
    const Mat3 rot = geometry::unit_rotation_matrix(q);
    const Vec3 x(0.0123, -0.045, 0.2071);
    for (std::size_t n = 0; n <= spheres.size(); ++n) {
        std::vector<double> out(4 * n + 4, -1.0); // one record past the end stays untouched
        pose_members(x, rot, member_columns(spheres.data(), n), out.data());
        for (std::size_t j = 0; j < n; ++j) {
            const Vec3 c = member_centre(x, rot, spheres[j].centre);
            EXPECT_EQ(out[4 * j], c.x()) << n << " members, member " << j;
            EXPECT_EQ(out[4 * j + 1], c.y()) << n << " members, member " << j;
            EXPECT_EQ(out[4 * j + 2], c.z()) << n << " members, member " << j;
            EXPECT_EQ(out[4 * j + 3], spheres[j].radius) << n << " members, member " << j;
            EXPECT_LT((c - (x + rot * spheres[j].centre)).norm(), 1e-15);
        }
        for (std::size_t k = 4 * n; k < out.size(); ++k) {
            EXPECT_EQ(out[k], -1.0) << n << " members: written past the end";
        }
    }
}

TEST(Bodies, FreeAsymmetricBodyKeepsAngularMomentumAndEnergy) {
    SceneSpec s = base_scene();
    s.gravity.setZero();
    s.shapes.push_back(shape("ellipsoid_123"));
    s.particles.push_back(body(0, Vec3::Zero(), Vec3::Zero(), Vec3(30, 1, 20)));
    System sys(s);
    const Vec3 l0 = sys.particles().ang_mom[0];
    const double e0 = sys.energies().rotational;
    double worst = 0.0;
    for (int k = 0; k < 20000; ++k) {
        sys.step();
        worst = std::max(worst, std::abs(sys.energies().rotational / e0 - 1.0));
    }
    constexpr double rounding = 1e-12; // the free rotation never changes L_world
    EXPECT_NEAR((sys.particles().ang_mom[0] - l0).norm() / l0.norm(), 0.0, rounding);
    constexpr double splitting = 1e-4; // O((omega dt)^2) energy error of the splitting
    EXPECT_LT(worst, splitting);
    // omega is derived from (q, L) and so is not constant for an asymmetric body.
    EXPECT_GT((sys.particles().omega[0] - Vec3(30, 1, 20)).norm(), 1.0);
}

TEST(Bodies, FreeSymmetricTopsFollowTheAnalyticMotionInASystem) {
    // The seed's 16-edged prism and 36-sphere cylinder (two equal moments across their axes, body
    // x) spinning free in a System, 20 000 steps at omega dt = 6e-4, with a second, asymmetric
    // body beside them (the splitting's batch): the step turns a symmetric top by its exact flow
    // (geometry::free_rotate_bodies), so the symmetry axis precesses about the fixed L at
    // |L| / i_p (Landau & Lifshitz, Sec. 33) to round-off, the rotational energy is kept to
    // round-off, and omega is R diag(1/I) R^T L.
    SceneSpec s = base_scene();
    s.gravity.setZero();
    s.shapes.push_back(shape("cylinder_16"));
    s.shapes.push_back(shape("cylinder_36"));
    s.shapes.push_back(shape("ellipsoid_123"));
    const Quat q0(Eigen::AngleAxisd(0.4, Vec3(1.0, 2.0, -1.0).normalized()));
    s.particles.push_back(body(0, Vec3::Zero(), Vec3::Zero(), Vec3(300, 40, -20), q0));
    s.particles.push_back(body(1, Vec3(0.05, 0, 0), Vec3::Zero(), Vec3(-100, 250, 60), q0));
    s.particles.push_back(body(2, Vec3(0.1, 0, 0), Vec3::Zero(), Vec3(30, 1, 20)));
    System sys(s);
    const ParticleStore& p = sys.particles();
    std::vector<Vec3> l0;
    std::vector<Vec3> axis0;
    std::vector<double> e0;
    for (std::size_t i = 0; i < 2; ++i) {
        ASSERT_EQ(geometry::symmetric_axis(p.inertia[i]), 0) << "body " << i;
        l0.push_back(p.ang_mom[i]);
        axis0.push_back(p.q[i] * Vec3::UnitX());
        e0.push_back(geometry::rotational_energy(p.q[i], p.ang_mom[i], p.inertia[i]));
    }
    ASSERT_EQ(geometry::symmetric_axis(p.inertia[2]), -1);
    const int steps = 20000;
    for (int k = 0; k < steps; ++k) {
        sys.step();
    }
    const double t = steps * s.time_step;
    for (std::size_t i = 0; i < 2; ++i) {
        const double ip = geometry::transverse_moment(p.inertia[i], 0);
        const Quat turn(Eigen::AngleAxisd(l0[i].norm() / ip * t, l0[i].normalized()));
        constexpr double kRoundOff = 1e-11; // 20 000 steps of ~1e-16 each, with room
        EXPECT_LT((p.q[i] * Vec3::UnitX() - turn * axis0[i]).norm(), kRoundOff) << "body " << i;
        EXPECT_LT((p.ang_mom[i] - l0[i]).norm(), kRoundOff * l0[i].norm()) << "body " << i;
        const double e = geometry::rotational_energy(p.q[i], p.ang_mom[i], p.inertia[i]);
        EXPECT_LT(std::abs(e / e0[i] - 1.0), kRoundOff) << "body " << i;
        const Mat3 r = geometry::unit_rotation_matrix(p.q[i]);
        const Vec3 full = r * (r.transpose() * p.ang_mom[i]).cwiseQuotient(p.inertia[i]);
        EXPECT_LT((p.omega[i] - full).norm(), 1e-13 * full.norm()) << "body " << i;
    }
}

TEST(Bodies, ClumpSettlesOnFloorOnItsSubSpheres) {
    SceneSpec s = base_scene();
    s.shapes.push_back(shape("cylinder_12"));
    s.walls.push_back({"floor", PlaneWall{Vec3::Zero(), Vec3::UnitZ()}, 0});
    // Upright, slightly tilted: it lands on one edge, rocks, and stands on its six lower spheres
    // (on its side it would roll on, as a cylinder does without rolling resistance). The body
    // frame is the principal frame, so the cylinder axis is found from the template axes.
    const auto& c = std::get<geometry::Clump>(s.shapes[0].shape);
    const Vec3 axis_body = c.template_axes.transpose() * Vec3::UnitZ();
    const Vec3 turn = axis_body.cross(Vec3::UnitZ());
    const Quat align =
        turn.norm() < 1e-12
            ? Quat::Identity()
            : Quat(Eigen::AngleAxisd(std::atan2(turn.norm(), axis_body.z()), turn.normalized()));
    const Quat up = Quat(Eigen::AngleAxisd(0.05, Vec3::UnitX())) * align;
    s.particles.push_back(body(0, Vec3(0, 0, 0.0035), Vec3::Zero(), Vec3::Zero(), up));
    s.time_step = 5e-6;
    System sys(s);
    for (int k = 0; k < 100000; ++k) {
        sys.step();
    }
    const ParticleStore& p = sys.particles();
    // At rest: the weight is carried by the floor and the body is still.
    constexpr double rest = 1e-3; // m/s, residual motion after 0.5 s of damped contacts
    EXPECT_LT(p.v[0].norm(), rest);
    EXPECT_LT(p.omega[0].norm() * p.radius[0], rest);
    // The lowest sub-sphere is at the floor within the static overlap.
    double lowest = 1.0;
    for (const auto& sph : c.spheres) {
        lowest = std::min(lowest, (p.x[0] + p.q[0] * sph.centre).z() - sph.radius);
    }
    constexpr double overlap_bound = 2e-5; // m; Hertz static overlap of ~6e-6 m at this weight
    EXPECT_LT(std::abs(lowest), overlap_bound);
    EXPECT_GT(sys.counters().wall_contacts, 0);
    // Standing upright: the centre is 3 mm up and the axis vertical.
    EXPECT_NEAR(p.x[0].z(), 3e-3, overlap_bound);
    constexpr double upright = 1e-3; // rad; the six lower spheres carry it symmetrically
    EXPECT_LT(std::acos(std::min(1.0, std::abs((p.q[0] * axis_body).z()))), upright);
}

TEST(Bodies, SpinningDimerHitsASphereItsCentreNeverApproaches) {
    // Clump members are found through a member-pair list built with a skin; the centre of this
    // dimer stays put (no neighbour-list rebuild), so only the rule that rebuilds the member list
    // when a member has turned by more than half a skin finds the contact.
    SceneSpec s = base_scene();
    s.gravity.setZero();
    const double r = 2e-3; // member radius (m), centres 2 mm apart as the LIGGGHTS dimer
    s.shapes.push_back(geometry::make_template(
        "dimer", geometry::make_clump({{Vec3(1e-3, 0, 0), r}, {Vec3(-1e-3, 0, 0), r}}, "dimer")));
    const auto& c = std::get<geometry::Clump>(s.shapes[0].shape);
    // Long axis along world x at the start; spin about world z (a principal axis).
    const Vec3 axis_body = (c.spheres[0].centre - c.spheres[1].centre).normalized();
    const Vec3 turn = axis_body.cross(Vec3::UnitX()); // zero when it is along +-x already
    const Quat q0 =
        turn.norm() < 1e-12
            ? Quat::Identity()
            : Quat(Eigen::AngleAxisd(std::atan2(turn.norm(), axis_body.x()), turn.normalized()));
    const double spin = 500.0; // rad/s: a quarter turn in 3.1 ms, member tips at 1.5 m/s
    s.particles.push_back(body(0, Vec3::Zero(), Vec3::Zero(), Vec3(0, 0, spin), q0));
    // A sphere of 1 mm whose surface is 0.74 mm from the members at the start (more than the
    // default skin of 0.6 mm) and 0.4 mm inside their reach after a quarter turn.
    const double y = 3.6e-3;
    s.particles.emplace_back(0, 1e-3, Vec3(0, y, 0), Vec3::Zero(), Vec3::Zero());
    System sys(s);
    const double reach = std::hypot(1e-3, y) - r - 1e-3;
    ASSERT_GT(reach, 0.2 * 3e-3); // apart by more than the skin at the start
    const Vec3 p0 = momentum(sys);
    sys.step();
    const long builds = sys.neighbour_builds();
    long builds_at_touch = -1;
    for (int k = 0; k < 2000 && builds_at_touch < 0; ++k) { // 4 ms: a quarter turn and a bit
        sys.step();
        builds_at_touch = sys.counters().particle_contacts > 0 ? sys.neighbour_builds() : -1;
    }
    // The contact is found, before any centre moved by half a skin (no list rebuild).
    EXPECT_EQ(builds_at_touch, builds);
    for (int k = 0; k < 1000; ++k) {
        sys.step();
    }
    const ParticleStore& p = sys.particles();
    const std::size_t sphere = p.shape[0] < 0 ? 0 : 1;
    constexpr double pushed = 0.05; // m/s; the hit transfers a fair part of the 1 m/s tip speed
    EXPECT_GT(p.v[sphere].y(), pushed);
    constexpr double conserved = 1e-12; // kg m/s; pair forces cancel to round-off
    EXPECT_LT((momentum(sys) - p0).norm(), conserved);
}

TEST(Bodies, ElasticHeadOnCollisionOfSuperquadricsConservesMomentumAndEnergy) {
    SceneSpec s = base_scene();
    s.gravity.setZero();
    s.materials[0].friction = 0.0;
    s.materials[0].restitution = 1.0;
    // The linear law has the potential k delta^2 / 2 in the MTD overlap, so energy is conserved up
    // to the integrator error (Hertz with a curvature-dependent R* is not exactly conservative).
    s.contact.law = contact::LinearSpringDashpot{2e3, 0.0};
    s.shapes.push_back(superquadric(Vec3(1e-3, 0.7e-3, 0.5e-3), 0.5, 0.7));
    const Quat tilt(Eigen::AngleAxisd(0.4, Vec3(1, 1, 0).normalized()));
    s.particles.push_back(body(0, Vec3(-1.2e-3, 0, 0), Vec3(0.5, 0, 0), Vec3::Zero(), tilt));
    s.particles.push_back(body(0, Vec3(1.2e-3, 0.2e-3, 0), Vec3(-0.5, 0, 0)));
    s.time_step = 1e-7;
    System sys(s);
    const Vec3 m0 = momentum(sys);
    const Vec3 l0 = angular_momentum(sys);
    const double e0 = sys.energies().total();
    long contacts = 0;
    for (int k = 0; k < 60000; ++k) {
        sys.step();
        contacts += sys.counters().particle_contacts;
    }
    EXPECT_GT(contacts, 0);
    EXPECT_EQ(sys.counters().particle_contacts, 0); // apart again
    constexpr double rounding = 1e-12;              // forces are applied as exact opposites
    const double scale = sys.particles().mass[0] * 0.5;
    EXPECT_NEAR((momentum(sys) - m0).norm() / scale, 0.0, rounding);
    constexpr double lever = 1e-9; // torques r x F at one contact point: exact up to round-off
    EXPECT_NEAR((angular_momentum(sys) - l0).norm() / (l0.norm()), 0.0, lever);
    constexpr double elastic = 2e-3; // O(dt^2) energy error of velocity Verlet, e = 1
    EXPECT_NEAR(sys.energies().total() / e0, 1.0, elastic);
    // Spin was transferred: the off-centre impact made the bodies rotate.
    EXPECT_GT(sys.energies().rotational, 0.0);
    EXPECT_EQ(sys.narrow_phase_counters().failures, 0);
}

SceneSpec mixed_pour(int threads) {
    SceneSpec s = base_scene();
    s.threads = threads;
    s.shapes.push_back(shape("cylinder_12"));
    s.shapes.push_back(superquadric(Vec3(1.5e-3, 1e-3, 1e-3), 0.5, 0.5));
    s.walls.push_back({"floor", PlaneWall{Vec3::Zero(), Vec3::UnitZ()}, 0});
    s.walls.push_back({"tube", CylinderWall{Vec3::Zero(), Vec3::UnitZ(), 0.012}, 0});
    // Clumps at the bottom, superquadrics above, spheres on top, each falling faster than the
    // layer below so that every kind of pair meets.
    const double z[4] = {0.001, 0.04, 0.055, 0.065};
    const int count[3] = {6, 15, 15};
    for (int k = 0; k < 3; ++k) {
        InsertSpec ins;
        ins.region = {Vec3(-0.008, -0.008, z[k]), Vec3(0.008, 0.008, z[k + 1])};
        ins.count = count[k];
        ins.shape = k < 2 ? k : -1;
        ins.size.radius = k < 2 ? s.shapes[static_cast<std::size_t>(k)].bounding_radius() : 1e-3;
        ins.orientation.random = true;
        ins.velocity = Vec3(0, 0, -0.5 - 0.5 * k);
        s.inserts.push_back(ins);
    }
    return s;
}

TEST(Bodies, EveryClumpMemberTouchingAWallMakesOneContact) {
    // The wall pass keeps a body's members within 1e-9 of their radius of touching a wall and the
    // exact test decides for those. A tilted 36-sphere clump pressed into a plane wall, then into
    // a cylinder wall, its deepest member 0.8 mm in: one wall contact per member whose sphere
    // overlaps the wall at the pose of the step, counted here from the template (no member within
    // 1e-6 of its radius of touching, so the count does not hang on round-off).
    const geometry::ShapeTemplate t = shape("cylinder_36");
    const auto& members = std::get<geometry::Clump>(t.shape).spheres;
    const Quat q(Eigen::AngleAxisd(0.4, Vec3(1.0, 2.0, 0.5).normalized()));
    const Mat3 r0 = q.toRotationMatrix();
    constexpr double depth = 0.8e-3;
    for (int kind = 0; kind < 2; ++kind) {
        SceneSpec s = base_scene();
        s.gravity.setZero();
        s.shapes.push_back(t);
        const double tube = 0.02;
        double reach = -1.0; // the largest of (R c).z - r (plane) or (R c).x + r (tube)
        for (const auto& m : members) {
            const Vec3 c = r0 * m.centre;
            reach = std::max(reach, kind == 0 ? m.radius - c.z() : c.x() + m.radius);
        }
        const Vec3 x = kind == 0 ? Vec3(0, 0, reach - depth) : Vec3(tube - reach + depth, 0, 0);
        const WallShape w = kind == 0 ? WallShape(PlaneWall{Vec3::Zero(), Vec3::UnitZ()})
                                      : WallShape(CylinderWall{Vec3::Zero(), Vec3::UnitZ(), tube});
        s.walls.push_back({"wall", w, 0});
        s.particles.push_back(body(0, x, Vec3::Zero(), Vec3::Zero(), q));
        System sys(s);
        sys.step();
        const Vec3 xb = sys.particles().x[0];
        const Mat3 rb = sys.particles().q[0].toRotationMatrix();
        long touching = 0;
        long razor = 0;
        for (const auto& m : members) {
            const Vec3 c = xb + rb * m.centre;
            const double overlap = std::visit(
                [&](const auto& ws) { return wall_contact(ws, c, m.radius).overlap; }, w);
            touching += overlap > 0.0 ? 1 : 0;
            razor += std::abs(overlap) < 1e-6 * m.radius ? 1 : 0;
        }
        EXPECT_EQ(razor, 0) << "wall " << kind;
        EXPECT_GE(touching, 3) << "wall " << kind;
        EXPECT_LT(touching, static_cast<long>(members.size())) << "wall " << kind;
        EXPECT_EQ(sys.counters().wall_contacts, touching) << "wall " << kind;
    }
}

TEST(Bodies, MixedPourGivesTheSameBitsForOneAndTwoThreads) {
    System a(mixed_pour(1));
    System b(mixed_pour(2));
    b.use_parallel_bodies(1); // posing and rotation in parallel from the first body on
    long contacts = 0;
    for (int k = 0; k < 6000; ++k) {
        a.step();
        b.step();
        contacts += a.counters().particle_contacts;
    }
    EXPECT_GT(contacts, 0);
    test::expect_same_bits(a.particles(), b.particles());
    EXPECT_EQ(a.narrow_phase_counters().failures, 0);
}

// A box of 6 x 6 x 6 seed cylinders (12-sphere clumps, shapes/cylinder_12.toml) on a lattice,
// randomly turned and moving in random directions at up to 1 m/s (a fixed pseudo-random
// sequence), and a sphere in every second cell between them: the clumps' members meet each
// other, the spheres and the six walls from the first steps. World frame.
SceneSpec clump_box(int threads) {
    SceneSpec s = base_scene();
    s.threads = threads;
    s.gravity.setZero();
    s.record_contact_onsets = true; // as heat's collision conduction asks
    s.shapes.push_back(shape("cylinder_12"));
    constexpr int n = 6;
    constexpr double pitch = 9e-3; // m; the cylinder's bounding radius is 4.24 mm
    const double side = n * pitch;
    for (int a = 0; a < 3; ++a) {
        const Vec3 e = Vec3::Unit(a);
        s.walls.push_back({"low", PlaneWall{Vec3::Zero(), e}, 0});
        s.walls.push_back({"high", PlaneWall{side * e, -e}, 0});
    }
    std::uint64_t state = 2026;
    const auto uniform = [&state] { // in [-1, 1)
        state = state * 6364136223846793005ULL + 1442695040888963407ULL;
        return static_cast<double>(state >> 11) * 0x1.0p-52 - 1.0;
    };
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
            for (int k = 0; k < n; ++k) {
                const Vec3 x = pitch * Vec3(i + 0.5, j + 0.5, k + 0.5);
                const Vec3 v = Vec3(uniform(), uniform(), uniform()) / std::sqrt(3.0);
                const Quat q = Quat(uniform(), uniform(), uniform(), uniform() + 1.5).normalized();
                s.particles.push_back(body(0, x, v, 300.0 * Vec3(uniform(), 0, uniform()), q));
                if (i < n - 1 && j < n - 1 && k < n - 1 && (i + j + k) % 2 == 0) {
                    s.particles.emplace_back(0, 0.4e-3, x + Vec3::Constant(0.5 * pitch), -v,
                                             Vec3::Zero());
                }
            }
        }
    }
    return s;
}

TEST(Bodies, ClumpBoxGivesTheSameBitsForOneAndTwoThreads) {
    // With two threads the posing of every particle's elements and the rotation of the bodies
    // run in parallel over the bodies (each reads and writes only its own), and the law of the
    // clumps' member pairs ahead of the serial pass that adds the forces in its order. Run here
    // from the first body on (the default waits for 256 bodies), so that both threads take part:
    // positions, velocities, orientations, angular momenta, contact counts and impact onsets at
    // every step and the contact records equal those of one thread.
    System a(clump_box(1));
    System b(clump_box(2));
    ASSERT_EQ(b.threads(), 2);
    b.use_parallel_bodies(1);
    long contacts = 0;
    long onsets = 0; // impacts recorded (heat's collision conduction reads them)
    for (int k = 0; k < 5000; ++k) {
        a.step();
        b.step();
        contacts += a.counters().particle_contacts;
        ASSERT_EQ(a.counters().particle_contacts, b.counters().particle_contacts) << k;
        ASSERT_EQ(a.counters().wall_contacts, b.counters().wall_contacts) << k;
        const auto& oa = a.contact_onsets();
        const auto& ob = b.contact_onsets();
        ASSERT_EQ(oa.size(), ob.size()) << k;
        for (std::size_t o = 0; o < oa.size(); ++o) {
            EXPECT_EQ(oa[o].id_i, ob[o].id_i);
            EXPECT_EQ(oa[o].id_j, ob[o].id_j);
            EXPECT_EQ(oa[o].speed, ob[o].speed);
            EXPECT_EQ(oa[o].m_eff, ob[o].m_eff);
            EXPECT_EQ(oa[o].r_eff, ob[o].r_eff);
            for (int c = 0; c < 3; ++c) {
                EXPECT_EQ(oa[o].normal[c], ob[o].normal[c]);
                EXPECT_EQ(oa[o].point[c], ob[o].point[c]);
            }
        }
        onsets += static_cast<long>(oa.size());
    }
    EXPECT_GT(contacts, 50000); // or the test proves little
    EXPECT_GT(onsets, 200);
    test::expect_same_bits(a.particles(), b.particles());
    const std::size_t records = test::expect_same_records(a, b);
    std::printf("%zu particles, %ld contacts and %ld onsets over the run, %zu element contacts at "
                "the end\n",
                a.particles().size(), contacts, onsets, records);
}

TEST(Bodies, MemberPairsInLanesAreTheDoubleLoops) {
    // The member build tests two clumps' members, and the first pass tests a clump's members
    // against a plane wall, eight at a time in vector lanes (AVX-512 builds) or one at a time:
    // the same pairs in the same order, so the same count over every build and the same bits
    // at every step (a pair the lanes missed would miss its contact; one they added would show
    // in the count; a member the wall's pass missed would miss its wall contact). The clump
    // box's 12-sphere clumps take the members' pre-selection, the route the lanes replace, and
    // meet the six walls from the first steps.
    System a(clump_box(1));
    System b(clump_box(1));
    b.use_member_lanes(false);
    long contacts = 0;
    long wall_contacts = 0;
    for (int k = 0; k < 3000; ++k) {
        a.step();
        b.step();
        contacts += a.counters().particle_contacts;
        wall_contacts += a.counters().wall_contacts;
        ASSERT_EQ(a.counters().particle_contacts, b.counters().particle_contacts) << k;
        ASSERT_EQ(a.counters().wall_contacts, b.counters().wall_contacts) << k;
        ASSERT_EQ(a.member_pairs_built(), b.member_pairs_built()) << k;
    }
    EXPECT_GT(contacts, 20000); // or the test proves little
    EXPECT_GT(wall_contacts, 1000);
    EXPECT_GT(a.member_pairs_built(), 2000);
    test::expect_same_bits(a.particles(), b.particles());
    std::printf("%ld member pairs listed over the builds, %ld contacts, %ld wall contacts\n",
                a.member_pairs_built(), contacts, wall_contacts);
}

// advance(k) defers every step's second half kick (of v and of the bodies' angular momentum) to
// the next step's first pass, clears forces and torques in that pass, and does not form a body's
// omega between two steps; the state between calls must be that of k calls of step(). Clumps,
// superquadrics and spheres against each other, a cylinder wall and a plane or mesh floor.
TEST(Bodies, AdvanceGivesTheBitsOfAsManySteps) {
    for (const bool mesh : {false, true}) {
        for (const int threads : {1, 2}) {
            SceneSpec s = mixed_pour(1);
            if (mesh) {
                s.walls.erase(s.walls.begin()); // the plane floor
                test::add_floor(s, true);
            }
            System stepped(s);
            s.threads = threads;
            System advanced(s);
            // Runs of 1 (the unfused path), 2 and longer, summing to 8000 steps.
            const std::vector<long> runs = {1, 2, 3, 97, 1, 396, 1000, 500, 2000, 4000};
            long pair_contacts = 0;
            long wall_contacts = 0;
            for (const long k : runs) {
                for (long n = 0; n < k; ++n) {
                    stepped.step();
                    pair_contacts += stepped.counters().particle_contacts;
                    wall_contacts += stepped.counters().wall_contacts;
                }
                advanced.advance(k);
                // Tolerance: none. The same operations in the same order, in fewer passes.
                ASSERT_EQ(stepped.step_count(), advanced.step_count());
                const ParticleStore& a = stepped.particles();
                const ParticleStore& b = advanced.particles();
                ASSERT_EQ(a.size(), b.size());
                std::size_t differing = 0;
                for (std::size_t i = 0; i < a.size(); ++i) {
                    differing += a.x[i] != b.x[i] || a.v[i] != b.v[i] || a.omega[i] != b.omega[i] ||
                                         a.force[i] != b.force[i] || a.torque[i] != b.torque[i] ||
                                         a.q[i].coeffs() != b.q[i].coeffs() ||
                                         a.ang_mom[i] != b.ang_mom[i]
                                     ? 1
                                     : 0;
                }
                EXPECT_EQ(differing, 0U) << (mesh ? "mesh floor, " : "plane floor, ") << threads
                                         << " threads, after step " << stepped.step_count();
                EXPECT_EQ(stepped.counters().particle_contacts,
                          advanced.counters().particle_contacts);
                EXPECT_EQ(stepped.counters().wall_contacts, advanced.counters().wall_contacts);
                EXPECT_EQ(stepped.counters().elastic_energy, advanced.counters().elastic_energy);
            }
            EXPECT_EQ(advanced.step_count(), 8000);
            EXPECT_GT(pair_contacts, 1000);
            EXPECT_GT(wall_contacts, 1000);
            std::printf("%s floor, %d threads: %ld pair and %ld wall contacts in all steps\n",
                        mesh ? "mesh" : "plane", threads, pair_contacts, wall_contacts);
        }
    }
}

TEST(Bodies, SphereElementRecordsMatchTheElementQueries) {
    // Sphere elements (clump members, spheres) are posed as centre-and-radius records and their
    // pairs found by a first pass over the member-pair list; sphere members meet walls without an
    // Element. Every such record must be the contact the element queries give from the
    // particle's pose, and every touching sphere-element pair involving a body must be recorded.
    System sys(mixed_pour(1));
    constexpr double length_tol = 1e-13; // m; posing with R(q) in two forms differs by round-off
    constexpr double normal_tol = 1e-9;  // unit normals of ~1e-5 m overlaps, same round-off
    long checked_pairs = 0;
    long checked_walls = 0;
    for (int k = 0; k < 6000; ++k) {
        sys.step();
        if (k % 50 != 49) {
            continue;
        }
        const ParticleStore& p = sys.particles();
        const SceneSpec& spec = sys.spec();
        std::vector<std::vector<Element>> el(p.size());
        std::map<std::int64_t, std::size_t> index;
        for (std::size_t i = 0; i < p.size(); ++i) {
            index[p.id[i]] = i;
            const auto* t =
                p.shape[i] >= 0 ? &spec.shapes[static_cast<std::size_t>(p.shape[i])] : nullptr;
            append_elements(t, p.x[i], p.q[i], p.radius[i], el[i]);
        }
        const auto sphere = [](const Element& e) { return e.kind == Element::Kind::sphere; };
        long recorded_pairs = 0;
        long recorded_walls = 0;
        for (const BodyContactEntry& e : sys.body_contacts()) {
            const Element& A = el[index.at(e.key.a)][static_cast<std::size_t>(e.key.ea)];
            if (!sphere(A)) {
                continue;
            }
            ElementContact q;
            if (e.key.b >= 0) {
                const Element& B = el[index.at(e.key.b)][static_cast<std::size_t>(e.key.eb)];
                if (!sphere(B)) {
                    continue;
                }
                q = element_contact(A, B, spec.narrow_phase, nullptr);
                ++recorded_pairs;
                ++checked_pairs;
            } else {
                q = element_wall_contact(A,
                                         spec.walls[static_cast<std::size_t>(-1 - e.key.b)].shape);
                ++checked_walls;
                ++recorded_walls;
            }
            ASSERT_TRUE(q.touching);
            EXPECT_NEAR(e.contact.overlap, q.overlap, length_tol);
            EXPECT_LT((e.contact.normal - q.normal).norm(), normal_tol);
            EXPECT_LT((e.contact.point - q.point).norm(), length_tol);
        }
        // Brute force: touching sphere-element pairs with a body on either side.
        long touching = 0;
        for (std::size_t i = 0; i < p.size(); ++i) {
            for (std::size_t j = i + 1; j < p.size(); ++j) {
                if (p.shape[i] < 0 && p.shape[j] < 0) {
                    continue; // sphere pairs are the sphere kernel's
                }
                for (const Element& a : el[i]) {
                    for (const Element& b : el[j]) {
                        const double rs = a.radius + b.radius;
                        touching +=
                            sphere(a) && sphere(b) && (a.centre - b.centre).squaredNorm() < rs * rs
                                ? 1
                                : 0;
                    }
                }
            }
        }
        EXPECT_EQ(recorded_pairs, touching) << "step " << k;
        // Brute force: touching sphere elements of bodies against the analytic walls.
        long touching_walls = 0;
        for (std::size_t i = 0; i < p.size(); ++i) {
            for (const Element& a : el[i]) {
                for (const Wall& w : spec.walls) {
                    touching_walls +=
                        p.shape[i] >= 0 && sphere(a) && element_wall_contact(a, w.shape).touching
                            ? 1
                            : 0;
                }
            }
        }
        EXPECT_EQ(recorded_walls, touching_walls) << "step " << k;
    }
    EXPECT_GT(checked_pairs, 0);
    EXPECT_GT(checked_walls, 0);
}

/// Superballs (m = 2/e = 4) poured into a tube with the given law and body radius rule.
TEST(Bodies, RecordsBuiltOnDemandCarryTheForceLoopsGeometry) {
    // Member-pair contacts keep only shear and force between steps; body_contacts() derives their
    // normal, point and R* from the posed elements when it is read. These must be, bit for bit,
    // the values the force loop used: the onset of a new contact carries the loop's normal, point
    // and R*, so every pair onset must find its record with exactly those values.
    SceneSpec spec = mixed_pour(1);
    spec.record_contact_onsets = true;
    System sys(spec);
    long member_onsets = 0;
    long pair_onsets = 0;
    for (int k = 0; k < 30000; ++k) {
        sys.step();
        const ParticleStore& p = sys.particles();
        std::map<std::int64_t, std::size_t> index;
        for (std::size_t i = 0; i < p.size(); ++i) {
            index[p.id[i]] = i;
        }
        for (const ContactOnset& o : sys.contact_onsets()) {
            if (o.id_j < 0) {
                continue; // walls: the table's records, not derived
            }
            const int shape_i = p.shape[index.at(o.id_i)];
            const int shape_j = p.shape[index.at(o.id_j)];
            if (shape_i < 0 && shape_j < 0) {
                continue; // two spheres: the sphere kernel's onset, no body contact
            }
            const Vec3 point(o.point[0], o.point[1], o.point[2]);
            const Vec3 normal(-o.normal[0], -o.normal[1], -o.normal[2]); // record: b to a
            long found = 0;
            for (const BodyContactEntry& e : sys.body_contacts()) {
                if (e.key.a == o.id_i && e.key.b == o.id_j && e.contact.point == point) {
                    ++found;
                    EXPECT_EQ(e.contact.normal, normal) << "step " << k;
                    EXPECT_EQ(e.contact.r_eff, o.r_eff) << "step " << k;
                }
            }
            EXPECT_EQ(found, 1) << "step " << k << ", ids " << o.id_i << " " << o.id_j;
            // Clumps and spheres (shape 0 or none) on both sides: a member pair.
            ++pair_onsets;
            member_onsets += shape_i != 1 && shape_j != 1 ? 1 : 0;
        }
    }
    EXPECT_GT(member_onsets, 40) << "pair onsets " << pair_onsets;
}

SceneSpec superball_pour(const contact::ContactLaw& law, BodyRadius rule) {
    SceneSpec s = base_scene();
    s.contact.law = law;
    s.body_radius = rule;
    s.shapes.push_back(superquadric(Vec3(1e-3, 1e-3, 1e-3), 0.5, 0.5));
    s.walls.push_back({"floor", PlaneWall{Vec3::Zero(), Vec3::UnitZ()}, 0});
    s.walls.push_back({"tube", CylinderWall{Vec3::Zero(), Vec3::UnitZ(), 0.005}, 0});
    InsertSpec ins;
    ins.region = {Vec3(-0.004, -0.004, 0.0), Vec3(0.004, 0.004, 0.012)};
    ins.count = 12;
    ins.shape = 0;
    ins.size.radius = s.shapes[0].bounding_radius();
    ins.orientation.random = true;
    ins.velocity = Vec3(0, 0, -0.5);
    s.inserts.push_back(ins);
    return s;
}

/// Largest position difference (m) of two runs of the same scene after `steps` steps; counts the
/// contact-steps of the first into `contacts`.
double pour_difference(const SceneSpec& sa, const SceneSpec& sb, int steps, long& contacts) {
    System a(sa);
    System b(sb);
    contacts = 0;
    for (int k = 0; k < steps; ++k) {
        a.step();
        b.step();
        contacts += a.counters().particle_contacts + a.counters().wall_contacts;
    }
    double worst = 0.0;
    for (std::size_t i = 0; i < a.particles().size(); ++i) {
        worst = std::max(worst, (a.particles().x[i] - b.particles().x[i]).norm());
    }
    return worst;
}

TEST(Bodies, BodyRadiusRuleDoesNotEnterTheLinearLaw) {
    // The linear law's stiffness, damping and tangential spring do not depend on R*, so freezing
    // R* at the first touch (first_touch) or re-evaluating it (per_step) must give the same bits
    // (validation 15 pours with this law; its change of packing fraction between the two rules was
    // not caused by R*). Without rolling resistance R* has no other use in the law.
    const contact::LinearSpringDashpot linear{500.0, 2.0 / 7.0};
    long contacts = 0;
    const double linear_diff =
        pour_difference(superball_pour(linear, BodyRadius::first_touch),
                        superball_pour(linear, BodyRadius::per_step), 8000, contacts);
    EXPECT_GT(contacts, 0);
    EXPECT_EQ(linear_diff, 0.0); // exact equality is the point
    // Control: Hertz's stiffness grows with sqrt(R*), so the rule matters there.
    const double hertz_diff = pour_difference(
        superball_pour(contact::HertzMindlin{}, BodyRadius::first_touch),
        superball_pour(contact::HertzMindlin{}, BodyRadius::per_step), 8000, contacts);
    EXPECT_GT(contacts, 0);
    EXPECT_GT(hertz_diff, 0.0);
}

TEST(Bodies, CollectContactsListsBodyContactsWithBodyIndices) {
    System sys(mixed_pour(1));
    std::vector<ContactRecord> contacts;
    long body_pairs = 0;
    long body_walls = 0;
    for (int k = 0; k < 6000; ++k) {
        sys.step();
        if (k % 200 != 199) {
            continue;
        }
        sys.collect_contacts(contacts);
        long pairs = 0;
        long walls = 0;
        const ParticleStore& p = sys.particles();
        for (const ContactRecord& c : contacts) {
            (c.wall ? walls : pairs) += 1;
            ASSERT_LT(c.i, p.size());
            EXPECT_GT(c.overlap, 0.0);
            EXPECT_GT(c.r_eff, 0.0);
            EXPECT_NEAR(c.normal.norm(), 1.0, 1e-12); // unit normal up to rounding
            const bool body = p.shape[c.i] >= 0 || (!c.wall && p.shape[c.j] >= 0);
            if (!body) {
                continue;
            }
            (c.wall ? body_walls : body_pairs) += 1;
            // The point lies within the bounding spheres (plus the overlap) and a wall normal
            // points from the body towards the wall.
            EXPECT_LE((c.point - p.x[c.i]).norm(), p.radius[c.i] + c.overlap);
            if (!c.wall) {
                ASSERT_LT(c.j, p.size());
                EXPECT_LE((c.point - p.x[c.j]).norm(), p.radius[c.j] + c.overlap);
                EXPECT_LT(p.id[c.i], p.id[c.j]); // records of bodies carry a = the smaller id
            } else {
                EXPECT_GT(c.normal.dot(c.point - p.x[c.i]), 0.0);
            }
        }
        // Every element contact the force loop counted is listed once, and no other.
        EXPECT_EQ(pairs, sys.counters().particle_contacts);
        EXPECT_EQ(walls, sys.counters().wall_contacts);
    }
    EXPECT_GT(body_pairs, 0);
    EXPECT_GT(body_walls, 0);
}

} // namespace
} // namespace kiln::dynamics
