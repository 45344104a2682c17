#include "core/material.hpp"

#include "core/error.hpp"

#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <numbers>

namespace kiln {

double damping_beta(double restitution) {
    const double l = std::log(restitution);
    return l / std::sqrt(l * l + std::numbers::pi * std::numbers::pi);
}

double clamped_rebound(double damping_restitution) {
    const double b = std::abs(damping_beta(damping_restitution));
    return std::pow(damping_restitution, 1.0 - 2.0 / std::numbers::pi * std::asin(b));
}

namespace {
/// e' at which clamped_rebound is lowest: below it the rebound ratio rises again towards 1.
double argmin_clamped_rebound() {
    // clamped_rebound falls and then rises as e' goes from 1 to 0; golden-section search on
    // log e' over [1e-12, 1].
    double a = std::log(1e-12);
    double b = 0.0;
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    for (int it = 0; it < 200; ++it) {
        const double c1 = b - g * (b - a);
        const double c2 = a + g * (b - a);
        if (clamped_rebound(std::exp(c1)) < clamped_rebound(std::exp(c2))) {
            b = c2;
        } else {
            a = c1;
        }
    }
    return std::exp(0.5 * (a + b));
}
} // namespace

double lowest_clamped_rebound() {
    static const double low = clamped_rebound(argmin_clamped_rebound());
    return low;
}

double damping_restitution_for_clamped(double rebound) {
    static const double e_min = argmin_clamped_rebound();
    if (rebound < lowest_clamped_rebound()) {
        return std::numeric_limits<double>::quiet_NaN();
    }
    if (rebound >= 1.0) {
        return 1.0;
    }
    // clamped_rebound increases monotonically on [e_min, 1]: bisection to rounding.
    double lo = e_min;
    double hi = 1.0;
    for (int it = 0; it < 200 && hi - lo > 1e-15; ++it) {
        const double mid = 0.5 * (lo + hi);
        (clamped_rebound(mid) < rebound ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

PairTable::PairTable(const std::vector<Material>& mats, const std::vector<PairOverride>& overrides,
                     bool rebound_with_clamp)
    : n_(static_cast<int>(mats.size())), props_(mats.size() * mats.size()) {
    for (int a = 0; a < n_; ++a) {
        for (int b = 0; b < n_; ++b) {
            const Material& m1 = mats[static_cast<std::size_t>(a)];
            const Material& m2 = mats[static_cast<std::size_t>(b)];
            PairProperties p;
            p.effective_modulus =
                1.0 / ((1.0 - m1.poisson_ratio * m1.poisson_ratio) / m1.youngs_modulus +
                       (1.0 - m2.poisson_ratio * m2.poisson_ratio) / m2.youngs_modulus);
            // (2 - nu)/G, not the (2 - nu^2)/G printed in Oschmann 2019
            // (notes/seed001_shape.md, 8.6).
            p.effective_shear = 1.0 / ((2.0 - m1.poisson_ratio) / m1.shear_modulus() +
                                       (2.0 - m2.poisson_ratio) / m2.shear_modulus());
            p.restitution = 0.5 * (m1.restitution + m2.restitution);
            p.friction = 0.5 * (m1.friction + m2.friction);
            p.rolling_friction = 0.5 * (m1.rolling_friction + m2.rolling_friction);
            for (const PairOverride& o : overrides) {
                if ((o.a == a && o.b == b) || (o.a == b && o.b == a)) {
                    if (o.restitution >= 0) {
                        p.restitution = o.restitution;
                    }
                    if (o.friction >= 0) {
                        p.friction = o.friction;
                    }
                    if (o.rolling_friction >= 0) {
                        p.rolling_friction = o.rolling_friction;
                    }
                }
            }
            p.damping_restitution = p.restitution;
            if (rebound_with_clamp) {
                p.damping_restitution = damping_restitution_for_clamped(p.restitution);
                if (std::isnan(p.damping_restitution)) {
                    throw InputError(
                        "", 0, "restitution",
                        fmt::format("{} (materials \"{}\" and \"{}\") is below {:.4f}, the lowest "
                                    "rebound a contact with clamp_normal_force = true can reach; "
                                    "set clamp_normal_force = false or "
                                    "restitution_meaning = \"dashpot\"",
                                    p.restitution, m1.name, m2.name, lowest_clamped_rebound()));
                }
            }
            p.beta = damping_beta(p.damping_restitution);
            props_[static_cast<std::size_t>(a * n_ + b)] = p;
        }
    }
}

} // namespace kiln
