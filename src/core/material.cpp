#include "core/material.hpp"

#include <cmath>
#include <numbers>

namespace kiln {

double damping_beta(double restitution) {
    const double l = std::log(restitution);
    return l / std::sqrt(l * l + std::numbers::pi * std::numbers::pi);
}

PairTable::PairTable(const std::vector<Material>& mats, const std::vector<PairOverride>& overrides)
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
            p.beta = damping_beta(p.restitution);
            props_[static_cast<std::size_t>(a * n_ + b)] = p;
        }
    }
}

} // namespace kiln
