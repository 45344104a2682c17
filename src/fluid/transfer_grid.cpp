#include "fluid/transfer_grid.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fmt/format.h>
#include <limits>

namespace kiln::fluid {

TransferGrid::TransferGrid(const Vec3& origin, const std::array<int, 3>& cells, double cell_size,
                           int refinement)
    : origin_(origin), cells_(cells), cell_size_(cell_size), refinement_(refinement),
      sub_size_(cell_size / refinement) {
    if (!origin.allFinite()) {
        throw InputError("transfer grid: origin must be finite");
    }
    if (cells[0] < 1 || cells[1] < 1 || cells[2] < 1) {
        throw InputError(fmt::format("transfer grid: cell counts must be >= 1 along every axis, "
                                     "got ({}, {}, {})",
                                     cells[0], cells[1], cells[2]));
    }
    if (!(cell_size > 0.0) || !std::isfinite(cell_size)) {
        throw InputError(fmt::format(
            "transfer grid: cell size must be positive and finite (m), got {}", cell_size));
    }
    if (refinement < 1) {
        throw InputError(fmt::format(
            "transfer grid: refinement s (sub-cells per cell edge) must be >= 1, got {}",
            refinement));
    }
    // Flat cell indices and sub-cell indices along an axis are 32-bit.
    constexpr auto kMax = static_cast<double>(std::numeric_limits<std::int32_t>::max());
    const double n = static_cast<double>(cells[0]) * cells[1] * cells[2];
    const int largest = std::max({cells[0], cells[1], cells[2]});
    if (n > kMax || static_cast<double>(largest) * refinement > kMax) {
        throw InputError(fmt::format("transfer grid: {} x {} x {} cells with s = {} exceed the "
                                     "32-bit index range (at most {} cells, {} sub-cells per axis)",
                                     cells[0], cells[1], cells[2], refinement, kMax, kMax));
    }
}

} // namespace kiln::fluid
