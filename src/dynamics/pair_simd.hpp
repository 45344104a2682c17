#pragma once
// Register path of the sphere pair loop (System::pair_chunk) with AVX2: the touching pairs are
// taken four at a time, the particles' Vec3 records (x, y, z at a 24-byte stride, world frame) are
// read as one 16-byte (x, y) and one 8-byte (z) load each and transposed into one register per
// component, geometry and law (contact::evaluate_lanes) run on the four lanes, and the results are
// transposed back and added to the particles in list order. Nothing is staged through memory, as
// in notes/limits.md's dem2 (AoS records and 4 x 4 register transposes). The contact filter that
// finds the touching pairs also takes four list entries at a time. Without AVX2 the pair loop uses
// its one-entry filter and its blocked structure-of-arrays path only.

#include "contact/contact_law.hpp"
#include "core/material.hpp"
#include "core/types.hpp"
#include "dynamics/wall.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <type_traits>

#ifdef __AVX2__
#include <immintrin.h>
#endif

namespace kiln::dynamics::simd {

/// |a - b|^2 (m^2, any common frame) as the pair loop's touch test takes it: explicit
/// multiply-adds, so that the one-entry and the four-entry filters give the same bits.
inline double squared_distance(const Vec3& a, const Vec3& b) {
    const double d0 = a[0] - b[0];
    const double d1 = a[1] - b[1];
    const double d2 = a[2] - b[2];
#ifdef __FMA__
    return std::fma(d2, d2, std::fma(d1, d1, d0 * d0));
#else
    return d2 * d2 + (d1 * d1 + d0 * d0);
#endif
}

/// Byte offset of particle record i in a Vec3 array (ActiveList and InnerChunk hand the register
/// path and the inner filter offsets instead of indices: an index takes an address computation
/// (i + 2 i, then times 8) per array, an offset none). Offsets are 32-bit: fewer than 2^32 / 24
/// particles (System::index_partners checks).
constexpr std::uint32_t record_bytes = sizeof(Vec3);

/// The record at byte offset `off` of a.
inline const Vec3& at(const Vec3* a, std::uint32_t off) {
    return *reinterpret_cast<const Vec3*>(reinterpret_cast<const char*>(a) + off);
}
/// The record at byte offset `off` of a.
inline Vec3& at(Vec3* a, std::uint32_t off) {
    return *reinterpret_cast<Vec3*>(reinterpret_cast<char*>(a) + off);
}

#ifdef __AVX2__
/// Components x, y, z of four records, one register each (lane l = record l).
struct Columns {
    __m256d c[3];
};

/// Transposes the records r0..r3 (three doubles each) into columns.
inline Columns columns_of(const double* r0, const double* r1, const double* r2, const double* r3) {
    // (x0, y0 | x2, y2) and (x1, y1 | x3, y3), unpacked into (x0, x1, x2, x3) and (y0, .., y3).
    const __m256d r02 =
        _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(r0)), _mm_loadu_pd(r2), 1);
    const __m256d r13 =
        _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(r1)), _mm_loadu_pd(r3), 1);
    const __m128d z01 = _mm_loadh_pd(_mm_load_sd(r0 + 2), r1 + 2);
    const __m128d z23 = _mm_loadh_pd(_mm_load_sd(r2 + 2), r3 + 2);
    return {{_mm256_unpacklo_pd(r02, r13), _mm256_unpackhi_pd(r02, r13),
             _mm256_insertf128_pd(_mm256_castpd128_pd256(z01), z23, 1)}};
}

/// Reads the records at byte offsets off[0..3] of a and transposes them into columns.
inline Columns columns_at(const Vec3* __restrict a, const std::uint32_t off[4]) {
    return columns_of(at(a, off[0]).data(), at(a, off[1]).data(), at(a, off[2]).data(),
                      at(a, off[3]).data());
}

/// The four 32-bit indices of v as byte offsets of Vec3 records.
inline __m128i offsets_of(__m128i v) {
    return _mm_mullo_epi32(v, _mm_set1_epi32(static_cast<int>(record_bytes)));
}

/// Reads the records a[p[0..3]] and transposes them into columns.
inline Columns columns(const Vec3* __restrict a, const std::uint32_t p[4]) {
    return columns_of(a[p[0]].data(), a[p[1]].data(), a[p[2]].data(), a[p[3]].data());
}
#endif

#ifdef __AVX2__
/// The (x, y) parts of four rows, from the columns col0 = x and col1 = y of four contacts.
struct RowsXY {
    __m128d r[4];
};

/// Transposes the x and y columns of four contacts, held in registers, into (x, y) rows.
inline RowsXY rows_xy(__m256d x, __m256d y) {
    const __m256d lo = _mm256_unpacklo_pd(x, y); // x0 y0 | x2 y2
    const __m256d hi = _mm256_unpackhi_pd(x, y); // x1 y1 | x3 y3
    return {{_mm256_castpd256_pd128(lo), _mm256_castpd256_pd128(hi), _mm256_extractf128_pd(lo, 1),
             _mm256_extractf128_pd(hi, 1)}};
}

/// a += (xy, z), component by component.
inline void add_to(Vec3& a, __m128d xy, double z) {
    double* p = a.data();
    _mm_storeu_pd(p, _mm_add_pd(_mm_loadu_pd(p), xy));
    p[2] += z;
}

/// a -= (xy, z), component by component.
inline void sub_from(Vec3& a, __m128d xy, double z) {
    double* p = a.data();
    _mm_storeu_pd(p, _mm_sub_pd(_mm_loadu_pd(p), xy));
    p[2] -= z;
}

/// a = (xy, z).
inline void set(Vec3& a, __m128d xy, double z) {
    double* p = a.data();
    _mm_storeu_pd(p, xy);
    p[2] = z;
}
#endif

#ifdef __AVX2__
/// The touching list entries of a chunk as the filters append them, with their particles, so that
/// the register path reads the particles' records from consecutive places.
struct ActiveList {
    std::uint32_t* k; ///< list entries, as byte offsets of their histories (record_bytes times k)
    std::uint32_t* i; ///< their owners, as byte offsets of records (record_bytes times the index)
    std::uint32_t* j; ///< their partners, as byte offsets of records
};

/// Appends the 32-bit lanes of v whose bit is set in the 4-bit mask m to out[0..), in lane order
/// (writes four values; those past the set lanes are overwritten by the next append).
inline void append_lanes(std::uint32_t* out, __m128i v, unsigned m) {
    // For each mask, the lanes that gather its set lanes at the front.
    alignas(16) static constexpr std::int32_t perm[16][4] = {
        {0, 0, 0, 0}, {0, 0, 0, 0}, {1, 0, 0, 0}, {0, 1, 0, 0}, {2, 0, 0, 0}, {0, 2, 0, 0},
        {1, 2, 0, 0}, {0, 1, 2, 0}, {3, 0, 0, 0}, {0, 3, 0, 0}, {1, 3, 0, 0}, {0, 1, 3, 0},
        {2, 3, 0, 0}, {0, 2, 3, 0}, {1, 2, 3, 0}, {0, 1, 2, 3}};
    const __m128i idx = _mm_load_si128(reinterpret_cast<const __m128i*>(perm[m]));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out),
                     _mm_castps_si128(_mm_permutevar_ps(_mm_castsi128_ps(v), idx)));
}

/// Particle arrays (world frame, SI) read and written by `contact_groups`, and the list's arrays.
struct PairArrays {
    const std::uint32_t* owner; ///< list entry -> particle i
    const std::uint32_t* nb;    ///< list entry -> partner j
    Vec3* shear;                ///< list entry -> tangential history (m)
    const Vec3* x;              ///< positions (m)
    const Vec3* vel;            ///< velocities (m/s)
    const Vec3* omega;          ///< angular velocities (rad/s)
    const double* radius;       ///< radii (m)
    const double* mass;         ///< masses (kg)
    Vec3* force;                ///< forces (N), one thread only
    Vec3* torque;               ///< torques (N m), one thread only
    double* rows;               ///< pair result rows (f, torque_i, torque_j), several threads only
    /// Per group of four list entries (entry k in group k / 4, bit k % 4): which entries touched
    /// at the last filter (touching_entries); a set bit where unknown. Bit clear implies a zero
    /// history.
    std::uint8_t* touched;
    const double* rsum2; ///< list entry -> (r_i + r_j)^2 (m^2)
    /// The radius of every particle (m) when all have the same radius and mass, else 0.
    double same_radius = 0.0;
    double same_mass = 0.0; ///< the mass of every particle (kg) when same_radius is set
};

#if defined(__AVX2__) && defined(__FMA__)
/// One chunk's inner list (two-level Verlet list, docs/architecture.md "Inner list"): the list
/// entries of the chunk whose gap |x_i - x_j| - (r_i + r_j) was below the inner gap at the
/// positions where it was built, and those of particles loose since, in increasing entry order. The
/// pointers are at the chunk's part of the arrays (its first entry index for the entries, a quarter
/// of it for `was`).
struct InnerChunk {
    std::uint32_t* k;  ///< list entries
    std::uint32_t* i;  ///< their owners, as byte offsets of records (record_bytes times the index)
    std::uint32_t* j;  ///< their partners, as byte offsets of records
    double* rsum2;     ///< their (r_i + r_j)^2 (m^2)
    std::uint8_t* was; ///< per group of four inner entries, bit l: inner entry 4 g + l touched
                       ///< at the last filter (the inner list's own `touched`)
    const double* near2; ///< list entry -> (r_i + r_j + inner gap)^2 (m^2), read when building
    std::size_t count;   ///< inner entries of the chunk
};

/// The contact filter of System::pair_chunk four list entries at a time, from `begin` while four
/// remain before `end`: which entries touch (squared distance below the squared radius sum, as
/// squared_distance), their indices appended to active[n_active..] without a branch, the histories
/// of the others cleared (bit mask) when one of them touched at the last call (`touched`, whose
/// group of four entries is updated; `begin` is a multiple of four); with `rows` (several threads)
/// the row of each entry, `begin` + its place among the touching ones or `zero_row`. With `build`,
/// the entries closer than the inner gap (squared distance below inner->near2, the touching ones
/// included) are written to `inner` (count and flags set). Returns the first entry not taken.
template <bool with_rows, bool build = false>
std::size_t touching_entries(const PairArrays& arrays, std::size_t begin, std::size_t end,
                             const ActiveList& list, std::size_t& n_active, std::uint32_t* rows,
                             std::uint32_t zero_row, InnerChunk* inner = nullptr) {
    static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 records are packed");
    // Local copies of what the loop reads through references: the intrinsics' stores may alias any
    // memory, so GCC would load the pointers again after each of them (the same operations).
    const PairArrays a = arrays;
    const ActiveList active = list;
    InnerChunk out{};
    if constexpr (build) {
        out = *inner;
    }
    std::size_t n = n_active;
    std::size_t k = begin;
    std::size_t c = 0; // inner entries so far (build)
    if constexpr (build) {
        std::fill_n(out.was, (end - begin) / 4, std::uint8_t{0});
    }
    for (; k + 4 <= end; k += 4) {
        const std::uint32_t* is = a.owner + k;
        const std::uint32_t* js = a.nb + k;
        const Columns xi = columns(a.x, is);
        const Columns xj = columns(a.x, js);
        const __m256d d0 = _mm256_sub_pd(xi.c[0], xj.c[0]);
        const __m256d d1 = _mm256_sub_pd(xi.c[1], xj.c[1]);
        const __m256d d2 = _mm256_sub_pd(xi.c[2], xj.c[2]);
        const __m256d dist2 =
            _mm256_fmadd_pd(d2, d2, _mm256_fmadd_pd(d1, d1, _mm256_mul_pd(d0, d0)));
        const __m256d touch = _mm256_cmp_pd(dist2, _mm256_loadu_pd(a.rsum2 + k), _CMP_LT_OQ);
        const auto m = static_cast<unsigned>(_mm256_movemask_pd(touch));
        // Only an entry that touched at the last filter and does not now can hold a history to
        // clear (the others that do not touch hold zero): the histories are read and written only
        // then, not at every step. The four histories (12 doubles) are cleared with each lane's
        // mask spread over its 3 components.
        std::uint8_t& was = a.touched[k / 4];
        if ((was & ~m) != 0U) {
            double* h = a.shear[k].data();
            _mm256_storeu_pd(h,
                             _mm256_and_pd(_mm256_loadu_pd(h), _mm256_permute4x64_pd(touch, 0x40)));
            _mm256_storeu_pd(
                h + 4, _mm256_and_pd(_mm256_loadu_pd(h + 4), _mm256_permute4x64_pd(touch, 0xA5)));
            _mm256_storeu_pd(
                h + 8, _mm256_and_pd(_mm256_loadu_pd(h + 8), _mm256_permute4x64_pd(touch, 0xFE)));
        }
        was = static_cast<std::uint8_t>(m);
        // The touching entries and their particles appended with one shuffle each (n + 3 stays
        // within the chunk: n counts touching entries before k).
        constexpr int rb = static_cast<int>(record_bytes);
        append_lanes(active.k + n,
                     _mm_add_epi32(_mm_set1_epi32(static_cast<int>(k * record_bytes)),
                                   _mm_setr_epi32(0, rb, 2 * rb, 3 * rb)),
                     m);
        append_lanes(active.i + n,
                     offsets_of(_mm_loadu_si128(reinterpret_cast<const __m128i*>(is))), m);
        append_lanes(active.j + n,
                     offsets_of(_mm_loadu_si128(reinterpret_cast<const __m128i*>(js))), m);
        if constexpr (with_rows) {
            std::size_t r = n;
            for (unsigned l = 0; l < 4; ++l) {
                const unsigned t = (m >> l) & 1U;
                rows[k + l] = t != 0 ? static_cast<std::uint32_t>(begin + r) : zero_row;
                r += t;
            }
        }
        n += static_cast<std::size_t>(std::popcount(m));
        if constexpr (build) {
            const __m256d near = _mm256_cmp_pd(dist2, _mm256_loadu_pd(out.near2 + k), _CMP_LT_OQ);
            const unsigned mn = m | static_cast<unsigned>(_mm256_movemask_pd(near));
            for (unsigned l = 0; l < 4; ++l) {
                out.k[c] = static_cast<std::uint32_t>(k + l);
                out.i[c] = is[l] * record_bytes;
                out.j[c] = js[l] * record_bytes;
                out.rsum2[c] = a.rsum2[k + l];
                out.was[c / 4] |= static_cast<std::uint8_t>(((m >> l) & 1U) << (c % 4));
                c += (mn >> l) & 1U;
            }
        }
    }
    if constexpr (build) {
        inner->count = c;
    }
    n_active = n;
    return k;
}

/// touching_entries on a chunk's inner list instead of all its entries (the same decisions, the
/// touching entries appended in the same order, while no entry outside the inner list can touch):
/// four inner entries at a time; the histories of those that stopped touching are cleared; the
/// last 0-3 inner entries one at a time (squared_distance, the history cleared or kept by mask).
/// With `rows`, the rows of the inner entries are set; the other entries keep the zero row
/// written when the inner list was built.
template <bool with_rows>
void inner_touching_entries(const PairArrays& arrays, const InnerChunk& chunk, std::size_t begin,
                            const ActiveList& list, std::size_t& n_active, std::uint32_t* rows,
                            std::uint32_t zero_row) {
    // Local copies of what the loop reads through references: the intrinsics' stores may alias any
    // memory, so GCC would load the pointers again after each of them (the same operations).
    const PairArrays a = arrays;
    const InnerChunk in = chunk;
    const ActiveList active = list;
    std::size_t n = n_active;
    std::size_t c = 0;
    for (; c + 4 <= in.count; c += 4) {
        const Columns xi = columns_at(a.x, in.i + c);
        const Columns xj = columns_at(a.x, in.j + c);
        const __m256d d0 = _mm256_sub_pd(xi.c[0], xj.c[0]);
        const __m256d d1 = _mm256_sub_pd(xi.c[1], xj.c[1]);
        const __m256d d2 = _mm256_sub_pd(xi.c[2], xj.c[2]);
        const __m256d dist2 =
            _mm256_fmadd_pd(d2, d2, _mm256_fmadd_pd(d1, d1, _mm256_mul_pd(d0, d0)));
        const __m256d touch = _mm256_cmp_pd(dist2, _mm256_loadu_pd(in.rsum2 + c), _CMP_LT_OQ);
        const auto m = static_cast<unsigned>(_mm256_movemask_pd(touch));
        std::uint8_t& was = in.was[c / 4];
        const unsigned stopped = was & ~m;
        if (stopped != 0U) {
            for (unsigned l = 0; l < 4; ++l) {
                if (((stopped >> l) & 1U) != 0U) {
                    a.shear[in.k[c + l]].setZero();
                }
            }
        }
        was = static_cast<std::uint8_t>(m);
        const auto lanes = [&](const std::uint32_t* p) {
            return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + c));
        };
        append_lanes(active.k + n, offsets_of(lanes(in.k)), m);
        append_lanes(active.i + n, lanes(in.i), m);
        append_lanes(active.j + n, lanes(in.j), m);
        if constexpr (with_rows) {
            std::size_t r = n;
            for (unsigned l = 0; l < 4; ++l) {
                const unsigned t = (m >> l) & 1U;
                rows[in.k[c + l]] = t != 0 ? static_cast<std::uint32_t>(begin + r) : zero_row;
                r += t;
            }
        }
        n += static_cast<std::size_t>(std::popcount(m));
    }
    for (; c < in.count; ++c) {
        const std::uint32_t k = in.k[c];
        const bool t = squared_distance(at(a.x, in.i[c]), at(a.x, in.j[c])) < in.rsum2[c];
        if (!t) {
            a.shear[k].setZero();
        }
        active.k[n] = k * record_bytes;
        active.i[n] = in.i[c];
        active.j[n] = in.j[c];
        if constexpr (with_rows) {
            rows[k] = t ? static_cast<std::uint32_t>(begin + n) : zero_row;
        }
        n += t ? 1U : 0U;
    }
    n_active = n;
}
#endif

/// The touching list entries active.k[0..n) of a chunk (entries and particles as the filter
/// appended them), four at a time with the law on the four lanes of a register (AVX2): records
/// transposed in registers, geometry and law (evaluate_lanes), then the results added to
/// force/torque contact by contact in list order (`direct`, one thread) or written to rows[9
/// (first_row + a)] (several threads). Pair properties from `pairs` by the particles' `material`.
/// Returns how many entries it took (a multiple of four); energy and max_ratio accumulate in entry
/// order, only `with_counters` (otherwise the law's elastic energy and the overlap ratios are not
/// formed and energy_sum and max_ratio_of are left as they are). `variant` selects the law's
/// contact::LaneVariant (without_rolling only when rolling is 0).
template <unsigned variant, class Law, bool direct, bool uniform, bool with_counters = true>
std::size_t contact_groups_as(const Law& law, const PairTable& pairs, const std::int32_t* material,
                              double fn_floor, double rolling, double dt, const PairArrays& arrays,
                              const ActiveList& list, std::size_t n, std::size_t first_row,
                              double& energy_sum, double& max_ratio_of) {
    constexpr int W = 4;
    // Local copies of what the loop reads through references: the intrinsics' stores may alias any
    // memory, so GCC would load the pointers again after each of them (the same operations).
    const PairArrays a = arrays;
    const ActiveList active = list;
    double energy = energy_sum;
    double max_ratio = max_ratio_of;
    using V = contact::lanes::V4;
    using contact::lanes::select;
    contact::ContactLanes<V> c{};
    const bool one_pair = pairs.size() == 1;
    if (one_pair) {
        const PairProperties& pp = pairs.at(0, 0);
        c.e_star = contact::lanes::splat(pp.effective_modulus, c.e_star);
        c.g_star = contact::lanes::splat(pp.effective_shear, c.e_star);
        c.beta = contact::lanes::splat(pp.beta, c.e_star);
        c.mu = contact::lanes::splat(pp.friction, c.e_star);
        c.mu_roll = contact::lanes::splat(pp.rolling_friction, c.e_star);
        c.damping_ratio = contact::lanes::splat(
            std::sqrt(4.0 * pp.effective_shear / pp.effective_modulus), c.e_star);
    }
    // Largest overlap / (2 min(ri, rj)) per lane, kept as a fraction (top / bottom) compared by
    // cross products, so that the divider (the busiest unit) does one division per lane per call.
    // Rounding may pick either of two ratios within an ulp of each other (a diagnostic only).
    V top = contact::lanes::splat(0.0, c.e_star);
    V bottom = contact::lanes::splat(1.0, c.e_star);
    // What the lanes' radii and masses give, with three divisions fewer than the blocked loop of
    // System::pair_chunk (the divider is the busiest unit here): one shared by R* and m*.
    struct Sizes {
        V ri, rj;   // radii (m)
        V rsum;     // r_i + r_j (m)
        V r_eff;    // R* (m)
        V m_eff;    // m* (kg)
        V diameter; // 2 min(r_i, r_j) (m)
    };
    const auto sizes = [](V ri, V rj, V mi, V mj) {
        const V rsum = ri + rj;
        const V msum = mi + mj;
        const V inv_rm = 1.0 / (rsum * msum);
        return Sizes{ri,
                     rj,
                     rsum,
                     ri * rj * msum * inv_rm,
                     mi * mj * rsum * inv_rm,
                     2.0 * select(rj < ri, rj, ri)};
    };
    // With every particle alike (`uniform`: one radius a.same_radius, one mass a.same_mass), the
    // sizes are the same for every group: taken once, the same bits.
    Sizes z{};
    if constexpr (uniform) {
        const V r = contact::lanes::splat(a.same_radius, c.e_star);
        const V m = contact::lanes::splat(a.same_mass, c.e_star);
        z = sizes(r, r, m, m);
    }
    std::size_t g = 0;
    for (; g + W <= n; g += W) {
        std::uint32_t ks[W];
        std::uint32_t is[W];
        std::uint32_t js[W];
        for (int l = 0; l < W; ++l) {
            ks[l] = active.k[g + l];
            is[l] = active.i[g + l];
            js[l] = active.j[g + l];
        }
        if constexpr (!uniform) {
            V ri{};
            V rj{};
            V mi{};
            V mj{};
            for (int l = 0; l < W; ++l) {
                const std::uint32_t i = is[l] / record_bytes;
                const std::uint32_t j = js[l] / record_bytes;
                ri[l] = a.radius[i];
                rj[l] = a.radius[j];
                mi[l] = a.mass[i];
                mj[l] = a.mass[j];
            }
            z = sizes(ri, rj, mi, mj);
        }
        if (!one_pair) {
            for (int l = 0; l < W; ++l) {
                const PairProperties& pp =
                    pairs.at(material[is[l] / record_bytes], material[js[l] / record_bytes]);
                c.e_star[l] = pp.effective_modulus;
                c.g_star[l] = pp.effective_shear;
                c.beta[l] = pp.beta;
                c.mu[l] = pp.friction;
                c.mu_roll[l] = pp.rolling_friction;
            }
        }
        const Columns xi = columns_at(a.x, is);
        const Columns xj = columns_at(a.x, js);
        const Columns vi = columns_at(a.vel, is);
        const Columns vj = columns_at(a.vel, js);
        const Columns wi = columns_at(a.omega, is);
        const Columns wj = columns_at(a.omega, js);
        const Columns sh = columns_at(a.shear, ks);
        V d[3];
        for (int q = 0; q < 3; ++q) {
            d[q] = xi.c[q] - xj.c[q];
            c.v[q] = vi.c[q] - vj.c[q];
            c.wi[q] = wi.c[q];
            c.wj[q] = wj.c[q];
            c.s[q] = sh.c[q];
        }
        // Geometry as in the blocked loop of System::pair_chunk, with one division for the normal.
        const V d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if constexpr ((variant & contact::project_by_distance) != 0) {
            for (int q = 0; q < 3; ++q) {
                c.d[q] = d[q];
            }
            c.inv_d2 = 1.0 / d2;
        }
        const V dist = contact::lanes::vsqrt(d2);
        const V overlap = z.rsum - dist;
        const V inv_dist = 1.0 / dist;
        for (int q = 0; q < 3; ++q) {
            c.n[q] = d[q] * inv_dist;
        }
        c.overlap = overlap;
        c.r_eff = z.r_eff;
        c.m_eff = z.m_eff;
        c.lever_i = z.ri - 0.5 * overlap;
        c.lever_j = z.rj - 0.5 * overlap;
        if constexpr (with_counters) {
            const auto larger = overlap * bottom > top * z.diameter;
            top = select(larger, overlap, top);
            bottom = select(larger, z.diameter, bottom);
        }
        contact::evaluate_lanes<variant>(law, fn_floor, rolling, c, dt);
        // The scatter reads the entries and offsets from the list again (L1): an empty asm that
        // may read and write memory keeps GCC from holding the twelve of them in registers through
        // the law, where they spilled others.
        asm volatile("" ::: "memory");
        for (int l = 0; l < W; ++l) {
            ks[l] = active.k[g + l];
            is[l] = active.i[g + l];
            js[l] = active.j[g + l];
        }

        const RowsXY f = rows_xy(c.f[0], c.f[1]);
        const RowsXY ti = rows_xy(c.ti[0], c.ti[1]);
        const RowsXY tj = rows_xy(c.tj[0], c.tj[1]);
        const RowsXY s = rows_xy(c.s[0], c.s[1]);
        for (int l = 0; l < W; ++l) {
            if constexpr (direct) {
                add_to(at(a.force, is[l]), f.r[l], c.f[2][l]);
                sub_from(at(a.force, js[l]), f.r[l], c.f[2][l]);
                add_to(at(a.torque, is[l]), ti.r[l], c.ti[2][l]);
                add_to(at(a.torque, js[l]), tj.r[l], c.tj[2][l]);
            } else {
                double* r = a.rows + 9 * (first_row + g + l);
                _mm_storeu_pd(r, f.r[l]);
                r[2] = c.f[2][l];
                _mm_storeu_pd(r + 3, ti.r[l]);
                r[5] = c.ti[2][l];
                _mm_storeu_pd(r + 6, tj.r[l]);
                r[8] = c.tj[2][l];
            }
            set(at(a.shear, ks[l]), s.r[l], c.s[2][l]);
            if constexpr (with_counters) {
                energy += c.energy[l];
            }
        }
    }
    if constexpr (with_counters) {
        for (int l = 0; l < W; ++l) {
            max_ratio = std::max(max_ratio, top[l] / bottom[l]);
        }
    }
    energy_sum = energy;
    max_ratio_of = max_ratio;
    return g;
}

#ifdef __AVX2__
/// The sphere-wall contacts of System::wall_unit four at a time on the lanes of a register, with
/// `variant` of the law (as contact_groups). Contact a is particle active[a] against wall
/// wall_of[a] (wall material wall_material[wall]) with geometry geo[a] (world frame; the wall is
/// body j, at rest, of infinite mass); histories in wall_shear[wall * stride + particle] (m).
/// Forces and torques are added to the particles; energy and max_ratio accumulate, contact by
/// contact in order, only `with_counters`. A last group of fewer than four repeats its last
/// contact in the free lanes, whose results are dropped (a copy of a lane does not change which
/// branch the group takes, so the kept lanes get the same bits). With `uniform`, every particle
/// has the radius a.same_radius and the mass a.same_mass (taken once instead of per lane).
template <unsigned variant, class Law, bool uniform, bool with_counters = true>
void wall_groups(const Law& law, const PairTable& pairs, const std::int32_t* material,
                 const int* wall_material, double fn_floor, double rolling, double dt,
                 const WallContact* geo, const std::uint32_t* active, const std::uint32_t* wall_of,
                 std::size_t n, std::size_t stride, const PairArrays& arrays, Vec3* wall_shear,
                 double& energy_sum, double& max_ratio_of) {
    // A contact's normal and overlap are read as four consecutive doubles.
    static_assert(sizeof(WallContact) == 5 * sizeof(double), "WallContact is n, overlap, r_eff");
    constexpr int W = 4;
    // Local copies of what the loop reads through references: the intrinsics' stores may alias any
    // memory, so GCC would load the pointers again after each of them (the same operations).
    const PairArrays a = arrays;
    double energy = energy_sum;
    double max_ratio = max_ratio_of;
    using V = contact::lanes::V4;
    using contact::lanes::splat;
    contact::ContactLanes<V> c{};
    for (int q = 0; q < 3; ++q) {
        c.wj[q] = splat(0.0, c.e_star);
    }
    c.lever_j = splat(0.0, c.e_star);
    const bool one_pair = pairs.size() == 1;
    const auto set_lane = [&c](int l, const PairProperties& pp) {
        c.e_star[l] = pp.effective_modulus;
        c.g_star[l] = pp.effective_shear;
        c.beta[l] = pp.beta;
        c.mu[l] = pp.friction;
        c.mu_roll[l] = pp.rolling_friction;
        if constexpr ((variant & contact::shared_damping_root) != 0) {
            c.damping_ratio[l] = std::sqrt(4.0 * pp.effective_shear / pp.effective_modulus);
        }
    };
    if (one_pair) {
        for (int l = 0; l < W; ++l) {
            set_lane(l, pairs.at(0, 0));
        }
    }
    V radius{}; // the lanes' particle radii (m)
    if constexpr (uniform) {
        radius = splat(a.same_radius, radius);
        c.m_eff = splat(a.same_mass, radius);
    }
    for (std::size_t g = 0; g < n; g += W) {
        const std::size_t m = std::min<std::size_t>(W, n - g);
        std::uint32_t is[W];
        std::uint32_t hs[W];
        std::size_t as[W];
        for (int l = 0; l < W; ++l) {
            as[l] = g + std::min<std::size_t>(static_cast<std::size_t>(l), m - 1);
            is[l] = active[as[l]];
            hs[l] = static_cast<std::uint32_t>(wall_of[as[l]] * stride + is[l]);
        }
        // (n0, n1, n2, overlap) of the four contacts, transposed into columns.
        const auto row = [&](int l) { return _mm256_loadu_pd(geo[as[l]].n.data()); };
        const __m256d g0 = row(0);
        const __m256d g1 = row(1);
        const __m256d g2 = row(2);
        const __m256d g3 = row(3);
        const __m256d lo01 = _mm256_unpacklo_pd(g0, g1); // n0 n0 | n2 n2 of lanes 0, 1
        const __m256d hi01 = _mm256_unpackhi_pd(g0, g1); // n1 n1 | overlap overlap
        const __m256d lo23 = _mm256_unpacklo_pd(g2, g3);
        const __m256d hi23 = _mm256_unpackhi_pd(g2, g3);
        c.n[0] = _mm256_permute2f128_pd(lo01, lo23, 0x20);
        c.n[1] = _mm256_permute2f128_pd(hi01, hi23, 0x20);
        c.n[2] = _mm256_permute2f128_pd(lo01, lo23, 0x31);
        c.overlap = _mm256_permute2f128_pd(hi01, hi23, 0x31);
        c.r_eff =
            _mm256_setr_pd(geo[as[0]].r_eff, geo[as[1]].r_eff, geo[as[2]].r_eff, geo[as[3]].r_eff);
        if constexpr (!uniform) {
            for (int l = 0; l < W; ++l) {
                c.m_eff[l] = a.mass[is[l]];
                radius[l] = a.radius[is[l]];
            }
        }
        c.lever_i = radius - c.overlap;
        if (!one_pair) {
            for (int l = 0; l < W; ++l) {
                set_lane(l, pairs.at(material[is[l]], wall_material[wall_of[as[l]]]));
            }
        }
        const Columns v = columns(a.vel, is);
        const Columns w = columns(a.omega, is);
        const Columns sh = columns(wall_shear, hs);
        for (int q = 0; q < 3; ++q) {
            c.v[q] = v.c[q];
            c.wi[q] = w.c[q];
            c.s[q] = sh.c[q];
        }
        contact::evaluate_lanes<variant>(law, fn_floor, rolling, c, dt);
        V ratio{};
        if constexpr (with_counters) {
            ratio = c.overlap / (2.0 * radius); // one division for the four lanes
        }
        const RowsXY f = rows_xy(c.f[0], c.f[1]);
        const RowsXY ti = rows_xy(c.ti[0], c.ti[1]);
        const RowsXY s = rows_xy(c.s[0], c.s[1]);
        for (std::size_t l = 0; l < m; ++l) {
            add_to(a.force[is[l]], f.r[l], c.f[2][l]);
            add_to(a.torque[is[l]], ti.r[l], c.ti[2][l]);
            set(wall_shear[hs[l]], s.r[l], c.s[2][l]);
            if constexpr (with_counters) {
                energy += c.energy[l];
                max_ratio = std::max(max_ratio, ratio[l]);
            }
        }
    }
    energy_sum = energy;
    max_ratio_of = max_ratio;
}
#endif

/// Calls run(std::integral_constant<unsigned, V>{}) with the variant V of the law that has the
/// fewest square roots and divisions for the scene: `base` (the Coulomb cap only when a lane
/// slides, and what else the caller adds), no rolling term when there is none (the same bits) and,
/// with one material pair, the tangential damping from the normal one (other round-off).
template <unsigned base, class Run>
decltype(auto) with_cheapest_variant(const PairTable& pairs, double rolling, Run&& run) {
    constexpr unsigned s = contact::shared_damping_root;
    constexpr unsigned r = contact::without_rolling;
    constexpr unsigned f = contact::with_friction;
    if (pairs.size() == 1 && pairs.at(0, 0).friction > 0.0) {
        return rolling == 0.0 ? run(std::integral_constant<unsigned, base | s | r | f>{})
                              : run(std::integral_constant<unsigned, base | s | f>{});
    }
    if (pairs.size() == 1) {
        return rolling == 0.0 ? run(std::integral_constant<unsigned, base | s | r>{})
                              : run(std::integral_constant<unsigned, base | s>{});
    }
    return rolling == 0.0 ? run(std::integral_constant<unsigned, base | r>{})
                          : run(std::integral_constant<unsigned, base>{});
}

/// Calls run(std::true_type) or run(std::false_type) as `on` says: a run-time switch turned into
/// a template argument.
template <class Run> decltype(auto) with_flag(bool on, Run&& run) {
    return on ? run(std::true_type{}) : run(std::false_type{});
}

/// wall_groups with the cheapest variant of the law (with_cheapest_variant; the walls give no
/// centre difference, so the history is projected with n). The elastic energy and the overlap
/// ratios are summed only `with_counters`.
template <class Law>
void wall_contacts(const Law& law, const PairTable& pairs, const std::int32_t* material,
                   const int* wall_material, double fn_floor, double rolling, double dt,
                   const WallContact* geo, const std::uint32_t* active,
                   const std::uint32_t* wall_of, std::size_t n, std::size_t stride,
                   const PairArrays& a, Vec3* wall_shear, double& energy, double& max_ratio,
                   bool with_counters) {
    with_cheapest_variant<contact::cap_when_sliding>(pairs, rolling, [&](auto variant) {
        with_flag(a.same_radius > 0.0, [&](auto uniform) {
            with_flag(with_counters, [&](auto sum_counters) {
                wall_groups<decltype(variant)::value, Law, decltype(uniform)::value,
                            decltype(sum_counters)::value>(
                    law, pairs, material, wall_material, fn_floor, rolling, dt, geo, active,
                    wall_of, n, stride, a, wall_shear, energy, max_ratio);
            });
        });
    });
}

/// contact_groups_as with the cheapest variant of the law (with_cheapest_variant), the history
/// projected with the centre difference; R* and m* taken once when a.same_radius is set; the
/// elastic energy and the overlap ratios summed only `with_counters`.
template <class Law, bool direct>
std::size_t contact_groups(const Law& law, const PairTable& pairs, const std::int32_t* material,
                           double fn_floor, double rolling, double dt, const PairArrays& a,
                           const ActiveList& active, std::size_t n, std::size_t first_row,
                           double& energy, double& max_ratio, bool with_counters) {
    constexpr unsigned base = contact::cap_when_sliding | contact::project_by_distance;
    return with_cheapest_variant<base>(pairs, rolling, [&](auto variant) {
        return with_flag(a.same_radius > 0.0, [&](auto uniform) {
            return with_flag(with_counters, [&](auto sum_counters) {
                return contact_groups_as<decltype(variant)::value, Law, direct,
                                         decltype(uniform)::value, decltype(sum_counters)::value>(
                    law, pairs, material, fn_floor, rolling, dt, a, active, n, first_row, energy,
                    max_ratio);
            });
        });
    });
}
#endif

} // namespace kiln::dynamics::simd
