// Reader tests of the heat keys: [heat], [material.heat], wall and particle temperatures.
#include "common/case_text.hpp"
#include "io/case_reader.hpp"

#include "core/error.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <string>

namespace kiln::io {
namespace {

const std::string base = R"([simulation]
time_step = 1e-5
end_time = 0.01

[[material]]
name = "glass"
youngs_modulus = 5e6
poisson_ratio = 0.45
density = 2500
restitution = 0.3

[material.heat]
conductivity = 1.4
specific_heat = 835
initial_temperature = 300
model = "resolved"
radial_cells = 6

[[material]]
name = "steel"
youngs_modulus = 5e6
poisson_ratio = 0.3
density = 7900
restitution = 0.3

[[wall]]
type = "box"
material = "glass"
min = [0, 0, 0]
max = [0.02, 0.02, 0.04]
temperature = 600

[[particle]]
material = "glass"
radius = 1e-3
position = [0.01, 0.01, 0.01]
temperature = 500

[[particle]]
material = "steel"
radius = 1e-3
position = [0.01, 0.01, 0.02]

[heat]
step_multiple = 50
solver = "bicgstab"
heat_transfer_coefficient = 20
flow_direction = [0, 0, 1]
)";

std::string edit(const std::string& from, const std::string& to) {
    return test::edited(base, from, to);
}

std::string error_of(const std::string& text) {
    return test::case_error(text);
}

TEST(CaseReaderHeat, HeatKeysReadWithDefaults) {
    const CaseSpec c = read_case_text(base, "case.toml");
    const thermal::HeatSpec& h = c.heat;
    EXPECT_TRUE(h.enabled);
    EXPECT_EQ(h.step_multiple, 50);
    EXPECT_EQ(h.solver.kind, heat::SolverKind::bicgstab);
    EXPECT_DOUBLE_EQ(h.solver.tolerance, 1e-10);
    EXPECT_TRUE(h.extrapolated_guess); // default initial_guess = "extrapolated"
    EXPECT_DOUBLE_EQ(h.ambient_temperature, 293.15);
    EXPECT_TRUE(h.stagnation);
    ASSERT_EQ(h.materials.size(), 2U);
    EXPECT_TRUE(h.materials[0].enabled);
    EXPECT_FALSE(h.materials[1].enabled); // steel has no heat table: no temperature
    EXPECT_EQ(h.materials[0].model, heat::HeatModel::resolved);
    EXPECT_EQ(h.materials[0].spherical.n_r, 6);
    EXPECT_EQ(h.materials[0].spherical.n_theta, 8);
    EXPECT_DOUBLE_EQ(h.materials[0].real_youngs_modulus, 5e6); // default: the simulation's
    ASSERT_EQ(h.wall_temperature.size(), 6U);                  // the box's six planes
    for (const double t : h.wall_temperature) {
        EXPECT_DOUBLE_EQ(t, 600.0);
    }
    ASSERT_EQ(h.particle_temperature.size(), 2U);
    EXPECT_DOUBLE_EQ(h.particle_temperature[0], 500.0);
    EXPECT_TRUE(std::isnan(h.particle_temperature[1]));
    // The resolved text carries the heat keys with defaults filled in.
    EXPECT_NE(c.resolved_toml.find("biot_threshold"), std::string::npos);
    EXPECT_NE(c.resolved_toml.find("azimuthal_cells"), std::string::npos);
}

TEST(CaseReaderHeat, SceneWithoutHeatHasItDisabled) {
    const std::string text = base.substr(0, base.find("[heat]"));
    const std::string no_heat = [&] {
        std::string s = text;
        for (const char* key : {"temperature = 600\n", "temperature = 500\n"}) {
            s.erase(s.find(key), std::string(key).size());
        }
        const auto a = s.find("[material.heat]");
        return s.erase(a, s.find("[[material]]", a) - a);
    }();
    const CaseSpec c = read_case_text(no_heat, "case.toml");
    EXPECT_FALSE(c.heat.enabled);
}

TEST(CaseReaderHeat, HeatDataWithoutHeatSectionIsLocated) {
    const std::string text = base.substr(0, base.find("[heat]"));
    // The wall temperature on line 43 of the text without [heat] comes after the material table:
    // the first offending key is reported with its line.
    const std::string e = error_of(text);
    EXPECT_NE(e.find("case.toml:12: material[0].heat"), std::string::npos) << e;
    EXPECT_NE(e.find("needs a [heat] section"), std::string::npos) << e;
}

TEST(CaseReaderHeat, RangesAndChoicesAreChecked) {
    EXPECT_NE(error_of(edit("conductivity = 1.4", "conductivity = -1"))
                  .find("case.toml:13: material[0].heat.conductivity: -1 W/(m K) is out of range"),
              std::string::npos);
    EXPECT_NE(error_of(edit("model = \"resolved\"", "model = \"fancy\"")).find("\"auto\""),
              std::string::npos);
    EXPECT_NE(error_of(edit("step_multiple = 50", "step_multiple = 0")).find("heat.step_multiple"),
              std::string::npos);
    EXPECT_NE(error_of(edit("solver = \"bicgstab\"", "solver = \"lu\"")).find("\"cg\""),
              std::string::npos);
    EXPECT_NE(error_of(edit("solver = \"bicgstab\"", "initial_guess = \"zero\""))
                  .find("heat.initial_guess"),
              std::string::npos);
    EXPECT_FALSE(
        read_case_text(edit("solver = \"bicgstab\"", "initial_guess = \"last\""), "case.toml")
            .heat.extrapolated_guess);
    EXPECT_NE(error_of(edit("step_multiple = 50", "step_multiple = 50\nbogus = 1"))
                  .find("heat.bogus: unknown key"),
              std::string::npos);
    EXPECT_NE(error_of(edit("heat_transfer_coefficient = 20", "heat_transfer_coefficient = 0"))
                  .find("heat.flow_direction"),
              std::string::npos);
    EXPECT_NE(error_of(edit("radial_cells = 6", "radial_cells = 0")).find("radial_cells"),
              std::string::npos);
}

TEST(CaseReaderHeat, GasGapKeysReadWithDefaultsAndRanges) {
    // Defaults: no gas (k_f = 0), the seed's porosity 0.4 and cut-off H/R = 0.5.
    const CaseSpec d = read_case_text(base, "case.toml");
    EXPECT_DOUBLE_EQ(d.heat.gas.conductivity, 0.0);
    EXPECT_DOUBLE_EQ(d.heat.gas.porosity, 0.4);
    EXPECT_DOUBLE_EQ(d.heat.gas.cutoff, 0.5);
    EXPECT_NE(d.resolved_toml.find("gas_porosity"), std::string::npos);
    const CaseSpec c = read_case_text(
        edit("step_multiple = 50",
             "step_multiple = 50\ngas_conductivity = 0.02818\ngas_porosity = 0.42\ngas_cutoff = "
             "0.3"),
        "case.toml");
    EXPECT_DOUBLE_EQ(c.heat.gas.conductivity, 0.02818);
    EXPECT_DOUBLE_EQ(c.heat.gas.porosity, 0.42);
    EXPECT_DOUBLE_EQ(c.heat.gas.cutoff, 0.3);
    std::string e =
        error_of(edit("step_multiple = 50", "step_multiple = 50\ngas_conductivity = -0.1"));
    EXPECT_NE(e.find("case.toml:46: heat.gas_conductivity: -0.1 W/(m K) is out of range"),
              std::string::npos)
        << e;
    e = error_of(edit("step_multiple = 50", "step_multiple = 50\ngas_porosity = 1"));
    EXPECT_NE(e.find("heat.gas_porosity"), std::string::npos) << e;
    EXPECT_NE(e.find("0 < value < 1"), std::string::npos) << e;
    e = error_of(edit("step_multiple = 50", "step_multiple = 50\ngas_cutoff = 0"));
    EXPECT_NE(e.find("heat.gas_cutoff"), std::string::npos) << e;
}

TEST(CaseReaderHeat, RadiationKeysReadWithDefaultsAndRanges) {
    const CaseSpec d = read_case_text(base, "case.toml");
    EXPECT_DOUBLE_EQ(d.heat.materials[0].emissivity, 0.0); // default: no radiation
    EXPECT_DOUBLE_EQ(d.heat.radiation_cutoff, 0.5);        // seed: neighbours within R
    const CaseSpec c = read_case_text(
        edit("radial_cells = 6", "radial_cells = 6\nemissivity = 0.85"), "case.toml");
    EXPECT_DOUBLE_EQ(c.heat.materials[0].emissivity, 0.85);
    std::string e = error_of(edit("radial_cells = 6", "radial_cells = 6\nemissivity = 1.2"));
    EXPECT_NE(e.find("material[0].heat.emissivity: 1.2 is out of range"), std::string::npos) << e;
    e = error_of(edit("step_multiple = 50", "step_multiple = 50\nradiation_cutoff = -1"));
    EXPECT_NE(e.find("heat.radiation_cutoff"), std::string::npos) << e;
    const CaseSpec r = read_case_text(
        edit("step_multiple = 50", "step_multiple = 50\nradiation_cutoff = 2"), "case.toml");
    EXPECT_DOUBLE_EQ(r.heat.radiation_cutoff, 2.0);
}

TEST(CaseReaderHeat, WallGapKeysReadWithDefaultsAndNeedGas) {
    // Default off: hot walls exchange by contact and collision conduction only, as before.
    const CaseSpec d = read_case_text(base, "case.toml");
    EXPECT_FALSE(d.heat.wall_gas);
    EXPECT_FALSE(d.heat.wall_radiation);
    EXPECT_NE(d.resolved_toml.find("wall_gas_gap = false"), std::string::npos);
    EXPECT_NE(d.resolved_toml.find("wall_radiation = false"), std::string::npos);
    const CaseSpec c = read_case_text(
        edit("step_multiple = 50", "step_multiple = 50\ngas_conductivity = 0.026\nwall_gas_gap = "
                                   "true\nwall_radiation = true"),
        "case.toml");
    EXPECT_TRUE(c.heat.wall_gas);
    EXPECT_TRUE(c.heat.wall_radiation);
    // Gas to the walls without a gas: refused, naming file, line, key and what is allowed.
    std::string e = error_of(edit("step_multiple = 50", "step_multiple = 50\nwall_gas_gap = true"));
    EXPECT_NE(e.find("case.toml:46: heat.wall_gas_gap"), std::string::npos) << e;
    EXPECT_NE(e.find("gas_conductivity > 0"), std::string::npos) << e;
    e = error_of(edit("step_multiple = 50", "step_multiple = 50\nwall_radiation = 2"));
    EXPECT_NE(e.find("heat.wall_radiation"), std::string::npos) << e;
    EXPECT_NE(e.find("expected true or false"), std::string::npos) << e;
}

TEST(CaseReaderHeat, CollisionConductionKeySwitchesOnsetRecording) {
    // Default off: the force loop records nothing (the sphere kernel runs as without heat).
    const CaseSpec d = read_case_text(base, "case.toml");
    EXPECT_FALSE(d.heat.collision_conduction);
    EXPECT_FALSE(d.scene.record_contact_onsets);
    EXPECT_NE(d.resolved_toml.find("collision_conduction = false"), std::string::npos);
    const CaseSpec c = read_case_text(
        edit("step_multiple = 50", "step_multiple = 50\ncollision_conduction = true"), "case.toml");
    EXPECT_TRUE(c.heat.collision_conduction);
    EXPECT_TRUE(c.scene.record_contact_onsets);
    const std::string e =
        error_of(edit("step_multiple = 50", "step_multiple = 50\ncollision_conduction = 1"));
    EXPECT_NE(e.find("heat.collision_conduction"), std::string::npos) << e;
}

TEST(CaseReaderHeat, RadiationTemperatureIsOptionalAndPositive) {
    const CaseSpec d = read_case_text(base, "case.toml");
    EXPECT_TRUE(std::isnan(d.heat.radiation_temperature)); // default: no ambient radiation
    const CaseSpec c = read_case_text(
        edit("step_multiple = 50", "step_multiple = 50\nradiation_temperature = 350"), "case.toml");
    EXPECT_DOUBLE_EQ(c.heat.radiation_temperature, 350.0);
    EXPECT_NE(c.resolved_toml.find("radiation_temperature = 350"), std::string::npos);
    const std::string e =
        error_of(edit("step_multiple = 50", "step_multiple = 50\nradiation_temperature = 0"));
    EXPECT_NE(e.find("heat.radiation_temperature"), std::string::npos) << e;
}

TEST(CaseReaderHeat, HotWallNeedsAMaterialWithConductivity) {
    const std::string e = error_of(edit("material = \"glass\"\nmin", "material = \"steel\"\nmin"));
    EXPECT_NE(e.find("wall[0].temperature"), std::string::npos) << e;
    EXPECT_NE(e.find("no heat table"), std::string::npos) << e;
}

/// A folder holding a 2 x 2 m plate in z = 0 facing +z (plate.obj) for mesh-wall cases.
struct PlateFolder {
    std::filesystem::path dir;
    PlateFolder() : dir(std::filesystem::temp_directory_path() / "kiln_heat_mesh_wall") {
        std::filesystem::create_directories(dir);
        std::ofstream(dir / "plate.obj") << "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
                                            "f 1 2 3\nf 1 3 4\n";
    }
    ~PlateFolder() { std::filesystem::remove_all(dir); }
    PlateFolder(const PlateFolder&) = delete;
    PlateFolder& operator=(const PlateFolder&) = delete;
    [[nodiscard]] std::string path() const { return (dir / "case.toml").string(); }
};

/// The base case with its hot box replaced by the plate at `keys` (material, temperature).
std::string with_plate(const std::string& keys) {
    return edit("type = \"box\"\nmaterial = \"glass\"\nmin = [0, 0, 0]\nmax = [0.02, 0.02, "
                "0.04]\ntemperature = 600",
                "type = \"mesh\"\nfile = \"plate.obj\"\n" + keys);
}

TEST(CaseReaderHeat, MeshWallTakesATemperature) {
    const PlateFolder folder;
    const CaseSpec c =
        read_case_text(with_plate("material = \"glass\"\ntemperature = 550\n"), folder.path());
    ASSERT_EQ(c.heat.mesh_wall_temperature.size(), 1U);
    EXPECT_EQ(c.heat.mesh_wall_temperature[0], 550.0);
    EXPECT_TRUE(c.heat.wall_temperature.empty());
    // Without the key the mesh wall is adiabatic.
    const CaseSpec a = read_case_text(with_plate("material = \"glass\"\n"), folder.path());
    ASSERT_EQ(a.heat.mesh_wall_temperature.size(), 1U);
    EXPECT_TRUE(std::isnan(a.heat.mesh_wall_temperature[0]));
    // A material without a heat table cannot conduct: located error.
    try {
        (void)read_case_text(with_plate("material = \"steel\"\ntemperature = 550\n"),
                             folder.path());
        FAIL() << "a hot mesh wall of a material without heat must be refused";
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("wall[0].temperature"), std::string::npos) << what;
        EXPECT_NE(what.find("no heat table"), std::string::npos) << what;
    }
}

} // namespace
} // namespace kiln::io
