// Shape template files: the shipped templates load, and bad files are located input errors.

#include "core/error.hpp"
#include "io/shape_reader.hpp"
#include "io/shape_vtk.hpp"

#include <filesystem>
#include <gtest/gtest.h>
#include <numbers>
#include <vtkCellData.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkXMLPolyDataReader.h>

namespace io = kiln::io;
namespace g = kiln::geometry;

TEST(ShapeReader, EveryShippedTemplateLoads) {
    const auto dirs = io::default_shape_dirs();
    const g::ShapeRegistry reg = io::load_shape_folder(dirs.back());
    for (const char* name : {"cylinder_36", "cylinder_12", "cylinder_36_corrected", "sphere_7mm",
                             "ellipsoid_123", "superball", "near_cube", "cylinder_sq", "plate"}) {
        ASSERT_TRUE(reg.contains(name)) << name;
        const g::ShapeTemplate& t = reg.get(name);
        EXPECT_GT(t.volume, 0.0) << name;
        EXPECT_TRUE((t.inertia_unit_density.array() > 0.0).all()) << name;
    }
    EXPECT_THROW((void)reg.get("no_such_shape"), kiln::InputError);
}

TEST(ShapeReader, RingsBuildTheSeedLayout) {
    const g::ShapeTemplate t =
        io::read_shape_file(io::find_shape_file("cylinder_36", io::default_shape_dirs()));
    const auto& c = std::get<g::Clump>(t.shape);
    EXPECT_EQ(c.spheres.size(), 36U);
    // Every sphere lies inside the 6 x 6 mm cylinder (touching it), in the body frame whose x axis
    // is the cylinder axis (smallest moment).
    for (const auto& s : c.spheres) {
        EXPECT_LE(std::abs(s.centre.x()) + s.radius, 3e-3 + 1e-9);
        EXPECT_LE(std::hypot(s.centre.y(), s.centre.z()) + s.radius, 3e-3 + 1e-9);
    }
}

TEST(ShapeReader, DensityCorrectionMatchesTheReferenceMass) {
    const g::ShapeTemplate t =
        io::read_shape_file(io::find_shape_file("cylinder_36_corrected", io::default_shape_dirs()));
    const double cylinder = std::numbers::pi * 9e-6 * 6e-3;
    EXPECT_NEAR(t.mass(1380.0) / (1380.0 * cylinder), 1.0, 1e-12);
}

TEST(ShapeReader, ErrorsNameFileLineAndKey) {
    const auto message = [](const std::string& text) {
        try {
            (void)io::read_shape_text(text, "bad.toml");
        } catch (const kiln::InputError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_NE(message("kind = \"superquadric\"\nhalf_axes = [1e-3, 1e-3, 1e-3]\n"
                      "exponents = [2.5, 1.0]\n")
                  .find("bad.toml:3: exponents"),
              std::string::npos);
    EXPECT_NE(message("kind = \"sphere\"\nradius = 1e-3\ncolour = 2\n").find("bad.toml:3: colour"),
              std::string::npos);
    EXPECT_NE(message("kind = \"cube\"\n").find("allowed"), std::string::npos);
    EXPECT_NE(message("kind = \"clump\"\n").find("[[sphere]]"), std::string::npos);
    EXPECT_NE(message("kind = \"clump\"\ndensity_correction = true\n[[sphere]]\ncentre = [0,0,0]\n"
                      "radius = 1e-3\n")
                  .find("reference"),
              std::string::npos);
    EXPECT_NE(message("kind = \"clump\"\n[[sphere]]\ncentre = [0,0]\nradius = 1e-3\n")
                  .find("sphere[0].centre"),
              std::string::npos);
}

TEST(ShapeReader, SurfaceMeshOfPosedClumpsReadsBack) {
    const g::ShapeTemplate t =
        io::read_shape_file(io::find_shape_file("cylinder_12", io::default_shape_dirs()));
    const g::SurfaceMesh m = g::surface_mesh(t.shape, 6);
    const std::vector<g::SurfaceMesh> parts = {
        g::posed(m, kiln::Vec3::Zero(), kiln::Quat::Identity()),
        g::posed(m, kiln::Vec3(0.01, 0, 0),
                 kiln::Quat(Eigen::AngleAxisd(1.0, kiln::Vec3::UnitY())))};
    const auto file = std::filesystem::temp_directory_path() / "kiln_test_shape_mesh.vtp";
    io::write_surface_vtp(file, parts);
    vtkNew<vtkXMLPolyDataReader> reader;
    reader->SetFileName(file.string().c_str());
    reader->Update();
    vtkPolyData* poly = reader->GetOutput();
    EXPECT_EQ(poly->GetNumberOfPoints(), static_cast<vtkIdType>(2 * m.vertices.size()));
    EXPECT_EQ(poly->GetNumberOfCells(), static_cast<vtkIdType>(2 * m.triangles.size()));
    EXPECT_NE(poly->GetCellData()->GetArray("part"), nullptr);
    std::filesystem::remove(file);
}
