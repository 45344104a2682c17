#pragma once
// Broad phase: linked cells build a half Verlet list (each pair once) with a skin; the list is
// rebuilt when any particle has moved more than half the skin since the last build. Each list entry
// carries the pair's tangential contact history, which is carried over to the new list on rebuild.

#include "core/particle_store.hpp"

#include <cstdint>
#include <vector>

namespace kiln::contact {

/// Half neighbour list in compressed rows: the partners of particle i are j[offsets[i] ..
/// offsets[i+1]).
class NeighbourList {
  public:
    /// `skin` is the extra distance (m) added to r_i + r_j when building.
    explicit NeighbourList(double skin = 0.0) : skin_(skin) {}

    /// True when some particle moved more than skin/2 since the last build, or the size changed.
    [[nodiscard]] bool needs_rebuild(const ParticleStore& p) const;

    /// Rebuilds the list. When `sort` is set, the store is first reordered by cell for locality and
    /// the applied order (new k <- old order[k]) is returned so other per-particle data can follow;
    /// otherwise the returned vector is empty. Contact history is carried over by particle id.
    std::vector<std::uint32_t> build(ParticleStore& p, bool sort);

    /// Row offsets, size n+1.
    [[nodiscard]] const std::vector<std::uint32_t>& offsets() const { return offsets_; }
    /// Partner indices (j > i is not guaranteed; each unordered pair appears once).
    [[nodiscard]] const std::vector<std::uint32_t>& partners() const { return partners_; }
    /// Owning particle i of each entry (the row it sits in).
    [[nodiscard]] const std::vector<std::uint32_t>& owners() const { return owners_; }
    /// Tangential history per entry (m, world; displacement of i relative to j).
    [[nodiscard]] std::vector<Vec3>& shear() { return shear_; }
    [[nodiscard]] const std::vector<Vec3>& shear() const { return shear_; }
    /// Skin distance (m).
    [[nodiscard]] double skin() const { return skin_; }
    /// Threads used by `build` (the list is the same for any number).
    void set_threads(int threads) { threads_ = threads > 0 ? threads : 1; }
    /// Number of builds so far.
    [[nodiscard]] long builds() const { return builds_; }

    /// Restores a saved list exactly (checkpoint); positions at the last build included.
    void restore(std::vector<std::uint32_t> offsets, std::vector<std::uint32_t> partners,
                 std::vector<Vec3> shear, std::vector<Vec3> x_at_build,
                 std::vector<std::int64_t> ids_at_build, long builds);
    /// Positions at the last build (m, world), for checkpoints.
    [[nodiscard]] const std::vector<Vec3>& positions_at_build() const { return x_build_; }

  private:
    double skin_;
    int threads_ = 1;
    long builds_ = 0;
    std::vector<std::uint32_t> offsets_{0};
    std::vector<std::uint32_t> partners_;
    std::vector<std::uint32_t> owners_;
    std::vector<Vec3> shear_;
    void fill_owners();
    std::vector<Vec3> x_build_;
    // Scratch reused between builds.
    std::vector<std::uint32_t> cell_of_, cell_start_, order_, new_row_of_id_;
    std::vector<std::int64_t> old_ids_;
    // Partners found by each thread (buffers only grow) and how many of them are this build's.
    std::vector<std::vector<std::uint32_t>> thread_partners_;
    std::vector<std::size_t> thread_count_;
    std::vector<std::vector<std::uint32_t>> thread_held_; // entries with a history (scratch)

    struct CellGrid;
    /// Partners of particles [i0, i1) into `buf` (from its start), row lengths into offsets_;
    /// returns how many. search_sorted needs the store sorted by cell, search_unsorted reads the
    /// cells through order_.
    std::size_t search_sorted(const ParticleStore& p, const CellGrid& g, std::size_t i0,
                              std::size_t i1, std::vector<std::uint32_t>& buf);
    std::size_t search_unsorted(const ParticleStore& p, const CellGrid& g, std::size_t i0,
                                std::size_t i1, std::vector<std::uint32_t>& buf);
    /// Sets shear_ of the new list from the old list's histories (owners and partners of the old
    /// entries by old index, `old_ids` the particle ids by old index).
    void carry_histories(const ParticleStore& p, const std::vector<std::int64_t>& old_ids,
                         const std::vector<std::uint32_t>& old_owners,
                         const std::vector<std::uint32_t>& old_partners,
                         const std::vector<Vec3>& old_shear);
};

} // namespace kiln::contact
