// ThermalSystem: the particle surface to the surroundings: convection (lagged stagnation
// correction of turning bodies), radiation to the ambient, and the lumped particles' update.

#include "thermal/thermal_system_detail.hpp"

#include "heat/convection.hpp"
#include "heat/radiation.hpp"

#include <algorithm>
#include <cmath>

namespace kiln::thermal {

using namespace detail;

void ThermalSystem::prepare_surface(const dynamics::System& sys, double& worst) {
    const ParticleStore& p = sys.particles();
    // Bodies under f(theta): h per face for the current orientation (flow direction turned into
    // the body frame with q^-1); the lagged part (G_b(h f) - G_b(h)) / C_cell joins the lag limit.
    // Resolved spheres whose grid has turned (sphere_rotation): the same against the world-axes
    // distribution their template matrix holds.
    // Resolved particles radiating to the ambient: the lagged face rate's linearised conductance
    // A / (1 / (4 eps sigma T^3) + d / k) at the hotter of node and ambient joins the lag limit.
    const double t_rad = spec_.radiation_temperature;
    radiating_.assign(static_cast<std::size_t>(pool_.size()), 0);
    if (!std::isnan(t_rad)) {
        for (int slot = 0; slot < pool_.size(); ++slot) {
            const Template& t = *templates_[static_cast<std::size_t>(
                pool_template_[static_cast<std::size_t>(slot)])];
            // Emissivity times each face's share of the view that reaches the ambient.
            const double e = spec_.materials[static_cast<std::size_t>(t.material)].emissivity;
            const double* view = face_view_.data() + face_offset_[static_cast<std::size_t>(slot)];
            const std::size_t nb = t.grid->boundary.size();
            if (!(e > 0.0) || std::none_of(view, view + nb, [](double v) { return v > 0.0; })) {
                continue;
            }
            radiating_[static_cast<std::size_t>(slot)] = 1;
            const std::span<const double> f = pool_.field(slot);
            for (std::size_t b = 0; b < nb; ++b) {
                const heat::BoundaryFace& face = t.grid->boundary[b];
                const double eps = e * view[b];
                if (!(eps > 0.0)) {
                    continue;
                }
                const auto cell = static_cast<std::size_t>(face.cell);
                const double tm = std::max(f[cell], t_rad);
                const double hr = 4.0 * eps * heat::stefan_boltzmann * tm * tm * tm;
                const double g = face.area / (1.0 / hr + face.distance / t.props.conductivity);
                worst = std::max(worst, g / t.capacity[cell]);
            }
        }
    }
    stagnant_.assign(static_cast<std::size_t>(pool_.size()), 0);
    for (std::size_t i = 0; i < p.size(); ++i) {
        const Record& r = by_id_[static_cast<std::size_t>(p.id[i])];
        if (r.templ < 0) {
            continue;
        }
        const Template& t = *templates_[static_cast<std::size_t>(r.templ)];
        const Quat q = grid_orientation(p, i, r);
        if (!t.turning_stagnation &&
            !(t.sphere_stagnation && q.coeffs() != Quat::Identity().coeffs())) {
            continue;
        }
        const std::vector<double> hf = heat::stagnation_distribution(
            *t.grid, q.conjugate() * (-spec_.flow_direction), spec_.heat_transfer_coefficient);
        const std::size_t off = face_offset_[static_cast<std::size_t>(r.slot)];
        for (std::size_t b = 0; b < hf.size(); ++b) {
            stag_h_[off + b] = hf[b];
            const heat::BoundaryFace& f = t.grid->boundary[b];
            const double h_matrix = t.h_face.size() == 1 ? t.h_face[0] : t.h_face[b];
            const double dg = heat::surface_conductance(f, hf[b], t.props.conductivity) -
                              heat::surface_conductance(f, h_matrix, t.props.conductivity);
            worst = std::max(worst, std::abs(dg) / t.capacity[static_cast<std::size_t>(f.cell)]);
        }
        stagnant_[static_cast<std::size_t>(r.slot)] = 1;
    }
}

void ThermalSystem::step_lumped(double dt_sub) {
    const double t_rad = spec_.radiation_temperature;
    // Lumped particles: backward Euler with implicit convection (h mean: f(theta) averages
    // to 1 over a sphere).
    // Radiation to the ambient linearised about T^n, eps sigma A (T_a^4 - T^n^4 - 4 T^n^3
    // (T^(n+1) - T^n)): implicit in the linear part, so never below T_a when cooling
    // ((T_a^4 + 3 T^4) / (4 T^3) >= T_a), first order in dt like the rest.
    const double h = spec_.heat_transfer_coefficient;
    const double ta4 = std::isnan(t_rad) ? 0.0 : t_rad * t_rad * t_rad * t_rad;
    for (std::size_t k = 0; k < lumped_.size(); ++k) {
        const double c = lumped_capacity_[k];
        const double a = lumped_area_[k];
        const double t_old = lumped_[k];
        const double gr = std::isnan(t_rad) ? 0.0
                                            : lumped_emissivity_[k] * lumped_view_[k] *
                                                  heat::stefan_boltzmann * a;
        const double t3 = t_old * t_old * t_old;
        const double t_new =
            (c * t_old + dt_sub * (h * a * spec_.ambient_temperature + spec_.flux * a +
                                   lumped_rate_[k] + gr * (ta4 + 3.0 * t3 * t_old))) /
            (c + dt_sub * (h * a + 4.0 * gr * t3));
        external_heat_ += dt_sub * (h * a * (spec_.ambient_temperature - t_new) + spec_.flux * a +
                                    gr * (ta4 + 3.0 * t3 * t_old - 4.0 * t3 * t_new));
        lumped_[k] = t_new;
    }
}

void ThermalSystem::add_surface_rates() {
    const double t_rad = spec_.radiation_temperature;
    const double ta4 = std::isnan(t_rad) ? 0.0 : t_rad * t_rad * t_rad * t_rad;
    // Bodies under f(theta): the lagged convection correction from the field at the start of
    // the sub-step, added to the contact rates (and booked as external heat below).
    const double t_inf = spec_.ambient_temperature;
    const double h_mean = spec_.heat_transfer_coefficient;
    for (int slot = 0; slot < pool_.size(); ++slot) {
        if (stagnant_[static_cast<std::size_t>(slot)] == 0) {
            continue;
        }
        const Template& t =
            *templates_[static_cast<std::size_t>(pool_template_[static_cast<std::size_t>(slot)])];
        const std::size_t off = face_offset_[static_cast<std::size_t>(slot)];
        const std::size_t nb = t.grid->boundary.size();
        const std::span<double> conv(conv_rate_.data() + off, nb);
        heat::lagged_convection(*t.grid, t.props.conductivity,
                                std::span<const double>(stag_h_.data() + off, nb),
                                t.sphere_stagnation ? std::span<const double>(t.h_face)
                                                    : std::span<const double>(&h_mean, 1),
                                std::span<const double>(&t_inf, 1), pool_.field(slot), conv);
        for (std::size_t b = 0; b < nb; ++b) {
            face_rate_[off + b] += conv[b];
        }
    }
    // Radiation to the ambient of resolved particles: per face eps sigma A (T_a^4 - T_s^4),
    // T_s from the surface balance with the node at the start of the sub-step (lagged; booked
    // as external heat below).
    for (int slot = 0; slot < pool_.size(); ++slot) {
        if (radiating_[static_cast<std::size_t>(slot)] == 0) {
            continue;
        }
        const Template& t =
            *templates_[static_cast<std::size_t>(pool_template_[static_cast<std::size_t>(slot)])];
        const double e = spec_.materials[static_cast<std::size_t>(t.material)].emissivity;
        const std::size_t off = face_offset_[static_cast<std::size_t>(slot)];
        const std::span<const double> f = pool_.field(slot);
        for (std::size_t b = 0; b < t.grid->boundary.size(); ++b) {
            const heat::BoundaryFace& face = t.grid->boundary[b];
            // This face's emissivity times its share of the view that reaches the ambient.
            const double eps = e * face_view_[off + b];
            if (!(eps > 0.0)) {
                rad_rate_[off + b] = 0.0; // the neighbours fill its whole view
                continue;
            }
            const double ts = heat::radiating_surface_temperature(
                f[static_cast<std::size_t>(face.cell)], face.distance, t.props.conductivity, eps,
                t_rad);
            const double q = eps * heat::stefan_boltzmann * face.area * (ta4 - ts * ts * ts * ts);
            rad_rate_[off + b] = q;
            face_rate_[off + b] += q;
        }
    }
}

} // namespace kiln::thermal
