#include "io/checkpoint.hpp"

#include "core/error.hpp"
#include "io/shape_reader.hpp"

#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>

namespace kiln::io {
namespace {

dynamics::SceneSpec pour() {
    dynamics::SceneSpec s;
    s.materials.push_back({"m", 5e6, 0.45, 2500, 0.3, 0.5, 0.0});
    s.time_step = 1e-5;
    s.walls.push_back({"floor", dynamics::PlaneWall{Vec3::Zero(), Vec3::UnitZ()}, 0});
    s.walls.push_back({"tube", dynamics::CylinderWall{Vec3::Zero(), Vec3::UnitZ(), 0.01}, 0});
    dynamics::InsertSpec ins;
    ins.region = {Vec3(-0.007, -0.007, 0.0), Vec3(0.007, 0.007, 0.03)};
    ins.count = 200;
    ins.size.radius = 1e-3;
    ins.velocity = Vec3(0, 0, -0.3);
    s.inserts.push_back(ins);
    return s;
}

TEST(Checkpoint, RestartContinuesBitForBit) {
    const auto file = std::filesystem::temp_directory_path() / "kiln_test_checkpoint.bin";
    dynamics::System a(pour());
    for (int k = 0; k < 3000; ++k) {
        a.step();
    }
    write_checkpoint(file, a.save_state());
    for (int k = 0; k < 3000; ++k) {
        a.step();
    }
    dynamics::System b(pour());
    b.restore_state(read_checkpoint(file));
    for (int k = 0; k < 3000; ++k) {
        b.step();
    }
    ASSERT_EQ(a.particles().size(), b.particles().size());
    EXPECT_EQ(a.step_count(), b.step_count());
    for (std::size_t i = 0; i < a.particles().size(); ++i) {
        EXPECT_EQ(a.particles().id[i], b.particles().id[i]);
        EXPECT_EQ(a.particles().x[i], b.particles().x[i]); // exact equality is the point
        EXPECT_EQ(a.particles().v[i], b.particles().v[i]);
        EXPECT_EQ(a.particles().omega[i], b.particles().omega[i]);
    }
    EXPECT_GT(a.counters().particle_contacts, 0);
    std::filesystem::remove(file);
}

/// Heat for pour(): resolved particles, a hot floor (wall 0), convection with f(theta).
thermal::HeatSpec pour_heat() {
    thermal::HeatSpec h;
    h.enabled = true;
    h.step_multiple = 50;
    h.solver.tolerance = 1e-8;
    h.heat_transfer_coefficient = 30.0;
    h.stagnation = true;
    h.ambient_temperature = 350.0;
    thermal::MaterialHeat m;
    m.enabled = true;
    m.conductivity = 2.0;
    m.specific_heat = 800.0;
    m.initial_temperature = 300.0;
    m.model = heat::HeatModel::resolved;
    m.spherical = {3, 4, 6};
    h.materials = {m};
    h.wall_temperature = {500.0, thermal::unset};
    return h;
}

/// Runs `steps` mechanical steps with the heat after each.
void advance(dynamics::System& s, thermal::ThermalSystem& h, int steps) {
    for (int k = 0; k < steps; ++k) {
        s.step();
        h.after_step(s);
    }
}

/// Checkpoints run a (with heat ha, whose state `saved` holds pending impacts) to `file`, runs on
/// `steps`, restarts a second run from the file and runs it as far: temperatures and heat must
/// agree exactly, and the impacts must have been exchanged.
void expect_restart_keeps_pending_impacts(const dynamics::SceneSpec& scene,
                                          const thermal::HeatSpec& heat,
                                          const std::filesystem::path& file, dynamics::System& a,
                                          thermal::ThermalSystem& ha,
                                          const thermal::ThermalState& saved, int steps) {
    write_checkpoint(file, a.save_state(), &saved);
    advance(a, ha, steps);
    dynamics::System b(scene);
    thermal::ThermalSystem hb(heat, b);
    b.restore_state(read_checkpoint(file));
    const auto restored = read_checkpoint_heat(file);
    ASSERT_TRUE(restored.has_value());
    EXPECT_EQ(restored->onsets.size(), saved.onsets.size());
    hb.restore_state(*restored, b);
    advance(b, hb, steps);
    thermal::ParticleTemperatures ta;
    thermal::ParticleTemperatures tb;
    ha.particle_temperatures(a, ta);
    hb.particle_temperatures(b, tb);
    EXPECT_EQ(ta.mean, tb.mean); // exact equality is the point
    EXPECT_EQ(ha.thermal_energy(), hb.thermal_energy());
    EXPECT_GT(ha.collisions(), 0);
    std::filesystem::remove(file);
}

TEST(Checkpoint, RestartContinuesTemperaturesBitForBit) {
    const auto file = std::filesystem::temp_directory_path() / "kiln_test_checkpoint_heat.bin";
    dynamics::System a(pour());
    thermal::ThermalSystem ha(pour_heat(), a);
    advance(a, ha, 3000);
    const thermal::ThermalState saved = ha.save_state();
    // The spheres' grids have turned with their spin (sphere_rotation): the restart needs them.
    EXPECT_EQ(saved.orientations.size(), 4 * a.particles().size());
    // The extrapolated guess's second field (the default) goes into the file too.
    EXPECT_EQ(saved.previous_fields.size(), saved.fields.size());
    write_checkpoint(file, a.save_state(), &saved);
    advance(a, ha, 3000);
    dynamics::System b(pour());
    thermal::ThermalSystem hb(pour_heat(), b);
    b.restore_state(read_checkpoint(file));
    const auto restored = read_checkpoint_heat(file);
    ASSERT_TRUE(restored.has_value());
    EXPECT_EQ(restored->previous_fields, saved.previous_fields);
    hb.restore_state(*restored, b);
    advance(b, hb, 3000);
    thermal::ParticleTemperatures ta;
    thermal::ParticleTemperatures tb;
    ha.particle_temperatures(a, ta);
    hb.particle_temperatures(b, tb);
    ASSERT_EQ(ta.mean.size(), tb.mean.size());
    EXPECT_EQ(ta.mean, tb.mean); // exact equality is the point
    EXPECT_EQ(ta.surface, tb.surface);
    EXPECT_EQ(ha.thermal_energy(), hb.thermal_energy());
    EXPECT_GT(ha.temperature_range().second, 300.0); // the hot floor did heat something
    // A checkpoint without heat has no temperature section.
    write_checkpoint(file, a.save_state());
    EXPECT_FALSE(read_checkpoint_heat(file).has_value());
    std::filesystem::remove(file);
}

TEST(Checkpoint, RestartKeepsPendingImpactsOfCollisionConduction) {
    // Onsets taken since the last thermal step are exchanged at the next one: a checkpoint
    // between the two must carry them, or the restarted run would lose those impacts.
    const auto file = std::filesystem::temp_directory_path() / "kiln_test_checkpoint_onsets.bin";
    dynamics::SceneSpec scene = pour();
    scene.record_contact_onsets = true;
    thermal::HeatSpec heat = pour_heat();
    heat.collision_conduction = true;
    dynamics::System a(scene);
    thermal::ThermalSystem ha(heat, a);
    advance(a, ha, 3000);
    int extra = 0;
    while (ha.save_state().onsets.empty() && extra < 20000) {
        advance(a, ha, 1);
        ++extra;
    }
    const thermal::ThermalState saved = ha.save_state();
    ASSERT_FALSE(saved.onsets.empty()); // the pour has impacts
    expect_restart_keeps_pending_impacts(scene, heat, file, a, ha, saved, 3000);
}

/// A pour of clumps and superquadrics onto spheres in a tube.
dynamics::SceneSpec body_pour() {
    dynamics::SceneSpec s = pour();
    s.inserts[0].count = 40;
    s.inserts[0].region = {Vec3(-0.007, -0.007, 0.0), Vec3(0.007, 0.007, 0.01)};
    s.shapes.push_back(read_shape_file(find_shape_file("cylinder_12", default_shape_dirs())));
    s.shapes.push_back(read_shape_file(find_shape_file("superball", default_shape_dirs())));
    for (int k = 0; k < 2; ++k) {
        dynamics::InsertSpec ins = s.inserts[0];
        ins.count = k == 0 ? 4 : 8;
        ins.shape = k;
        ins.size.radius = s.shapes[static_cast<std::size_t>(k)].bounding_radius();
        ins.orientation.random = true;
        // Inside the tube: the region's corners are within its radius of 10 mm.
        ins.region = {Vec3(-0.0068, -0.0068, 0.011 + 0.04 * k),
                      Vec3(0.0068, 0.0068, 0.05 + 0.03 * k)};
        s.inserts.push_back(ins);
    }
    s.time_step = 5e-6;
    return s;
}

TEST(Checkpoint, RestartOfBodiesContinuesBitForBit) {
    const auto file = std::filesystem::temp_directory_path() / "kiln_test_checkpoint_bodies.bin";
    dynamics::System a(body_pour());
    for (int k = 0; k < 12000; ++k) {
        a.step();
    }
    ASSERT_FALSE(a.body_contacts().empty()); // histories are part of what is restored
    write_checkpoint(file, a.save_state());
    for (int k = 0; k < 2000; ++k) {
        a.step();
    }
    dynamics::System b(body_pour());
    b.restore_state(read_checkpoint(file));
    for (int k = 0; k < 2000; ++k) {
        b.step();
    }
    ASSERT_EQ(a.particles().size(), b.particles().size());
    for (std::size_t i = 0; i < a.particles().size(); ++i) {
        EXPECT_EQ(a.particles().x[i], b.particles().x[i]); // exact equality is the point
        EXPECT_EQ(a.particles().v[i], b.particles().v[i]);
        EXPECT_EQ(a.particles().q[i].coeffs(), b.particles().q[i].coeffs());
        EXPECT_EQ(a.particles().ang_mom[i], b.particles().ang_mom[i]);
    }
    EXPECT_EQ(a.body_contacts().size(), b.body_contacts().size());
    EXPECT_EQ(a.narrow_phase_counters().calls, b.narrow_phase_counters().calls);
    std::filesystem::remove(file);
}

TEST(Checkpoint, RestartKeepsPendingImpactsOfBodies) {
    // Pending impacts of bodies carry their contact in each body frame of the step that found
    // them: the restarted run must exchange them on the same cells (lumped here: same bodies).
    const auto file = std::filesystem::temp_directory_path() / "kiln_test_checkpoint_impacts.bin";
    dynamics::SceneSpec scene = body_pour();
    scene.record_contact_onsets = true;
    thermal::HeatSpec heat = pour_heat();
    heat.collision_conduction = true;
    heat.materials[0].model = heat::HeatModel::lumped;
    dynamics::System a(scene);
    thermal::ThermalSystem ha(heat, a);
    advance(a, ha, 12000);
    int extra = 0;
    const auto body_pending = [&] {
        for (const thermal::PendingImpact& m : ha.save_state().onsets) {
            for (std::size_t i = 0; i < a.particles().size(); ++i) {
                if (a.particles().id[i] == m.onset.id_i && a.particles().shape[i] >= 0) {
                    return true;
                }
            }
        }
        return false;
    };
    while (!body_pending() && extra < 20000) {
        advance(a, ha, 1);
        ++extra;
    }
    const thermal::ThermalState saved = ha.save_state();
    ASSERT_TRUE(body_pending()); // the pour has impacts of bodies
    expect_restart_keeps_pending_impacts(scene, heat, file, a, ha, saved, 2000);
}

TEST(Checkpoint, ForeignFileIsRefused) {
    const auto file = std::filesystem::temp_directory_path() / "kiln_test_not_a_checkpoint.bin";
    {
        std::ofstream f(file);
        f << "hello";
    }
    EXPECT_THROW(read_checkpoint(file), InputError);
    std::filesystem::remove(file);
}

} // namespace
} // namespace kiln::io
