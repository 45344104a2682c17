#include "heat/convection.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>

namespace kiln::heat {

double stagnation_factor(double theta) {
    return 2.1098 + theta * (0.208 + theta * (-1.018 + theta * 0.2552));
}

std::vector<double> stagnation_distribution(const ThermalGrid& grid, const Vec3& towards_flow,
                                            double h_mean) {
    KILN_ASSERT(towards_flow.norm() > 0.0);
    const Vec3 s = towards_flow.normalized();
    std::vector<double> h(grid.boundary.size());
    for (std::size_t f = 0; f < h.size(); ++f) {
        const Vec3& c = grid.boundary[f].centroid;
        const double cn = c.norm();
        const double cosine = cn > 0.0 ? std::clamp(s.dot(c) / cn, -1.0, 1.0) : 1.0;
        h[f] = h_mean * stagnation_factor(std::acos(cosine));
    }
    return h;
}

double surface_conductance(const BoundaryFace& b, double h, double k) {
    return h > 0.0 ? b.area / (1.0 / h + b.distance / k) : 0.0;
}

void lagged_convection(const ThermalGrid& grid, double conductivity, std::span<const double> h,
                       std::span<const double> h_template, std::span<const double> ambient,
                       std::span<const double> temperature, std::span<double> heat_rate) {
    const std::size_t nb = grid.boundary.size();
    KILN_ASSERT(h.size() == nb && heat_rate.size() == nb);
    KILN_ASSERT(h_template.size() == 1 || h_template.size() == nb);
    KILN_ASSERT(ambient.size() == 1 || ambient.size() == nb);
    for (std::size_t f = 0; f < nb; ++f) {
        const double h0 = h_template[h_template.size() == 1 ? 0 : f];
        const double t_inf = ambient[ambient.size() == 1 ? 0 : f];
        const BoundaryFace& b = grid.boundary[f];
        heat_rate[f] = (surface_conductance(b, h[f], conductivity) -
                        surface_conductance(b, h0, conductivity)) *
                       (t_inf - temperature[static_cast<std::size_t>(b.cell)]);
    }
}

} // namespace kiln::heat
