#include "io/vtk_writer.hpp"

#include "core/error.hpp"
#include "geometry/mesh_wall.hpp"
#include "io/files.hpp"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkIdTypeArray.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>
#include <vtkTypeInt64Array.h>
#include <vtkXMLPolyDataWriter.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <fmt/format.h>
#include <fstream>
#include <limits>
#include <numbers>
#include <system_error>
#include <utility>
#include <variant>

namespace kiln::io {

namespace {

/// Facets of a tessellated cylinder wall (-).
constexpr int cylinder_segments = 48;
/// Growth of the particle region used to size wall drawings (-): 20 % larger edge lengths.
constexpr double region_growth = 1.2;
/// Edge length of the region drawn when the scene has neither particles nor insert blocks (m).
constexpr double default_region_size = 1.0;

/// Writes `pd` to `file` as appended raw binary, zlib-compressed VTK XML polydata. Level 1, the
/// fastest: the arrays are doubles, whose mantissas deflate barely shrinks at any level (the
/// showcase cut to 0.4 s writes 77.3 MB at VTK's default level, 78.6 MB at level 1), and the
/// default level's compression was 12 % of the showcase's run time (docs/performance.md,
/// "Session 23").
void write_polydata(vtkPolyData* pd, const std::filesystem::path& file) {
    vtkNew<vtkXMLPolyDataWriter> w;
    w->SetFileName(file.string().c_str());
    w->SetInputData(pd);
    w->SetDataModeToAppended();
    w->EncodeAppendedDataOff();
    w->SetCompressorTypeToZLib();
    w->SetCompressionLevel(1);
    w->SetHeaderTypeToUInt64();
    if (w->Write() != 1) {
        throw InputError(file.string(), 0, "", "cannot write the VTK file");
    }
}

/// Adds a 3-component double point array `name` holding `v` (world frame).
void add_vec3_array(vtkPointData* pd, const char* name, const std::vector<Vec3>& v) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(name);
    a->SetNumberOfComponents(3);
    a->SetNumberOfTuples(static_cast<vtkIdType>(v.size()));
    for (std::size_t i = 0; i < v.size(); ++i) {
        a->SetTypedTuple(static_cast<vtkIdType>(i), v[i].data());
    }
    pd->AddArray(a);
}

/// The region holding the scene's particles and insert blocks, enlarged by 20 % about its centre
/// (m, world); a 1 m cube about the origin when there is nothing to bound.
Aabb drawing_region(const dynamics::SceneSpec& scene) {
    bool any = false;
    Aabb box;
    const auto grow = [&](const Vec3& lo, const Vec3& hi) {
        box.lo = any ? Vec3(box.lo.cwiseMin(lo)) : lo;
        box.hi = any ? Vec3(box.hi.cwiseMax(hi)) : hi;
        any = true;
    };
    for (const auto& ins : scene.inserts) {
        grow(ins.region.lo, ins.region.hi);
    }
    for (const auto& p : scene.particles) {
        grow(p.x - Vec3::Constant(p.radius), p.x + Vec3::Constant(p.radius));
    }
    if (!any) {
        const Vec3 half = Vec3::Constant(0.5 * default_region_size);
        return {-half, half};
    }
    const Vec3 centre = 0.5 * (box.lo + box.hi);
    const Vec3 half = 0.5 * region_growth * box.extent();
    return {centre - half, centre + half};
}

/// The eight corners of `box` (m, world).
std::array<Vec3, 8> corners(const Aabb& box) {
    std::array<Vec3, 8> c;
    for (std::size_t k = 0; k < 8; ++k) {
        const Vec3& x = (k & 1U) != 0 ? box.hi : box.lo;
        const Vec3& y = (k & 2U) != 0 ? box.hi : box.lo;
        const Vec3& z = (k & 4U) != 0 ? box.hi : box.lo;
        c[k] = Vec3(x.x(), y.y(), z.z());
    }
    return c;
}

/// Unit vectors u, v spanning the plane normal to the unit vector n, with u x v = n (world).
void plane_basis(const Vec3& n, Vec3& u, Vec3& v) {
    Eigen::Index k = 0;
    n.cwiseAbs().minCoeff(&k);
    u = n.cross(Vec3::Unit(k)).normalized();
    v = n.cross(u);
}

/// Appends the points of a rectangle on plane `w` covering the projection of `region`, and one quad
/// cell ordered counter-clockwise seen from the side the normal points to.
void add_plane(const dynamics::PlaneWall& w, const Aabb& region, vtkPoints* pts,
               vtkCellArray* cells) {
    const Vec3 n = w.normal.normalized();
    Vec3 u;
    Vec3 v;
    plane_basis(n, u, v);
    const Vec3 centre = 0.5 * (region.lo + region.hi);
    // The rectangle is centred on the region centre projected on the plane, not on w.point, so
    // that it lies under the particles wherever the plane's reference point is.
    const Vec3 origin = centre - (centre - w.point).dot(n) * n;
    double u_lo = 0;
    double u_hi = 0;
    double v_lo = 0;
    double v_hi = 0;
    for (const Vec3& c : corners(region)) {
        u_lo = std::min(u_lo, (c - origin).dot(u));
        u_hi = std::max(u_hi, (c - origin).dot(u));
        v_lo = std::min(v_lo, (c - origin).dot(v));
        v_hi = std::max(v_hi, (c - origin).dot(v));
    }
    const std::array<Vec3, 4> quad = {origin + u_lo * u + v_lo * v, origin + u_hi * u + v_lo * v,
                                      origin + u_hi * u + v_hi * v, origin + u_lo * u + v_hi * v};
    std::array<vtkIdType, 4> ids{};
    for (std::size_t k = 0; k < 4; ++k) {
        ids[k] = pts->InsertNextPoint(quad[k].data());
    }
    cells->InsertNextCell(4, ids.data());
}

/// Appends an open tube of `cylinder_segments` quads for cylinder `w`, spanning the projection of
/// `region` on the axis; quads face the axis (the side particles live on). Returns the cell count.
int add_cylinder(const dynamics::CylinderWall& w, const Aabb& region, vtkPoints* pts,
                 vtkCellArray* cells) {
    const Vec3 a = w.axis.normalized();
    Vec3 u;
    Vec3 v;
    plane_basis(a, u, v);
    double t_lo = std::numeric_limits<double>::infinity();
    double t_hi = -t_lo;
    for (const Vec3& c : corners(region)) {
        t_lo = std::min(t_lo, (c - w.axis_point).dot(a));
        t_hi = std::max(t_hi, (c - w.axis_point).dot(a));
    }
    const Vec3 bottom = w.axis_point + t_lo * a;
    const Vec3 top = w.axis_point + t_hi * a;
    const vtkIdType first = pts->GetNumberOfPoints();
    for (int k = 0; k < cylinder_segments; ++k) {
        const double phi = 2.0 * std::numbers::pi * k / cylinder_segments;
        const Vec3 r = w.radius * (std::cos(phi) * u + std::sin(phi) * v);
        pts->InsertNextPoint(Vec3(bottom + r).data());
        pts->InsertNextPoint(Vec3(top + r).data());
    }
    for (vtkIdType k = 0; k < cylinder_segments; ++k) {
        const vtkIdType b0 = first + 2 * k;
        const vtkIdType b1 = first + 2 * ((k + 1) % cylinder_segments);
        const std::array<vtkIdType, 4> ids = {b0, b0 + 1, b1 + 1, b1};
        cells->InsertNextCell(4, ids.data());
    }
    return cylinder_segments;
}

} // namespace

ParticleSeriesWriter::ParticleSeriesWriter(std::filesystem::path out_dir)
    : dir_(std::move(out_dir)) {
    make_directory(dir_ / "particles");
}

void ParticleSeriesWriter::write(const dynamics::System& sys) {
    const ParticleStore& p = sys.particles();
    const auto n = static_cast<vtkIdType>(p.size());

    vtkNew<vtkPoints> pts;
    pts->SetDataTypeToDouble();
    pts->SetNumberOfPoints(n);
    vtkNew<vtkIdTypeArray> connectivity;
    connectivity->SetNumberOfTuples(n);
    vtkNew<vtkTypeInt64Array> id;
    id->SetName("id");
    id->SetNumberOfTuples(n);
    vtkNew<vtkIntArray> material;
    material->SetName("material");
    material->SetNumberOfTuples(n);
    vtkNew<vtkDoubleArray> radius;
    radius->SetName("radius");
    radius->SetNumberOfTuples(n);
    for (std::size_t i = 0; i < p.size(); ++i) {
        const auto k = static_cast<vtkIdType>(i);
        pts->SetPoint(k, p.x[i].data());
        connectivity->SetValue(k, k);
        id->SetValue(k, p.id[i]);
        material->SetValue(k, p.material[i]);
        radius->SetValue(k, p.radius[i]);
    }
    vtkNew<vtkCellArray> verts;
    verts->SetData(1, connectivity);

    vtkNew<vtkPolyData> pd;
    pd->SetPoints(pts);
    pd->SetVerts(verts);
    vtkPointData* data = pd->GetPointData();
    data->AddArray(id);
    data->AddArray(material);
    data->AddArray(radius);
    add_vec3_array(data, "velocity", p.v);
    add_vec3_array(data, "angular_velocity", p.omega);
    add_vec3_array(data, "force", p.force);
    if (heat_ != nullptr) {
        thermal::ParticleTemperatures t;
        heat_->particle_temperatures(sys, t);
        const std::pair<const char*, const std::vector<double>*> arrays[] = {
            {"temperature_mean", &t.mean},
            {"temperature_core", &t.core},
            {"temperature_surface", &t.surface}};
        for (const auto& [label, values] : arrays) {
            vtkNew<vtkDoubleArray> a;
            a->SetName(label);
            a->SetNumberOfTuples(n);
            for (vtkIdType k = 0; k < n; ++k) {
                a->SetValue(k, (*values)[static_cast<std::size_t>(k)]);
            }
            data->AddArray(a);
        }
    }

    if (sys.has_bodies()) {
        vtkNew<vtkDoubleArray> orientation;
        orientation->SetName("orientation");
        orientation->SetNumberOfComponents(4);
        orientation->SetNumberOfTuples(n);
        for (std::size_t i = 0; i < p.size(); ++i) {
            const Quat& q = p.q[i];
            const double wxyz[4] = {q.w(), q.x(), q.y(), q.z()};
            orientation->SetTypedTuple(static_cast<vtkIdType>(i), wxyz);
        }
        data->AddArray(orientation);
        vtkNew<vtkIntArray> shape;
        shape->SetName("shape");
        shape->SetNumberOfTuples(n);
        for (std::size_t i = 0; i < p.size(); ++i) {
            shape->SetValue(static_cast<vtkIdType>(i), p.shape[i]);
        }
        data->AddArray(shape);
    }

    const std::string name = fmt::format("particles/particles_{:06d}.vtp", frames_.size());
    write_polydata(pd, dir_ / name);
    frames_.push_back({sys.time(), name});
    write_collection(frames_, "particles.pvd");
    if (sys.has_bodies()) {
        write_bodies(sys);
    }
}

void ParticleSeriesWriter::write_bodies(const dynamics::System& sys) {
    const ParticleStore& p = sys.particles();
    vtkNew<vtkPoints> pts;
    pts->SetDataTypeToDouble();
    vtkNew<vtkCellArray> cells;
    vtkNew<vtkTypeInt64Array> id;
    id->SetName("id");
    vtkNew<vtkDoubleArray> velocity;
    velocity->SetName("velocity");
    velocity->SetNumberOfComponents(3);
    for (std::size_t i = 0; i < p.size(); ++i) {
        if (p.shape[i] < 0) {
            continue;
        }
        auto it = meshes_.find(p.shape[i]);
        if (it == meshes_.end()) {
            const auto& t = sys.spec().shapes.at(static_cast<std::size_t>(p.shape[i]));
            it = meshes_.emplace(p.shape[i], geometry::surface_mesh(t.shape, 12)).first;
        }
        const geometry::SurfaceMesh m = geometry::posed(it->second, p.x[i], p.q[i]);
        const vtkIdType first = pts->GetNumberOfPoints();
        for (const Vec3& v : m.vertices) {
            pts->InsertNextPoint(v.data());
        }
        for (const auto& t : m.triangles) {
            const vtkIdType ids[3] = {first + t[0], first + t[1], first + t[2]};
            cells->InsertNextCell(3, ids);
            id->InsertNextValue(p.id[i]);
            velocity->InsertNextTuple(p.v[i].data());
        }
    }
    vtkNew<vtkPolyData> pd;
    pd->SetPoints(pts);
    pd->SetPolys(cells);
    pd->GetCellData()->AddArray(id);
    pd->GetCellData()->AddArray(velocity);
    make_directory(dir_ / "bodies");
    const std::string name = fmt::format("bodies/bodies_{:06d}.vtp", body_frames_.size());
    write_polydata(pd, dir_ / name);
    body_frames_.push_back({sys.time(), name});
    write_collection(body_frames_, "bodies.pvd");
}

std::size_t ParticleSeriesWriter::resume(double time) {
    resume_collection(time, "bodies.pvd", body_frames_);
    return resume_collection(time, "particles.pvd", frames_);
}

std::size_t ParticleSeriesWriter::resume_collection(double time, const std::string& pvd,
                                                    std::vector<Frame>& frames) {
    frames.clear();
    const std::filesystem::path file = dir_ / pvd;
    if (!std::filesystem::exists(file)) {
        return 0;
    }
    std::ifstream in(file);
    if (!in) {
        throw InputError(file.string(), 0, "", "cannot read the series to continue it");
    }
    // The collection was written by write_collection(): one DataSet element per line.
    const double time_limit = time * (1.0 + 1e-12) + 1e-300;
    std::string line;
    int line_no = 0;
    while (std::getline(in, line)) {
        ++line_no;
        const auto t = line.find("timestep=\"");
        const auto f = line.find("file=\"");
        if (t == std::string::npos || f == std::string::npos) {
            continue;
        }
        const double frame_time = std::strtod(line.c_str() + t + 10, nullptr);
        const auto end = line.find('"', f + 6);
        if (end == std::string::npos) {
            throw InputError(file.string(), line_no, "", "malformed DataSet element");
        }
        Frame frame{frame_time, line.substr(f + 6, end - f - 6)};
        if (frame.time <= time_limit) {
            frames.push_back(std::move(frame));
        } else {
            std::error_code ec; // a frame file already gone is not an error
            std::filesystem::remove(dir_ / frame.file, ec);
        }
    }
    write_collection(frames, pvd);
    return frames.size();
}

void ParticleSeriesWriter::write_collection(const std::vector<Frame>& frames,
                                            const std::string& pvd) const {
    constexpr const char* byte_order =
        std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian";
    std::string xml = fmt::format("<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" "
                                  "version=\"0.1\" byte_order=\"{}\">\n  <Collection>\n",
                                  byte_order);
    for (const Frame& f : frames) {
        xml += fmt::format("    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>\n",
                           f.time, f.file);
    }
    xml += "  </Collection>\n</VTKFile>\n";

    const std::filesystem::path file = dir_ / pvd;
    const std::filesystem::path tmp = dir_ / (pvd + ".tmp");
    write_text_file(tmp, xml);
    std::error_code ec;
    std::filesystem::rename(tmp, file, ec);
    if (ec) {
        throw InputError(file.string(), 0, "", "cannot replace the file: " + ec.message());
    }
}

void ParticleSeriesWriter::write_walls(const dynamics::SceneSpec& scene,
                                       const std::filesystem::path& file) const {
    const Aabb region = drawing_region(scene);
    vtkNew<vtkPoints> pts;
    pts->SetDataTypeToDouble();
    vtkNew<vtkCellArray> polys;
    vtkNew<vtkIntArray> wall_index;
    wall_index->SetName("wall");
    vtkNew<vtkStringArray> names;
    names->SetName("wall_name");
    for (std::size_t k = 0; k < scene.walls.size(); ++k) {
        const dynamics::Wall& w = scene.walls[k];
        int n_cells = 0;
        if (const auto* plane = std::get_if<dynamics::PlaneWall>(&w.shape)) {
            add_plane(*plane, region, pts, polys);
            n_cells = 1;
        } else if (const auto* cyl = std::get_if<dynamics::CylinderWall>(&w.shape)) {
            n_cells = add_cylinder(*cyl, region, pts, polys);
        }
        for (int c = 0; c < n_cells; ++c) {
            wall_index->InsertNextValue(static_cast<int>(k));
        }
        names->InsertNextValue(w.name);
    }
    // Mesh walls: their own triangles, wall index walls.size() + mesh index (the contact records'
    // numbering).
    for (std::size_t m = 0; m < scene.mesh_walls.size(); ++m) {
        const dynamics::MeshWallSpec& mw = scene.mesh_walls[m];
        const vtkIdType base = pts->GetNumberOfPoints();
        for (const Vec3& v : mw.mesh->vertices()) {
            pts->InsertNextPoint(v.x(), v.y(), v.z());
        }
        for (const auto& t : mw.mesh->triangles()) {
            const vtkIdType ids[3] = {base + t[0], base + t[1], base + t[2]};
            polys->InsertNextCell(3, ids);
            wall_index->InsertNextValue(static_cast<int>(scene.walls.size() + m));
        }
        names->InsertNextValue(mw.name);
    }
    vtkNew<vtkPolyData> pd;
    pd->SetPoints(pts);
    pd->SetPolys(polys);
    pd->GetCellData()->AddArray(wall_index);
    pd->GetFieldData()->AddArray(names);
    write_polydata(pd, file);
}

} // namespace kiln::io
