#pragma once
// Surface-to-surface radiation between neighbouring spheres (seed: Oschmann et al. 2016, Inv. V
// eqs. 10-11, L1931-1935, with view factors after Jones 1965 for sphere pairs; the seed computes
// them only for neighbours within R). kiln's model, our own simplification:
//
//   Q_ij = sigma (T_j^4 - T_i^4) / ( (1 - e_i)/(e_i A_i) + 1/(A F)_ij + (1 - e_j)/(e_j A_j) ),
//
// the heat rate into i of two grey diffuse surfaces that see each other through (A F)_ij and
// nothing else (the two-surface radiosity network, e.g. Incropera, Fundamentals of Heat and Mass
// Transfer, 6th ed., eq. 13.23). The rest of each surface's view (other neighbours, the gas, the
// ambient) is not part of this pair's exchange: pairs are independent, which is exact only when the
// surroundings are at one of the two temperatures, and an estimate in a bed (documented choice).
//
// View factor of sphere i to sphere j (centre distance s, radius R_j): the fraction of directions
// from the centre of i that hit j, F = (1 - sqrt(1 - (R_j / s)^2)) / 2 (no pair formula from
// Jones 1965 at hand). Against a Monte Carlo ray count (tests/heat) it is exact for distant equal
// spheres (s >= 3 R within the count's noise) and low for close ones: 11 % at contact, 7.4 % at
// s = 2.2 R (a surface element facing the partner sees more of it than the centre). For unequal
// spheres A_i F_ij != A_j F_ji with this estimate; kiln uses the mean (A F)_ij = (A_i F_ij +
// A_j F_ji) / 2 on both sides, so the exchange stays reciprocal and conservative.

namespace kiln::heat {

/// Stefan-Boltzmann constant (W/(m^2 K^4)), CODATA 2018 (exact from h, c, k_B).
inline constexpr double stefan_boltzmann = 5.670374419e-8;

/// View factor (-) of a sphere to a sphere of radius `r_j` (m) whose centre is `distance` (m)
/// away: (1 - sqrt(1 - (r_j / s)^2)) / 2. Throws InputError for r_j <= 0 or s <= r_j.
[[nodiscard]] double sphere_view_factor(double r_j, double distance);

/// View area (A F)_ij (m^2) of the pair as kiln uses it, (A_i F_ij + A_j F_ji) / 2 (reciprocal),
/// for spheres of radii `r_i`, `r_j` (m) with centres `distance` (m) >= r_i + r_j apart.
[[nodiscard]] double pair_view_area(double r_i, double r_j, double distance);

/// Radiative exchange coefficient K (W/K^4) of spheres of radii `r_i`, `r_j` (m), centres
/// `distance` (m) apart, emissivities `e_i`, `e_j` (0 < e <= 1): the heat rate into i is
/// K (T_j^4 - T_i^4); symmetric in the pair. Zero when either emissivity is 0. Throws InputError
/// for emissivities outside [0, 1], non-positive radii or overlapping spheres.
[[nodiscard]] double radiative_coefficient(double r_i, double r_j, double distance, double e_i,
                                           double e_j);

/// Linearised radiative conductance 4 K T^3 (W/K) at the larger of `t_i`, `t_j` (K): bounds
/// d Q / d T for the lag limit.
[[nodiscard]] double radiative_conductance_bound(double coefficient, double t_i, double t_j);

/// Surface temperature T_s (K) of a grey surface of emissivity `emissivity` radiating to a black
/// enclosure at `t_ambient` (K), fed by conduction from a node at `t_node` (K) through `distance`
/// (m) of conductivity `conductivity` (W/(m K)): the root of the surface balance
/// (k / d) (T_node - T_s) = eps sigma (T_s^4 - T_amb^4), by Newton (the left side is linear and the
/// right convex and increasing, so the root is unique; relative 1e-14). `distance` 0 gives T_node.
[[nodiscard]] double radiating_surface_temperature(double t_node, double distance,
                                                   double conductivity, double emissivity,
                                                   double t_ambient);

} // namespace kiln::heat
