// Heat output read back with VTK's own readers: temperatures in the particle frames and the
// intra-particle field files.
#include "dynamics/system.hpp"
#include "geometry/shape.hpp"
#include "io/field_vtk.hpp"
#include "io/vtk_writer.hpp"
#include "thermal/thermal_system.hpp"

#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <filesystem>
#include <gtest/gtest.h>
#include <numbers>

namespace kiln::io {
namespace {

TEST(HeatOutput, ParticleTemperaturesAndFieldsReadBack) {
    const auto dir = std::filesystem::temp_directory_path() / "kiln_test_heat_output";
    std::filesystem::remove_all(dir);
    dynamics::SceneSpec s;
    s.materials.push_back({"a", 1e7, 0.3, 2700, 0.2, 0.3, 0.0});
    s.materials.push_back({"b", 1e7, 0.3, 2700, 0.2, 0.3, 0.0});
    s.time_step = 1e-5;
    s.gravity = Vec3::Zero();
    s.particles.push_back({0, 1e-3, Vec3(0, 0, 0), Vec3::Zero(), Vec3::Zero()});
    s.particles.push_back({1, 1e-3, Vec3(0.01, 0, 0), Vec3::Zero(), Vec3::Zero()});
    dynamics::System sys(s);
    thermal::HeatSpec h;
    h.enabled = true;
    thermal::MaterialHeat m;
    m.enabled = true;
    m.conductivity = 1;
    m.specific_heat = 1000;
    m.initial_temperature = 320;
    m.model = heat::HeatModel::resolved;
    m.spherical = {3, 4, 6};
    h.materials = {m, m};
    h.materials[1].model = heat::HeatModel::lumped;
    h.materials[1].initial_temperature = 280;
    thermal::ThermalSystem heat(h, sys);

    ParticleSeriesWriter vtk(dir);
    vtk.set_heat(&heat);
    vtk.write(sys);
    FieldSeriesWriter fields(dir, 0);
    fields.write(sys, heat, {});

    vtkNew<vtkXMLPolyDataReader> pr;
    pr->SetFileName((dir / "particles/particles_000000.vtp").string().c_str());
    pr->Update();
    vtkDataArray* mean = pr->GetOutput()->GetPointData()->GetArray("temperature_mean");
    ASSERT_NE(mean, nullptr);
    ASSERT_NE(pr->GetOutput()->GetPointData()->GetArray("temperature_core"), nullptr);
    ASSERT_NE(pr->GetOutput()->GetPointData()->GetArray("temperature_surface"), nullptr);
    const double t0 = mean->GetTuple1(0);
    const double t1 = mean->GetTuple1(1);
    EXPECT_DOUBLE_EQ(std::min(t0, t1), 280.0);
    EXPECT_NEAR(std::max(t0, t1), 320.0, 1e-12); // uniform field: its mean, up to rounding

    vtkNew<vtkXMLUnstructuredGridReader> fr;
    fr->SetFileName((dir / "fields/fields_000000.vtu").string().c_str());
    fr->Update();
    vtkUnstructuredGrid* g = fr->GetOutput();
    EXPECT_EQ(g->GetNumberOfCells(), 1 + 3 * 4 * 6); // only the resolved particle
    vtkDataArray* t = g->GetCellData()->GetArray("temperature");
    ASSERT_NE(t, nullptr);
    EXPECT_DOUBLE_EQ(t->GetRange()[0], 320.0);
    // The cells lie inside the particle's sphere in world position (radius 1 mm about its centre).
    double b[6];
    g->GetBounds(b);
    EXPECT_LE(b[1] - b[0], 2e-3 + 1e-12);
    EXPECT_TRUE(std::filesystem::exists(dir / "fields.pvd"));
    std::filesystem::remove_all(dir);
}

TEST(HeatOutput, BodyFieldsAreWrittenTurnedByTheOrientation) {
    const auto dir = std::filesystem::temp_directory_path() / "kiln_test_body_field_output";
    std::filesystem::remove_all(dir);
    dynamics::SceneSpec s;
    s.materials.push_back({"a", 1e7, 0.3, 2700, 0.2, 0.3, 0.0});
    s.time_step = 1e-5;
    s.gravity = Vec3::Zero();
    geometry::Superquadric e; // 6 x 2 x 2 mm ellipsoid, long axis along body x
    e.half_axes = Vec3(3e-3, 1e-3, 1e-3);
    s.shapes.push_back(geometry::make_template("cigar", e));
    dynamics::ParticleSpec p;
    p.shape = 0;
    p.x = Vec3(0.01, 0, 0);
    // 90 degrees about z: body x -> world y.
    p.orientation.fixed = Quat(Eigen::AngleAxisd(0.5 * std::numbers::pi, Vec3::UnitZ()));
    s.particles.push_back(p);
    dynamics::System sys(s);
    thermal::HeatSpec h;
    h.enabled = true;
    thermal::MaterialHeat m;
    m.enabled = true;
    m.conductivity = 1;
    m.specific_heat = 1000;
    m.model = heat::HeatModel::resolved;
    m.cells_across = 12;
    h.materials = {m};
    thermal::ThermalSystem heat(h, sys);
    FieldSeriesWriter fields(dir, 0);
    fields.write(sys, heat, {});

    vtkNew<vtkXMLUnstructuredGridReader> fr;
    fr->SetFileName((dir / "fields/fields_000000.vtu").string().c_str());
    fr->Update();
    double b[6];
    fr->GetOutput()->GetBounds(b);
    // The long axis lies along world y: extents 6 mm in y and 2 mm in x and z, up to the cubes
    // drawn about the surface nodes (half a cell, 0.25 mm, on each side).
    constexpr double cell_slack = 0.6e-3; // m
    EXPECT_NEAR(b[3] - b[2], 6e-3, cell_slack);
    EXPECT_NEAR(b[1] - b[0], 2e-3, cell_slack);
    EXPECT_NEAR(b[5] - b[4], 2e-3, cell_slack);
    EXPECT_NEAR(0.5 * (b[0] + b[1]), 0.01, 1e-9); // centred on the body, world position
    std::filesystem::remove_all(dir);
}

} // namespace
} // namespace kiln::io
