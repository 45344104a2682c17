#pragma once
// Body-fixed Cartesian cut-cell grid for any shape of shape.hpp. Cell faces are apertures (the part
// of each cell face inside the body), boundary cells carry the surface patch clipped from a fine
// triangulation, and cut-cell volumes follow from the divergence theorem; total area (that of the
// clipped triangulation) and volume converge at about second order in the cell size.

#include "heat/shape.hpp"
#include "heat/thermal_grid.hpp"

namespace kiln::heat {

/// Resolution and construction parameters of a Cartesian grid.
struct CartesianResolution {
    int cells_across = 10;            ///< cells across the largest bounding-box extent (-)
    int aperture_samples = 8;         ///< sub-squares per cell-face edge for apertures (-)
    double mesh_edge_fraction = 0.25; ///< surface-triangle edge / cell size (-)
    double merge_fraction = 0.5;      ///< cut cells below this volume fraction join a neighbour (-)
};

/// Cell size (m) of `res` for `shape`: the largest bounding-box extent / cells_across.
[[nodiscard]] double cartesian_cell_size(const Shape& shape, const CartesianResolution& res);

/// Builds the cut-cell grid of `shape`. Throws InputError for invalid shapes or resolutions.
[[nodiscard]] ThermalGrid make_cartesian_grid(const Shape& shape, const CartesianResolution& res);

} // namespace kiln::heat
