#include "io/checkpoint.hpp"

#include "core/error.hpp"

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
