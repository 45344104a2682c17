#pragma once
// Intra-particle temperature fields as VTK unstructured grids ParaView can cut (Slice, Clip): every
// cell of every selected resolved particle as a hexahedron in world position, with cell data
// "temperature" (K) and "id" (particle id). Spherical-grid cells are drawn with their true corners
// (centre cell: the cube inscribed in its ball); Cartesian cut cells as cubes of the cell's volume
// about its node (exact for full cells, an approximation at the surface).

#include "dynamics/system.hpp"
#include "thermal/thermal_system.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace kiln::io {

/// Writes out_dir/fields/fields_NNNNNN.vtu and keeps out_dir/fields.pvd listing the frames.
class FieldSeriesWriter {
  public:
    /// Creates out_dir/fields/; frames are numbered from `first_index` (e.g. the particle frames
    /// kept after a restart). Throws InputError when the folder cannot be made.
    FieldSeriesWriter(std::filesystem::path out_dir, std::size_t first_index);

    /// Writes the fields of particles `ids` (all resolved particles when empty) at the current
    /// time (m, world frame: a body's cells turned by its orientation q, spheres with body axes =
    /// world axes). Throws InputError on write errors.
    void write(const dynamics::System& sys, const thermal::ThermalSystem& heat,
               const std::vector<long>& ids);

  private:
    std::filesystem::path dir_;
    std::size_t next_;
    std::vector<std::pair<double, std::string>> frames_;
};

} // namespace kiln::io
