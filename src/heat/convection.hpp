#pragma once
// Heat transfer coefficients per boundary patch: the local distribution around a stagnation point
// h = f(theta) h_mean (Oschmann & Kruggel-Emden 2017, Inv. VI eqs. 8-9, after Sudbrock et al.
// 2015), and the lagged form that keeps a particle-specific h out of a shared matrix.

#include "heat/thermal_grid.hpp"

#include <span>
#include <vector>

namespace kiln::heat {

/// f(theta) = 2.1098 + 0.208 theta - 1.018 theta^2 + 0.2552 theta^3, theta in [0, pi] (rad) the
/// angle at the centroid between the stagnation direction and the surface point (Inv. VI eq. 9).
/// Its area-weighted mean over a sphere is 1.0001 (seed notes §2.8).
[[nodiscard]] double stagnation_factor(double theta);

/// h (W/(m^2 K)) per boundary patch of `grid` for mean coefficient `h_mean` and the direction
/// `towards_flow` (body frame, any length > 0) pointing from the centroid to the stagnation point
/// (against the flow). theta is measured to each patch centroid.
[[nodiscard]] std::vector<double> stagnation_distribution(const ThermalGrid& grid,
                                                          const Vec3& towards_flow, double h_mean);

/// Series conductance node -> surface -> fluid A_b / (1/h + d_b/k) of patch `b` (W/K), 0 for h = 0;
/// `k` the conductivity (W/(m K)), `h` (W/(m^2 K)).
[[nodiscard]] double surface_conductance(const BoundaryFace& b, double h, double k);

/// Lagged convective heat rates (W) into each patch: (G_b(h_b) - G_b(h_template,b)) (T_inf,b -
/// T_node^n) with G_b the series conductance above and T_node^n the patch cell's temperature from
/// the last step. Passed as BoundaryLoad::heat_rate, it applies a particle-specific h while the
/// operator (and its factor) keeps the template h; the difference to the implicit treatment is
/// first order in dt. `h_template` and `ambient` have one entry per patch or one uniform entry.
void lagged_convection(const ThermalGrid& grid, double conductivity, std::span<const double> h,
                       std::span<const double> h_template, std::span<const double> ambient,
                       std::span<const double> temperature, std::span<double> heat_rate);

} // namespace kiln::heat
