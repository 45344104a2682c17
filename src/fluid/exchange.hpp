#pragma once
// Exchange between particles and fluid cells through their footprints (footprints.hpp):
// solid volume and porosity per cell, conservative spreading of per-particle sources, and the
// average of a fluid field over each particle's sub-cells. Sums over a cell run in increasing
// particle order, so results are the same bits for any thread count.

#include "core/types.hpp"
#include "fluid/footprints.hpp"
#include "fluid/transfer_grid.hpp"

#include <span>
#include <vector>

namespace kiln::fluid {

/// Solid volume per fluid cell (m^3): sub-cell volume times the sub-cells of every particle in the
/// cell, plus the true volume of particles too small for the sub-grid. `out` has one value per
/// cell and is overwritten.
void solid_volume(const Footprints& f, std::span<double> out, int threads = 1);

/// Porosity per fluid cell (-): 1 - solid volume / cell volume. Not clipped: overlapping particles
/// can push it below 0, and the caller decides on a floor.
[[nodiscard]] std::vector<double> porosity(const TransferGrid& g, const Footprints& f,
                                           int threads = 1);

/// Spreads one scalar source per particle (e.g. a heat rate, W) over its sub-cells: cell c gets
/// the sum over particles of value * (share of the particle's sub-cells in c). The cell values
/// sum to the particle values to round-off (except particles placed `outside`). `out` (one
/// value per cell) is overwritten.
void spread(const Footprints& f, std::span<const double> value, std::span<double> out,
            int threads = 1);

/// Spreads one vector source per particle (e.g. the drag reaction on the gas, N, world frame),
/// as the scalar overload.
void spread(const Footprints& f, std::span<const Vec3> value, std::span<Vec3> out, int threads = 1);

/// Average of a cell-centred scalar field over each particle's sub-cells, the field taken as the
/// trilinear interpolant of the cell centres (constant beyond the outermost centres). A linear
/// field gives its value at the particle's sub-cell centroid. `out` has one value per particle.
void interpolate(const Footprints& f, std::span<const double> field, std::span<double> out,
                 int threads = 1);

/// Average of a cell-centred vector field (e.g. gas velocity, m/s, world frame) over each
/// particle's sub-cells, as the scalar overload.
void interpolate(const Footprints& f, std::span<const Vec3> field, std::span<Vec3> out,
                 int threads = 1);

} // namespace kiln::fluid
