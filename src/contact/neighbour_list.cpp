#include "contact/neighbour_list.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace kiln::contact {

namespace {
constexpr std::uint32_t none = std::numeric_limits<std::uint32_t>::max();
} // namespace

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
    owners_.resize(partners_.size());
    for (std::size_t i = 0; i + 1 < offsets_.size(); ++i) {
        for (std::uint32_t k = offsets_[i]; k < offsets_[i + 1]; ++k) {
            owners_[k] = static_cast<std::uint32_t>(i);
        }
    }
}

std::vector<std::uint32_t> NeighbourList::build(ParticleStore& p, bool sort) {
    const std::size_t n = p.size();
    ++builds_;

    // Keep the old list (with old indices and ids) for the history transfer.
    std::vector<std::uint32_t> old_offsets = std::move(offsets_);
    std::vector<std::uint32_t> old_partners = std::move(partners_);
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
    const double inv = 1.0 / cell;
    const auto coord = [&](const Vec3& x, int a, long na) {
        return std::clamp(static_cast<long>((x[a] - lo[a]) * inv), 0L, na - 1);
    };

    // Counting sort of particles by cell.
    const std::size_t ncell = static_cast<std::size_t>(nx * ny * nz);
    cell_of_.resize(n);
    cell_start_.assign(ncell + 1, 0);
    for (std::size_t i = 0; i < n; ++i) {
        const long c =
            (coord(p.x[i], 2, nz) * ny + coord(p.x[i], 1, ny)) * nx + coord(p.x[i], 0, nx);
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
        p.permute(order_);
        std::vector<std::uint32_t> s;
        permute_array(cell_of_, order_, s);
        applied = order_;
        for (std::size_t k = 0; k < n; ++k) {
            order_[k] = static_cast<std::uint32_t>(k);
        }
    }

    // Old row of each particle id.
    if (have_old) {
        const auto max_id = *std::max_element(prev_ids.begin(), prev_ids.end());
        const auto max_new = *std::max_element(p.id.begin(), p.id.end());
        old_row_of_id_.assign(static_cast<std::size_t>(std::max(max_id, max_new)) + 1, none);
        for (std::size_t k = 0; k < prev_ids.size(); ++k) {
            old_row_of_id_[static_cast<std::size_t>(prev_ids[k])] = static_cast<std::uint32_t>(k);
        }
    }
    const auto find_old = [&](std::int64_t a, std::int64_t b, Vec3& s) {
        const std::uint32_t oa = old_row_of_id_[static_cast<std::size_t>(a)];
        if (oa == none) {
            return false;
        }
        for (std::uint32_t k = old_offsets[oa]; k < old_offsets[oa + 1]; ++k) {
            if (prev_ids[old_partners[k]] == b) {
                s = old_shear[k];
                return true;
            }
        }
        return false;
    };

    // When the store is sorted by cell, particle indices follow the cell order: partners j > i lie
    // in i's own cell after i or in neighbour cells of higher index, so the other cells and the
    // start of i's own cell are skipped (same list, in the same order, for half the distance
    // tests).
    // Each thread searches a contiguous range of particles into its own buffer; the buffers are
    // joined in order, so the list does not depend on the number of threads.
    offsets_.assign(n + 1, 0);
    if (thread_partners_.size() < static_cast<std::size_t>(threads_)) {
        thread_partners_.resize(static_cast<std::size_t>(threads_));
    }
#pragma omp parallel num_threads(threads_)
    {
        int t = 0;
        int nt = 1;
#ifdef _OPENMP
        t = omp_get_thread_num();
        nt = omp_get_num_threads();
#endif
        std::vector<std::uint32_t>& buf = thread_partners_[static_cast<std::size_t>(t)];
        buf.clear();
        const std::size_t i0 = n * static_cast<std::size_t>(t) / static_cast<std::size_t>(nt);
        const std::size_t i1 = n * static_cast<std::size_t>(t + 1) / static_cast<std::size_t>(nt);
        for (std::size_t i = i0; i < i1; ++i) {
            const Vec3& xi = p.x[i];
            const double ri = p.radius[i] + skin_;
            const long cx = coord(xi, 0, nx);
            const long cy = coord(xi, 1, ny);
            const long cz = coord(xi, 2, nz);
            const std::size_t own = cell_of_[i];
            const std::size_t before = buf.size();
            for (long z = std::max(0L, cz - 1); z <= std::min(nz - 1, cz + 1); ++z) {
                for (long y = std::max(0L, cy - 1); y <= std::min(ny - 1, cy + 1); ++y) {
                    for (long x = std::max(0L, cx - 1); x <= std::min(nx - 1, cx + 1); ++x) {
                        const std::size_t c = static_cast<std::size_t>((z * ny + y) * nx + x);
                        if (sort && c < own) {
                            continue;
                        }
                        const std::uint32_t first =
                            sort && c == own ? static_cast<std::uint32_t>(i + 1) : cell_start_[c];
                        for (std::uint32_t k = first; k < cell_start_[c + 1]; ++k) {
                            const std::uint32_t j = order_[k];
                            if (j <= i) {
                                continue;
                            }
                            const double cut = ri + p.radius[j];
                            if ((p.x[j] - xi).squaredNorm() < cut * cut) {
                                buf.push_back(j);
                            }
                        }
                    }
                }
            }
            offsets_[i + 1] = static_cast<std::uint32_t>(buf.size() - before);
        }
    }
    for (std::size_t i = 0; i < n; ++i) {
        offsets_[i + 1] += offsets_[i];
    }
    partners_.resize(offsets_[n]);
    {
        std::size_t at = 0;
        for (const auto& buf : thread_partners_) {
            std::copy(buf.begin(), buf.end(), partners_.begin() + static_cast<std::ptrdiff_t>(at));
            at += buf.size();
        }
    }

    // Carry the tangential history over, by particle id; flip its sign if the pair swapped roles.
    shear_.assign(partners_.size(), Vec3::Zero());
    if (have_old) {
#pragma omp parallel for num_threads(threads_) schedule(static)
        for (std::size_t i = 0; i < n; ++i) {
            for (std::uint32_t k = offsets_[i]; k < offsets_[i + 1]; ++k) {
                const std::int64_t a = p.id[i];
                const std::int64_t b = p.id[partners_[k]];
                Vec3 s;
                if (find_old(a, b, s)) {
                    shear_[k] = s;
                } else if (find_old(b, a, s)) {
                    shear_[k] = -s;
                }
            }
        }
    }

    fill_owners();
    old_ids_ = p.id;
    x_build_ = p.x;
    return applied;
}

} // namespace kiln::contact
