#include "heat/gas_conduction.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <unordered_map>

namespace kiln::heat {

namespace {

/// Relative accuracy of the conductance quadrature (-).
constexpr double quadrature_tolerance = 1e-10;
/// Deepest bisection of the adaptive Simpson rule (a panel of 2^-depth of the interval).
constexpr int max_depth = 40;

/// Equal-radius equivalent R = 2 r_i r_j / (r_i + r_j) (m): same gas gap near the axis.
double equivalent_radius(double r_i, double r_j) {
    return 2.0 * r_i * r_j / (r_i + r_j);
}

void check_gas(const GasGap& gas) {
    if (!(gas.conductivity >= 0.0)) {
        throw InputError("heat: gas conduction needs a gas conductivity k_f >= 0 (W/(m K))");
    }
    if (!(gas.porosity > 0.0 && gas.porosity < 1.0)) {
        throw InputError("heat: gas conduction needs a porosity 0 < eps < 1");
    }
    if (!(gas.cutoff > 0.0)) {
        throw InputError("heat: gas conduction needs a cut-off H/R > 0");
    }
}

void check_pair(double r_i, double r_j, double distance) {
    if (!(r_i > 0.0) || !(r_j > 0.0)) {
        throw InputError("heat: gas conduction needs sphere radii > 0 (m)");
    }
    if (!(distance > std::abs(r_i - r_j))) {
        throw InputError("heat: gas conduction needs a centre distance > |R_i - R_j| (m)");
    }
}

template <class F>
double simpson(const F& f, double a, double b, double fa, double fm, double fb, double whole,
               double eps, int depth) {
    const double m = 0.5 * (a + b);
    const double lm = 0.5 * (a + m);
    const double rm = 0.5 * (m + b);
    const double flm = f(lm);
    const double frm = f(rm);
    const double left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
    const double right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
    const double diff = left + right - whole;
    if (depth >= max_depth || std::abs(diff) <= 15.0 * eps) {
        return left + right + diff / 15.0; // Richardson step of the two Simpson estimates
    }
    return simpson(f, a, m, fa, flm, fm, left, 0.5 * eps, depth + 1) +
           simpson(f, m, b, fm, frm, fb, right, 0.5 * eps, depth + 1);
}

} // namespace

double voronoi_face_radius(double r, double porosity) {
    if (!(porosity > 0.0 && porosity < 1.0)) {
        throw InputError("heat: gas conduction needs a porosity 0 < eps < 1");
    }
    return 0.560 * r * std::pow(1.0 - porosity, -1.0 / 3.0);
}

double gas_gap_reach(double r_i, double r_j, double cutoff) {
    return r_i + r_j + 2.0 * cutoff * equivalent_radius(r_i, r_j);
}

double gas_gap_radius(double r_i, double r_j, double distance, const GasGap& gas) {
    check_pair(r_i, r_j, distance);
    check_gas(gas);
    const double big_r = equivalent_radius(r_i, r_j);
    const double a = big_r + 0.5 * (distance - r_i - r_j); // R + H_g: centre to mid-plane (m)
    const double r_ij = voronoi_face_radius(big_r, gas.porosity);
    return big_r * r_ij / std::sqrt(r_ij * r_ij + a * a);
}

double gas_gap_conductance(double r_i, double r_j, double distance, double k_i, double k_j,
                           const GasGap& gas) {
    check_pair(r_i, r_j, distance);
    check_gas(gas);
    if (!(k_i > 0.0) || !(k_j > 0.0)) {
        throw InputError("heat: gas conduction needs solid conductivities k > 0 (W/(m K))");
    }
    const double big_r = equivalent_radius(r_i, r_j);
    const double half_gap = 0.5 * (distance - r_i - r_j); // H_g (m)
    const double a = big_r + half_gap;
    if (gas.conductivity == 0.0 || half_gap > gas.cutoff * big_r || !(a > 0.0)) {
        return 0.0;
    }
    const double r_ij = voronoi_face_radius(big_r, gas.porosity);
    const double r_sf = big_r * r_ij / std::sqrt(r_ij * r_ij + a * a);
    // Lower limit: where the undeformed surfaces meet (0 without overlap), see the header.
    const double r_lo = half_gap < 0.0 ? std::sqrt(std::max(0.0, big_r * big_r - a * a)) : 0.0;
    if (!(r_sf > r_lo)) {
        return 0.0;
    }
    const double solid = 1.0 / k_i + 1.0 / k_j;
    const double inv_kf = 1.0 / gas.conductivity;
    const auto f = [&](double r) {
        const double z = std::sqrt(std::max(0.0, big_r * big_r - r * r)); // surface height (m)
        const double l_solid = std::max(0.0, z - r * a / r_ij); // in each sphere, to the cone
        const double l_gas = std::max(0.0, 2.0 * (a - z));      // between the surfaces
        return 2.0 * std::numbers::pi * r / (l_solid * solid + l_gas * inv_kf);
    };
    // A first estimate on 16 panels sets the absolute tolerance; the peak of the integrand near
    // the axis of a nearly touching pair (width ~ sqrt(R k_f / k_s) R) is then refined adaptively.
    constexpr int panels = 16;
    const double h = (r_sf - r_lo) / panels;
    std::array<double, 2 * panels + 1> fv{};
    for (int k = 0; k <= 2 * panels; ++k) {
        fv[static_cast<std::size_t>(k)] = f(r_lo + 0.5 * h * k);
    }
    double estimate = 0.0;
    for (int k = 0; k < panels; ++k) {
        const auto q = static_cast<std::size_t>(2 * k);
        estimate += h / 6.0 * (fv[q] + 4.0 * fv[q + 1] + fv[q + 2]);
    }
    const double eps = quadrature_tolerance * std::abs(estimate) / panels;
    double sum = 0.0;
    for (int k = 0; k < panels; ++k) {
        const auto q = static_cast<std::size_t>(2 * k);
        const double a0 = r_lo + h * k;
        const double whole = h / 6.0 * (fv[q] + 4.0 * fv[q + 1] + fv[q + 2]);
        sum += simpson(f, a0, a0 + h, fv[q], fv[q + 1], fv[q + 2], whole, eps, 0);
    }
    return sum;
}

std::vector<NearPair> near_sphere_pairs(std::span<const Vec3> x, std::span<const double> r,
                                        double cutoff) {
    std::vector<NearPair> out;
    double r_max = 0.0;
    for (const double ri : r) {
        r_max = std::max(r_max, ri);
    }
    if (!(r_max > 0.0) || x.size() != r.size()) {
        return out;
    }
    const double cell = 2.0 * r_max * (1.0 + 2.0 * cutoff);
    const auto key_of = [&](const Vec3& p) {
        const auto c = [&](double v) { return static_cast<std::int64_t>(std::floor(v / cell)); };
        return std::array<std::int64_t, 3>{c(p.x()), c(p.y()), c(p.z())};
    };
    const auto hash = [](const std::array<std::int64_t, 3>& k) {
        return static_cast<std::uint64_t>(k[0] * 73856093LL) ^
               static_cast<std::uint64_t>(k[1] * 19349663LL) ^
               static_cast<std::uint64_t>(k[2] * 83492791LL);
    };
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells;
    std::vector<std::array<std::int64_t, 3>> keys(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
        if (!(r[i] > 0.0)) {
            continue;
        }
        keys[i] = key_of(x[i]);
        cells[hash(keys[i])].push_back(static_cast<std::uint32_t>(i));
    }
    for (std::size_t i = 0; i < x.size(); ++i) {
        if (!(r[i] > 0.0)) {
            continue;
        }
        for (int dx = -1; dx <= 1; ++dx) {
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dz = -1; dz <= 1; ++dz) {
                    const std::array<std::int64_t, 3> k{keys[i][0] + dx, keys[i][1] + dy,
                                                        keys[i][2] + dz};
                    const auto it = cells.find(hash(k));
                    if (it == cells.end()) {
                        continue;
                    }
                    for (const std::uint32_t j : it->second) {
                        if (j <= i || keys[j] != k) { // hash collisions: compare the key
                            continue;
                        }
                        const double reach = gas_gap_reach(r[i], r[j], cutoff);
                        if ((x[j] - x[i]).squaredNorm() < reach * reach) {
                            out.push_back({static_cast<std::uint32_t>(i), j});
                        }
                    }
                }
            }
        }
    }
    std::sort(out.begin(), out.end(), [](const NearPair& a, const NearPair& b) {
        return a.i != b.i ? a.i < b.i : a.j < b.j;
    });
    return out;
}

} // namespace kiln::heat
