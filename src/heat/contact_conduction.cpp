#include "heat/contact_conduction.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>

namespace kiln::heat {

double softened_modulus_correction(double e_sim, double e_real) {
    if (!(e_sim > 0.0) || !(e_real > 0.0)) {
        throw InputError("heat: contact conduction needs Young's moduli E_sim, E_real > 0 (Pa)");
    }
    return std::pow(e_sim / e_real, 0.2);
}

namespace {

void check_radii(double overlap, double r_i, double r_j) {
    if (!(r_i > 0.0) || !(r_j > 0.0)) {
        throw InputError("heat: contact radius needs particle radii > 0 (m)");
    }
    if (!(overlap >= 0.0)) {
        throw InputError("heat: contact radius needs an overlap >= 0 (m)");
    }
}

} // namespace

double hertz_contact_radius(double overlap, double r_i, double r_j) {
    check_radii(overlap, r_i, r_j);
    const double r_eff = r_i * r_j / (r_i + r_j);
    return std::sqrt(r_eff * overlap);
}

double lens_contact_radius(double overlap, double r_i, double r_j) {
    check_radii(overlap, r_i, r_j);
    if (!(overlap < 2.0 * std::min(r_i, r_j))) {
        throw InputError("heat: lens contact radius needs an overlap < 2 min(R_i, R_j) (m)");
    }
    // Cap height of sphere i beyond the intersection plane, h_i = delta (2 R_j - delta) / (2 d)
    // with d the centre distance (free of the cancellation in the textbook form of the plane's
    // position, (d^2 + R_i^2 - R_j^2) / (2 d), for a large partner); a^2 = h_i (2 R_i - h_i).
    const double d = r_i + r_j - overlap;
    const double h = overlap * (2.0 * r_j - overlap) / (2.0 * d);
    return std::sqrt(std::max(h * (2.0 * r_i - h), 0.0));
}

double static_contact_conductance(double k_i, double k_j, double contact_radius,
                                  double correction) {
    if (!(k_i > 0.0) || !(k_j > 0.0)) {
        throw InputError("heat: contact conduction needs conductivities k > 0 (W/(m K))");
    }
    if (!(contact_radius >= 0.0)) {
        throw InputError("heat: contact conduction needs a contact radius >= 0 (m)");
    }
    if (!(correction > 0.0)) {
        throw InputError("heat: contact conduction needs a correction factor c > 0");
    }
    return 4.0 * correction * contact_radius / (1.0 / k_i + 1.0 / k_j);
}

double static_contact_conductance(double k_i, double k_j, double overlap, double r_i, double r_j,
                                  double e_sim, double e_real) {
    return static_contact_conductance(k_i, k_j, hertz_contact_radius(overlap, r_i, r_j),
                                      softened_modulus_correction(e_sim, e_real));
}

std::vector<int> contact_patches(const ThermalGrid& grid, const Vec3& point, const Vec3& normal,
                                 double contact_radius) {
    const double n_len = normal.norm();
    if (!(n_len > 0.0)) {
        throw InputError("heat: contact patches need a non-zero contact normal");
    }
    const Vec3 n = normal / n_len;
    std::vector<int> out;
    int nearest = -1;
    double nearest_d2 = std::numeric_limits<double>::infinity();
    for (std::size_t b = 0; b < grid.boundary.size(); ++b) {
        const BoundaryFace& f = grid.boundary[b];
        const Vec3 rel = f.centroid - point;
        const double d2 = rel.squaredNorm();
        if (d2 < nearest_d2) {
            nearest_d2 = d2;
            nearest = static_cast<int>(b);
        }
        if (f.area_normal.dot(n) <= 0.0) {
            continue;
        }
        const Vec3 lateral = rel - rel.dot(n) * n; // offset from the contact axis (m)
        if (lateral.norm() <= contact_radius) {
            out.push_back(static_cast<int>(b));
        }
    }
    if (out.empty() && nearest >= 0) {
        out.push_back(nearest);
    }
    return out;
}

std::vector<int> distribute_contact_heat(const ThermalGrid& grid, const Vec3& point,
                                         const Vec3& normal, double contact_radius, double rate,
                                         std::span<double> heat_rate) {
    if (heat_rate.size() != grid.boundary.size()) {
        throw InputError("heat: contact heat rates need one entry per boundary patch (" +
                         std::to_string(grid.boundary.size()) + ")");
    }
    std::vector<int> patches = contact_patches(grid, point, normal, contact_radius);
    double area = 0.0;
    for (const int b : patches) {
        area += grid.boundary[static_cast<std::size_t>(b)].area;
    }
    double given = 0.0;
    for (std::size_t i = 0; i + 1 < patches.size(); ++i) {
        const auto b = static_cast<std::size_t>(patches[i]);
        const double part = rate * (grid.boundary[b].area / area);
        heat_rate[b] += part;
        given += part;
    }
    if (!patches.empty()) {
        heat_rate[static_cast<std::size_t>(patches.back())] += rate - given;
    }
    return patches;
}

double undisturbed_temperature(const ThermalGrid& grid, const SphericalResolution& res,
                               std::span<const double> temperature, std::span<const int> patches,
                               const UndisturbedSettings& settings) {
    if (patches.empty()) {
        throw InputError("heat: undisturbed temperature needs at least one contact patch");
    }
    if (static_cast<int>(temperature.size()) != grid.size()) {
        throw InputError("heat: undisturbed temperature needs one value per cell (" +
                         std::to_string(grid.size()) + ")");
    }
    const int band_size = res.n_theta * res.n_phi;
    const int outer_first = spherical_index(res, res.n_r, 0, 0);
    double sum = 0.0;
    double weight = 0.0;
    for (const int b : patches) {
        const BoundaryFace& f = grid.boundary.at(static_cast<std::size_t>(b));
        const int jk = f.cell - outer_first; // j * n_phi + k of the outer cell
        if (jk < 0 || jk >= band_size) {
            throw InputError("heat: undisturbed temperature needs the spherical grid of `res`");
        }
        const int j = jk / res.n_phi;
        const int k = jk % res.n_phi;
        const double t0 = temperature[0];
        const double slope = temperature[static_cast<std::size_t>(spherical_index(res, 1, j, k))] -
                             t0; // per shell (K)
        const double tol = settings.relative * std::abs(slope) + settings.absolute;
        double row = t0 + slope;
        for (int i = 2; i <= res.n_r; ++i) {
            const double ti = temperature[static_cast<std::size_t>(spherical_index(res, i, j, k))];
            if (std::abs(ti - (t0 + i * slope)) > tol) {
                break;
            }
            row = ti;
        }
        sum += f.area * row;
        weight += f.area;
    }
    return sum / weight;
}

} // namespace kiln::heat
