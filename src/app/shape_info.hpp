#pragma once
// `kiln info SHAPE`: mass properties and shape factors of a template.

#include <string>

namespace kiln::app {

/// Prints volume, mass, centre of mass, principal inertia, surface area, equivalent diameters,
/// sphericity and crosswise sphericity of the template `shape` (name or .toml path) for a material
/// density (kg/m^3); writes the template's surface mesh to `vtk_file` (.vtp) unless empty.
/// Returns the process exit code; input problems throw kiln::InputError.
int print_shape_info(const std::string& shape, double density, const std::string& vtk_file);

} // namespace kiln::app
