#pragma once
// Critical time steps from material data.

namespace kiln::dynamics {

/// Rayleigh time step of a sphere of radius r (s): pi r sqrt(rho/G) / (0.1631 nu + 0.8766)
/// (Li, Xu and Thornton 2005, Powder Technol. 160:219).
double rayleigh_time_step(double radius, double density, double shear_modulus, double poisson);

/// Duration of a Hertz elastic impact (s), 2.87 (m*^2 / (R* E*^2 v))^(1/5) (Johnson 1985).
double hertz_contact_time(double m_eff, double r_eff, double e_eff, double impact_speed);

/// Duration of a damped linear spring contact (s), pi / sqrt(k/m* - (gamma/(2 m*))^2)
/// (Oschmann 2019, Eq. 5), with gamma = -2 beta sqrt(m* k).
double linear_contact_time(double m_eff, double stiffness, double beta);

} // namespace kiln::dynamics
