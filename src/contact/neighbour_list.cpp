#include "contact/neighbour_list.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#if defined(__AVX512F__)
#include "core/records_avx512.hpp"
#endif

#ifdef _OPENMP
#include <omp.h>
#endif

namespace kiln::contact {

namespace {
constexpr std::uint32_t none = std::numeric_limits<std::uint32_t>::max();

/// Inside a parallel region: this thread's number and its contiguous share [first, last) of n
/// items split in equal parts (the whole range without OpenMP).
struct ThreadShare {
    std::size_t thread = 0;
    std::size_t first = 0;
    std::size_t last = 0;
};
ThreadShare thread_share(std::size_t n) {
    std::size_t t = 0;
    std::size_t nt = 1;
#ifdef _OPENMP
    t = static_cast<std::size_t>(omp_get_thread_num());
    nt = static_cast<std::size_t>(omp_get_num_threads());
#endif
    return {t, n * t / nt, n * (t + 1) / nt};
}

/// Appends to `out` the indices j of [j0, j1) with |x_j - xi|^2 < (ri + r_j)^2 (positions in m,
/// world frame; ri already holds r_i + skin), in increasing order; returns how many. `out` must
/// have room for j1 - j0 + 16 indices (the vector path stores whole registers). The squared
/// distance is formed as Eigen's squaredNorm() of the scalar search: (dx^2 + dy^2), then dz^2 by a
/// fused multiply-add, so both paths keep the same pairs to the bit.
std::size_t scan_range(const Vec3* x, const double* radius, const Vec3& xi, double ri,
                       std::uint32_t j0, std::uint32_t j1, std::uint32_t* out) {
    std::size_t m = 0;
#if defined(__AVX512F__)
    const __m512d cx = _mm512_set1_pd(xi[0]);
    const __m512d cy = _mm512_set1_pd(xi[1]);
    const __m512d cz = _mm512_set1_pd(xi[2]);
    const __m512d cr = _mm512_set1_pd(ri);
    const __m512i lane = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 0, 0, 0, 0, 0, 0, 0, 0);
    for (std::uint32_t j = j0; j < j1; j += 8) {
        const std::uint32_t k = std::min<std::uint32_t>(8, j1 - j);
        const __mmask8 rec = static_cast<__mmask8>((1U << k) - 1U);
        const Columns8 c = load_columns8(x + j, k);
        const __m512d dx = _mm512_sub_pd(c.x, cx);
        const __m512d dy = _mm512_sub_pd(c.y, cy);
        const __m512d dz = _mm512_sub_pd(c.z, cz);
        // The empty asm statements keep the compiler from fusing a product into the sum.
        __m512d sx = _mm512_mul_pd(dx, dx);
        __m512d sy = _mm512_mul_pd(dy, dy);
        asm("" : "+v"(sx), "+v"(sy));
        const __m512d dxy = _mm512_add_pd(sx, sy);
        const __m512d d2 = _mm512_fmadd_pd(dz, dz, dxy);
        const __m512d cut = _mm512_add_pd(cr, _mm512_maskz_loadu_pd(rec, radius + j));
        const __mmask8 hit = _mm512_mask_cmp_pd_mask(rec, d2, _mm512_mul_pd(cut, cut), _CMP_LT_OQ);
        const __m512i idx = _mm512_add_epi32(_mm512_set1_epi32(static_cast<int>(j)), lane);
        // The whole register is stored (16 indices); only the first popcount(hit) count.
        _mm512_storeu_si512(out + m, _mm512_maskz_compress_epi32(static_cast<__mmask16>(hit), idx));
        m += static_cast<std::size_t>(__builtin_popcount(hit));
    }
#else
    for (std::uint32_t j = j0; j < j1; ++j) {
        const double cut = ri + radius[j];
        if ((x[j] - xi).squaredNorm() < cut * cut) {
            out[m++] = j;
        }
    }
#endif
    return m;
}
} // namespace

/// Cells of a build: nx * ny * nz cubes of side 1/inv from `lo` (m, world), x fastest;
/// start[c] .. start[c + 1] are the places of cell c's particles in the cell order.
struct NeighbourList::CellGrid {
    long nx, ny, nz;
    Vec3 lo;
    double inv;
    const std::uint32_t* start;

    /// Cell coordinate along axis a of position x (m, world), clamped to the grid.
    [[nodiscard]] long coord(const Vec3& x, int a) const {
        const long na = a == 0 ? nx : (a == 1 ? ny : nz);
        return std::clamp(static_cast<long>((x[a] - lo[a]) * inv), 0L, na - 1);
    }
};

std::size_t NeighbourList::search_sorted(const ParticleStore& p, const CellGrid& g, std::size_t i0,
                                         std::size_t i1, std::vector<std::uint32_t>& buf) {
    // The store is sorted by cell, so particle indices follow the cell order and a run of cells
    // along x is one range of indices. The partners j > i of i lie in i's own cell after i, the
    // next cell along x, the three cells of the next row (y + 1) and the nine of the next layer
    // (z + 1): five ranges, visited in increasing index order. The list is the one the cell by
    // cell search gave (same pairs, same order).
    std::size_t used = 0;
    const auto scan = [&](std::size_t i, std::uint32_t j0, std::uint32_t j1) {
        if (j1 <= j0) {
            return;
        }
        if (buf.size() < used + (j1 - j0) + 16) {
            buf.resize(std::max(2 * buf.size(), used + (j1 - j0) + 16));
        }
        used += scan_range(p.x.data(), p.radius.data(), p.x[i], p.radius[i] + skin_, j0, j1,
                           buf.data() + used);
    };
    const auto row = [&](long y, long z) {
        return static_cast<std::size_t>((z * g.ny + y) * g.nx);
    };
    for (std::size_t i = i0; i < i1; ++i) {
        const Vec3& xi = p.x[i];
        const long cx = g.coord(xi, 0);
        const long cy = g.coord(xi, 1);
        const long cz = g.coord(xi, 2);
        const long xlo = std::max(0L, cx - 1);
        const long xhi = std::min(g.nx - 1, cx + 1);
        const std::size_t before = used;
        scan(i, static_cast<std::uint32_t>(i + 1),
             g.start[row(cy, cz) + static_cast<std::size_t>(xhi) + 1]);
        if (cy + 1 < g.ny) {
            const std::size_t r = row(cy + 1, cz);
            scan(i, g.start[r + static_cast<std::size_t>(xlo)],
                 g.start[r + static_cast<std::size_t>(xhi) + 1]);
        }
        if (cz + 1 < g.nz) {
            for (long y = std::max(0L, cy - 1); y <= std::min(g.ny - 1, cy + 1); ++y) {
                const std::size_t r = row(y, cz + 1);
                scan(i, g.start[r + static_cast<std::size_t>(xlo)],
                     g.start[r + static_cast<std::size_t>(xhi) + 1]);
            }
        }
        offsets_[i + 1] = static_cast<std::uint32_t>(used - before);
    }
    return used;
}

std::size_t NeighbourList::search_unsorted(const ParticleStore& p, const CellGrid& g,
                                           std::size_t i0, std::size_t i1,
                                           std::vector<std::uint32_t>& buf) {
    // Every neighbour cell, each pair taken from its lower index.
    std::size_t used = 0;
    for (std::size_t i = i0; i < i1; ++i) {
        const Vec3& xi = p.x[i];
        const double ri = p.radius[i] + skin_;
        const long cx = g.coord(xi, 0);
        const long cy = g.coord(xi, 1);
        const long cz = g.coord(xi, 2);
        const std::size_t before = used;
        for (long z = std::max(0L, cz - 1); z <= std::min(g.nz - 1, cz + 1); ++z) {
            for (long y = std::max(0L, cy - 1); y <= std::min(g.ny - 1, cy + 1); ++y) {
                for (long x = std::max(0L, cx - 1); x <= std::min(g.nx - 1, cx + 1); ++x) {
                    const std::size_t c = static_cast<std::size_t>((z * g.ny + y) * g.nx + x);
                    for (std::uint32_t k = g.start[c]; k < g.start[c + 1]; ++k) {
                        const std::uint32_t j = order_[k];
                        if (j <= i) {
                            continue;
                        }
                        const double cut = ri + p.radius[j];
                        if ((p.x[j] - xi).squaredNorm() < cut * cut) {
                            if (buf.size() <= used) {
                                buf.resize(std::max<std::size_t>(2 * buf.size(), 64));
                            }
                            buf[used++] = j;
                        }
                    }
                }
            }
        }
        offsets_[i + 1] = static_cast<std::uint32_t>(used - before);
    }
    return used;
}

void NeighbourList::carry_histories(const ParticleStore& p,
                                    const std::vector<std::int64_t>& old_ids,
                                    const std::vector<std::uint32_t>& old_owners,
                                    const std::vector<std::uint32_t>& old_partners,
                                    const std::vector<Vec3>& old_shear) {
    // Only entries with a history are looked for: the pair loop clears the history of a pair that
    // stopped touching, so most entries (pairs within the skin, apart) hold zero, which the new
    // list starts with anyway. Each one is found in the new list through the particles' new indices
    // (by id): in a's row with the same sign, or in b's with the opposite one (roles swapped).
    const std::int64_t max_id = std::max(*std::max_element(old_ids.begin(), old_ids.end()),
                                         *std::max_element(p.id.begin(), p.id.end()));
    new_row_of_id_.assign(static_cast<std::size_t>(max_id) + 1, none);
    for (std::size_t k = 0; k < p.size(); ++k) {
        new_row_of_id_[static_cast<std::size_t>(p.id[k])] = static_cast<std::uint32_t>(k);
    }
    const auto entry = [&](std::uint32_t a, std::uint32_t b) {
        for (std::uint32_t k = offsets_[a]; k < offsets_[a + 1]; ++k) {
            if (partners_[k] == b) {
                return k;
            }
        }
        return none;
    };
    // Entries with a history are picked without a branch (whether a pair touched is random
    // along the list), then looked up; each thread takes a contiguous part of the old list.
    const std::size_t n_entries = old_partners.size();
    if (thread_held_.size() < static_cast<std::size_t>(threads_)) {
        thread_held_.resize(static_cast<std::size_t>(threads_));
    }
#pragma omp parallel num_threads(threads_)
    {
        const ThreadShare share = thread_share(n_entries);
        const std::size_t k0 = share.first;
        const std::size_t k1 = share.last;
        std::vector<std::uint32_t>& held = thread_held_[share.thread];
        held.resize(k1 - k0);
        std::size_t m = 0;
        for (std::size_t k = k0; k < k1; ++k) {
            const Vec3& s = old_shear[k];
            held[m] = static_cast<std::uint32_t>(k);
            m += static_cast<std::size_t>((s[0] != 0.0) | (s[1] != 0.0) | (s[2] != 0.0));
        }
        for (std::size_t h = 0; h < m; ++h) {
            const std::uint32_t k = held[h];
            const std::uint32_t a =
                new_row_of_id_[static_cast<std::size_t>(old_ids[old_owners[k]])];
            const std::uint32_t b =
                new_row_of_id_[static_cast<std::size_t>(old_ids[old_partners[k]])];
            if (a == none || b == none) {
                continue;
            }
            // Each unordered pair is in one row only, of the old list and of the new one.
            if (const std::uint32_t e = entry(a, b); e != none) {
                shear_[e] = old_shear[k];
            } else if (const std::uint32_t f = entry(b, a); f != none) {
                shear_[f] = -old_shear[k];
            }
        }
    }
}

bool NeighbourList::needs_rebuild(const ParticleStore& p) const {
    if (x_build_.size() != p.size() || offsets_.size() != p.size() + 1) {
        return true;
    }
    const double lim2 = 0.25 * skin_ * skin_;
    for (std::size_t i = 0; i < p.size(); ++i) {
        if ((p.x[i] - x_build_[i]).squaredNorm() > lim2) {
            return true;
        }
    }
    return false;
}

void NeighbourList::restore(std::vector<std::uint32_t> offsets, std::vector<std::uint32_t> partners,
                            std::vector<Vec3> shear, std::vector<Vec3> x_at_build,
                            std::vector<std::int64_t> ids_at_build, long builds) {
    old_ids_ = std::move(ids_at_build);
    offsets_ = std::move(offsets);
    partners_ = std::move(partners);
    shear_ = std::move(shear);
    x_build_ = std::move(x_at_build);
    builds_ = builds;
    fill_owners();
}

void NeighbourList::fill_owners() {
    const std::size_t entries = partners_.size();
#if defined(__AVX512F__)
    // Sixteen copies of i per store, row after row: the stores past a row's end are overwritten by
    // the next rows (rows are short; the loop over a row's length would mispredict).
    owners_.resize(entries + 16);
    for (std::size_t i = 0; i + 1 < offsets_.size(); ++i) {
        const __m512i own = _mm512_set1_epi32(static_cast<int>(i));
        std::uint32_t k = offsets_[i];
        do {
            _mm512_storeu_si512(owners_.data() + k, own);
            k += 16;
        } while (k < offsets_[i + 1]);
    }
    owners_.resize(entries);
#else
    owners_.resize(entries);
    for (std::size_t i = 0; i + 1 < offsets_.size(); ++i) {
        for (std::uint32_t k = offsets_[i]; k < offsets_[i + 1]; ++k) {
            owners_[k] = static_cast<std::uint32_t>(i);
        }
    }
#endif
}

std::vector<std::uint32_t> NeighbourList::build(ParticleStore& p, bool sort) {
    const std::size_t n = p.size();
    ++builds_;

    // Keep the old list (with old indices and ids) for the history transfer.
    std::vector<std::uint32_t> old_offsets = std::move(offsets_);
    std::vector<std::uint32_t> old_partners = std::move(partners_);
    std::vector<std::uint32_t> old_owners = std::move(owners_);
    std::vector<Vec3> old_shear = std::move(shear_);
    const bool have_old = old_offsets.size() == old_ids_.size() + 1 && !old_ids_.empty();

    offsets_.assign(1, 0);
    partners_.clear();
    owners_.clear();
    shear_.clear();
    if (n == 0) {
        x_build_.clear();
        old_ids_.clear();
        return {};
    }

    // Cell grid over the particles' bounding box; cells at least as wide as the largest cut-off.
    Vec3 lo = p.x[0];
    Vec3 hi = p.x[0];
    double rmax = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        lo = lo.cwiseMin(p.x[i]);
        hi = hi.cwiseMax(p.x[i]);
        rmax = std::max(rmax, p.radius[i]);
    }
    double cell = 2.0 * rmax + skin_;
    const Vec3 ext = (hi - lo).cwiseMax(Vec3::Constant(cell));
    // Bound the number of cells (a lone escaping particle must not create a huge grid).
    const double max_cells = std::max(1000.0, 8.0 * static_cast<double>(n));
    while ((ext / cell).array().ceil().prod() > max_cells) {
        cell *= 1.26;
    }
    const auto dim = [&](int a) {
        return std::max(1L, static_cast<long>(std::ceil(ext[a] / cell)));
    };
    const long nx = dim(0);
    const long ny = dim(1);
    const long nz = dim(2);

    // Counting sort of particles by cell.
    const std::size_t ncell = static_cast<std::size_t>(nx * ny * nz);
    cell_of_.resize(n);
    cell_start_.assign(ncell + 1, 0);
    const CellGrid grid{nx, ny, nz, lo, 1.0 / cell, cell_start_.data()};
    for (std::size_t i = 0; i < n; ++i) {
        const long c =
            (grid.coord(p.x[i], 2) * ny + grid.coord(p.x[i], 1)) * nx + grid.coord(p.x[i], 0);
        cell_of_[i] = static_cast<std::uint32_t>(c);
        ++cell_start_[static_cast<std::size_t>(c) + 1];
    }
    for (std::size_t c = 0; c < ncell; ++c) {
        cell_start_[c + 1] += cell_start_[c];
    }
    order_.resize(n);
    {
        std::vector<std::uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
        for (std::size_t i = 0; i < n; ++i) {
            order_[fill[cell_of_[i]]++] = static_cast<std::uint32_t>(i);
        }
    }

    // Remember old ids by old index before any reordering.
    std::vector<std::int64_t> prev_ids = std::move(old_ids_);
    std::vector<std::uint32_t> applied;
    if (sort) {
        // The search of a sorted store reads cells as ranges of indices; order_ is not used.
        p.permute(order_);
        applied = order_;
    }

    // Each thread searches a contiguous range of particles into its own buffer; the buffers are
    // joined in order, so the list does not depend on the number of threads.
    offsets_.assign(n + 1, 0);
    if (thread_partners_.size() < static_cast<std::size_t>(threads_)) {
        thread_partners_.resize(static_cast<std::size_t>(threads_));
        thread_count_.resize(static_cast<std::size_t>(threads_));
    }
    // A thread the runtime did not start adds nothing (no count left from an earlier build).
    std::fill(thread_count_.begin(), thread_count_.end(), std::size_t{0});
#pragma omp parallel num_threads(threads_)
    {
        const ThreadShare share = thread_share(n);
        std::vector<std::uint32_t>& buf = thread_partners_[share.thread];
        thread_count_[share.thread] = sort ? search_sorted(p, grid, share.first, share.last, buf)
                                           : search_unsorted(p, grid, share.first, share.last, buf);
    }
    for (std::size_t i = 0; i < n; ++i) {
        offsets_[i + 1] += offsets_[i];
    }
    partners_.resize(offsets_[n]);
    {
        std::size_t at = 0;
        for (std::size_t t = 0; t < thread_partners_.size(); ++t) {
            const std::size_t m = t < static_cast<std::size_t>(threads_) ? thread_count_[t] : 0;
            std::copy_n(thread_partners_[t].begin(), m,
                        partners_.begin() + static_cast<std::ptrdiff_t>(at));
            at += m;
        }
    }

    shear_.assign(partners_.size(), Vec3::Zero());
    if (have_old) {
        carry_histories(p, prev_ids, old_owners, old_partners, old_shear);
    }

    fill_owners();
    old_ids_ = p.id;
    x_build_ = p.x;
    return applied;
}

} // namespace kiln::contact
