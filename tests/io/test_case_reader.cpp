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

const std::string good = R"([simulation]
time_step = 1e-5
end_time = 0.01

[[material]]
name = "glass"
youngs_modulus = 5e6
poisson_ratio = 0.45
density = 2500
restitution = 0.3
friction = 0.5

[[wall]]
type = "box"
material = "glass"
min = [0, 0, 0]
max = [0.02, 0.02, 0.04]

[[insert]]
type = "random"
material = "glass"
region = { min = [0, 0, 0.01], max = [0.02, 0.02, 0.04] }
count = 100
radius = { distribution = "uniform", min = 0.8e-3, max = 1.2e-3 }
)";

/// The good case with the first occurrence of `from` replaced by `to`.
std::string edit(const std::string& from, const std::string& to) {
    return test::edited(good, from, to);
}

/// The error message of reading `text` (as case.toml, or as the file `path`), or "" when it reads
/// fine.
std::string error_of(const std::string& text) {
    return test::case_error(text);
}
std::string error_of_file(const std::string& text, const std::string& path) {
    return test::case_error(text, path);
}

TEST(CaseReader, GoodCaseReadsWithDefaultsFilledIn) {
    const CaseSpec c = read_case_text(good, "cases/pour/case.toml");
    EXPECT_EQ(c.run.name, "pour");
    EXPECT_EQ(c.scene.materials.size(), 1U);
    EXPECT_EQ(c.scene.walls.size(), 6U); // a box is six planes
    EXPECT_DOUBLE_EQ(c.scene.materials[0].rolling_friction, 0.0);
    EXPECT_DOUBLE_EQ(c.scene.gravity.z(), -9.81);
    EXPECT_NE(c.resolved_toml.find("rolling_friction"), std::string::npos);
    EXPECT_NE(c.resolved_toml.find("clamp_normal_force"), std::string::npos);
    // The resolved text is itself a valid case that reads back to the same values.
    const CaseSpec again = read_case_text(c.resolved_toml, "resolved.toml");
    EXPECT_EQ(again.resolved_toml, c.resolved_toml);
}

TEST(CaseReader, RunThreadsDefaultsToZeroAndIsRangeChecked) {
    EXPECT_EQ(read_case_text(good, "case.toml").scene.threads, 0);
    EXPECT_EQ(read_case_text(good + "\n[run]\nthreads = 2\n", "case.toml").scene.threads, 2);
    EXPECT_NE(error_of(good + "\n[run]\nthreads = -1\n").find("run.threads"), std::string::npos);
}

TEST(CaseReader, UnknownKeyNamesFileLineAndAllowedKeys) {
    const std::string e = error_of(edit("friction = 0.5", "friction = 0.5\nfriktion = 0.4"));
    EXPECT_NE(e.find("case.toml:12: material[0].friktion: unknown key"), std::string::npos) << e;
    EXPECT_NE(e.find("allowed here:"), std::string::npos) << e;
}

TEST(CaseReader, NegativeDensityIsOutOfRange) {
    const std::string e = error_of(edit("density = 2500", "density = -2500"));
    EXPECT_NE(
        e.find(
            "case.toml:9: material[0].density: -2500 kg/m^3 is out of range; allowed: value > 0"),
        std::string::npos)
        << e;
}

TEST(CaseReader, PoissonRatioOutsideOpenIntervalIsRejected) {
    const std::string e = error_of(edit("poisson_ratio = 0.45", "poisson_ratio = 0.5"));
    EXPECT_NE(e.find("material[0].poisson_ratio: 0.5 is out of range; allowed: -1 < value < 0.5"),
              std::string::npos)
        << e;
}

TEST(CaseReader, RestitutionMustBeInZeroOne) {
    EXPECT_NE(
        error_of(edit("restitution = 0.3", "restitution = 0")).find("allowed: 0 < value <= 1"),
        std::string::npos);
    EXPECT_NE(error_of(edit("restitution = 0.3", "restitution = 1.2")).find("restitution"),
              std::string::npos);
    EXPECT_EQ(error_of(edit("restitution = 0.3", "restitution = 1")), "");
}

TEST(CaseReader, TimeStepMustBePositive) {
    const std::string e = error_of(edit("time_step = 1e-5", "time_step = 0"));
    EXPECT_NE(e.find("case.toml:2: simulation.time_step: 0 s is out of range; allowed: value > 0"),
              std::string::npos)
        << e;
}

TEST(CaseReader, MissingRequiredValueIsNamed) {
    const std::string e = error_of(edit("youngs_modulus = 5e6\n", ""));
    EXPECT_NE(e.find("material[0].youngs_modulus: missing required value (Pa, value > 0)"),
              std::string::npos)
        << e;
}

TEST(CaseReader, WrongTypeIsNamed) {
    const std::string e = error_of(edit("count = 100", "count = \"many\""));
    EXPECT_NE(e.find("insert[0].count: expected an integer, got string"), std::string::npos) << e;
    const std::string v = error_of(edit("max = [0.02, 0.02, 0.04]", "max = [0.02, 0.02]"));
    EXPECT_NE(v.find("wall[0].max: expected an array of 3 numbers (m)"), std::string::npos) << v;
}

TEST(CaseReader, UnknownMaterialAndChoicesAreListed) {
    const std::string e = error_of(edit("material = \"glass\"\nmin", "material = \"steel\"\nmin"));
    EXPECT_NE(e.find("wall[0].material: \"steel\" is not allowed; allowed: \"glass\""),
              std::string::npos)
        << e;
    const std::string t = error_of(edit("type = \"box\"", "type = \"sphere\""));
    EXPECT_NE(t.find("allowed: \"plane\", \"box\", \"cylinder\""), std::string::npos) << t;
}

TEST(CaseReader, SyntaxErrorGivesLine) {
    const std::string e = error_of(edit("end_time = 0.01", "end_time = = 0.01"));
    EXPECT_NE(e.find("case.toml:3: TOML syntax error"), std::string::npos) << e;
}

TEST(CaseReader, LinearModelNeedsStiffnessAndHertzRefusesIt) {
    const std::string lin = good + "\n[contact]\nmodel = \"linear\"\n";
    EXPECT_NE(error_of(lin).find("contact.stiffness: missing required value (N/m"),
              std::string::npos);
    const std::string hertz = good + "\n[contact]\nstiffness = 1e5\n";
    EXPECT_NE(error_of(hertz).find("only used by model = \"linear\""), std::string::npos);
}

TEST(CaseReader, RegionMaxMustExceedMin) {
    const std::string e = error_of(edit("max = [0.02, 0.02, 0.04] }", "max = [0.02, 0.02, 0.0] }"));
    EXPECT_NE(e.find("insert[0].region.max: must exceed min in every coordinate"),
              std::string::npos)
        << e;
}

TEST(CaseReader, UnknownMonitorIsRejected) {
    const std::string e = error_of(good + "\n[output]\nmonitors = [\"time\", \"temperature\"]\n");
    EXPECT_NE(e.find("output.monitors: \"temperature\" is not allowed"), std::string::npos) << e;
}

TEST(CaseReader, GroupTemperatureMonitorsNameTheSpheresOrAShapeOfTheCase) {
    EXPECT_EQ(error_of(good + "\n[output]\nmonitors = [\"time\", \"mean_temperature:sphere\"]\n"),
              "");
    // The good case has no shape templates: a template name is not a group of it.
    const std::string e = error_of(good + "\n[output]\nmonitors = [\"mean_temperature:cube\"]\n");
    EXPECT_NE(e.find("output.monitors: \"mean_temperature:cube\" is not allowed"),
              std::string::npos)
        << e;
    EXPECT_NE(e.find("mean_temperature:sphere"), std::string::npos) << e; // listed as allowed
}

// --- Non-spherical particles -------------------------------------------------------------------

/// A folder under the temporary directory named for `stem` and the running test: ctest runs the
/// tests in parallel processes, and two tests writing and removing one folder raced (a test found
/// its mesh file deleted by the other).
std::filesystem::path test_folder(const std::string& stem) {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    return std::filesystem::temp_directory_path() / (stem + "_" + info->name());
}

namespace shapes_test {

/// A folder with one case and its own shape templates, removed at the end of the test.
struct CaseFolder {
    std::filesystem::path dir;
    CaseFolder() {
        dir = test_folder("kiln_test_case_shapes");
        std::filesystem::create_directories(dir);
        write("rod_ok.toml", "kind = \"superquadric\"\nhalf_axes = [1.0e-3, 1.0e-4, 1.0e-4]\n"
                             "exponents = [0.5, 1.0]\n");
        write("rod_long.toml", "kind = \"superquadric\"\nhalf_axes = [1.1e-3, 1.0e-4, 1.0e-4]\n"
                               "exponents = [0.5, 1.0]\n");
    }
    ~CaseFolder() { std::filesystem::remove_all(dir); }
    CaseFolder(const CaseFolder&) = delete;
    CaseFolder& operator=(const CaseFolder&) = delete;
    void write(const std::string& name, const std::string& text) const {
        std::ofstream(dir / name) << text;
    }
    [[nodiscard]] std::string path() const { return (dir / "case.toml").string(); }
};

const std::string insert_sphere = R"([[insert]]
type = "random"
material = "glass"
region = { min = [0, 0, 0.01], max = [0.02, 0.02, 0.04] }
count = 100
radius = { distribution = "uniform", min = 0.8e-3, max = 1.2e-3 }
)";

std::string with_bodies(const std::string& body_tables) {
    std::string s = good;
    return s.replace(s.find(insert_sphere), insert_sphere.size(), body_tables);
}

} // namespace shapes_test

TEST(CaseReader, ShapesAreLoadedByNameWithOrientationAndNarrowPhase) {
    const std::string text = shapes_test::with_bodies(R"([contact]
narrow_phase = "gjk_epa"

[[insert]]
type = "random"
material = "glass"
region = { min = [0, 0, 0.01], max = [0.02, 0.02, 0.04] }
count = 10
shape = "ellipsoid_123"

[[insert]]
type = "random"
material = "glass"
region = { min = [0, 0, 0.01], max = [0.02, 0.02, 0.04] }
count = 10
shape = "ellipsoid_123"
orientation = [1, 0, 0, 1]

[[particle]]
material = "glass"
position = [0.01, 0.01, 0.005]
shape = "cylinder_12"
)");
    const CaseSpec c = read_case_text(text, "case.toml");
    ASSERT_EQ(c.scene.shapes.size(), 2U); // loaded once per name
    EXPECT_EQ(c.scene.narrow_phase, dynamics::NarrowPhase::gjk_epa);
    ASSERT_EQ(c.scene.inserts.size(), 2U);
    EXPECT_EQ(c.scene.inserts[0].shape, c.scene.inserts[1].shape);
    EXPECT_TRUE(c.scene.inserts[0].orientation.random); // inserts default to random
    EXPECT_FALSE(c.scene.inserts[1].orientation.random);
    constexpr double rounding = 1e-15; // normalised quaternion of [1, 0, 0, 1]
    EXPECT_NEAR(c.scene.inserts[1].orientation.fixed.w(), std::sqrt(0.5), rounding);
    EXPECT_DOUBLE_EQ(
        c.scene.inserts[0].size.radius,
        c.scene.shapes[static_cast<std::size_t>(c.scene.inserts[0].shape)].bounding_radius());
    ASSERT_EQ(c.scene.particles.size(), 1U);
    EXPECT_FALSE(c.scene.particles[0].orientation.random); // particles default to identity
    EXPECT_NE(c.resolved_toml.find("narrow_phase = 'gjk_epa'"), std::string::npos);
}

TEST(CaseReader, GroupTemperatureMonitorsAcceptTheCasesShapes) {
    const std::string text = shapes_test::with_bodies(R"([[particle]]
material = "glass"
position = [0.01, 0.01, 0.005]
shape = "cylinder_12"

[output]
monitors = ["time", "mean_temperature:cylinder_12", "mean_temperature:sphere"]
)");
    const CaseSpec c = read_case_text(text, "case.toml");
    EXPECT_EQ(c.output.monitors.size(), 3U);
    EXPECT_NE(
        error_of(test::edited(text, "mean_temperature:cylinder_12", "mean_temperature:cylinder"))
            .find("\"mean_temperature:cylinder\" is not allowed"),
        std::string::npos);
}

TEST(CaseReader, NarrowPhaseDefaultsToNewton) {
    EXPECT_EQ(read_case_text(good, "case.toml").scene.narrow_phase, dynamics::NarrowPhase::newton);
    EXPECT_NE(error_of(edit("[[insert]]", "[contact]\nnarrow_phase = \"mpr\"\n\n[[insert]]"))
                  .find("contact.narrow_phase"),
              std::string::npos);
}

TEST(CaseReader, BodyRadiusDefaultsToFirstTouchAndIsChecked) {
    EXPECT_EQ(read_case_text(good, "case.toml").scene.body_radius,
              dynamics::BodyRadius::first_touch);
    const CaseSpec c = read_case_text(
        edit("[[insert]]", "[contact]\nbody_radius = \"per_step\"\n\n[[insert]]"), "case.toml");
    EXPECT_EQ(c.scene.body_radius, dynamics::BodyRadius::per_step);
    EXPECT_NE(c.resolved_toml.find("body_radius = 'per_step'"), std::string::npos);
    const std::string e =
        error_of(edit("[[insert]]", "[contact]\nbody_radius = \"equivalent\"\n\n[[insert]]"));
    EXPECT_NE(e.find("contact.body_radius"), std::string::npos) << e;
    EXPECT_NE(e.find("first_touch"), std::string::npos) << e; // names what is allowed
}

TEST(CaseReader, ShapeErrorsAreLocated) {
    const auto body = [](const std::string& extra) {
        return shapes_test::with_bodies("[[particle]]\nmaterial = \"glass\"\n"
                                        "position = [0.01, 0.01, 0.005]\n" +
                                        extra);
    };
    // Unknown template: the folders searched are listed.
    const std::string unknown = error_of(body("shape = \"no_such_shape\"\n"));
    EXPECT_NE(unknown.find("case.toml:22: particle[0].shape"), std::string::npos) << unknown;
    // A radius next to a shape.
    EXPECT_NE(error_of(body("shape = \"ellipsoid_123\"\nradius = 1e-3\n")).find("remove radius"),
              std::string::npos);
    // Orientation: only "random" or four numbers, and only with a shape.
    EXPECT_NE(error_of(body("shape = \"ellipsoid_123\"\norientation = [1, 0, 0]\n"))
                  .find("particle[0].orientation"),
              std::string::npos);
    EXPECT_NE(error_of(body("shape = \"ellipsoid_123\"\norientation = \"any\"\n"))
                  .find("allowed: \"random\""),
              std::string::npos);
    EXPECT_NE(error_of(body("shape = \"ellipsoid_123\"\norientation = [0, 0, 0, 0]\n"))
                  .find("must not be zero"),
              std::string::npos);
    EXPECT_NE(error_of(body("radius = 1e-3\norientation = \"random\"\n")).find("only used with"),
              std::string::npos);
    // Polyhedra run, also next to superquadrics.
    EXPECT_EQ(error_of(body("shape = \"cube\"\n")), "");
    const std::string mixed = error_of(
        body("shape = \"cube\"\n") + "\n[[particle]]\nmaterial = \"glass\"\n"
                                     "position = [0.01, 0.01, 0.015]\nshape = \"ellipsoid_123\"\n");
    EXPECT_EQ(mixed, "");
}

TEST(CaseReader, SuperquadricAspectRatioAboveTenIsRefused) {
    const shapes_test::CaseFolder folder;
    const auto text = [](const std::string& name) {
        return shapes_test::with_bodies("[[particle]]\nmaterial = \"glass\"\n"
                                        "position = [0.01, 0.01, 0.005]\nshape = \"" +
                                        name + "\"\n");
    };
    // Templates next to the case file are found first.
    EXPECT_EQ(read_case_text(text("rod_ok"), folder.path()).scene.shapes.size(), 1U);
    const std::string e = error_of_file(text("rod_long"), folder.path());
    EXPECT_NE(e.find("aspect ratios up to 10"), std::string::npos) << e;
}

/// A case folder with mesh files: an open square plate (flat), a closed box with outward normals
/// and a mesh with a zero-area triangle.
struct MeshFolder {
    std::filesystem::path dir;
    MeshFolder() {
        dir = test_folder("kiln_test_case_meshes");
        std::filesystem::create_directories(dir);
        std::ofstream(dir / "plate.obj") << "v 0 0 0\nv 0.02 0 0\nv 0.02 0.02 0\nv 0 0.02 0\n"
                                            "f 1 2 3\nf 1 3 4\n";
        std::ofstream(dir / "sliver.obj") << "v 0 0 0\nv 0.01 0 0\nv 0.02 0 0\nf 1 2 3\n";
        // Unit cube with outward normals, scaled to 20 mm by the case.
        std::ofstream(dir / "box.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                          "v 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                                          "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\n"
                                          "f 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\n"
                                          "f 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n";
    }
    ~MeshFolder() { std::filesystem::remove_all(dir); }
    MeshFolder(const MeshFolder&) = delete;
    MeshFolder& operator=(const MeshFolder&) = delete;
    [[nodiscard]] std::string path() const { return (dir / "case.toml").string(); }
};

/// The good case with its analytic box replaced by a mesh wall of the given keys.
std::string with_mesh(const std::string& keys) {
    return edit("type = \"box\"\nmaterial = \"glass\"\nmin = [0, 0, 0]\nmax = [0.02, 0.02, 0.04]",
                "type = \"mesh\"\nmaterial = \"glass\"\n" + keys);
}

TEST(CaseReader, MeshWallReadsRelativeToTheCaseFile) {
    const MeshFolder folder;
    // A flat, open plate is a valid wall (no closure check for walls); translate moves it.
    const CaseSpec c = read_case_text(
        with_mesh("file = \"plate.obj\"\ntranslate = [0, 0, 0.001]\n"), folder.path());
    ASSERT_EQ(c.scene.mesh_walls.size(), 1U);
    EXPECT_TRUE(c.scene.walls.empty());
    const auto& mesh = *c.scene.mesh_walls[0].mesh;
    EXPECT_EQ(mesh.triangles().size(), 2U);
    EXPECT_DOUBLE_EQ(mesh.vertices()[0].z(), 0.001);
    // The closed box flipped into a container, scaled to a 40 mm cube around the insert region: the
    // particles are inside.
    const CaseSpec box = read_case_text(
        with_mesh("file = \"box.obj\"\nscale = 0.04\ntranslate = [-0.01, -0.01, 0]\nflip = true\n"),
        folder.path());
    EXPECT_EQ(box.scene.mesh_walls[0].mesh->facet_count(), 6);
    EXPECT_NE(box.resolved_toml.find("flip = true"), std::string::npos);
    // The resolved text names the mesh absolutely and reads again from anywhere.
    const CaseSpec again = read_case_text(box.resolved_toml, "elsewhere/resolved.toml");
    EXPECT_EQ(again.scene.mesh_walls.size(), 1U);
}

TEST(CaseReader, MeshWallErrorsAreLocated) {
    const MeshFolder folder;
    // Missing file: the key and the path are named.
    const std::string missing = error_of_file(with_mesh("file = \"nope.stl\"\n"), folder.path());
    EXPECT_NE(missing.find("wall[0].file"), std::string::npos) << missing;
    EXPECT_NE(missing.find("nope.stl"), std::string::npos) << missing;
    // Unknown format.
    EXPECT_NE(error_of_file(with_mesh("file = \"plate.ply\"\n"), folder.path())
                  .find("unknown mesh format"),
              std::string::npos);
    // A triangle of zero area (collinear corners).
    const std::string sliver = error_of_file(with_mesh("file = \"sliver.obj\"\n"), folder.path());
    EXPECT_NE(sliver.find("wall[0].file"), std::string::npos) << sliver;
    // Wrong side: the box with outward normals and the particles inside it.
    const std::string side = error_of_file(
        with_mesh("file = \"box.obj\"\nscale = 0.04\ntranslate = [-0.01, -0.01, 0]\n"),
        folder.path());
    EXPECT_NE(side.find("wall[0].flip"), std::string::npos) << side;
    EXPECT_NE(side.find("behind the mesh"), std::string::npos) << side;
    // Scale must be positive.
    EXPECT_NE(error_of_file(with_mesh("file = \"plate.obj\"\nscale = 0\n"), folder.path())
                  .find("wall[0].scale"),
              std::string::npos);
}

} // namespace
} // namespace kiln::io
