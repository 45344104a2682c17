#pragma once
// Contact force laws for two bodies touching at one point. A law is a small value type; the step loop
// dispatches on the variant once per step, so the per-contact code is a direct (inlined) call.
//
// Hertz-Mindlin: normal force after Hertz with the damping of Tsuji et al. (1992) written in the
// restitution-based form of the LIGGGHTS manual (gamma_n = -2 sqrt(5/6) beta sqrt(S_n m*),
// S_n = 2 E* sqrt(R* delta)), tangential spring after Mindlin, k_t = 8 G* sqrt(R* delta), with the
// shear modulus combination of Di Renzo & Di Maio (2004), G* = 1/((2-nu1)/G1 + (2-nu2)/G2). Oschmann
// (2019, Inv. VI/VII) prints (2 - nu^2)/G, which is a typo (notes/seed001_shape.md section 8.6).
//
// Linear spring-dashpot (Cundall & Strack 1979, as used in Oschmann 2019 Inv. I-IV, Table 1):
// F_n = k_n delta - gamma_n v_n with gamma_n = -2 beta sqrt(m* k_n), which gives exactly the
// prescribed restitution when the contact ends at delta = 0; tangential spring k_t = ratio * k_n with
// a Coulomb cap and no tangential damper (as in the seed).
//
// Rolling resistance: constant directional torque, model A of Ai et al. (2011),
// M_r = -mu_r R* |F_n| omega_rel/|omega_rel|. The seed's Eq. 12 variant is not used (notes 8.5).

#include "core/material.hpp"
#include "core/types.hpp"

#include <algorithm>
#include <cmath>
#include <variant>

namespace kiln::contact {

/// Hertz normal + Mindlin tangential law; all parameters come from the material pair.
struct HertzMindlin {};

/// Linear spring-dashpot law with a global normal stiffness.
struct LinearSpringDashpot {
    double stiffness = 0;         ///< k_n (N/m)
    double tangential_ratio = 0;  ///< k_t / k_n (-)
};

/// The normal/tangential law of a scene.
using ContactLaw = std::variant<HertzMindlin, LinearSpringDashpot>;

/// Rolling resistance models.
enum class RollingModel { none, constant_torque };

/// Everything that selects and tunes the contact model of a scene.
struct ContactModel {
    ContactLaw law = HertzMindlin{};             ///< normal and tangential law
    RollingModel rolling = RollingModel::none;   ///< rolling resistance model
    bool clamp_normal_force = true;              ///< forbid attractive (negative) normal force
};

/// Geometry and kinematics of one contact, world frame. Index i is the body receiving `force`.
struct ContactInput {
    Vec3 n;            ///< unit normal pointing from body j to body i
    double overlap;    ///< delta > 0 (m)
    double r_eff;      ///< effective radius R* (m)
    double m_eff;      ///< effective mass m* (kg)
    double lever_i;    ///< distance from centre of i to the contact point (m)
    double lever_j;    ///< distance from centre of j to the contact point (m)
    Vec3 v_rel;        ///< v_i - v_j of the centres (m/s)
    Vec3 omega_i;      ///< angular velocity of i (rad/s)
    Vec3 omega_j;      ///< angular velocity of j (rad/s)
};

/// Result of one contact evaluation, world frame.
struct ContactOutput {
    Vec3 force;         ///< force on i (N); j receives -force
    Vec3 torque_i;      ///< torque on i about its centre (N m)
    Vec3 torque_j;      ///< torque on j about its centre (N m)
    double normal_force; ///< signed normal force magnitude on i along n (N)
    double elastic_energy; ///< energy stored in the normal spring (J)
};

namespace detail {

/// Rotates the shear history into the current tangent plane, keeping its length.
inline void project_shear(Vec3& shear, const Vec3& n) {
    const double len2 = shear.squaredNorm();
    if (len2 == 0.0) {
        return;
    }
    shear -= shear.dot(n) * n;
    const double new2 = shear.squaredNorm();
    if (new2 > 0.0) {
        shear *= std::sqrt(len2 / new2);
    }
}

struct Stiffness {
    double kn;      // normal secant stiffness, F_el = kn * delta (N/m)
    double gn;      // normal damping coefficient (kg/s), >= 0
    double kt;      // tangential stiffness (N/m)
    double gt;      // tangential damping coefficient (kg/s), >= 0
    double energy;  // elastic energy of the normal spring (J)
};

inline Stiffness stiffness(const HertzMindlin&, const PairProperties& p, const ContactInput& c) {
    const double a = std::sqrt(c.r_eff * c.overlap); // contact radius (m)
    const double sn = 2.0 * p.effective_modulus * a;
    const double st = 8.0 * p.effective_shear * a;
    constexpr double k56 = 1.8257418583505538; // 2 sqrt(5/6)
    const double kn = 2.0 / 3.0 * sn;           // 4/3 E* sqrt(R* delta)
    return {kn, -k56 * p.beta * std::sqrt(sn * c.m_eff), st, -k56 * p.beta * std::sqrt(st * c.m_eff),
            0.4 * kn * c.overlap * c.overlap};
}

inline Stiffness stiffness(const LinearSpringDashpot& law, const PairProperties& p,
                           const ContactInput& c) {
    return {law.stiffness, -2.0 * p.beta * std::sqrt(c.m_eff * law.stiffness),
            law.tangential_ratio * law.stiffness, 0.0,
            0.5 * law.stiffness * c.overlap * c.overlap};
}

} // namespace detail

/// Evaluates one contact and updates its tangential history `shear` (m, world, on i relative to j).
template <class Law>
[[gnu::always_inline]] inline ContactOutput evaluate(const Law& law, const ContactModel& model, const PairProperties& p,
                              const ContactInput& c, Vec3& shear, double dt) {
    const detail::Stiffness s = detail::stiffness(law, p, c);
    const double vn = c.v_rel.dot(c.n);
    double fn = s.kn * c.overlap - s.gn * vn;
    if (model.clamp_normal_force && fn < 0.0) {
        fn = 0.0;
    }
    ContactOutput out;
    out.normal_force = fn;
    out.elastic_energy = s.energy;
    out.force = fn * c.n;
    out.torque_i.setZero();
    out.torque_j.setZero();

    // Tangential velocity of the contact point of i relative to j.
    const Vec3 w = c.lever_i * c.omega_i + c.lever_j * c.omega_j;
    const Vec3 vc = c.v_rel - w.cross(c.n);
    const Vec3 vt = vc - vc.dot(c.n) * c.n;

    if (p.friction > 0.0) {
        detail::project_shear(shear, c.n);
        shear += vt * dt;
        Vec3 ft = -s.kt * shear - s.gt * vt;
        const double ft2 = ft.squaredNorm();
        const double cap = p.friction * std::abs(fn);
        if (ft2 > cap * cap) {
            // Sliding: cap the force and reset the spring so it carries exactly the capped force.
            ft *= cap / std::sqrt(ft2);
            shear = -(ft + s.gt * vt) / s.kt;
        }
        out.force += ft;
        const Vec3 nxf = c.n.cross(ft);
        out.torque_i = -c.lever_i * nxf;
        out.torque_j = -c.lever_j * nxf;
    } else {
        shear.setZero();
    }

    if (model.rolling == RollingModel::constant_torque && p.rolling_friction > 0.0) {
        const Vec3 wr = c.omega_i - c.omega_j;
        const double wn = wr.norm();
        if (wn > 1e-12) {
            const Vec3 mr = -(p.rolling_friction * c.r_eff * std::abs(fn) / wn) * wr;
            out.torque_i += mr;
            out.torque_j -= mr;
        }
    }
    return out;
}

} // namespace kiln::contact
