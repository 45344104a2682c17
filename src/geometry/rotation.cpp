// Rotation convention and splitting integrator; see rotation.hpp and docs/theory/rotation.md.

#include "geometry/rotation.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

namespace kiln::geometry {

Mat3 rotation_matrix(const Quat& q) {
    // unit_rotation_matrix (rotation.hpp); the seed's printed matrix (Oschmann 2019, Table 3) has
    // a wrong (2,2) entry and sign errors and is not used.
    return unit_rotation_matrix(q.normalized());
}

Vec3 angular_velocity_world(const Quat& q, const Vec3& L_world, const Vec3& inertia_principal) {
    if (spherical_top(inertia_principal)) {               // as the Mat3 form (rotation.hpp)
        return L_world * (3.0 / inertia_principal.sum()); // L / spherical_moment, one division
    }
    if (const int s = symmetric_axis(inertia_principal); s >= 0) {
        return symmetric_omega(body_to_world(q, Vec3::Unit(s)), L_world, inertia_principal, s);
    }
    const Vec3 l_body = world_to_body(q, L_world);
    return body_to_world(q, l_body.cwiseQuotient(inertia_principal));
}

Vec3 angular_momentum_world(const Quat& q, const Vec3& omega_world, const Vec3& inertia_principal) {
    const Vec3 w_body = world_to_body(q, omega_world);
    return body_to_world(q, w_body.cwiseProduct(inertia_principal));
}

double rotational_energy(const Quat& q, const Vec3& L_world, const Vec3& inertia_principal) {
    const Vec3 l_body = world_to_body(q, L_world);
    return 0.5 * l_body.cwiseProduct(l_body).cwiseQuotient(inertia_principal).sum();
}

namespace {

/// Largest half angle (rad) whose sine and cosine come from the series.
constexpr double kSeriesLimit = 0.0625;

/// Sine and cosine of x (rad). For |x| <= kSeriesLimit (a body turning by less than 1/8 rad per
/// half step, the usual case by far) the Taylor series to x^9 and x^10: the first omitted terms,
/// x^11/11! and x^12/12!, are below 2e-20 relative, far under one unit in the last place; the
/// library otherwise (never with `series_only`, whose caller has checked the bound).
/// The series' two polynomials in x2 = x^2: sin(x) / x and cos(x).
[[gnu::always_inline]] inline void sinc_cos_series(double x2, double& sinc, double& c) {
    sinc =
        1.0 + x2 * (-1.0 / 6.0 + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362880.0))));
    c = 1.0 +
        x2 * (-0.5 + x2 * (1.0 / 24.0 +
                           x2 * (-1.0 / 720.0 + x2 * (1.0 / 40320.0 + x2 * (-1.0 / 3628800.0)))));
}

template <bool series_only>
[[gnu::always_inline]] inline void sin_cos(double x, double& s, double& c) {
    if constexpr (!series_only) {
        if (std::abs(x) > kSeriesLimit) {
            s = std::sin(x);
            c = std::cos(x);
            return;
        }
    }
    double sinc = 1.0;
    sinc_cos_series(x * x, sinc, c);
    s = x * sinc;
}

/// Exact flow of T_k = L_k^2 / (2 I_k) over h: the body turns by phi = h L_k / I_k about body axis
/// k, so q <- q * exp(phi/2 e_k) and the body components of L turn by -phi about e_k.
/// One sine and cosine of the half angle serve both: cos phi = ch^2 - sh^2, sin phi = 2 sh ch.
/// The quaternion product with the single-axis factor (ch, sh e_k) is written out: with (i, j, k)
/// cyclic, w' = ch w - sh v_k, v_k' = ch v_k + sh w, v_i' = ch v_i + sh v_j,
/// v_j' = ch v_j - sh v_i. `qv` = (x, y, z, w), the vector part first as Eigen stores it.
template <bool series_only>
[[gnu::always_inline]] inline void rotate_about_axis(double& li, double& lj, double lk, double& vi,
                                                     double& vj, double& vk, double& w,
                                                     double inv_ik, double h) {
    const double phi = h * lk * inv_ik;
    double sh = 0.0;
    double ch = 1.0;
    sin_cos<series_only>(0.5 * phi, sh, ch);
    const double c = (ch - sh) * (ch + sh);
    const double s = 2.0 * sh * ch;
    const double li0 = li;
    const double lj0 = lj;
    li = c * li0 + s * lj0;
    lj = -s * li0 + c * lj0;
    const double w0 = w;
    const double vi0 = vi;
    const double vj0 = vj;
    const double vk0 = vk;
    w = ch * w0 - sh * vk0;
    vk = ch * vk0 + sh * w0;
    vi = ch * vi0 + sh * vj0;
    vj = ch * vj0 - sh * vi0;
}

/// The splitting X(dt/2) Y(dt/2) Z(dt) Y(dt/2) X(dt/2) on plain numbers: (l0, l1, l2) = body-frame
/// L (consumed), (x, y, z, w) the quaternion, turned and renormalised; (i, j, k) cyclic per axis.
template <bool series_only>
[[gnu::always_inline]] inline void split_rotation(double& x, double& y, double& z, double& w,
                                                  double l0, double l1, double l2, double i0,
                                                  double i1, double i2, double dt) {
    const double h = 0.5 * dt;
    rotate_about_axis<series_only>(l1, l2, l0, y, z, x, w, i0, h);
    rotate_about_axis<series_only>(l2, l0, l1, z, x, y, w, i1, h);
    rotate_about_axis<series_only>(l0, l1, l2, x, y, z, w, i2, dt);
    rotate_about_axis<series_only>(l2, l0, l1, z, x, y, w, i1, h);
    rotate_about_axis<series_only>(l1, l2, l0, y, z, x, w, i0, h);
    const double norm = std::sqrt(x * x + y * y + z * z + w * w);
    x /= norm;
    y /= norm;
    z /= norm;
    w /= norm;
}

/// (x, y, z, w) <- (c, v) (w, x, y, z) with `left`, else (w, x, y, z) (c, v): the quaternion
/// product by a factor of scalar part c and vector part v on plain numbers, not renormalised.
/// (Written once for both sides so that each keeps its order of operations: w c - v.q, and
/// c q + w v plus v x q on the left, q x v on the right.)
template <bool left>
[[gnu::always_inline]] inline void multiply_by(double c, double v0, double v1, double v2, double& x,
                                               double& y, double& z, double& w) {
    const double w1 = c * w - (v0 * x + v1 * y + v2 * z);
    const double x1 = c * x + w * v0 + (left ? v1 * z - v2 * y : y * v2 - z * v1);
    const double y1 = c * y + w * v1 + (left ? v2 * x - v0 * z : z * v0 - x * v2);
    const double z1 = c * z + w * v2 + (left ? v0 * y - v1 * x : x * v1 - y * v0);
    x = x1;
    y = y1;
    z = z1;
    w = w1;
}

/// The turn about the fixed world L at the rate |L| / i on plain numbers, not renormalised:
/// (x, y, z, w) <- (cos x, sin x L / |L|) q, the factor in the world frame on the left, with the
/// half angle x = |L| k, k = dt / (2 i). sin(x) / x and cos(x) from their series in x^2 (no square
/// root; to the terms of sin_cos) where x <= kSeriesLimit, the library beyond (never with
/// `series_only`, whose caller has checked).
template <bool series_only>
[[gnu::always_inline]] inline void turn_about_l(double& x, double& y, double& z, double& w,
                                                double l0, double l1, double l2, double k) {
    const double x2 = (l0 * l0 + l1 * l1 + l2 * l2) * (k * k);
    double sinc = 1.0;
    double c = 1.0;
    sinc_cos_series(x2, sinc, c);
    if constexpr (!series_only) {
        if (x2 > kSeriesLimit * kSeriesLimit) {
            const double a = std::sqrt(x2);
            sinc = std::sin(a) / a;
            c = std::cos(a);
        }
    }
    const double f = k * sinc; // v = sin(x) L / |L| = f L
    multiply_by<true>(c, f * l0, f * l1, f * l2, x, y, z, w);
}

/// (x, y, z, w) divided by its norm.
[[gnu::always_inline]] inline void renormalise(double& x, double& y, double& z, double& w) {
    const double inv = 1.0 / std::sqrt(x * x + y * y + z * z + w * w);
    x *= inv;
    y *= inv;
    z *= inv;
    w *= inv;
}

/// The exact torque-free flow of a spherical top (spherical_top(I), one moment i: the body turns
/// about the fixed world L at omega = L / i) on plain numbers: turn_about_l with k = dt / (2 i),
/// (x, y, z, w) renormalised.
template <bool series_only>
[[gnu::always_inline]] inline void spherical_turn(double& x, double& y, double& z, double& w,
                                                  double l0, double l1, double l2, double k) {
    turn_about_l<series_only>(x, y, z, w, l0, l1, l2, k);
    renormalise(x, y, z, w);
}

/// The exact torque-free flow of a symmetric top (symmetric_axis(I) = s, moments i_p, i_p, i_s;
/// Landau & Lifshitz, Mechanics, Sec. 33) on plain numbers: q <- A q B. A = (cos a, sin a L / |L|)
/// turns the body about the fixed world L at |L| / i_p (turn_about_l, k = dt / (2 i_p)); B =
/// (cos b, sin b e_s), in the body frame on the right, spins it about its symmetry axis e_s by
/// the half angle b = L_s dt (1 / i_s - 1 / i_p) / 2, L_s = L . (R e_s), which the flow keeps
/// constant. Their rates add up to omega = L / i_p + L_s (1 / i_s - 1 / i_p) R e_s = R diag(1/I)
/// R^T L, so A(t) q0 B(t) is the flow itself, not an approximation of it. (e0, e1, e2) = e_s, a
/// unit axis of the body frame; sin b and cos b as turn_about_l's; (x, y, z, w) renormalised.
template <bool series_only>
[[gnu::always_inline]] inline void symmetric_turn(double& x, double& y, double& z, double& w,
                                                  double l0, double l1, double l2, double k,
                                                  double b, double e0, double e1, double e2) {
    turn_about_l<series_only>(x, y, z, w, l0, l1, l2, k);
    double s = 0.0;
    double c = 1.0;
    sin_cos<series_only>(b, s, c);
    // q (c, s e); e has one non-zero component, so the products with it are exact.
    multiply_by<false>(c, s * e0, s * e1, s * e2, x, y, z, w);
    renormalise(x, y, z, w);
}

/// Half angle per unit |L| of a spherical top over dt: dt / (2 i).
inline double spherical_rate(const Vec3& inertia_principal, double dt) {
    return 0.5 * dt / spherical_moment(inertia_principal);
}

/// The numbers of symmetric_turn for a symmetric top about body axis s (symmetric_axis(I)) with
/// rotation matrix rot (body -> world) and world L, over dt: k = dt / (2 i_p) and the half angle b
/// of the spin about e_s.
struct SymmetricRates {
    double k;
    double b;
};
inline SymmetricRates symmetric_rates(const Vec3& inertia_principal, int s, const Mat3& rot,
                                      const Vec3& L_world, double dt) {
    const auto a = static_cast<Eigen::Index>(s);
    const double ip = transverse_moment(inertia_principal, s);
    const double l_s = rot.col(a).dot(L_world);
    return {0.5 * dt / ip, 0.5 * dt * l_s * (1.0 / inertia_principal[a] - 1.0 / ip)};
}

} // namespace

void free_rotate(Quat& q, Mat3& rot, const Vec3& L_world, const Vec3& inertia_principal,
                 double dt) {
    KILN_ASSERT((inertia_principal.array() > 0.0).all());
    if (spherical_top(inertia_principal)) {
        double qv[4] = {q.x(), q.y(), q.z(), q.w()};
        spherical_turn<false>(qv[0], qv[1], qv[2], qv[3], L_world.x(), L_world.y(), L_world.z(),
                              spherical_rate(inertia_principal, dt));
        q = Quat(qv[3], qv[0], qv[1], qv[2]);
        rot = unit_rotation_matrix(q);
        return;
    }
    if (const int s = symmetric_axis(inertia_principal); s >= 0) {
        const SymmetricRates r = symmetric_rates(inertia_principal, s, rot, L_world, dt);
        const Vec3 e = Vec3::Unit(static_cast<Eigen::Index>(s));
        double qv[4] = {q.x(), q.y(), q.z(), q.w()};
        symmetric_turn<false>(qv[0], qv[1], qv[2], qv[3], L_world.x(), L_world.y(), L_world.z(),
                              r.k, r.b, e.x(), e.y(), e.z());
        q = Quat(qv[3], qv[0], qv[1], qv[2]);
        rot = unit_rotation_matrix(q);
        return;
    }
    const Vec3 l = rot.transpose() * L_world;
    const Vec3 inv_i = inertia_principal.cwiseInverse();
    double qv[4] = {q.x(), q.y(), q.z(), q.w()};
    split_rotation<false>(qv[0], qv[1], qv[2], qv[3], l.x(), l.y(), l.z(), inv_i.x(), inv_i.y(),
                          inv_i.z(), dt);
    q = Quat(qv[3], qv[0], qv[1], qv[2]);
    rot = unit_rotation_matrix(q);
}

void free_rotate_bodies(const std::uint32_t* index, std::size_t n, Quat* q, const Mat3* rot,
                        const Vec3* L_world, const Vec3* inertia_principal, double dt) {
    // Bodies by batches of `lanes` in structure-of-arrays form, spherical tops (cubes, regular
    // polyhedra: the exact turn), symmetric tops (the exact turn and spin) and the others (the
    // splitting) in batches of their own, taken from pieces of `piece` bodies; a batch is
    // evaluated lane-parallel (vectorised) with the series only, then any body whose half angle
    // could pass kSeriesLimit is redone alone with the general path (splitting: |L| dt / (2 I_min),
    // an upper bound since |L| is kept). Lanes past the end are padded with a body at rest, so
    // every batch is the same full loop.
    constexpr std::size_t lanes = 8;
    constexpr std::size_t piece = 64;
    alignas(64) double qv[4][lanes];
    alignas(64) double l[3][lanes];
    alignas(64) double inv_i[3][lanes];
    alignas(64) double axis[3][lanes];
    bool general[lanes];
    enum class Kind { spherical, symmetric, other };
    // Batch [b0, b0 + m) of `list` into the lanes: the quaternion, L (world frame for a spherical
    // or symmetric top, body frame for the splitting) and 1 / I (spherical: dt / (2 i) in
    // inv_i[0]; symmetric: symmetric_rates' k and b in inv_i[0] and inv_i[1], e_s in axis).
    // `axes`: a symmetric top's axis per body of the list (symmetric_axis, taken where the bodies
    // were sorted).
    const auto load = [&](const std::uint32_t* list, std::size_t m, Kind kind,
                          const int* axes = nullptr) {
        for (std::size_t b = 0; b < lanes; ++b) {
            if (b >= m) {
                for (int c = 0; c < 3; ++c) {
                    qv[c][b] = 0.0;
                    l[c][b] = 0.0;
                    inv_i[c][b] = 1.0;
                    axis[c][b] = 0.0;
                }
                qv[3][b] = 1.0;
                general[b] = false;
                continue;
            }
            const std::uint32_t i = list[b];
            for (int c = 0; c < 3; ++c) {
                qv[c][b] = q[i].coeffs()[c];
            }
            qv[3][b] = q[i].w();
            if (kind == Kind::symmetric) {
                const int s = axes[b];
                const SymmetricRates r =
                    symmetric_rates(inertia_principal[i], s, rot[i], L_world[i], dt);
                for (int c = 0; c < 3; ++c) {
                    l[c][b] = L_world[i][c];
                    axis[c][b] = c == s ? 1.0 : 0.0;
                }
                inv_i[0][b] = r.k;
                inv_i[1][b] = r.b;
                general[b] = L_world[i].squaredNorm() * (r.k * r.k) > kSeriesLimit * kSeriesLimit ||
                             std::abs(r.b) > kSeriesLimit;
                continue;
            }
            if (kind == Kind::spherical) {
                const double k = spherical_rate(inertia_principal[i], dt);
                for (int c = 0; c < 3; ++c) {
                    l[c][b] = L_world[i][c];
                }
                inv_i[0][b] = k;
                general[b] = L_world[i].squaredNorm() * (k * k) > kSeriesLimit * kSeriesLimit;
                continue;
            }
            const Vec3 lb = rot[i].transpose() * L_world[i];
            const Vec3 ii = inertia_principal[i].cwiseInverse();
            for (int c = 0; c < 3; ++c) {
                l[c][b] = lb[c];
                inv_i[c][b] = ii[c];
            }
            general[b] = L_world[i].norm() * dt * 0.5 * ii.maxCoeff() > kSeriesLimit;
        }
    };
    const auto store = [&](const std::uint32_t* list, std::size_t m) {
        for (std::size_t b = 0; b < m; ++b) {
            const std::uint32_t i = list[b];
            if (general[b]) {
                Mat3 r = rot[i];
                free_rotate(q[i], r, L_world[i], inertia_principal[i], dt);
            } else {
                q[i] = Quat(qv[3][b], qv[0][b], qv[1][b], qv[2][b]);
            }
        }
    };
    for (std::size_t p0 = 0; p0 < n; p0 += piece) {
        std::uint32_t top[piece];
        std::uint32_t sym[piece];
        int sym_axis[piece];
        std::uint32_t other[piece];
        std::size_t n_top = 0;
        std::size_t n_sym = 0;
        std::size_t n_other = 0;
        for (std::size_t b = p0; b < std::min(n, p0 + piece); ++b) {
            const std::uint32_t i = index[b];
            if (spherical_top(inertia_principal[i])) {
                top[n_top++] = i;
            } else if (const int s = symmetric_axis(inertia_principal[i]); s >= 0) {
                sym_axis[n_sym] = s;
                sym[n_sym++] = i;
            } else {
                other[n_other++] = i;
            }
        }
        for (std::size_t b0 = 0; b0 < n_top; b0 += lanes) {
            const std::size_t m = std::min(lanes, n_top - b0);
            load(top + b0, m, Kind::spherical);
#pragma omp simd
            for (std::size_t b = 0; b < lanes; ++b) {
                spherical_turn<true>(qv[0][b], qv[1][b], qv[2][b], qv[3][b], l[0][b], l[1][b],
                                     l[2][b], inv_i[0][b]);
            }
            store(top + b0, m);
        }
        for (std::size_t b0 = 0; b0 < n_sym; b0 += lanes) {
            const std::size_t m = std::min(lanes, n_sym - b0);
            load(sym + b0, m, Kind::symmetric, sym_axis + b0);
#pragma omp simd
            for (std::size_t b = 0; b < lanes; ++b) {
                symmetric_turn<true>(qv[0][b], qv[1][b], qv[2][b], qv[3][b], l[0][b], l[1][b],
                                     l[2][b], inv_i[0][b], inv_i[1][b], axis[0][b], axis[1][b],
                                     axis[2][b]);
            }
            store(sym + b0, m);
        }
        for (std::size_t b0 = 0; b0 < n_other; b0 += lanes) {
            const std::size_t m = std::min(lanes, n_other - b0);
            load(other + b0, m, Kind::other);
#pragma omp simd
            for (std::size_t b = 0; b < lanes; ++b) {
                split_rotation<true>(qv[0][b], qv[1][b], qv[2][b], qv[3][b], l[0][b], l[1][b],
                                     l[2][b], inv_i[0][b], inv_i[1][b], inv_i[2][b], dt);
            }
            store(other + b0, m);
        }
    }
}

void free_rotate(Quat& q, const Vec3& L_world, const Vec3& inertia_principal, double dt) {
    Mat3 rot = unit_rotation_matrix(q.normalized());
    free_rotate(q, rot, L_world, inertia_principal, dt);
}

void rotation_step(Quat& q, Vec3& L_world, const Vec3& inertia_principal, const Vec3& torque_world,
                   double dt) {
    kick_angular_momentum(L_world, torque_world, 0.5 * dt);
    free_rotate(q, L_world, inertia_principal, dt);
    kick_angular_momentum(L_world, torque_world, 0.5 * dt);
}

double elliptic_k(double m) {
    KILN_ASSERT(m >= 0.0 && m < 1.0);
    double a = 1.0;
    double b = std::sqrt(1.0 - m);
    for (int it = 0; it < 60 && std::abs(a - b) > 1e-16 * a; ++it) {
        const double an = 0.5 * (a + b);
        b = std::sqrt(a * b);
        a = an;
    }
    return std::numbers::pi / (2.0 * a);
}

double free_rotor_half_period(const Vec3& inertia_sorted, double L2, double energy) {
    double i1 = inertia_sorted[0];
    const double i2 = inertia_sorted[1];
    double i3 = inertia_sorted[2];
    KILN_ASSERT(i1 < i2 && i2 < i3);
    // Landau & Lifshitz Eq. 37.10 holds for L^2 > 2 E I2; for L^2 < 2 E I2 the suffixes 1 and 3
    // are interchanged (their remark after Eq. 37.12).
    if (L2 < 2.0 * energy * i2) {
        std::swap(i1, i3);
    }
    const double rate = std::sqrt((i3 - i2) * (L2 - 2.0 * energy * i1) / (i1 * i2 * i3));
    const double m = (i2 - i1) * (2.0 * energy * i3 - L2) / ((i3 - i2) * (L2 - 2.0 * energy * i1));
    KILN_ASSERT(m >= 0.0 && m < 1.0);
    return 2.0 * elliptic_k(m) / rate;
}

} // namespace kiln::geometry
