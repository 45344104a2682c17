#pragma once
// Particle-fluid-particle conduction across the gas gap of two spheres (Cheng, Yu & Zulli 1999,
// Chem. Eng. Sci. 54, 4199, Voronoi-polyhedron model, as used by the seed: Oschmann et al. 2016,
// Inv. V eqs. 13-16, L1948-1958; Inv. VII eqs. 23-26, L2509-2517):
//
//   Q_ij = (T_j - T_i) H,
//   H = int_{r_lo}^{r_sf} 2 pi r dr / ( [sqrt(R^2 - r^2) - r (R + H_g) / r_ij] (1/k_i + 1/k_j)
//                                       + 2 [(R + H_g) - sqrt(R^2 - r^2)] / k_f ),
//   H_g = (s - 2R) / 2 (half the surface gap; negative when the spheres overlap),
//   r_sf = R r_ij / sqrt(r_ij^2 + (R + H_g)^2),  r_ij = 0.560 R (1 - eps)^(-1/3).
//
// Heat flows in tubes parallel to the line of centres inside the double cone whose base is the
// Voronoi face of the pair (radius r_ij at the mid-plane): a tube at radius r crosses solid in both
// spheres (from the surface down to the cone) and the gas between the surfaces. The pair conducts
// only while H_g / R <= 0.5 (the seed's cut-off after Zhou et al. 2009, L1958).
//
// Our choices where the seed is silent or cannot be used as printed:
// - Lower limit. The seed takes r_lo = 0 without contact and r_lo = r_c in contact. With the Hertz
//   radius r_c = sqrt(R* delta) < the lens radius sqrt(R^2 - (R + H_g)^2), the gas length
//   2 [(R + H_g) - sqrt(R^2 - r^2)] is negative for r_c < r < lens radius and the integrand changes
//   sign. kiln integrates from the radius where the undeformed surfaces meet (the lens radius; 0
//   without overlap), so the gas length is never negative; the disc inside belongs to the static
//   contact law (contact_conduction.hpp).
// - Unequal radii. The formula is for monodisperse packings (seed L1958). For R_i != R_j kiln uses
//   R = 2 R_i R_j / (R_i + R_j), the radius whose gas gap 2H_g + r^2/R near the axis equals the
//   true gap of the two spheres to second order in r, and H_g = (s - R_i - R_j) / 2. Equal radii:
//   the seed's form exactly.
// - Porosity. eps is the porosity around the pair; kiln takes one value per scene (a case key).

#include "core/types.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace kiln::heat {

/// Gas-gap model constants of a scene.
struct GasGap {
    double conductivity = 0; ///< gas conductivity k_f (W/(m K)); 0 = no gas conduction
    double porosity = 0.4;   ///< porosity eps around a pair, in (0, 1) (-)
    double cutoff = 0.5;     ///< largest H_g / R that still conducts (-) (seed L1958: 0.5)
};

/// Cheng et al.'s Voronoi-face radius r_ij = 0.560 R (1 - eps)^(-1/3) (m) for sphere radius `r`
/// (m) and porosity `porosity` (-) (seed Inv. V eq. 16). Throws InputError outside 0 < eps < 1.
[[nodiscard]] double voronoi_face_radius(double r, double porosity);

/// Largest centre distance (m) at which spheres of radii `r_i`, `r_j` (m) still conduct through
/// the gas: r_i + r_j + 2 cutoff R with R = 2 r_i r_j / (r_i + r_j).
[[nodiscard]] double gas_gap_reach(double r_i, double r_j, double cutoff);

/// Particle-fluid-particle conductance H (W/K) of spheres of radii `r_i`, `r_j` (m) whose centres
/// are `distance` (m) apart (overlap allowed), solid conductivities `k_i`, `k_j` (W/(m K)) and the
/// gas `gas`; the heat rate into i is H (T_j - T_i). Zero when k_f = 0 or H_g / R > cutoff.
/// Adaptive Simpson quadrature to a relative error of 1e-10. Throws InputError for non-positive
/// radii or solid conductivities, negative k_f, eps outside (0, 1) or a distance <= |r_i - r_j|.
[[nodiscard]] double gas_gap_conductance(double r_i, double r_j, double distance, double k_i,
                                         double k_j, const GasGap& gas);

/// The upper limit r_sf (m) of the conductance integral (the radius where the Voronoi cone leaves
/// the sphere surface) for the same arguments: the radius of the lens over which the heat enters.
[[nodiscard]] double gas_gap_radius(double r_i, double r_j, double distance, const GasGap& gas);

/// A pair of spheres within gas-gap reach of each other.
struct NearPair {
    std::uint32_t i = 0; ///< index into the position span, i < j
    std::uint32_t j = 0; ///< partner index
};

/// Every pair of spheres (centres `x`, m, world; radii `r`, m) whose centre distance is below
/// gas_gap_reach(r_i, r_j, cutoff), touching pairs included; found with a cell list of cell size
/// 2 max(r) (1 + 2 cutoff) (>= every reach, as R <= 2 min(r_i, r_j)), independent of the
/// mechanics' neighbour list and its skin. Sorted by (i, j).
/// Entries with r <= 0 are skipped (non-spherical bodies are the caller's business).
[[nodiscard]] std::vector<NearPair> near_sphere_pairs(std::span<const Vec3> x,
                                                      std::span<const double> r, double cutoff);

} // namespace kiln::heat
