#pragma once
// Footprints of particles on the transfer grid: for every particle, the fluid cells its sub-cells
// fall in (with the solid volume and the share of its sub-cells in each), and the stencil that
// averages a cell-centred fluid field over its sub-cells. Computed once per coupling step, then
// used for the porosity, the sources and the interpolation back (exchange.hpp).
//
// Rules (docs/theory/fluid.md):
// - A particle's sub-cells are those whose centres lie inside it, found row by row along x over
//   the rows crossing its bounding sphere: spheres by their chord, polyhedra by clipping the row
//   against their face planes (the points of a row's ends within round-off are settled by the
//   inside test), clumps by the union of their members' chords, superquadrics by the body-frame
//   inside test at every sub-cell of the row's chord of the bounding sphere.
// - Only sub-cells inside the domain count. A particle reaching out of the domain deposits the
//   volume of its sub-cells inside it and spreads its sources over those (still conservative);
//   it is counted as `clipped`.
// - A particle containing no sub-cell centre (too small for the sub-grid) deposits its true
//   volume and its sources in the fluid cell holding its centre; counted as `too_small`. If its
//   centre is outside the domain as well it deposits nothing and is counted as `outside` (its
//   sources are lost: the only non-conservative case, reported so it is seen).

#include "core/types.hpp"
#include "fluid/deposit_body.hpp"
#include "fluid/transfer_grid.hpp"

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace kiln::fluid {

/// How a particle lies on the grid.
enum class Placement : std::uint8_t {
    inside,    ///< its world box lies in the domain and it holds at least one sub-cell centre
    clipped,   ///< its world box crosses the domain boundary; only sub-cells inside count
    too_small, ///< no sub-cell centre inside it: true volume in the cell holding its centre
    outside,   ///< no sub-cell and centre outside the domain: nothing deposited
};

/// Poses of the particles to deposit (one entry per particle in each span).
struct ParticlePoses {
    std::span<const int> shape;        ///< template index into the templates span
    std::span<const Vec3> position;    ///< centre of mass (m, world frame)
    std::span<const Quat> orientation; ///< unit quaternion, body -> world
};

namespace detail {
/// Scratch of one fixed chunk of particles (results and the per-particle accumulators).
struct ChunkBuffer {
    std::vector<std::size_t> begin;         // per particle of the chunk: first deposit entry
    std::vector<std::int32_t> cell;         // deposit entries
    std::vector<double> volume;             // deposit entries
    std::vector<double> weight;             // deposit entries
    std::vector<std::size_t> stencil_begin; // per particle: first stencil entry
    std::vector<std::int32_t> stencil_cell; // stencil entries
    std::vector<double> stencil_weight;     // stencil entries
    std::vector<std::int64_t> count;        // sub-cells per cell of a particle's local box
    std::vector<double> stencil;            // stencil weights on the local box
    std::vector<double> row;                // x weights of one sub-cell run
    std::vector<RowRun> runs;               // a clump row's runs
    std::vector<Vec3> centres;              // a clump's member centres (m, world frame)
    PosedPlanes posed;                      // a polyhedron's face planes (world frame)
};
} // namespace detail

/// Footprints of a set of particles. Entries of particle p are [begin[p], begin[p + 1]) in
/// `cell`, `volume`, `weight`, and [stencil_begin[p], stencil_begin[p + 1]) in the stencil arrays,
/// in increasing cell index.
struct Footprints {
    std::vector<std::size_t> begin; ///< per particle + 1: first deposit entry
    std::vector<std::int32_t> cell; ///< deposit entry: flat fluid cell index
    std::vector<double> volume;     ///< deposit entry: solid volume put in the cell (m^3)
    std::vector<double> weight;     ///< deposit entry: share of the particle's sub-cells (-)
    std::vector<std::size_t> stencil_begin; ///< per particle + 1: first stencil entry
    std::vector<std::int32_t> stencil_cell; ///< stencil entry: flat fluid cell index
    std::vector<double> stencil_weight;     ///< stencil entry: weight of the cell's value (-)
    std::vector<Vec3> centroid;             ///< mean of the particle's sub-cell centres (m, world)
    std::vector<std::int64_t> sub_cells;    ///< number of the particle's sub-cells in the domain
    std::vector<Placement> placement;       ///< how each particle lies on the grid
    std::size_t clipped = 0;   ///< particles whose world box crosses the domain boundary
    std::size_t too_small = 0; ///< particles holding no sub-cell centre (sub-grid too coarse)
    std::size_t outside = 0;   ///< particles deposited nowhere
    std::size_t cells = 0;     ///< fluid cell count of the grid
    /// Deposit entries by cell: those of cell c are cell_entry[cell_begin[c] .. cell_begin[c+1]),
    /// in increasing particle order (sums over a cell in a fixed order, any thread count).
    std::vector<std::size_t> cell_begin;
    std::vector<std::size_t> cell_entry;    ///< deposit entry indices grouped by cell (see above)
    std::vector<std::size_t> cell_particle; ///< particle of each cell_entry
    std::vector<detail::ChunkBuffer> work;  ///< scratch reused between calls
};

/// Particles per fixed chunk of work; results do not depend on the thread count.
inline constexpr std::size_t kFootprintChunk = 64;

/// Computes the footprints of all particles on `grid` into `out` (its storage is reused), with
/// up to `threads` OpenMP threads (1 without OpenMP). The same bits for any thread count.
void compute_footprints(const TransferGrid& grid, std::span<const DepositTemplate> templates,
                        const ParticlePoses& poses, Footprints& out, int threads = 1);

} // namespace kiln::fluid
