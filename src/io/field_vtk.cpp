#include "io/field_vtk.hpp"

#include "core/error.hpp"
#include "io/files.hpp"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkTypeInt64Array.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <array>
#include <cmath>
#include <fmt/format.h>
#include <numbers>

namespace kiln::io {

namespace {

/// Point at radius r, polar angle t, azimuth p (m, body frame).
Vec3 polar_point(double r, double t, double p) {
    return {r * std::sin(t) * std::cos(p), r * std::sin(t) * std::sin(p), r * std::cos(t)};
}

/// The eight corners of cell c of a spherical grid of resolution `res` whose outer radius is
/// `radius` (m, body frame), in VTK hexahedron order.
std::array<Vec3, 8> spherical_corners(const heat::SphericalResolution& res, double radius, int c) {
    const double dr = radius / (res.n_r + 0.5);
    std::array<Vec3, 8> x;
    if (c == 0) {
        const double h = dr / (2.0 * std::sqrt(3.0));
        for (int k = 0; k < 8; ++k) {
            const double sx = ((k + 1) / 2) % 2 == 1 ? h : -h; // 0,1,1,0 pattern
            const double sy = (k % 4) >= 2 ? h : -h;
            const double sz = k >= 4 ? h : -h;
            x[static_cast<std::size_t>(k)] = Vec3(sx, sy, sz);
        }
        return x;
    }
    const int m = c - 1;
    const int band = res.n_theta * res.n_phi;
    const int i = 1 + m / band;
    const int j = (m % band) / res.n_phi;
    const int k = m % res.n_phi;
    const double r0 = dr / 2.0 + (i - 1) * dr;
    const double r1 = i == res.n_r ? radius : r0 + dr;
    const double dt = std::numbers::pi / res.n_theta;
    const double dp = 2.0 * std::numbers::pi / res.n_phi;
    const double t0 = j * dt;
    const double t1 = t0 + dt;
    const double p0 = k * dp;
    const double p1 = p0 + dp;
    x = {polar_point(r0, t0, p0), polar_point(r1, t0, p0), polar_point(r1, t1, p0),
         polar_point(r0, t1, p0), polar_point(r0, t0, p1), polar_point(r1, t0, p1),
         polar_point(r1, t1, p1), polar_point(r0, t1, p1)};
    return x;
}

/// Radius (m) of a spherical grid: the farthest boundary-patch centroid lies on the surface.
double grid_radius(const heat::ThermalGrid& g) {
    double r = 0.0;
    for (const auto& b : g.boundary) {
        r = std::max(r, b.centroid.norm());
    }
    return r;
}

} // namespace

FieldSeriesWriter::FieldSeriesWriter(std::filesystem::path out_dir, std::size_t first_index)
    : dir_(std::move(out_dir)), next_(first_index) {
    make_directory(dir_ / "fields");
}

void FieldSeriesWriter::write(const dynamics::System& sys, const thermal::ThermalSystem& heat,
                              const std::vector<long>& ids) {
    const std::vector<thermal::FieldView> views = heat.fields(sys, ids);
    vtkNew<vtkPoints> pts;
    pts->SetDataTypeToDouble();
    vtkNew<vtkUnstructuredGrid> ug;
    vtkNew<vtkDoubleArray> temp;
    temp->SetName("temperature");
    vtkNew<vtkTypeInt64Array> pid;
    pid->SetName("id");
    ug->Allocate();
    for (const thermal::FieldView& v : views) {
        const heat::ThermalGrid& g = *v.grid;
        const double radius = v.spherical != nullptr ? grid_radius(g) : 0.0;
        for (int c = 0; c < g.size(); ++c) {
            std::array<Vec3, 8> x;
            if (v.spherical != nullptr) {
                x = spherical_corners(*v.spherical, radius, c);
            } else {
                const double h = 0.5 * std::cbrt(g.volume[static_cast<std::size_t>(c)]);
                const Vec3& o = g.node[static_cast<std::size_t>(c)];
                x = {o + Vec3(-h, -h, -h), o + Vec3(h, -h, -h), o + Vec3(h, h, -h),
                     o + Vec3(-h, h, -h),  o + Vec3(-h, -h, h), o + Vec3(h, -h, h),
                     o + Vec3(h, h, h),    o + Vec3(-h, h, h)};
            }
            std::array<vtkIdType, 8> ids8{};
            for (std::size_t q = 0; q < 8; ++q) {
                const Vec3 w = v.position + v.q * x[q]; // body -> world
                ids8[q] = pts->InsertNextPoint(w.data());
            }
            ug->InsertNextCell(VTK_HEXAHEDRON, 8, ids8.data());
            temp->InsertNextValue(v.field[static_cast<std::size_t>(c)]);
            pid->InsertNextValue(v.id);
        }
    }
    ug->SetPoints(pts);
    ug->GetCellData()->AddArray(temp);
    ug->GetCellData()->AddArray(pid);
    const std::string name = fmt::format("fields/fields_{:06d}.vtu", next_++);
    vtkNew<vtkXMLUnstructuredGridWriter> w;
    w->SetFileName((dir_ / name).string().c_str());
    w->SetInputData(ug);
    w->SetDataModeToAppended();
    w->EncodeAppendedDataOff();
    w->SetCompressorTypeToZLib();
    w->SetCompressionLevel(1); // the fastest, as vtk_writer.cpp's files (see there)
    w->SetHeaderTypeToUInt64();
    if (w->Write() != 1) {
        throw InputError((dir_ / name).string(), 0, "", "cannot write the VTK field file");
    }
    frames_.emplace_back(sys.time(), name);
    std::string pvd = "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n"
                      "  <Collection>\n";
    for (const auto& [t, file] : frames_) {
        pvd += fmt::format("    <DataSet timestep=\"{}\" file=\"{}\"/>\n", t, file);
    }
    pvd += "  </Collection>\n</VTKFile>\n";
    write_text_file(dir_ / "fields.pvd", pvd);
}

} // namespace kiln::io
