// Polyhedron templates from .obj and .stl: ASCII and binary STL give the same solid as OBJ,
// non-convex input is replaced by its hull with a warning, degenerate files are refused by name.

#include "common/cube_template.hpp"
#include "core/error.hpp"
#include "io/mesh_reader.hpp"
#include "io/shape_reader.hpp"

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <gtest/gtest.h>

namespace io = kiln::io;
namespace g = kiln::geometry;
namespace fs = std::filesystem;
using kiln::Vec3;

namespace {

constexpr double kExact = 1e-12; // relative: float STL coordinates of 1, 2, 3 are exact

/// A fresh scratch folder for one test.
fs::path scratch(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("kiln_test_mesh_" + name);
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

void write_text(const fs::path& f, const std::string& text) {
    std::ofstream(f) << text;
}

/// Box [0,1]x[0,2]x[0,3] as 12 outward triangles: the test cube [-1, 1]^3 moved and stretched
/// (its corners land exactly on 0, 1, 2 and 3).
std::vector<std::array<Vec3, 3>> box_triangles() {
    const kiln::test::TriangleMesh m = kiln::test::cube_mesh(1.0);
    const auto c = [&](int i) {
        return ((m.vertices[static_cast<std::size_t>(i)] + Vec3::Ones()) / 2)
            .cwiseProduct(Vec3(1.0, 2.0, 3.0))
            .eval();
    };
    std::vector<std::array<Vec3, 3>> t;
    for (const auto& f : m.triangles) {
        t.push_back({c(f[0]), c(f[1]), c(f[2])});
    }
    return t;
}

std::string ascii_stl(const std::vector<std::array<Vec3, 3>>& tris) {
    std::string s = "solid box\n";
    for (const auto& t : tris) {
        s += " facet normal 0 0 0\n  outer loop\n";
        for (const Vec3& v : t) {
            s += fmt::format("   vertex {} {} {}\n", v.x(), v.y(), v.z());
        }
        s += "  endloop\n endfacet\n";
    }
    return s + "endsolid box\n";
}

void write_binary_stl(const fs::path& f, const std::vector<std::array<Vec3, 3>>& tris) {
    std::ofstream out(f, std::ios::binary);
    const std::string header(80, ' ');
    out.write(header.data(), 80);
    const auto n = static_cast<std::uint32_t>(tris.size());
    out.write(reinterpret_cast<const char*>(&n), 4);
    for (const auto& t : tris) {
        float rec[12] = {};
        for (int k = 0; k < 3; ++k) {
            for (int q = 0; q < 3; ++q) {
                rec[3 + 3 * k + q] = static_cast<float>(t[static_cast<std::size_t>(k)][q]);
            }
        }
        out.write(reinterpret_cast<const char*>(rec), 48);
        const std::uint16_t attr = 0;
        out.write(reinterpret_cast<const char*>(&attr), 2);
    }
}

std::string toml_for(const std::string& mesh) {
    return fmt::format("kind = \"polyhedron\"\nmesh = \"{}\"\nscale = 1e-3\n", mesh);
}

} // namespace

TEST(MeshReader, AsciiAndBinaryStlGiveTheBox) {
    const fs::path d = scratch("stl");
    const auto tris = box_triangles();
    write_text(d / "ascii.stl", ascii_stl(tris));
    write_binary_stl(d / "binary.stl", tris);
    for (const char* mesh : {"ascii.stl", "binary.stl"}) {
        const fs::path toml = d / (std::string(mesh) + ".toml");
        write_text(toml, toml_for(mesh));
        const g::ShapeTemplate t = io::read_shape_file(toml);
        const double v = 6e-9;
        EXPECT_NEAR(t.volume, v, kExact * v) << mesh;
        // Box 1 x 2 x 3 mm: moments V/12 (b^2 + c^2) with the edge pairs (1,2), (1,3), (2,3) mm,
        // ascending.
        const double sq[3] = {1.0 + 4.0, 1.0 + 9.0, 4.0 + 9.0};
        for (int k = 0; k < 3; ++k) {
            const double m = v / 12.0 * sq[k] * 1e-6;
            EXPECT_NEAR(t.inertia_unit_density[k], m, kExact * m) << mesh << k;
        }
        EXPECT_TRUE(t.warnings.empty()) << mesh;
        EXPECT_EQ(std::get<g::ConvexPolyhedron>(t.shape).faces.size(), 12U);
    }
}

TEST(MeshReader, NonConvexObjIsReplacedByItsHullWithAWarning) {
    // An L-shaped prism: the unit square [0,2]^2 without its [1,2]^2 corner, extruded by 1.
    const fs::path d = scratch("nonconvex");
    const double xy[6][2] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
    std::string obj;
    for (int z = 0; z < 2; ++z) {
        for (const auto& p : xy) {
            obj += fmt::format("v {} {} {}\n", p[0], p[1], z);
        }
    }
    obj += "f 6 5 4 3 2 1\nf 7 8 9 10 11 12\n"; // bottom (seen from below), top
    for (int k = 0; k < 6; ++k) {
        const int a = k + 1;
        const int b = (k + 1) % 6 + 1;
        obj += fmt::format("f {} {} {} {}\n", a, b, b + 6, a + 6);
    }
    write_text(d / "l.obj", obj);
    write_text(d / "l.toml", toml_for("l.obj"));
    const g::ShapeTemplate t = io::read_shape_file(d / "l.toml");
    const double v_mesh = 3.0;
    const double v_hull = 3.5; // the hull cuts the notch with the plane x + y = 3
    EXPECT_NEAR(t.volume, v_hull * 1e-9, kExact * 1e-9);
    ASSERT_EQ(t.warnings.size(), 1U);
    EXPECT_NE(t.warnings[0].find("not convex"), std::string::npos) << t.warnings[0];
    EXPECT_NE(t.warnings[0].find(fmt::format("{:.6f}", v_mesh / v_hull)), std::string::npos)
        << t.warnings[0];
}

TEST(MeshReader, DegenerateFilesAreRefusedByName) {
    const fs::path d = scratch("degenerate");
    const auto message = [&](const std::string& mesh_name) {
        write_text(d / "t.toml", toml_for(mesh_name));
        try {
            (void)io::read_shape_file(d / "t.toml");
        } catch (const kiln::InputError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    // Flat: a square in the plane z = 0.
    write_text(d / "flat.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nf 4 3 2 1\n");
    std::string m = message("flat.obj");
    EXPECT_NE(m.find("flat.obj"), std::string::npos) << m;
    EXPECT_NE(m.find("coplanar"), std::string::npos) << m;
    // Three points.
    write_text(d / "three.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\n");
    m = message("three.obj");
    EXPECT_NE(m.find("at least 4 points"), std::string::npos) << m;
    // An STL box missing one triangle is not closed.
    auto tris = box_triangles();
    tris.pop_back();
    write_text(d / "open.stl", ascii_stl(tris));
    m = message("open.stl");
    EXPECT_NE(m.find("open.stl"), std::string::npos) << m;
    EXPECT_NE(m.find("not closed"), std::string::npos) << m;
    // Missing file and unknown format.
    EXPECT_NE(message("missing.obj").find("not found"), std::string::npos);
    write_text(d / "box.ply", "ply\n");
    EXPECT_NE(message("box.ply").find("allowed: .obj, .stl"), std::string::npos);
    // A face index beyond the vertices read so far.
    write_text(d / "index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 9\n");
    m = message("index.obj");
    EXPECT_NE(m.find("index.obj:5"), std::string::npos) << m;
}

TEST(MeshReader, ShippedPolyhedraLoadWithoutWarnings) {
    const auto dirs = io::default_shape_dirs();
    for (const char* name : {"cube", "cuboid_6x6x5", "plate_10x9x2", "pyramid", "icosahedron",
                             "cylinder_8", "cylinder_16"}) {
        const g::ShapeTemplate t = io::read_shape_file(io::find_shape_file(name, dirs));
        const auto& p = std::get<g::ConvexPolyhedron>(t.shape);
        EXPECT_GT(t.volume, 0.0) << name;
        EXPECT_TRUE(t.warnings.empty()) << name;
        // Euler: V - E + F = 2 for a closed convex surface.
        EXPECT_EQ(static_cast<long>(p.vertices.size()) - static_cast<long>(p.edges.size()) +
                      static_cast<long>(p.faces.size()),
                  2)
            << name;
    }
}
