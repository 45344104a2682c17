#pragma once
// Eight packed Vec3 records as one AVX-512 register per component (the neighbour build's distance
// tests and the wall candidates' plane tests read positions so).

#include "core/types.hpp"

#if defined(__AVX512F__)
#include <immintrin.h>

namespace kiln {

/// Components x, y, z of up to eight records, one register each (lane l = record l).
struct Columns8 {
    __m512d x, y, z;
};

/// Records first[0 .. k) (k <= 8, any frame and unit) in lanes 0 .. k-1, zero in the others; no
/// memory past record k is read (masked loads).
inline Columns8 load_columns8(const Vec3* first, unsigned k) {
    static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 records are packed");
    const __m512i x_lo = _mm512_setr_epi64(0, 3, 6, 9, 12, 15, 0, 0);
    const __m512i x_hi = _mm512_setr_epi64(0, 1, 2, 3, 4, 5, 10, 13);
    const __m512i y_lo = _mm512_setr_epi64(1, 4, 7, 10, 13, 0, 0, 0);
    const __m512i y_hi = _mm512_setr_epi64(0, 1, 2, 3, 4, 8, 11, 14);
    const __m512i z_lo = _mm512_setr_epi64(2, 5, 8, 11, 14, 0, 0, 0);
    const __m512i z_hi = _mm512_setr_epi64(0, 1, 2, 3, 4, 9, 12, 15);
    const unsigned dm = (1U << (3 * k)) - 1U; // the 3k doubles of the k records
    const double* base = first->data();
    const __m512d a0 = _mm512_maskz_loadu_pd(static_cast<__mmask8>(dm), base);
    const __m512d a1 = _mm512_maskz_loadu_pd(static_cast<__mmask8>(dm >> 8), base + 8);
    const __m512d a2 = _mm512_maskz_loadu_pd(static_cast<__mmask8>(dm >> 16), base + 16);
    return {_mm512_permutex2var_pd(_mm512_permutex2var_pd(a0, x_lo, a1), x_hi, a2),
            _mm512_permutex2var_pd(_mm512_permutex2var_pd(a0, y_lo, a1), y_hi, a2),
            _mm512_permutex2var_pd(_mm512_permutex2var_pd(a0, z_lo, a1), z_hi, a2)};
}

} // namespace kiln

#endif
