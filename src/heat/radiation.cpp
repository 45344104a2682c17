#include "heat/radiation.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace kiln::heat {

double sphere_view_factor(double r_j, double distance) {
    if (!(r_j > 0.0) || !(distance > r_j)) {
        throw InputError("heat: sphere view factor needs R_j > 0 and a centre distance > R_j (m)");
    }
    const double x = r_j / distance;
    // 1 - sqrt(1 - x^2) written without cancellation for distant spheres.
    return 0.5 * x * x / (1.0 + std::sqrt(1.0 - x * x));
}

double pair_view_area(double r_i, double r_j, double distance) {
    const double a_i = 4.0 * std::numbers::pi * r_i * r_i;
    const double a_j = 4.0 * std::numbers::pi * r_j * r_j;
    return 0.5 *
           (a_i * sphere_view_factor(r_j, distance) + a_j * sphere_view_factor(r_i, distance));
}

double radiative_coefficient(double r_i, double r_j, double distance, double e_i, double e_j) {
    if (!(e_i >= 0.0 && e_i <= 1.0) || !(e_j >= 0.0 && e_j <= 1.0)) {
        throw InputError("heat: radiation needs emissivities 0 <= e <= 1");
    }
    if (!(r_i > 0.0) || !(r_j > 0.0)) {
        throw InputError("heat: radiation needs sphere radii > 0 (m)");
    }
    if (!(distance >= r_i + r_j)) {
        throw InputError("heat: radiation between spheres needs a centre distance >= R_i + R_j");
    }
    if (e_i == 0.0 || e_j == 0.0) {
        return 0.0;
    }
    const double a_i = 4.0 * std::numbers::pi * r_i * r_i;
    const double a_j = 4.0 * std::numbers::pi * r_j * r_j;
    const double af = pair_view_area(r_i, r_j, distance);
    const double resistance = (1.0 - e_i) / (e_i * a_i) + 1.0 / af + (1.0 - e_j) / (e_j * a_j);
    return stefan_boltzmann / resistance;
}

double radiative_conductance_bound(double coefficient, double t_i, double t_j) {
    const double t = std::max(t_i, t_j);
    return 4.0 * coefficient * t * t * t;
}

double radiating_surface_temperature(double t_node, double distance, double conductivity,
                                     double emissivity, double t_ambient) {
    if (!(distance > 0.0) || emissivity == 0.0) {
        return t_node;
    }
    const double g = conductivity / distance; // W/(m^2 K)
    const double es = emissivity * stefan_boltzmann;
    const double a4 = t_ambient * t_ambient * t_ambient * t_ambient;
    // f(T) = g (T - T_node) + es (T^4 - T_amb^4) is increasing and convex for T > 0: Newton from
    // T_node reaches the root monotonically after at most one step past it.
    double t = t_node;
    for (int it = 0; it < 100; ++it) {
        const double t3 = t * t * t;
        const double f = g * (t - t_node) + es * (t3 * t - a4);
        const double step = f / (g + 4.0 * es * t3);
        t -= step;
        if (std::abs(step) <= 1e-14 * std::abs(t)) {
            break;
        }
    }
    return t;
}

} // namespace kiln::heat
