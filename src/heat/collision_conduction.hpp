#pragma once
// Heat exchanged during a short elastic impact of two spheres (Sun & Chen 1988, Int. J. Heat Mass
// Transfer 31, 969, with the correction factor of Zhou, Yu & Horio 2008, Chem. Eng. J. 139, 510;
// seed: Oschmann & Kruggel-Emden 2018, Inv. VII eqs. 17-22, L2493-2507):
//
//   E_ij = c' (T_j - T_i) pi r_c^2 t_c^(1/2) / [ (rho_i c_i k_i)^(-1/2) + (rho_j c_j k_j)^(-1/2) ]
//
// is the heat (J) that enters i during one impact of duration t_c with maximum contact radius r_c.
// The seed prints this as a heat rate Q_ij (notes §8): with t_c^(+1/2) it has units of J, i.e. it
// is the energy per collision (Sun & Chen's form); the mean rate over the impact is E_ij / t_c.
//   c' = 0.435 (sqrt(c2^2 - 4 c1 (c3 - Fo)) - c2) / c1,  Fo = alpha t_c / r_c^2 (a Fourier number;
//   the seed calls it "the thermal diffusivity"), c1..c3 quadratics in rho_hat = rho_i c_i /
//   (rho_j c_j) (Inv. VII eqs. 19-21).
//   t_c = 2.94 (15 m* / (16 E*))^(2/5) (R* v)^(-1/5): the Hertz impact duration (Johnson 1985,
//   §11.1: t_c = 2.94 delta_max / v). The seed writes (5 m / (4 E_ij))^(2/5); that is the same
//   number when its E_ij is the force constant of F = E_ij sqrt(R) delta^(3/2), i.e. 4/3 E*.
//
// Our choices: the seed gives c' for an ordered pair (rho_hat and alpha of i); kiln averages c'
// over both orders (alpha of i with rho_hat_ij, alpha of j with rho_hat_ji), so the exchange is
// symmetric and conservative; equal materials give the seed's c' exactly.
// Switching rule (seed L2507): when t_c < the contact duration t_d of the simulation, the impact
// heat is exchanged during t_c and the static law (contact_conduction.hpp) for the remaining
// t_d - t_c; otherwise only the impact heat (collision_contact_heat). In the run loop
// (thermal::ThermalSystem, `[heat] collision_conduction`) every contact onset recorded by the
// force loop exchanges impact_heat once, lagged; the static law acts on sampled contacts as before.

namespace kiln::heat {

/// Thermal data of one side of an impact.
struct ImpactSide {
    double density = 0;       ///< rho (kg/m^3)
    double specific_heat = 0; ///< c_p (J/(kg K))
    double conductivity = 0;  ///< k (W/(m K))
};

/// Hertz impact duration t_c = 2.94 (15 m* / (16 E*))^(2/5) (R* v)^(-1/5) (s) for effective mass
/// `m_eff` (kg), effective modulus `e_eff` = 1 / ((1 - nu_i^2)/E_i + (1 - nu_j^2)/E_j) (Pa),
/// effective radius `r_eff` (m) and normal approach speed `speed` (m/s). Throws InputError for
/// non-positive arguments.
[[nodiscard]] double hertz_impact_duration(double m_eff, double e_eff, double r_eff, double speed);

/// Largest Hertz contact radius of the same impact, r_c = sqrt(R* delta_max) (m), with
/// delta_max = (15 m* v^2 / (16 E* sqrt(R*)))^(2/5) (Johnson 1985, §11.1; t_c = 2.94 delta_max /
/// v). Same arguments and errors as hertz_impact_duration.
[[nodiscard]] double hertz_impact_radius(double m_eff, double e_eff, double r_eff, double speed);

/// Zhou et al.'s factor c' (-) for side i against side j, impact duration `t_c` (s) and maximum
/// contact radius `r_c` (m), with Fo = alpha_i t_c / r_c^2 (Inv. VII eq. 18-21, ordered as
/// printed). Throws InputError for non-positive arguments or a negative discriminant.
[[nodiscard]] double impact_correction(const ImpactSide& i, const ImpactSide& j, double t_c,
                                       double r_c);

/// Heat (J) that enters i during one impact with j: the Sun-Chen energy with c' averaged over both
/// orders (symmetric: the heat into j is the negative), for temperatures `t_i`, `t_j` (K).
[[nodiscard]] double impact_heat(const ImpactSide& i, const ImpactSide& j, double t_c, double r_c,
                                 double t_i, double t_j);

/// Heat (J) into i over a contact of simulated duration `t_d` (s): impact_heat for the impact and,
/// when t_d > t_c, the static law `static_conductance` (W/K) for the remaining t_d - t_c (seed
/// L2507). Temperatures held at `t_i`, `t_j` (K).
[[nodiscard]] double collision_contact_heat(const ImpactSide& i, const ImpactSide& j, double t_c,
                                            double r_c, double t_d, double static_conductance,
                                            double t_i, double t_j);

} // namespace kiln::heat
