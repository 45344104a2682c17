#pragma once
// Contact force laws for two bodies touching at one point. A law is a small value type; the step
// loop dispatches on the variant once per step, so the per-contact code is a direct (inlined) call.
//
// Hertz-Mindlin: normal force after Hertz with the damping of Tsuji et al. (1992) written in the
// restitution-based form of the LIGGGHTS manual (gamma_n = -2 sqrt(5/6) beta sqrt(S_n m*),
// S_n = 2 E* sqrt(R* delta)), tangential spring after Mindlin, k_t = 8 G* sqrt(R* delta), with the
// shear modulus combination of Di Renzo & Di Maio (2004), G* = 1/((2-nu1)/G1 + (2-nu2)/G2).
// Oschmann (2019, Inv. VI/VII) prints (2 - nu^2)/G, which is a typo (notes/seed001_shape.md
// section 8.6).
//
// Linear spring-dashpot (Cundall & Strack 1979, as used in Oschmann 2019 Inv. I-IV, Table 1):
// F_n = k_n delta - gamma_n v_n with gamma_n = -2 beta sqrt(m* k_n), which gives exactly the
// prescribed restitution when the contact ends at delta = 0; tangential spring k_t = ratio * k_n
// with a Coulomb cap and no tangential damper (as in the seed).
//
// Rolling resistance: constant directional torque, model A of Ai et al. (2011),
// M_r = -mu_r R* |F_n| omega_rel/|omega_rel|. The seed's Eq. 12 variant is not used (notes 8.5).

#include "core/material.hpp"
#include "core/types.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <variant>

#ifdef __AVX__
#include <immintrin.h>
#endif

namespace kiln::contact {

/// Hertz normal + Mindlin tangential law; all parameters come from the material pair.
struct HertzMindlin {};

/// Linear spring-dashpot law with a global normal stiffness.
struct LinearSpringDashpot {
    double stiffness = 0;        ///< k_n (N/m)
    double tangential_ratio = 0; ///< k_t / k_n (-)
};

/// The normal/tangential law of a scene.
using ContactLaw = std::variant<HertzMindlin, LinearSpringDashpot>;

/// Rolling resistance models.
enum class RollingModel { none, constant_torque };

/// Everything that selects and tunes the contact model of a scene.
struct ContactModel {
    ContactLaw law = HertzMindlin{};           ///< normal and tangential law
    RollingModel rolling = RollingModel::none; ///< rolling resistance model
    bool clamp_normal_force = true;            ///< forbid attractive (negative) normal force
    /// True: e is the rebound ratio of a normal binary impact (the damping is tuned for the clamp);
    /// false: the damping is built from e directly (the LIGGGHTS convention), which gives the
    /// rebound ratio e only without the clamp.
    bool rebound_restitution = true;
};

/// Geometry and kinematics of one contact, world frame. Index i is the body receiving `force`.
struct ContactInput {
    Vec3 n;         ///< unit normal pointing from body j to body i
    double overlap; ///< delta > 0 (m)
    double r_eff;   ///< effective radius R* (m)
    double m_eff;   ///< effective mass m* (kg)
    double lever_i; ///< distance from centre of i to the contact point (m)
    double lever_j; ///< distance from centre of j to the contact point (m)
    Vec3 v_rel;     ///< v_i - v_j of the centres (m/s)
    Vec3 omega_i;   ///< angular velocity of i (rad/s)
    Vec3 omega_j;   ///< angular velocity of j (rad/s)
};

/// Result of one contact evaluation, world frame.
struct ContactOutput {
    Vec3 force;            ///< force on i (N); j receives -force
    Vec3 torque_i;         ///< torque on i about its centre (N m)
    Vec3 torque_j;         ///< torque on j about its centre (N m)
    double normal_force;   ///< signed normal force magnitude on i along n (N)
    double elastic_energy; ///< energy stored in the normal spring (J)
};

namespace lanes {

// The law's operations on one contact (double) or on several at once (a GCC/Clang vector type,
// whose comparisons give lane masks), so that the law below is written once for both. Each is
// exact or correctly rounded, so it gives the same bits per lane for either type; the compiler may
// still fuse the law's products and sums into different multiply-adds (round-off only).

/// a (the second argument only selects the type).
inline double splat(double a, double /*type*/) {
    return a;
}
/// a where m, else b.
inline double select(bool m, double a, double b) {
    return m ? a : b;
}
/// Square root.
inline double vsqrt(double a) {
    return std::sqrt(a);
}
/// Absolute value.
inline double vabs(double a) {
    return std::abs(a);
}
/// a in every lane of a vector of type T.
template <class T> T splat(double a, T /*type*/) {
    return a - T{};
}
/// Per lane: a where the mask m is set, else b.
template <class M, class T> T select(M m, T a, T b) {
    return m ? a : b;
}
#ifdef __AVX__
/// Four doubles, one contact per lane (the GCC/Clang vector type behind __m256d).
using V4 = double __attribute__((vector_size(32)));
/// Square root per lane.
inline V4 vsqrt(V4 a) {
    return _mm256_sqrt_pd(a);
}
/// Absolute value per lane (sign bit cleared, as std::abs).
inline V4 vabs(V4 a) {
    return _mm256_andnot_pd(_mm256_set1_pd(-0.0), a);
}
#endif
/// std::max(a, b): a unless a < b.
template <class T> T vmax(T a, T b) {
    return select(a < b, b, a);
}
/// True when the mask m is set (one contact).
inline bool any(bool m) {
    return m;
}
#ifdef __AVX__
/// True when the mask m is set in any lane (four contacts).
template <class M> bool any(M m) {
    return _mm256_movemask_pd(_mm256_castsi256_pd(reinterpret_cast<__m256i>(m))) != 0;
}
#endif

} // namespace lanes

namespace detail {

template <class T> struct Stiffness {
    T kn;     // normal secant stiffness, F_el = kn * delta (N/m)
    T gn;     // normal damping coefficient (kg/s), >= 0
    T kt;     // tangential stiffness (N/m)
    T gt;     // tangential damping coefficient (kg/s), >= 0
    T energy; // elastic energy of the normal spring (J)
};

// With `shared_root`, g_t = g_n sqrt(S_t / S_n) = g_n damping_ratio (one square root fewer).
template <bool shared_root, class T>
inline Stiffness<T> stiffness(const HertzMindlin&, T e_star, T g_star, T beta, T r_eff, T m_eff,
                              T overlap, T damping_ratio) {
    using lanes::vsqrt;
    const T a = vsqrt(r_eff * overlap); // contact radius (m)
    const T sn = 2.0 * e_star * a;
    const T st = 8.0 * g_star * a;
    constexpr double k56 = 1.8257418583505538; // 2 sqrt(5/6)
    const T kn = 2.0 / 3.0 * sn;               // 4/3 E* sqrt(R* delta)
    const T gn = -k56 * beta * vsqrt(sn * m_eff);
    if constexpr (shared_root) {
        return {kn, gn, st, gn * damping_ratio, 0.4 * kn * overlap * overlap};
    }
    return {kn, gn, st, -k56 * beta * vsqrt(st * m_eff), 0.4 * kn * overlap * overlap};
}

template <bool shared_root, class T>
inline Stiffness<T> stiffness(const LinearSpringDashpot& law, T, T, T beta, T, T m_eff, T overlap,
                              T) {
    using lanes::splat;
    return {splat(law.stiffness, beta), -2.0 * beta * lanes::vsqrt(m_eff * law.stiffness),
            splat(law.tangential_ratio * law.stiffness, beta), splat(0.0, beta),
            0.5 * law.stiffness * overlap * overlap};
}

} // namespace detail

/// Normal-force floor of a model: 0 when clamped, -inf otherwise (N).
inline double floor_of(const ContactModel& m) {
    return m.clamp_normal_force ? 0.0 : -std::numeric_limits<double>::infinity();
}
/// 1 when the model has rolling resistance, else 0.
inline double rolling_of(const ContactModel& m) {
    return m.rolling == RollingModel::constant_torque ? 1.0 : 0.0;
}

/// B contacts in structure-of-arrays form (world frame), the layout the pair kernel vectorises.
/// Index [component][contact] for vectors. Inputs as in ContactInput and PairProperties; `s` is the
/// tangential history, updated in place.
template <std::size_t B> struct ContactBlock {
    double n[3][B], overlap[B], r_eff[B], m_eff[B], lever_i[B], lever_j[B]; // geometry
    double v[3][B], wi[3][B], wj[3][B];                                     // kinematics
    double e_star[B], g_star[B], beta[B], mu[B], mu_roll[B];                // pair properties
    double s[3][B];                                                         // history, in/out
    double f[3][B], ti[3][B], tj[3][B], fn[B], energy[B];                   // results

    /// Copies the pair properties of contact b.
    void set_pair(std::size_t b, const PairProperties& p) {
        e_star[b] = p.effective_modulus;
        g_star[b] = p.effective_shear;
        beta[b] = p.beta;
        mu[b] = p.friction;
        mu_roll[b] = p.rolling_friction;
    }
};

/// One contact (T = double) or several side by side (T a vector type, one contact per lane): the
/// inputs of ContactBlock, world frame, with the history s updated in place and the results.
template <class T> struct ContactLanes {
    T n[3], overlap, r_eff, m_eff, lever_i, lever_j; // geometry
    T v[3], wi[3], wj[3];                            // kinematics
    T e_star, g_star, beta, mu, mu_roll;             // pair properties
    T damping_ratio; // sqrt(4 G*/E*), g_t / g_n of Hertz-Mindlin; read by `shared_damping_root`
    // Centre difference d (m, world, parallel to n) and 1 / |d|^2 (1/m^2); read by
    // `project_by_distance` only.
    T d[3], inv_d2;
    T s[3];                           // history, in/out
    T f[3], ti[3], tj[3], fn, energy; // results
};

/// Variants of evaluate_lanes chosen at compile time.
enum LaneVariant : unsigned {
    /// Branch-free (the loops over blocks vectorise only so).
    branch_free = 0,
    /// No rolling resistance term: only when `rolling` is 0 (the term is then +-0).
    without_rolling = 1,
    /// The Coulomb cap (a square root and two divisions) is computed only when a lane slides: one
    /// branch per call, for the register path, where the divider is the busiest unit.
    cap_when_sliding = 2,
    /// Hertz-Mindlin's tangential damping from the normal one times `damping_ratio` (set by the
    /// caller): one square root fewer, other round-off (not the same bits as the others).
    shared_damping_root = 4,
    /// The history is projected on the tangent plane with the centre difference d and 1/|d|^2
    /// (set by the caller) instead of n: those are known before the square root of the distance,
    /// so the history's chain starts earlier (other round-off).
    project_by_distance = 8,
    /// Every lane has friction (mu > 0, set by the caller): the products by the friction switch,
    /// which is then 1, are left out (exact either way).
    with_friction = 16,
};

/// Evaluates the law on c; written without branches (variant `branch_free`), so that it runs on
/// vector lanes and a loop over the contacts of a block vectorises. This is the single
/// implementation of the laws above; `evaluate_block` and `evaluate` wrap it. `fn_floor` is 0 when
/// the normal force is clamped, -inf otherwise; `rolling` is 1 with rolling resistance, 0 without
/// (scalars, so the loop carries no flag loads).
template <unsigned variant = branch_free, class Law, class T>
[[gnu::always_inline]] inline void evaluate_lanes(const Law& law, double fn_floor, double rolling,
                                                  ContactLanes<T>& c, double dt) {
    using lanes::select;
    using lanes::vabs;
    using lanes::vsqrt;
    const T zero = lanes::splat(0.0, c.overlap);
    const T one = lanes::splat(1.0, c.overlap);
    const detail::Stiffness<T> k = detail::stiffness<(variant & shared_damping_root) != 0>(
        law, c.e_star, c.g_star, c.beta, c.r_eff, c.m_eff, c.overlap, c.damping_ratio);
    const T n0 = c.n[0];
    const T n1 = c.n[1];
    const T n2 = c.n[2];
    const T vn = c.v[0] * n0 + c.v[1] * n1 + c.v[2] * n2;
    T fn = k.kn * c.overlap - k.gn * vn;
    fn = lanes::vmax(fn, lanes::splat(fn_floor, fn));

    // Tangential velocity of the contact point of i relative to j: v - (l_i w_i + l_j w_j) x n.
    const T w0 = c.lever_i * c.wi[0] + c.lever_j * c.wj[0];
    const T w1 = c.lever_i * c.wi[1] + c.lever_j * c.wj[1];
    const T w2 = c.lever_i * c.wi[2] + c.lever_j * c.wj[2];
    const T vc0 = c.v[0] - (w1 * n2 - w2 * n1);
    const T vc1 = c.v[1] - (w2 * n0 - w0 * n2);
    const T vc2 = c.v[2] - (w0 * n1 - w1 * n0);
    const T vcn = vc0 * n0 + vc1 * n1 + vc2 * n2;
    const T vt0 = vc0 - vcn * n0;
    const T vt1 = vc1 - vcn * n1;
    const T vt2 = vc2 - vcn * n2;

    // History: rotate into the tangent plane keeping its length, then add this step's slip.
    T s0 = c.s[0];
    T s1 = c.s[1];
    T s2 = c.s[2];
    const T len2 = s0 * s0 + s1 * s1 + s2 * s2;
    if constexpr ((variant & project_by_distance) != 0) {
        // s - (s.d) d / |d|^2, the same projection as s - (s.n) n.
        const T sd = (s0 * c.d[0] + s1 * c.d[1] + s2 * c.d[2]) * c.inv_d2;
        s0 -= sd * c.d[0];
        s1 -= sd * c.d[1];
        s2 -= sd * c.d[2];
    } else {
        const T sn = s0 * n0 + s1 * n1 + s2 * n2;
        s0 -= sn * n0;
        s1 -= sn * n1;
        s2 -= sn * n2;
    }
    const T new2 = s0 * s0 + s1 * s1 + s2 * s2;
    // Square roots and divisions are taken of safe arguments and selected afterwards: no branches.
    const T keep_raw = vsqrt(len2 / select(new2 > zero, new2, one));
    const T keep = select(new2 > zero, keep_raw, one);
    s0 = s0 * keep + vt0 * dt;
    s1 = s1 * keep + vt1 * dt;
    s2 = s2 * keep + vt2 * dt;
    T ft0 = -k.kt * s0 - k.gt * vt0;
    T ft1 = -k.kt * s1 - k.gt * vt1;
    T ft2 = -k.kt * s2 - k.gt * vt2;

    // Coulomb: when sliding, cap the force and reset the spring so it carries exactly the cap.
    // Without friction there is no spring and no history.
    const T ftsq = ft0 * ft0 + ft1 * ft1 + ft2 * ft2;
    const T cap = c.mu * vabs(fn);
    const auto slide = ftsq > cap * cap;
    const T on = select(c.mu > zero, one, zero);
    if ((variant & cap_when_sliding) != 0 && !lanes::any(slide)) {
        // What the selects below give when no lane slides (scale = on), without the divider.
        if constexpr ((variant & with_friction) == 0) {
            ft0 *= on;
            ft1 *= on;
            ft2 *= on;
            s0 *= on;
            s1 *= on;
            s2 *= on;
        }
        c.s[0] = s0;
        c.s[1] = s1;
        c.s[2] = s2;
    } else {
        const T capped = cap / vsqrt(select(ftsq > zero, ftsq, one));
        const T scale = on * select(slide, capped, one);
        ft0 *= scale;
        ft1 *= scale;
        ft2 *= scale;
        const T inv_kt = 1.0 / k.kt;
        c.s[0] = on * select(slide, -ft0 * inv_kt, s0);
        c.s[1] = on * select(slide, -ft1 * inv_kt, s1);
        c.s[2] = on * select(slide, -ft2 * inv_kt, s2);
    }
    c.f[0] = fn * n0 + ft0;
    c.f[1] = fn * n1 + ft1;
    c.f[2] = fn * n2 + ft2;
    const T nxf0 = n1 * ft2 - n2 * ft1;
    const T nxf1 = n2 * ft0 - n0 * ft2;
    const T nxf2 = n0 * ft1 - n1 * ft0;

    c.fn = fn;
    c.energy = k.energy;
    if constexpr ((variant & without_rolling) != 0) {
        c.ti[0] = -c.lever_i * nxf0;
        c.ti[1] = -c.lever_i * nxf1;
        c.ti[2] = -c.lever_i * nxf2;
        c.tj[0] = -c.lever_j * nxf0;
        c.tj[1] = -c.lever_j * nxf1;
        c.tj[2] = -c.lever_j * nxf2;
        return;
    }
    // Rolling resistance, constant directional torque.
    const T wr0 = c.wi[0] - c.wj[0];
    const T wr1 = c.wi[1] - c.wj[1];
    const T wr2 = c.wi[2] - c.wj[2];
    const T wn = vsqrt(wr0 * wr0 + wr1 * wr1 + wr2 * wr2);
    const T tiny = lanes::splat(1e-12, wn);
    const T mr_raw = -rolling * c.mu_roll * c.r_eff * vabs(fn) / select(wn > tiny, wn, one);
    const T mr = select(wn > tiny, mr_raw, zero);
    c.ti[0] = -c.lever_i * nxf0 + mr * wr0;
    c.ti[1] = -c.lever_i * nxf1 + mr * wr1;
    c.ti[2] = -c.lever_i * nxf2 + mr * wr2;
    c.tj[0] = -c.lever_j * nxf0 - mr * wr0;
    c.tj[1] = -c.lever_j * nxf1 - mr * wr1;
    c.tj[2] = -c.lever_j * nxf2 - mr * wr2;
}

/// Evaluates contact b of a block (evaluate_lanes on one contact); a loop over b vectorises.
template <class Law, std::size_t B>
[[gnu::always_inline]] inline void evaluate_block(const Law& law, double fn_floor, double rolling,
                                                  ContactBlock<B>& c, std::size_t b, double dt) {
    ContactLanes<double> l;
    l.damping_ratio = 0.0; // not read by this variant
    for (int q = 0; q < 3; ++q) {
        l.n[q] = c.n[q][b];
        l.v[q] = c.v[q][b];
        l.wi[q] = c.wi[q][b];
        l.wj[q] = c.wj[q][b];
        l.s[q] = c.s[q][b];
    }
    l.overlap = c.overlap[b];
    l.r_eff = c.r_eff[b];
    l.m_eff = c.m_eff[b];
    l.lever_i = c.lever_i[b];
    l.lever_j = c.lever_j[b];
    l.e_star = c.e_star[b];
    l.g_star = c.g_star[b];
    l.beta = c.beta[b];
    l.mu = c.mu[b];
    l.mu_roll = c.mu_roll[b];
    evaluate_lanes(law, fn_floor, rolling, l, dt);
    for (int q = 0; q < 3; ++q) {
        c.s[q][b] = l.s[q];
        c.f[q][b] = l.f[q];
        c.ti[q][b] = l.ti[q];
        c.tj[q][b] = l.tj[q];
    }
    c.fn[b] = l.fn;
    c.energy[b] = l.energy;
}

/// Evaluates one contact and updates its tangential history `shear` (m, world, on i relative to j).
template <class Law>
[[gnu::always_inline]] inline ContactOutput
evaluate(const Law& law, const ContactModel& model, const PairProperties& p, const ContactInput& in,
         Vec3& shear, double dt) {
    ContactBlock<1> c;
    for (int a = 0; a < 3; ++a) {
        c.n[a][0] = in.n[a];
        c.v[a][0] = in.v_rel[a];
        c.wi[a][0] = in.omega_i[a];
        c.wj[a][0] = in.omega_j[a];
        c.s[a][0] = shear[a];
    }
    c.overlap[0] = in.overlap;
    c.r_eff[0] = in.r_eff;
    c.m_eff[0] = in.m_eff;
    c.lever_i[0] = in.lever_i;
    c.lever_j[0] = in.lever_j;
    c.set_pair(0, p);
    evaluate_block(law, floor_of(model), rolling_of(model), c, 0, dt);
    ContactOutput out;
    out.force = Vec3(c.f[0][0], c.f[1][0], c.f[2][0]);
    out.torque_i = Vec3(c.ti[0][0], c.ti[1][0], c.ti[2][0]);
    out.torque_j = Vec3(c.tj[0][0], c.tj[1][0], c.tj[2][0]);
    out.normal_force = c.fn[0];
    out.elastic_energy = c.energy[0];
    shear = Vec3(c.s[0][0], c.s[1][0], c.s[2][0]);
    return out;
}

} // namespace kiln::contact
