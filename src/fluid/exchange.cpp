#include "fluid/exchange.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <type_traits>

namespace kiln::fluid {
namespace {

template <class T> T zero() {
    if constexpr (std::is_same_v<T, double>) {
        return 0.0;
    } else {
        return T::Zero();
    }
}

// out[c] = sum over the entries of cell c, in particle order, of term(entry, particle).
template <class T, class Term>
void gather_cells(const Footprints& f, std::span<T> out, int threads, const Term& term) {
    KILN_ASSERT(out.size() == f.cells);
    const auto n = static_cast<long>(f.cells);
    (void)threads;
#pragma omp parallel for num_threads(std::max(threads, 1)) schedule(static)
    for (long c = 0; c < n; ++c) {
        const auto cu = static_cast<std::size_t>(c);
        T sum = zero<T>();
        for (std::size_t k = f.cell_begin[cu]; k < f.cell_begin[cu + 1]; ++k) {
            sum += term(f.cell_entry[k], f.cell_particle[k]);
        }
        out[cu] = sum;
    }
}

template <class T>
void spread_any(const Footprints& f, std::span<const T> value, std::span<T> out, int threads) {
    KILN_ASSERT(value.size() + 1 == f.begin.size());
    gather_cells<T>(f, out, threads,
                    [&](std::size_t e, std::size_t p) -> T { return f.weight[e] * value[p]; });
}

template <class T>
void interpolate_any(const Footprints& f, std::span<const T> field, std::span<T> out, int threads) {
    KILN_ASSERT(field.size() == f.cells && out.size() + 1 == f.stencil_begin.size());
    const auto n = static_cast<long>(out.size());
    (void)threads;
#pragma omp parallel for num_threads(std::max(threads, 1)) schedule(static)
    for (long p = 0; p < n; ++p) {
        const auto pu = static_cast<std::size_t>(p);
        T sum = zero<T>();
        for (std::size_t k = f.stencil_begin[pu]; k < f.stencil_begin[pu + 1]; ++k) {
            sum += f.stencil_weight[k] * field[static_cast<std::size_t>(f.stencil_cell[k])];
        }
        out[pu] = sum;
    }
}

} // namespace

void solid_volume(const Footprints& f, std::span<double> out, int threads) {
    gather_cells<double>(f, out, threads, [&](std::size_t e, std::size_t) { return f.volume[e]; });
}

std::vector<double> porosity(const TransferGrid& g, const Footprints& f, int threads) {
    std::vector<double> out(f.cells);
    solid_volume(f, out, threads);
    const double inv = 1.0 / g.cell_volume();
    for (double& v : out) {
        v = 1.0 - v * inv;
    }
    return out;
}

void spread(const Footprints& f, std::span<const double> value, std::span<double> out,
            int threads) {
    spread_any<double>(f, value, out, threads);
}

void spread(const Footprints& f, std::span<const Vec3> value, std::span<Vec3> out, int threads) {
    spread_any<Vec3>(f, value, out, threads);
}

void interpolate(const Footprints& f, std::span<const double> field, std::span<double> out,
                 int threads) {
    interpolate_any<double>(f, field, out, threads);
}

void interpolate(const Footprints& f, std::span<const Vec3> field, std::span<Vec3> out,
                 int threads) {
    interpolate_any<Vec3>(f, field, out, threads);
}

} // namespace kiln::fluid
