#include "common/cube_template.hpp"
#include "core/error.hpp"
#include "dynamics/system.hpp"
#include "geometry/mesh_wall.hpp"
#include "io/case_spec.hpp"
#include "io/monitors.hpp"
#include "io/shape_reader.hpp"
#include "io/summary.hpp"
#include "io/vtk_writer.hpp"

#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>
#include <vtkXMLPolyDataReader.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace kiln::io {
namespace {

namespace fs = std::filesystem;
using dynamics::CylinderWall;
using dynamics::PlaneWall;
using dynamics::SceneSpec;
using dynamics::System;

/// Edge of the test box (m).
constexpr double box = 0.01;

/// Six particles in a box of six plane walls, default gravity.
SceneSpec box_scene() {
    SceneSpec s;
    s.materials.push_back({"m", 1e7, 0.3, 2500, 0.5, 0.3, 0.0});
    s.time_step = 1e-6;
    s.walls.push_back({"floor", PlaneWall{Vec3(0, 0, 0), Vec3(0, 0, 1)}, 0});
    s.walls.push_back({"lid", PlaneWall{Vec3(0, 0, box), Vec3(0, 0, -1)}, 0});
    s.walls.push_back({"x0", PlaneWall{Vec3(0, 0, 0), Vec3(1, 0, 0)}, 0});
    s.walls.push_back({"x1", PlaneWall{Vec3(box, 0, 0), Vec3(-1, 0, 0)}, 0});
    s.walls.push_back({"y0", PlaneWall{Vec3(0, 0, 0), Vec3(0, 1, 0)}, 0});
    s.walls.push_back({"y1", PlaneWall{Vec3(0, box, 0), Vec3(0, -1, 0)}, 0});
    for (int k = 0; k < 6; ++k) {
        const double r = 0.8e-3 + 0.05e-3 * k;
        const int column = k % 3;
        const int row = k / 3;
        const Vec3 x(0.002 + 0.003 * column, 0.003 + 0.004 * row, 0.002 + 0.001 * k);
        const Vec3 v(0.1 * k, -0.05 * k, 0.02);
        s.particles.push_back({0, r, x, v, Vec3(0, 0, 10.0 * k)});
    }
    return s;
}

/// A fresh directory under the system temporary folder, removed with everything in it.
class TempDir {
  public:
    TempDir() {
        std::string pattern = (fs::temp_directory_path() / "kiln_test_io_XXXXXX").string();
        if (mkdtemp(pattern.data()) == nullptr) {
            throw std::runtime_error("cannot create a temporary directory");
        }
        path_ = pattern;
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(path_, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    TempDir(TempDir&&) = delete;
    TempDir& operator=(TempDir&&) = delete;
    [[nodiscard]] const fs::path& path() const { return path_; }

  private:
    fs::path path_;
};

std::string read_text(const fs::path& file) {
    std::ifstream f(file);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

long count_of(const std::string& text, std::string_view what) {
    long n = 0;
    for (auto pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) {
        ++n;
    }
    return n;
}

/// Minimal recursive-descent JSON validator (RFC 8259 grammar, numbers checked with strtod).
class JsonChecker {
  public:
    explicit JsonChecker(std::string_view text) : t_(text) {}
    /// True when the whole text is exactly one JSON value.
    bool valid() {
        ws();
        if (!value()) {
            return false;
        }
        ws();
        return i_ == t_.size();
    }

  private:
    bool value() {
        if (i_ >= t_.size()) {
            return false;
        }
        switch (t_[i_]) {
        case '{':
            return members('}', true);
        case '[':
            return members(']', false);
        case '"':
            return string();
        default:
            return literal("true") || literal("false") || literal("null") || number();
        }
    }
    bool members(char close, bool object) {
        ++i_;
        ws();
        if (eat(close)) {
            return true;
        }
        for (;;) {
            ws();
            if (object) {
                if (!string()) {
                    return false;
                }
                ws();
                if (!eat(':')) {
                    return false;
                }
                ws();
            }
            if (!value()) {
                return false;
            }
            ws();
            if (eat(',')) {
                continue;
            }
            return eat(close);
        }
    }
    bool string() {
        if (!eat('"')) {
            return false;
        }
        while (i_ < t_.size()) {
            const char c = t_[i_++];
            if (c == '"') {
                return true;
            }
            if (static_cast<unsigned char>(c) < 0x20) {
                return false;
            }
            if (c == '\\') {
                if (i_ >= t_.size()) {
                    return false;
                }
                const char e = t_[i_++];
                if (e == 'u') {
                    for (int k = 0; k < 4; ++k) {
                        if (i_ >= t_.size() ||
                            std::isxdigit(static_cast<unsigned char>(t_[i_++])) == 0) {
                            return false;
                        }
                    }
                } else if (std::string_view("\"\\/bfnrt").find(e) == std::string_view::npos) {
                    return false;
                }
            }
        }
        return false;
    }
    bool number() {
        const std::size_t start = i_;
        while (i_ < t_.size() &&
               std::string_view("+-0123456789.eE").find(t_[i_]) != std::string_view::npos) {
            ++i_;
        }
        if (i_ == start ||
            (t_[start] != '-' && std::isdigit(static_cast<unsigned char>(t_[start])) == 0)) {
            return false;
        }
        const std::string s(t_.substr(start, i_ - start));
        char* end = nullptr;
        std::strtod(s.c_str(), &end);
        return end == s.c_str() + s.size();
    }
    bool literal(std::string_view word) {
        if (t_.substr(i_, word.size()) == word) {
            i_ += word.size();
            return true;
        }
        return false;
    }
    bool eat(char c) {
        if (i_ < t_.size() && t_[i_] == c) {
            ++i_;
            return true;
        }
        return false;
    }
    void ws() {
        while (i_ < t_.size() &&
               std::string_view(" \t\r\n").find(t_[i_]) != std::string_view::npos) {
            ++i_;
        }
    }

    std::string_view t_;
    std::size_t i_ = 0;
};

/// Reads `file` back and checks it holds exactly the particles of `sys`.
void expect_frame_matches(const fs::path& file, const System& sys) {
    vtkNew<vtkXMLPolyDataReader> reader;
    reader->SetFileName(file.string().c_str());
    reader->Update();
    vtkPolyData* pd = reader->GetOutput();
    const ParticleStore& p = sys.particles();
    ASSERT_EQ(pd->GetNumberOfPoints(), static_cast<vtkIdType>(p.size()));
    EXPECT_EQ(pd->GetNumberOfVerts(), static_cast<vtkIdType>(p.size()));
    vtkDataArray* id = pd->GetPointData()->GetArray("id");
    vtkDataArray* radius = pd->GetPointData()->GetArray("radius");
    vtkDataArray* velocity = pd->GetPointData()->GetArray("velocity");
    ASSERT_NE(id, nullptr);
    ASSERT_NE(radius, nullptr);
    ASSERT_NE(velocity, nullptr);
    ASSERT_NE(pd->GetPointData()->GetArray("material"), nullptr);
    ASSERT_NE(pd->GetPointData()->GetArray("angular_velocity"), nullptr);
    ASSERT_NE(pd->GetPointData()->GetArray("force"), nullptr);
    EXPECT_EQ(id->GetDataTypeSize(), 8);
    EXPECT_EQ(velocity->GetNumberOfComponents(), 3);
    // Exact comparisons: raw appended binary, losslessly compressed, round-trips every double.
    for (std::size_t i = 0; i < p.size(); ++i) {
        const auto k = static_cast<vtkIdType>(i);
        EXPECT_EQ(static_cast<std::int64_t>(id->GetComponent(k, 0)), p.id[i]);
        EXPECT_EQ(radius->GetComponent(k, 0), p.radius[i]);
        for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(velocity->GetComponent(k, c), p.v[i][c]);
            EXPECT_EQ(pd->GetPoint(k)[c], p.x[i][c]);
        }
    }
}

TEST(ParticleSeriesWriter, FramesReadBackAndCollectionListsThem) {
    const TempDir dir;
    System sys(box_scene());
    ParticleSeriesWriter w(dir.path());
    w.write(sys);
    expect_frame_matches(dir.path() / "particles" / "particles_000000.vtp", sys);
    for (int k = 0; k < 200; ++k) {
        sys.step();
    }
    w.write(sys);
    expect_frame_matches(dir.path() / "particles" / "particles_000001.vtp", sys);
    EXPECT_EQ(w.frames(), 2U);

    const std::string pvd = read_text(dir.path() / "particles.pvd");
    EXPECT_EQ(count_of(pvd, "<DataSet "), 2);
    EXPECT_NE(pvd.find("file=\"particles/particles_000001.vtp\""), std::string::npos);
    EXPECT_NE(pvd.find("</VTKFile>"), std::string::npos);
    EXPECT_FALSE(fs::exists(dir.path() / "particles.pvd.tmp"));
}

TEST(ParticleSeriesWriter, BodiesAreDrawnAsTheirPosedSurfaces) {
    const TempDir dir;
    SceneSpec s;
    s.materials.push_back({"m", 1e7, 0.3, 2500, 0.5, 0.3, 0.0});
    s.time_step = 1e-5;
    s.shapes.push_back(read_shape_file(find_shape_file("superball", default_shape_dirs())));
    dynamics::ParticleSpec b;
    b.shape = 0;
    b.x = Vec3(0.001, 0.002, 0.003);
    b.v = Vec3(0.1, 0, 0);
    b.orientation.fixed = Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
    s.particles.push_back(b);
    s.particles.emplace_back(0, 1e-3, Vec3(0.01, 0, 0), Vec3::Zero(), Vec3::Zero());
    const System sys(s);
    ParticleSeriesWriter w(dir.path());
    w.write(sys);
    ASSERT_TRUE(fs::exists(dir.path() / "bodies.pvd"));
    vtkNew<vtkXMLPolyDataReader> reader;
    reader->SetFileName((dir.path() / "bodies" / "bodies_000000.vtp").string().c_str());
    reader->Update();
    vtkPolyData* pd = reader->GetOutput();
    // One body (the sphere is not drawn here): its mesh, every vertex on the posed surface.
    const geometry::SurfaceMesh mesh = geometry::surface_mesh(s.shapes[0].shape, 12);
    ASSERT_EQ(pd->GetNumberOfPoints(), static_cast<vtkIdType>(mesh.vertices.size()));
    EXPECT_EQ(pd->GetNumberOfPolys(), static_cast<vtkIdType>(mesh.triangles.size()));
    const auto& sq = std::get<geometry::Superquadric>(s.shapes[0].shape);
    const ParticleStore& p = sys.particles();
    const std::size_t i = p.shape[0] >= 0 ? 0 : 1;
    constexpr double on_surface = 1e-9; // |F| of a vertex mapped back to the body frame
    for (vtkIdType k = 0; k < pd->GetNumberOfPoints(); ++k) {
        const Vec3 x(pd->GetPoint(k)[0], pd->GetPoint(k)[1], pd->GetPoint(k)[2]);
        EXPECT_NEAR(sq.inside_outside(p.q[i].conjugate() * (x - p.x[i])), 0.0, on_surface);
    }
    vtkDataArray* id = pd->GetCellData()->GetArray("id");
    vtkDataArray* velocity = pd->GetCellData()->GetArray("velocity");
    ASSERT_NE(id, nullptr);
    ASSERT_NE(velocity, nullptr);
    EXPECT_EQ(static_cast<std::int64_t>(id->GetComponent(0, 0)), p.id[i]);
    EXPECT_EQ(velocity->GetComponent(0, 0), 0.1);
    EXPECT_NE(read_text(dir.path() / "bodies.pvd").find("bodies/bodies_000000.vtp"),
              std::string::npos);
}

TEST(ParticleSeriesWriter, WallsAreOneQuadPerPlaneAndATubePerCylinder) {
    const TempDir dir;
    SceneSpec s = box_scene();
    s.walls.push_back({"drum", CylinderWall{Vec3(0.005, 0.005, 0), Vec3(0, 0, 1), 0.02}, 0});
    const ParticleSeriesWriter w(dir.path());
    w.write_walls(s, dir.path() / "walls.vtp");

    vtkNew<vtkXMLPolyDataReader> reader;
    reader->SetFileName((dir.path() / "walls.vtp").string().c_str());
    reader->Update();
    vtkPolyData* pd = reader->GetOutput();
    constexpr vtkIdType tube_facets = 48;
    ASSERT_EQ(pd->GetNumberOfPolys(), 6 + tube_facets);
    vtkDataArray* wall = pd->GetCellData()->GetArray("wall");
    ASSERT_NE(wall, nullptr);
    for (vtkIdType c = 0; c < pd->GetNumberOfCells(); ++c) {
        EXPECT_EQ(wall->GetComponent(c, 0), static_cast<double>(std::min<vtkIdType>(c, 6)));
    }
    // The floor quad lies in z = 0; the tube points lie on the cylinder radius.
    constexpr double rounding = 1e-15; // coordinates built from unit vectors of O(1) (m)
    for (vtkIdType k = 0; k < 4; ++k) {
        EXPECT_NEAR(pd->GetPoint(k)[2], 0.0, rounding);
    }
    for (vtkIdType k = 24; k < pd->GetNumberOfPoints(); ++k) {
        const double* x = pd->GetPoint(k);
        EXPECT_NEAR(std::hypot(x[0] - 0.005, x[1] - 0.005), 0.02, rounding);
    }
}

TEST(ParticleSeriesWriter, MeshWallsAreWrittenAsTheirTriangles) {
    // A mesh wall (two triangles of a square, 5 mm above the floor) after the six box planes:
    // its triangles with their own corner points, wall index 6, and its name last.
    const TempDir dir;
    SceneSpec s = box_scene();
    const std::vector<Vec3> v{
        {0, 0, 0.005}, {0.01, 0, 0.005}, {0.01, 0.01, 0.005}, {0, 0.01, 0.005}};
    s.mesh_walls.push_back({"ramp",
                            std::make_shared<const geometry::MeshWall>(
                                v, std::vector<std::array<int, 3>>{{0, 1, 2}, {0, 2, 3}}, "ramp"),
                            0});
    const ParticleSeriesWriter w(dir.path());
    w.write_walls(s, dir.path() / "walls.vtp");

    vtkNew<vtkXMLPolyDataReader> reader;
    reader->SetFileName((dir.path() / "walls.vtp").string().c_str());
    reader->Update();
    vtkPolyData* pd = reader->GetOutput();
    ASSERT_EQ(pd->GetNumberOfPolys(), 6 + 2);
    vtkDataArray* wall = pd->GetCellData()->GetArray("wall");
    ASSERT_NE(wall, nullptr);
    EXPECT_EQ(wall->GetComponent(6, 0), 6.0);
    EXPECT_EQ(wall->GetComponent(7, 0), 6.0);
    // The last two cells are the triangles, on the mesh's own points (exact copies).
    vtkIdType n = 0;
    const vtkIdType* ids = nullptr;
    pd->GetCellPoints(7, n, ids);
    ASSERT_EQ(n, 3);
    for (vtkIdType k = 0; k < 3; ++k) {
        const double* x = pd->GetPoint(ids[k]);
        const Vec3& ref =
            v[static_cast<std::size_t>(std::array<int, 3>{0, 2, 3}[static_cast<std::size_t>(k)])];
        EXPECT_EQ(Vec3(x[0], x[1], x[2]), ref);
    }
    auto* names = vtkStringArray::SafeDownCast(pd->GetFieldData()->GetAbstractArray("wall_name"));
    ASSERT_NE(names, nullptr);
    ASSERT_EQ(names->GetNumberOfValues(), 7);
    EXPECT_EQ(names->GetValue(6), "ramp");
}

TEST(Monitors, KineticEnergyIsHalfMassSpeedSquared) {
    const System sys(box_scene());
    const ParticleStore& p = sys.particles();
    double expected = 0;
    double mean_z = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        expected += 0.5 * p.mass[i] * p.v[i].squaredNorm();
        mean_z += p.x[i].z() / static_cast<double>(p.size());
    }
    constexpr double rounding = 1e-12; // the same sum, possibly in another order (relative)
    EXPECT_NEAR(monitor_value(sys, "kinetic_energy"), expected, rounding * expected);
    EXPECT_NEAR(monitor_value(sys, "mean_height"), mean_z, rounding * mean_z);
    EXPECT_EQ(monitor_value(sys, "step"), 0.0);
}

TEST(Monitors, EveryNameEvaluatesAndUnknownNamesAreInputErrors) {
    const System sys(box_scene());
    EXPECT_EQ(monitor_names().size(), 20U);
    const std::vector<std::string> heat_names = {"mean_temperature", "min_temperature",
                                                 "max_temperature", "thermal_energy",
                                                 "external_heat"};
    for (const auto& name : monitor_names()) {
        const bool heat = std::find(heat_names.begin(), heat_names.end(), name) != heat_names.end();
        // Heat monitors are NaN in a run without heat; every other one is a number.
        EXPECT_EQ(std::isfinite(monitor_value(sys, name)), !heat) << name;
    }
    EXPECT_THROW(static_cast<void>(monitor_value(sys, "temperature")), InputError);
    const TempDir dir;
    EXPECT_THROW(MonitorWriter(dir.path() / "m.csv", {"time", "nonsense"}), InputError);
}

TEST(Monitors, GroupTemperaturesAreTheCapacityWeightedMeansOfEachShape) {
    // Two lumped spheres (r and 2 r, so capacities 1 : 8) at 300 and 400 K and two equal lumped
    // cubes at 500 and 600 K, far apart: the sphere group's mean is (300 + 8 400) / 9 K, the
    // cubes' 550 K; a template not in the scene and a run without heat give NaN.
    dynamics::SceneSpec s;
    s.materials.push_back({"a", 1e7, 0.3, 2700, 0.5, 0.3, 0.0});
    s.gravity = Vec3::Zero();
    s.time_step = 1e-5;
    s.shapes.push_back(test::cube_template(1e-3));
    s.particles.push_back({0, 1e-3, Vec3(0, 0, 0), Vec3::Zero(), Vec3::Zero()});
    s.particles.push_back({0, 2e-3, Vec3(0.01, 0, 0), Vec3::Zero(), Vec3::Zero()});
    for (const double x : {0.02, 0.03}) {
        dynamics::ParticleSpec cube;
        cube.x = Vec3(x, 0, 0);
        cube.shape = 0;
        s.particles.push_back(cube);
    }
    const System sys(s);
    thermal::HeatSpec h;
    h.enabled = true;
    thermal::MaterialHeat m;
    m.enabled = true;
    m.conductivity = 1.0;
    m.specific_heat = 900;
    m.initial_temperature = 300;
    m.model = heat::HeatModel::lumped;
    h.materials = {m};
    h.particle_temperature = {300.0, 400.0, 500.0, 600.0};
    const thermal::ThermalSystem heat(h, sys);
    EXPECT_NEAR(monitor_value(sys, &heat, "mean_temperature:sphere"), 3500.0 / 9.0, 1e-12 * 400);
    EXPECT_NEAR(monitor_value(sys, &heat, "mean_temperature:cube"), 550.0, 1e-12 * 550);
    EXPECT_TRUE(std::isnan(monitor_value(sys, &heat, "mean_temperature:pyramid")));
    EXPECT_TRUE(std::isnan(monitor_value(sys, nullptr, "mean_temperature:cube")));
    // The whole scene's mean weighs the groups by their capacities.
    double c_sphere = 0.0;
    double c_cube = 0.0;
    for (std::size_t i = 0; i < sys.particles().size(); ++i) {
        (sys.particles().shape[i] < 0 ? c_sphere : c_cube) += heat.heat_capacity(sys, i);
    }
    EXPECT_NEAR(c_sphere, 9.0 * 2700 * 900 * 4.0 / 3.0 * std::numbers::pi * 1e-9, 1e-12 * c_sphere);
    EXPECT_NEAR(monitor_value(sys, &heat, "mean_temperature"),
                (c_sphere * 3500.0 / 9.0 + c_cube * 550.0) / (c_sphere + c_cube), 1e-9);
    // The writer evaluates group columns like the others.
    const TempDir dir;
    MonitorWriter w(dir.path() / "m.csv", {"time", "mean_temperature:cube"});
    w.set_heat(&heat);
    w.write(sys);
    ASSERT_EQ(w.last_row().size(), 2U);
    EXPECT_NEAR(w.last_row()[1], 550.0, 1e-12 * 550);
}

TEST(MonitorWriter, CsvHasHeaderAndOneFullPrecisionRowPerWrite) {
    const TempDir dir;
    System sys(box_scene());
    const fs::path csv = dir.path() / "monitors.csv";
    MonitorWriter m(csv, {"time", "kinetic_energy", "contacts", "max_velocity"});
    m.write(sys);
    for (int k = 0; k < 10; ++k) {
        sys.step();
    }
    m.write(sys);
    ASSERT_EQ(m.last_row().size(), 4U);
    EXPECT_EQ(m.last_row()[0], sys.time());

    std::ifstream f(csv);
    std::string line;
    std::vector<std::string> lines;
    while (std::getline(f, line)) {
        lines.push_back(line);
    }
    ASSERT_EQ(lines.size(), 3U);
    EXPECT_EQ(lines[0], "time,kinetic_energy,contacts,max_velocity");
    EXPECT_EQ(count_of(lines[2], ","), 3);
    constexpr double ten_digits = 1e-9; // rows are printed with %.10g (relative)
    const double t = std::stod(lines[2].substr(0, lines[2].find(',')));
    EXPECT_NEAR(t, sys.time(), ten_digits * sys.time());
}

TEST(Summary, JsonIsValidAndEscapesStrings) {
    const TempDir dir;
    RunSummary s;
    s.case_name = "a \"quoted\" name\\ with\ttab\nand \x01";
    s.case_file = "cases/x/case.toml";
    s.kiln_version = "0.1.0";
    s.git_hash = "abc";
    s.steps = 1000;
    s.particles = 6;
    s.simulated_time = 1e-3;
    s.wall_seconds = std::numeric_limits<double>::quiet_NaN();
    s.particle_steps_per_second = 1.5e6;
    s.heat_wall_seconds = 0.25;
    s.warnings = {"first", "second \"one\""};
    s.final_monitors = {{"time", 1e-3}, {"max_velocity", std::numeric_limits<double>::infinity()}};
    s.status = "completed";
    const fs::path file = dir.path() / "summary.json";
    write_summary_json(file, s);

    const std::string json = read_text(file);
    EXPECT_TRUE(JsonChecker(json).valid()) << json;
    EXPECT_NE(json.find("\"particle_steps_per_second\": 1500000"), std::string::npos) << json;
    EXPECT_NE(json.find("\"heat_wall_seconds\": 0.25"), std::string::npos) << json;
    EXPECT_NE(json.find(R"("case_name": "a \"quoted\" name\\ with\ttab\nand \u0001")"),
              std::string::npos)
        << json;
    EXPECT_NE(json.find("\"wall_seconds\": null"), std::string::npos) << json;
    EXPECT_NE(json.find("\"max_velocity\": null"), std::string::npos) << json;

    const RunSummary empty;
    write_summary_json(file, empty);
    EXPECT_TRUE(JsonChecker(read_text(file)).valid()) << read_text(file);
}

} // namespace
} // namespace kiln::io
