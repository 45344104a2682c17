#include "dynamics/time_step.hpp"

#include <cmath>
#include <numbers>

namespace kiln::dynamics {

double rayleigh_time_step(double radius, double density, double shear_modulus, double poisson) {
    return std::numbers::pi * radius * std::sqrt(density / shear_modulus) /
           (0.1631 * poisson + 0.8766);
}

double hertz_contact_time(double m_eff, double r_eff, double e_eff, double impact_speed) {
    return 2.87 * std::pow(m_eff * m_eff / (r_eff * e_eff * e_eff * impact_speed), 0.2);
}

double linear_contact_time(double m_eff, double stiffness, double beta) {
    const double w0 = stiffness / m_eff;
    const double g = -2.0 * beta * std::sqrt(m_eff * stiffness) / (2.0 * m_eff);
    return std::numbers::pi / std::sqrt(w0 - g * g);
}

} // namespace kiln::dynamics
