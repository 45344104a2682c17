// VTK PolyData writer of shape surfaces; see shape_vtk.hpp.

#include "io/shape_vtk.hpp"

#include "core/error.hpp"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkXMLPolyDataWriter.h>

namespace kiln::io {

void write_surface_vtp(const std::filesystem::path& file,
                       const std::vector<geometry::SurfaceMesh>& meshes) {
    vtkNew<vtkPoints> points;
    points->SetDataTypeToDouble();
    vtkNew<vtkCellArray> cells;
    vtkNew<vtkIntArray> part;
    part->SetName("part");
    vtkIdType offset = 0;
    for (std::size_t k = 0; k < meshes.size(); ++k) {
        for (const Vec3& v : meshes[k].vertices) {
            points->InsertNextPoint(v.x(), v.y(), v.z());
        }
        for (const auto& t : meshes[k].triangles) {
            const vtkIdType ids[3] = {offset + t[0], offset + t[1], offset + t[2]};
            cells->InsertNextCell(3, ids);
            part->InsertNextValue(static_cast<int>(k));
        }
        offset += static_cast<vtkIdType>(meshes[k].vertices.size());
    }
    vtkNew<vtkPolyData> poly;
    poly->SetPoints(points);
    poly->SetPolys(cells);
    poly->GetCellData()->AddArray(part);
    vtkNew<vtkXMLPolyDataWriter> writer;
    writer->SetFileName(file.string().c_str());
    writer->SetInputData(poly);
    writer->SetDataModeToAppended();
    if (writer->Write() != 1) {
        throw InputError(file.string(), 0, "", "cannot write the surface file");
    }
}

} // namespace kiln::io
