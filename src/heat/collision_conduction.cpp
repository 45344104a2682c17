#include "heat/collision_conduction.hpp"

#include "core/error.hpp"

#include <cmath>
#include <numbers>

namespace kiln::heat {

namespace {

void check_side(const ImpactSide& s) {
    if (!(s.density > 0.0) || !(s.specific_heat > 0.0) || !(s.conductivity > 0.0)) {
        throw InputError("heat: collision conduction needs rho, c_p and k > 0 on both sides");
    }
}

} // namespace

double hertz_impact_duration(double m_eff, double e_eff, double r_eff, double speed) {
    if (!(m_eff > 0.0) || !(e_eff > 0.0) || !(r_eff > 0.0) || !(speed > 0.0)) {
        throw InputError("heat: the impact duration needs m*, E*, R* and the speed > 0");
    }
    return 2.94 * std::pow(15.0 * m_eff / (16.0 * e_eff), 0.4) * std::pow(r_eff * speed, -0.2);
}

double hertz_impact_radius(double m_eff, double e_eff, double r_eff, double speed) {
    if (!(m_eff > 0.0) || !(e_eff > 0.0) || !(r_eff > 0.0) || !(speed > 0.0)) {
        throw InputError("heat: the impact radius needs m*, E*, R* and the speed > 0");
    }
    const double delta_max =
        std::pow(15.0 * m_eff * speed * speed / (16.0 * e_eff * std::sqrt(r_eff)), 0.4);
    return std::sqrt(r_eff * delta_max);
}

double impact_correction(const ImpactSide& i, const ImpactSide& j, double t_c, double r_c) {
    check_side(i);
    check_side(j);
    if (!(t_c > 0.0) || !(r_c > 0.0)) {
        throw InputError("heat: collision conduction needs t_c > 0 (s) and r_c > 0 (m)");
    }
    const double rho_hat = i.density * i.specific_heat / (j.density * j.specific_heat);
    const double c1 = -2.300 * rho_hat * rho_hat + 8.909 * rho_hat - 4.235;
    const double c2 = 8.169 * rho_hat * rho_hat - 33.770 * rho_hat + 24.885;
    const double c3 = -5.785 * rho_hat * rho_hat + 24.464 * rho_hat - 20.511;
    const double fourier = i.conductivity / (i.density * i.specific_heat) * t_c / (r_c * r_c);
    const double disc = c2 * c2 - 4.0 * c1 * (c3 - fourier);
    if (!(disc >= 0.0) || c1 == 0.0) {
        throw InputError("heat: Zhou et al.'s collision correction is undefined for this heat "
                         "capacity ratio and Fourier number (negative discriminant)");
    }
    return 0.435 * (std::sqrt(disc) - c2) / c1;
}

double impact_heat(const ImpactSide& i, const ImpactSide& j, double t_c, double r_c, double t_i,
                   double t_j) {
    const double c = 0.5 * (impact_correction(i, j, t_c, r_c) + impact_correction(j, i, t_c, r_c));
    const double effusivity = 1.0 / std::sqrt(i.density * i.specific_heat * i.conductivity) +
                              1.0 / std::sqrt(j.density * j.specific_heat * j.conductivity);
    return c * (t_j - t_i) * std::numbers::pi * r_c * r_c * std::sqrt(t_c) / effusivity;
}

double collision_contact_heat(const ImpactSide& i, const ImpactSide& j, double t_c, double r_c,
                              double t_d, double static_conductance, double t_i, double t_j) {
    if (!(t_d >= 0.0) || !(static_conductance >= 0.0)) {
        throw InputError("heat: collision conduction needs t_d >= 0 (s) and H >= 0 (W/K)");
    }
    double q = impact_heat(i, j, t_c, r_c, t_i, t_j);
    if (t_d > t_c) {
        q += static_conductance * (t_j - t_i) * (t_d - t_c);
    }
    return q;
}

} // namespace kiln::heat
