#include "core/error.hpp"
#include "dynamics/system.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <random>
#include <string>
#include <variant>
#include <vector>

namespace kiln::dynamics {
namespace {

SceneSpec base_scene() {
    SceneSpec s;
    s.materials.push_back({"m", 1e7, 0.3, 2500, 0.5, 0.3, 0.0});
    s.time_step = 1e-5;
    return s;
}

TEST(System, FreeFallIsExactForConstantGravity) {
    SceneSpec s = base_scene();
    s.particles.push_back({0, 1e-3, Vec3(0, 0, 1), Vec3(0.1, 0, 2), Vec3::Zero()});
    System sys(s);
    for (int k = 0; k < 1000; ++k) {
        sys.step();
    }
    const double t = sys.time();
    const Vec3 expected = Vec3(0, 0, 1) + Vec3(0.1, 0, 2) * t + 0.5 * s.gravity * t * t;
    constexpr double rounding = 1e-12; // velocity Verlet integrates constant acceleration exactly
    EXPECT_NEAR((sys.particles().x[0] - expected).norm(), 0.0, rounding);
}

TEST(System, CollisionConservesMomentum) {
    SceneSpec s = base_scene();
    s.gravity.setZero();
    s.particles.push_back({0, 1e-3, Vec3(0, 0, 0), Vec3(1, 0.2, 0), Vec3(0, 0, 5)});
    s.particles.push_back({0, 2e-3, Vec3(3.5e-3, 0.5e-3, 0), Vec3(-1, 0, 0), Vec3::Zero()});
    s.time_step = 1e-7;
    System sys(s);
    const auto momentum = [&] {
        Vec3 m = Vec3::Zero();
        for (std::size_t i = 0; i < 2; ++i) {
            m += sys.particles().mass[i] * sys.particles().v[i];
        }
        return m;
    };
    const Vec3 m0 = momentum();
    long contacts = 0;
    for (int k = 0; k < 20000; ++k) {
        sys.step();
        contacts += sys.counters().particle_contacts;
    }
    EXPECT_GT(contacts, 0);
    constexpr double rounding = 1e-12; // pair forces are applied as exact opposites
    EXPECT_NEAR((momentum() - m0).norm() / m0.norm(), 0.0, rounding);
}

TEST(System, TooLargeTimeStepIsAnInputError) {
    SceneSpec s = base_scene();
    s.particles.push_back({0, 1e-3, Vec3::Zero(), Vec3::Zero(), Vec3::Zero()});
    s.time_step = 1e-3;
    EXPECT_THROW(System{s}, InputError);
    s.allow_unsafe_time_step = true;
    System sys(s);
    EXPECT_FALSE(sys.warnings().empty());
}

TEST(System, RandomInsertionPlacesNonOverlappingParticlesInRegion) {
    SceneSpec s = base_scene();
    InsertSpec ins;
    ins.region = {Vec3(0, 0, 0), Vec3(0.02, 0.02, 0.04)};
    ins.count = 300;
    ins.size.kind = SizeDistribution::Kind::uniform;
    ins.size.min = 0.5e-3;
    ins.size.max = 1.0e-3;
    s.inserts.push_back(ins);
    const System sys(s);
    const ParticleStore& p = sys.particles();
    ASSERT_EQ(p.size(), 300U);
    for (std::size_t i = 0; i < p.size(); ++i) {
        EXPECT_GE(p.radius[i], 0.5e-3);
        EXPECT_LE(p.radius[i], 1.0e-3);
        EXPECT_TRUE((p.x[i].array() - p.radius[i] >= ins.region.lo.array()).all());
        EXPECT_TRUE((p.x[i].array() + p.radius[i] <= ins.region.hi.array()).all());
        for (std::size_t j = i + 1; j < p.size(); ++j) {
            EXPECT_GE((p.x[i] - p.x[j]).norm(), p.radius[i] + p.radius[j]);
        }
    }
}

TEST(System, RandomInsertionKeepsTheSizeDistributionAtHighFill) {
    // A uniform distribution on [0.5, 1.5] mm has mean 1 mm and standard deviation 0.289 mm. At a
    // solid fraction near 0.3 small particles fit far more often than large ones, so any
    // re-drawing of radii on rejection shows as a low mean.
    SceneSpec s = base_scene();
    InsertSpec ins;
    ins.region = {Vec3(0, 0, 0), Vec3(0.03, 0.03, 0.03)};
    ins.count = 1400; // solid fraction 1400 * (4/3) pi <r^3> / V = 0.30 with <r^3> = 1.25e-9 m^3
    ins.size.kind = SizeDistribution::Kind::uniform;
    ins.size.min = 0.5e-3;
    ins.size.max = 1.5e-3;
    s.inserts.push_back(ins);
    const System sys(s);
    const ParticleStore& p = sys.particles();
    ASSERT_EQ(p.size(), 1400U);
    double mean = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        mean += p.radius[i] / static_cast<double>(p.size());
    }
    constexpr double sampling = 4.0 * 0.289e-3 / 37.4; // four standard errors of a 1400-sample mean
    EXPECT_NEAR(mean, 1.0e-3, sampling);
}

TEST(System, InsertionThatCannotFitIsAnInputError) {
    SceneSpec s = base_scene();
    InsertSpec ins;
    ins.region = {Vec3(0, 0, 0), Vec3(0.01, 0.01, 0.01)};
    ins.count = 1000; // would need a solid fraction of 4
    ins.size.radius = 1e-3;
    s.inserts.push_back(ins);
    EXPECT_THROW(System{s}, InputError);
}

TEST(System, LatticeFillsRegion) {
    SceneSpec s = base_scene();
    InsertSpec ins;
    ins.kind = InsertSpec::Kind::lattice;
    ins.region = {Vec3(0, 0, 0), Vec3(0.01, 0.01, 0.01)};
    ins.size.radius = 1e-3;
    s.inserts.push_back(ins);
    const System sys(s);
    EXPECT_EQ(sys.particles().size(), 125U); // 5 x 5 x 5 spheres of diameter 2 mm in 10 mm
}

TEST(System, SpheresComeToRestOnAPlane) {
    SceneSpec s = base_scene();
    s.walls.push_back({"floor", PlaneWall{Vec3::Zero(), Vec3::UnitZ()}, 0});
    s.particles.push_back({0, 1e-3, Vec3(0, 0, 3e-3), Vec3::Zero(), Vec3::Zero()});
    System sys(s);
    for (int k = 0; k < 50000; ++k) {
        sys.step();
    }
    const double m = sys.particles().mass[0];
    const double r = sys.particles().radius[0];
    EXPECT_NEAR(sys.particles().v[0].norm(), 0.0, 1e-6);
    // Static Hertz overlap against a rigid plane: m g = 4/3 E* sqrt(r) delta^1.5.
    const double e_star = 1e7 / (1 - 0.09) / 2; // wall of the same material
    const double delta = std::pow(m * 9.81 / (4.0 / 3.0 * e_star * std::sqrt(r)), 2.0 / 3.0);
    constexpr double settle = 1e-6; // relative: residual oscillation after 0.5 s of damping
    EXPECT_NEAR(sys.particles().x[0].z(), r - delta, settle * r);
}

// Wall contacts are evaluated four at a time on vector lanes (simd::wall_groups, a last group
// padded with copies of its last contact); each must get what the one-contact law gives it, its
// history carried from one evaluation to the next. Spheres against one, two or three planes and a
// cylinder, apart from each other; one material (the tangential damping shared with the normal
// one) and two materials with rolling resistance.
TEST(System, WallContactsOnLanesMatchOneContactAtATime) {
    for (const int materials : {1, 2}) {
        SceneSpec s = base_scene();
        s.gravity.setZero();
        if (materials == 2) {
            s.materials.push_back({"n", 3e7, 0.25, 1500, 0.4, 0.5, 0.02});
            s.contact.rolling = contact::RollingModel::constant_torque;
        }
        const double box = 0.02;
        for (int a = 0; a < 3; ++a) {
            s.walls.push_back({"lo", PlaneWall{Vec3::Zero(), Vec3::Unit(a)}, 0});
            s.walls.push_back(
                {"hi", PlaneWall{Vec3::Constant(box), -Vec3::Unit(a)}, materials - 1});
        }
        s.walls.push_back({"tube", CylinderWall{Vec3(0.01, 0.01, 0), Vec3::UnitZ(), 0.0125}, 0});
        const double r = 1e-3;
        const double in = r - 3e-5; // centre distance of a touching sphere from a plane
        // The cylinder (axis z through (0.01, 0.01), radius 0.0125) cuts the box's vertical edges:
        // a sphere where it meets x = 0 and z = 0 touches three walls.
        const double yc = 0.01 + std::sqrt(std::pow(0.0125 - in, 2) - std::pow(0.01 - in, 2));
        const double dc = (0.0125 - in) / std::sqrt(2.0);
        const std::vector<Vec3> centres = {
            {in, 0.01, 0.01}, {0.01, in, 0.01},           {0.01, 0.01, in},
            {in, 0.01, in},   {box - in, 0.01, box - in}, {0.01, box - in, in},
            {in, yc, in},     {0.01, 0.01, box - in},     {0.01 + dc, 0.01 + dc, 0.01}};
        std::mt19937_64 rng(3);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        for (std::size_t k = 0; k < centres.size(); ++k) {
            s.particles.push_back({static_cast<int>(k % static_cast<std::size_t>(materials)), r,
                                   centres[k], Vec3(0.2 * u(rng), 0.2 * u(rng), 0.2 * u(rng)),
                                   Vec3(50 * u(rng), 50 * u(rng), 50 * u(rng))});
        }
        System sys(s);
        const PairTable pairs(s.materials, s.pairs,
                              s.contact.clamp_normal_force && s.contact.rebound_restitution);
        std::vector<Vec3> shear(centres.size() * s.walls.size(), Vec3::Zero()); // by id, wall
        long touching = 0;
        for (int eval = 0; eval < 3; ++eval) {
            if (eval > 0) {
                sys.refresh(); // the same positions, the histories advanced once more
            }
            const ParticleStore& p = sys.particles();
            EXPECT_EQ(sys.counters().particle_contacts, 0);
            for (std::size_t i = 0; i < p.size(); ++i) {
                Vec3 f = Vec3::Zero();
                Vec3 t = Vec3::Zero();
                for (std::size_t w = 0; w < s.walls.size(); ++w) {
                    const WallContact g = std::visit(
                        [&](const auto& shape) { return wall_contact(shape, p.x[i], p.radius[i]); },
                        s.walls[w].shape);
                    if (!(g.overlap > 0.0)) {
                        continue;
                    }
                    touching += eval == 0 ? 1 : 0;
                    const contact::ContactInput c{
                        g.n, g.overlap, g.r_eff,    p.mass[i],   p.radius[i] - g.overlap,
                        0.0, p.v[i],    p.omega[i], Vec3::Zero()};
                    Vec3& h = shear[static_cast<std::size_t>(p.id[i]) * s.walls.size() + w];
                    const contact::ContactOutput o = contact::evaluate(
                        contact::HertzMindlin{}, s.contact,
                        pairs.at(p.material[i], s.walls[w].material), c, h, s.time_step);
                    f += o.force;
                    t += o.torque_i;
                }
                // Relative: other round-off only (fused multiply-adds, the shared damping root).
                EXPECT_LE((p.force[i] - f).norm(), 1e-11 * f.norm()) << "particle " << p.id[i];
                EXPECT_LE((p.torque[i] - t).norm(), 1e-11 * t.norm() + 1e-30)
                    << "particle " << p.id[i];
                EXPECT_GT(f.norm(), 0.0);
            }
        }
        EXPECT_EQ(touching, 14); // 1 + 1 + 1 + 2 + 2 + 2 + 3 + 1 + 1: three groups and a tail
        EXPECT_EQ(sys.counters().wall_contacts, 14);
    }
}

// A pour of two materials into a box closed by planes, with a cylinder around it and rolling
// resistance, so that every path of the step loop runs: pair contacts of two material pairs, plane
// and cylinder walls, list rebuilds with particle re-sorting.
SceneSpec threaded_pour(int threads) {
    SceneSpec s;
    s.materials.push_back({"a", 5e6, 0.45, 2500, 0.3, 0.5, 0.05});
    s.materials.push_back({"b", 2e7, 0.3, 1500, 0.6, 0.3, 0.0});
    s.contact.rolling = contact::RollingModel::constant_torque;
    s.time_step = 1e-5;
    s.skin = 0.4e-3;
    s.threads = threads;
    const Vec3 lo(-0.012, -0.012, 0.0);
    const Vec3 hi(0.012, 0.012, 0.05);
    for (int a = 0; a < 3; ++a) {
        s.walls.push_back({"lo", PlaneWall{lo, Vec3::Unit(a)}, 0});
        s.walls.push_back({"hi", PlaneWall{hi, -Vec3::Unit(a)}, 1});
    }
    s.walls.push_back({"tube", CylinderWall{Vec3::Zero(), Vec3::UnitZ(), 0.0155}, 1});
    for (int m = 0; m < 2; ++m) {
        InsertSpec ins;
        ins.material = m;
        ins.region = {Vec3(-0.011, -0.011, 0.002 + 0.02 * m), Vec3(0.011, 0.011, 0.022 + 0.02 * m)};
        ins.count = 300;
        ins.size.kind = SizeDistribution::Kind::uniform;
        ins.size.min = 0.7e-3;
        ins.size.max = 1.0e-3;
        ins.velocity = Vec3(0.05, 0, -0.5);
        ins.omega = Vec3(0, 20, 0);
        s.inserts.push_back(ins);
    }
    return s;
}

TEST(System, OneAndTwoThreadsGiveTheSameBits) {
    System one(threaded_pour(1));
    System two(threaded_pour(2));
#ifdef _OPENMP
    EXPECT_EQ(two.threads(), 2);
#endif
    long pair_contacts = 0;
    long wall_contacts = 0;
    for (int k = 0; k < 2500; ++k) {
        one.step();
        two.step();
        pair_contacts += one.counters().particle_contacts;
        wall_contacts += one.counters().wall_contacts;
    }
    EXPECT_GT(pair_contacts, 30000);
    EXPECT_GT(wall_contacts, 3000);
    EXPECT_GT(one.neighbour_builds(), 5);
    // Tolerance: none. Every force is summed in the same order whatever the thread count.
    const ParticleStore& a = one.particles();
    const ParticleStore& b = two.particles();
    ASSERT_EQ(a.size(), b.size());
    std::size_t differing = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        differing += a.id[i] != b.id[i] || a.x[i] != b.x[i] || a.v[i] != b.v[i] ||
                             a.omega[i] != b.omega[i] || a.force[i] != b.force[i] ||
                             a.torque[i] != b.torque[i]
                         ? 1
                         : 0;
    }
    EXPECT_EQ(differing, 0U);
    EXPECT_EQ(one.counters().particle_contacts, two.counters().particle_contacts);
    EXPECT_EQ(one.counters().wall_contacts, two.counters().wall_contacts);
    EXPECT_EQ(one.counters().elastic_energy, two.counters().elastic_energy);
    EXPECT_EQ(one.counters().max_overlap_ratio, two.counters().max_overlap_ratio);
}

// advance(k) fuses the second half kick of a step with the first of the next, the drift and the
// clearing of forces in one pass; the state between calls must be that of k calls of step().
TEST(System, AdvanceGivesTheBitsOfAsManySteps) {
    for (const int threads : {1, 2}) {
        System stepped(threaded_pour(1));
        System advanced(threaded_pour(threads));
        // Runs of 1 (the unfused path), 2 and longer, summing to 2500 steps.
        const std::vector<long> runs = {1, 2, 3, 97, 1, 396, 1000, 500, 500};
        long pair_contacts = 0;
        for (const long k : runs) {
            for (long s = 0; s < k; ++s) {
                stepped.step();
                pair_contacts += stepped.counters().particle_contacts;
            }
            advanced.advance(k);
            // Tolerance: none. The same operations in the same order, fused into fewer passes.
            ASSERT_EQ(stepped.step_count(), advanced.step_count());
            EXPECT_EQ(stepped.time(), advanced.time());
            EXPECT_EQ(stepped.neighbour_builds(), advanced.neighbour_builds());
            const ParticleStore& a = stepped.particles();
            const ParticleStore& b = advanced.particles();
            ASSERT_EQ(a.size(), b.size());
            std::size_t differing = 0;
            for (std::size_t i = 0; i < a.size(); ++i) {
                differing += a.id[i] != b.id[i] || a.x[i] != b.x[i] || a.v[i] != b.v[i] ||
                                     a.omega[i] != b.omega[i] || a.force[i] != b.force[i] ||
                                     a.torque[i] != b.torque[i]
                                 ? 1
                                 : 0;
            }
            EXPECT_EQ(differing, 0U) << threads << " threads, after step " << stepped.step_count();
            EXPECT_EQ(stepped.counters().particle_contacts, advanced.counters().particle_contacts);
            EXPECT_EQ(stepped.counters().wall_contacts, advanced.counters().wall_contacts);
            EXPECT_EQ(stepped.counters().elastic_energy, advanced.counters().elastic_energy);
        }
        EXPECT_EQ(stepped.step_count(), 2500);
        EXPECT_GT(pair_contacts, 30000);
        EXPECT_GT(stepped.neighbour_builds(), 5);
    }
}

// A lattice of 216 spheres (r = 0.5 mm, no gravity) almost at rest: rows along x with gaps of
// 10 um (inside the inner gap of 40 um), along y 60 um and along z 300 um (in the list, outside
// the inner gap); a few spheres are thrown at their neighbours. They become loose, meet others and
// set them moving (contacts start and end), and the one along z crosses half the skin (list
// builds).
SceneSpec quiet_lattice(int threads) {
    SceneSpec s = base_scene();
    s.gravity.setZero();
    s.skin = 0.4e-3;
    s.threads = threads;
    constexpr int n = 6;
    const double r = 0.5e-3;
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
            for (int k = 0; k < n; ++k) {
                const int id = (i * n + j) * n + k;
                Vec3 v = Vec3::Zero();
                if (id % 37 == 5) {
                    v = Vec3(id % 2 == 0 ? 0.05 : -0.05, 0, 0);
                } else if (id == 100) {
                    v = Vec3(0, 0.1, 0);
                } else if (id == 150) {
                    v = Vec3(0, 0, 0.1);
                }
                s.particles.push_back(
                    {0, r, Vec3(1.01e-3 * i, 1.06e-3 * j, 1.3e-3 * k), v, Vec3::Zero()});
            }
        }
    }
    return s;
}

// The pair filter's inner list (a two-level Verlet list) leaves out the entries that cannot touch;
// the touching entries, their order and hence every bit must be those of the filter over all
// entries. The lattice of quiet_lattice for 4000 steps: list builds, builds of the inner list,
// loose particles whose entries join it, contacts that start and end while the filter takes the
// inner list; one and two threads; a restart from a checkpoint half-way (the restored run builds
// its inner list anew).
TEST(System, InnerListGivesTheBitsOfTheFullFilter) {
    for (const int threads : {1, 2}) {
        System full(quiet_lattice(threads));
        full.use_inner_list(false);
        System inner(quiet_lattice(threads));
        std::unique_ptr<System> restarted;
        long contacts = 0;
        const auto same = [&](const System& a, const System& b) {
            const ParticleStore& pa = a.particles();
            const ParticleStore& pb = b.particles();
            std::size_t differing = pa.size() == pb.size() ? 0 : 1;
            for (std::size_t i = 0; i < std::min(pa.size(), pb.size()); ++i) {
                differing += pa.id[i] != pb.id[i] || pa.x[i] != pb.x[i] || pa.v[i] != pb.v[i] ||
                                     pa.omega[i] != pb.omega[i] || pa.force[i] != pb.force[i] ||
                                     pa.torque[i] != pb.torque[i]
                                 ? 1
                                 : 0;
            }
            const SystemState sa = a.save_state();
            const SystemState sb = b.save_state();
            differing += sa.nl_shear == sb.nl_shear && sa.wall_shear == sb.wall_shear ? 0 : 1;
            differing += a.counters().particle_contacts == b.counters().particle_contacts &&
                                 a.counters().elastic_energy == b.counters().elastic_energy
                             ? 0
                             : 1;
            return differing;
        };
        for (int chunk = 0; chunk < 16; ++chunk) {
            full.advance(250);
            inner.advance(250);
            contacts += full.counters().particle_contacts;
            // Tolerance: none. The same contacts evaluated in the same order.
            EXPECT_EQ(same(full, inner), 0U) << threads << " threads, step " << full.step_count();
            if (restarted) {
                restarted->advance(250);
                EXPECT_EQ(same(full, *restarted), 0U)
                    << threads << " threads, restarted, step " << full.step_count();
            }
            if (chunk == 7) {
                restarted = std::make_unique<System>(quiet_lattice(threads));
                restarted->restore_state(inner.save_state());
            }
        }
        EXPECT_GT(full.neighbour_builds(), 5);
        EXPECT_GT(contacts, 0);
        EXPECT_EQ(full.inner_list_steps(), 0);
#if defined(__AVX2__) && defined(__FMA__)
        EXPECT_GT(inner.inner_list_steps(), 500);   // the inner list was used (985 of 4000)
        EXPECT_GT(inner.inner_list_loosened(), 20); // and loose particles joined it
        EXPECT_GT(restarted->inner_list_steps(), 300);
#else
        // Without AVX2 and FMA there is no inner list (System::choose_filter): every step takes
        // the full filter, and the comparison above is of two identical runs.
        EXPECT_EQ(inner.inner_list_steps(), 0);
#endif
    }
}

// With every particle of one radius and mass, the register path takes R* and m* once per chunk
// instead of per group of four contacts; the operations are the same, so every bit must be. The
// lattice of quiet_lattice (one size, walls, contacts that start and end) for 2000 steps with one
// and two threads, and a restart half-way.
TEST(System, UniformSizesGiveTheBitsOfThePerContactSizes) {
    for (const int threads : {1, 2}) {
        System general(quiet_lattice(threads));
        general.use_uniform_sizes(false);
        System uniform(quiet_lattice(threads));
        long contacts = 0;
        for (int chunk = 0; chunk < 8; ++chunk) {
            if (chunk == 4) {
                System restarted(quiet_lattice(threads));
                restarted.restore_state(uniform.save_state());
                restarted.advance(250);
                uniform.advance(250);
                EXPECT_EQ(restarted.particles().x, uniform.particles().x) << threads;
                EXPECT_EQ(restarted.particles().v, uniform.particles().v) << threads;
                general.advance(250);
            } else {
                general.advance(250);
                uniform.advance(250);
            }
            contacts += general.counters().particle_contacts;
            const ParticleStore& pa = general.particles();
            const ParticleStore& pb = uniform.particles();
            // Tolerance: none. The same operations on the same contacts in the same order.
            EXPECT_EQ(pa.x, pb.x) << threads << " threads, step " << general.step_count();
            EXPECT_EQ(pa.v, pb.v) << threads << " threads, step " << general.step_count();
            EXPECT_EQ(pa.omega, pb.omega) << threads << " threads, step " << general.step_count();
            EXPECT_EQ(pa.force, pb.force) << threads << " threads, step " << general.step_count();
            EXPECT_EQ(pa.torque, pb.torque) << threads << " threads, step " << general.step_count();
            EXPECT_EQ(general.save_state().nl_shear, uniform.save_state().nl_shear) << threads;
            EXPECT_EQ(general.counters().elastic_energy, uniform.counters().elastic_energy);
        }
        EXPECT_GT(contacts, 0);
    }
}

// advance() forms the elastic energy and the largest overlap ratio of the sphere contacts only at
// its last step (the one whose counters can be read); with use_energy_on_demand(false) at every
// step. Both must give the same
// bits for the state and the same counters and energies whenever they can be read: after advance()
// runs of any length (1 takes the unfused path), after step() and after a restart. The pour has two
// material pairs, walls and rolling resistance; the lattice one radius and one material pair (the
// register path's sizes taken once and its variant with friction in every pair).
TEST(System, EnergyOnDemandGivesTheEnergiesOfEveryStep) {
    for (const int scene : {0, 1}) {
        for (const int threads : {1, 2}) {
            const auto spec = [&] {
                return scene == 0 ? threaded_pour(threads) : quiet_lattice(threads);
            };
            System every(spec());
            every.use_energy_on_demand(false);
            auto on_demand = std::make_unique<System>(spec());
            double largest = 0.0;
            double largest_ratio = 0.0;
            const std::vector<long> runs = {1, 2, 3, 97, 1, 396, 500};
            for (std::size_t r = 0; r < runs.size(); ++r) {
                every.advance(runs[r]);
                if (r == 4) {
                    auto restarted = std::make_unique<System>(spec());
                    restarted->restore_state(on_demand->save_state());
                    on_demand = std::move(restarted);
                }
                on_demand->advance(runs[r]);
                if (r == 5) {
                    every.step();
                    on_demand->step();
                }
                const std::string at = std::to_string(threads) + " threads, scene " +
                                       std::to_string(scene) + ", step " +
                                       std::to_string(every.step_count());
                ASSERT_EQ(every.step_count(), on_demand->step_count()) << at;
                const ParticleStore& a = every.particles();
                const ParticleStore& b = on_demand->particles();
                // Tolerance: none. The energy is a sum beside the forces, not an input to them.
                EXPECT_EQ(a.x, b.x) << at;
                EXPECT_EQ(a.v, b.v) << at;
                EXPECT_EQ(a.omega, b.omega) << at;
                EXPECT_EQ(a.force, b.force) << at;
                EXPECT_EQ(a.torque, b.torque) << at;
                EXPECT_EQ(every.counters().particle_contacts,
                          on_demand->counters().particle_contacts)
                    << at;
                EXPECT_EQ(every.counters().wall_contacts, on_demand->counters().wall_contacts)
                    << at;
                EXPECT_EQ(every.counters().elastic_energy, on_demand->counters().elastic_energy)
                    << at;
                EXPECT_EQ(every.counters().max_overlap_ratio,
                          on_demand->counters().max_overlap_ratio)
                    << at;
                EXPECT_EQ(every.energies().elastic, on_demand->energies().elastic) << at;
                EXPECT_EQ(every.energies().total(), on_demand->energies().total()) << at;
                largest = std::max(largest, on_demand->counters().elastic_energy);
                largest_ratio = std::max(largest_ratio, on_demand->counters().max_overlap_ratio);
            }
            EXPECT_GT(largest, 0.0) << threads << " threads, scene " << scene;
            EXPECT_GT(largest_ratio, 0.0) << threads << " threads, scene " << scene;
        }
    }
}

// At a list build with sorting, only the wall histories of the last build's candidates are moved
// to their particles' new places (the other particles hold none). Spheres sliding apart on a floor
// and beside a side wall, each touching walls only: with and without sorting every sphere meets
// the same contacts in the same order, so both runs must give the same bits, particle by particle.
TEST(System, WallHistoriesFollowTheirParticlesThroughTheSort) {
    SceneSpec s = base_scene();
    s.skin = 0.2e-3; // a build every few steps
    s.walls.push_back({"floor", PlaneWall{Vec3::Zero(), Vec3::UnitZ()}, 0});
    s.walls.push_back({"side", PlaneWall{Vec3(-0.0205, 0, 0), Vec3::UnitX()}, 0});
    constexpr int n = 24;
    for (int k = 0; k < n; ++k) {
        // On a line along -x (the sort reverses it), fanning out in y: no two ever meet. The
        // first sphere also presses on the side wall.
        const double x = -0.0195 + 0.006 * (n - 1 - k) - (k == n - 1 ? 1e-5 : 0.0);
        const double vy = 0.02 * (k - n / 2);
        s.particles.push_back(
            {0, 1e-3, Vec3(x, 0.0, 0.999e-3), Vec3(k == n - 1 ? -0.05 : 0.3, vy, 0), Vec3::Zero()});
    }
    SceneSpec unsorted = s;
    unsorted.sort_particles = false;
    System a(s);
    System b(unsorted);
    for (int step = 0; step < 3000; ++step) {
        a.step();
        b.step();
    }
    EXPECT_GT(a.neighbour_builds(), 100);
    const SystemState sa = a.save_state();
    const SystemState sb = b.save_state();
    const std::size_t nw = s.walls.size();
    std::size_t moved = 0;
    std::size_t with_history = 0;
    for (std::size_t i = 0; i < sa.particles.size(); ++i) {
        const std::int64_t id = sa.particles.id[i];
        ASSERT_EQ(sb.particles.id[static_cast<std::size_t>(id)], id); // b keeps insertion order
        const std::size_t j = static_cast<std::size_t>(id);
        moved += i != j ? 1 : 0;
        // Tolerance: none (the same contacts in the same order).
        EXPECT_EQ(sa.particles.x[i], sb.particles.x[j]);
        EXPECT_EQ(sa.particles.v[i], sb.particles.v[j]);
        EXPECT_EQ(sa.particles.omega[i], sb.particles.omega[j]);
        for (std::size_t w = 0; w < nw; ++w) {
            EXPECT_EQ(sa.wall_shear[i * nw + w], sb.wall_shear[j * nw + w]);
            with_history += sa.wall_shear[i * nw + w] != Vec3::Zero() ? 1 : 0;
        }
    }
    EXPECT_GT(moved, 0U);            // the sort did reorder
    EXPECT_GT(with_history, n / 2U); // floor contacts carry a history
}

TEST(System, CollectContactsMatchesTheForceLoopAndLeavesTheMechanicsAlone) {
    System probe(threaded_pour(1));
    System plain(threaded_pour(1));
    std::vector<ContactRecord> contacts;
    for (int k = 0; k < 2500; ++k) {
        probe.step();
        plain.step();
        if (k % 100 != 99) {
            continue;
        }
        probe.collect_contacts(contacts);
        long pairs = 0;
        long walls = 0;
        const ParticleStore& p = probe.particles();
        for (const ContactRecord& c : contacts) {
            walls += c.wall ? 1 : 0;
            pairs += c.wall ? 0 : 1;
            EXPECT_GT(c.overlap, 0.0);
            EXPECT_NEAR(c.normal.norm(), 1.0, 1e-12); // unit normal up to rounding
            // The contact point lies inside i, r_i - delta/2 from its centre along n.
            const double reach = (c.point - p.x[c.i]).dot(c.normal);
            EXPECT_NEAR(reach, p.radius[c.i] - 0.5 * c.overlap, 1e-12);
            if (!c.wall) {
                const double gap = (p.x[c.j] - p.x[c.i]).norm();
                EXPECT_NEAR(c.overlap, p.radius[c.i] + p.radius[c.j] - gap, 1e-15);
            }
        }
        // Same touch test as the force loop: the counts agree exactly.
        EXPECT_EQ(pairs, probe.counters().particle_contacts);
        EXPECT_EQ(walls, probe.counters().wall_contacts);
    }
    // Tolerance: none; collecting reads the state only.
    const ParticleStore& a = probe.particles();
    const ParticleStore& b = plain.particles();
    std::size_t differing = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        differing += a.x[i] != b.x[i] || a.v[i] != b.v[i] || a.force[i] != b.force[i] ? 1 : 0;
    }
    EXPECT_EQ(differing, 0U);
}

} // namespace
} // namespace kiln::dynamics
