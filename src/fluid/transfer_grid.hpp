#pragma once
// The transfer grid: a Cartesian fluid grid (world frame) with every fluid cell split into s^3
// equal sub-cells. Particles are deposited on the sub-cells (footprints.hpp) and the results are
// summed per fluid cell (exchange.hpp). See docs/theory/fluid.md.

#include "core/types.hpp"

#include <array>
#include <cstddef>
#include <cstdint>

namespace kiln::fluid {

/// Geometry of a uniform fluid grid with its sub-grid, world frame, SI units. Fluid cell (i, j, k)
/// spans origin + [i, i+1] x [j, j+1] x [k, k+1] times the cell size; its flat index is
/// i + nx (j + ny k). Sub-cell (a, b, c) along the three axes (0 <= a < nx s, ...) has its centre
/// at origin + (a + 1/2, b + 1/2, c + 1/2) h with h = cell size / s, and lies in fluid cell
/// (a / s, b / s, c / s).
class TransferGrid {
  public:
    /// Grid with lower corner `origin` (m, world), `cells` = (nx, ny, nz) fluid cells of edge
    /// `cell_size` (m) and `refinement` = s sub-cells per fluid-cell edge. Throws kiln::InputError
    /// when a count is below 1, the cell size is not positive and finite, s < 1, or the grid
    /// is too large for 32-bit cell and sub-cell indices.
    TransferGrid(const Vec3& origin, const std::array<int, 3>& cells, double cell_size,
                 int refinement);

    /// Lower corner of the grid (m, world frame).
    [[nodiscard]] const Vec3& origin() const { return origin_; }
    /// Fluid cell counts (nx, ny, nz).
    [[nodiscard]] const std::array<int, 3>& cells() const { return cells_; }
    /// Edge of a fluid cell (m).
    [[nodiscard]] double cell_size() const { return cell_size_; }
    /// Sub-cells per fluid-cell edge, s (-).
    [[nodiscard]] int refinement() const { return refinement_; }
    /// Edge of a sub-cell, h = cell size / s (m).
    [[nodiscard]] double sub_cell_size() const { return sub_size_; }
    /// Volume of a fluid cell (m^3).
    [[nodiscard]] double cell_volume() const { return cell_size_ * cell_size_ * cell_size_; }
    /// Volume of a sub-cell, h^3 (m^3).
    [[nodiscard]] double sub_cell_volume() const { return sub_size_ * sub_size_ * sub_size_; }
    /// Number of fluid cells nx ny nz.
    [[nodiscard]] std::size_t cell_count() const {
        return static_cast<std::size_t>(cells_[0]) * cells_[1] * cells_[2];
    }
    /// Flat index of fluid cell (i, j, k), each within its count.
    [[nodiscard]] std::int32_t cell_index(int i, int j, int k) const {
        return i + cells_[0] * (j + cells_[1] * k);
    }
    /// Centre of fluid cell (i, j, k) (m, world frame).
    [[nodiscard]] Vec3 cell_centre(int i, int j, int k) const {
        return origin_ + cell_size_ * Vec3(i + 0.5, j + 0.5, k + 0.5);
    }
    /// Box covered by the grid (m, world frame).
    [[nodiscard]] Aabb bounds() const {
        return {origin_, origin_ + cell_size_ * Vec3(cells_[0], cells_[1], cells_[2])};
    }

  private:
    Vec3 origin_;
    std::array<int, 3> cells_;
    double cell_size_;
    int refinement_;
    double sub_size_;
};

} // namespace kiln::fluid
