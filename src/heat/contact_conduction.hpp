#pragma once
// Static particle-particle contact conduction (Batchelor & O'Brien 1977, Proc. R. Soc. A 355,
// 313, as modified by Zhou, Yu & Zulli 2010; seed: Oschmann et al. 2016, Inv. V eq. 12, L1944,
// and Inv. VII eq. 16, L2489):
//   Q_ij = 4 r_c c (T_j - T_i) / (1/k_i + 1/k_j),   c = (E_sim / E_real)^(1/5),
// the heat rate into particle i. The factor c rescales a contact radius obtained with a softened
// Young's modulus E_sim to the radius the real modulus E_real would give (seed L1946; c = 1 for
// real moduli). The seed never writes the contact radius (notes §2.4, §8): its r_c = 1.11e-2 m for
// delta = 2.5e-3 m, R = 0.05 m is the geometric lens radius, not the Hertz value sqrt(R* delta).
// Both are offered here; the caller decides.
//
// For resolved particles the temperatures in the law are "undisturbed" temperatures near the
// contact (Inv. V L1965, after Cooper, Mikic & Yovanovich 1969): along each radial row of the
// spherical grid under the contact, the tangent through the centre node and the first-shell node
// is followed outwards; the last node that still lies on it gives the row's value; rows are
// averaged. The contact heat rate then enters the particle as lagged per-patch heat rates
// (BoundaryLoad::heat_rate), spread over the patches under the contact at a uniform flux
// Q / sum A_b (seed notes §9.3: the seed's eq. 15 divides by a single node area, which does not
// conserve heat when several nodes are in contact).

#include "core/types.hpp"
#include "heat/spherical_grid.hpp"
#include "heat/thermal_grid.hpp"

#include <span>
#include <vector>

namespace kiln::heat {

/// Zhou et al.'s correction c = (E_sim / E_real)^(1/5) (-) of a contact radius computed with the
/// softened modulus `e_sim` (Pa) to the real modulus `e_real` (Pa) (seed Inv. V eq. 12). The
/// exponent 1/5 is that of the Hertz contact radius at a given impact velocity. Throws InputError
/// for non-positive moduli.
[[nodiscard]] double softened_modulus_correction(double e_sim, double e_real);

/// Hertz contact radius sqrt(R* delta) (m) of two spheres of radii `r_i`, `r_j` (m) with normal
/// overlap `overlap` (m), R* = r_i r_j / (r_i + r_j) (Johnson 1985, §4.2, eq. 4.23 with
/// a^2 = R delta). Throws InputError for non-positive radii or negative overlap.
[[nodiscard]] double hertz_contact_radius(double overlap, double r_i, double r_j);

/// Radius (m) of the circle in which the two undeformed sphere surfaces intersect (the lens
/// radius) at overlap `overlap` (m): the seed's r_c (equal radii: sqrt(R delta - delta^2 / 4)).
/// Throws InputError for non-positive radii, negative overlap or overlap >= 2 min(r_i, r_j).
[[nodiscard]] double lens_contact_radius(double overlap, double r_i, double r_j);

/// Static contact conductance H = 4 c r_c / (1/k_i + 1/k_j) (W/K) for conductivities `k_i`, `k_j`
/// (W/(m K)), contact radius `contact_radius` (m, from the simulation's modulus) and correction
/// `correction` c (-, softened_modulus_correction; 1 for real moduli). The heat rate into i is
/// H (T_j - T_i). Equal k: H = 2 k c r_c, the constriction conductance of two half-spaces touching
/// on a disc (Batchelor & O'Brien 1977). Throws InputError for negative radius, non-positive k or
/// correction.
[[nodiscard]] double static_contact_conductance(double k_i, double k_j, double contact_radius,
                                                double correction = 1.0);

/// The same from the overlap (m), radii (m) and moduli (Pa): r_c = hertz_contact_radius(overlap,
/// r_i, r_j), c = softened_modulus_correction(e_sim, e_real).
[[nodiscard]] double static_contact_conductance(double k_i, double k_j, double overlap, double r_i,
                                                double r_j, double e_sim, double e_real);

/// The boundary patches of `grid` under a contact disc: body-frame contact point `point` (m),
/// outward unit normal `normal` (body frame, pointing from this particle to the partner) and
/// radius `contact_radius` (m). A patch is under the disc when its centroid lies on the contact
/// side (area normal . normal > 0) within `contact_radius` of the contact axis. If no centroid
/// does (a disc smaller than the patches), the patch whose centroid is nearest to `point` is
/// returned alone. Indices into grid.boundary, ascending.
[[nodiscard]] std::vector<int> contact_patches(const ThermalGrid& grid, const Vec3& point,
                                               const Vec3& normal, double contact_radius);

/// Adds the contact heat rate `rate` (W, into the particle) to `heat_rate` (one entry per boundary
/// patch of `grid`, W), spread over contact_patches(...) at a uniform flux rate / sum A_b.
/// Conservative: the added amounts sum to `rate` up to one rounding (the last patch takes the
/// remainder). Returns the patch indices used.
std::vector<int> distribute_contact_heat(const ThermalGrid& grid, const Vec3& point,
                                         const Vec3& normal, double contact_radius, double rate,
                                         std::span<double> heat_rate);

/// Tolerance of the tangent test in undisturbed_temperature.
struct UndisturbedSettings {
    /// A node lies on the tangent when |T_i - T_tangent(r_i)| <= relative |T_1 - T_0| + absolute;
    /// the seed gives no criterion (Inv. V L1965), this one is ours (-).
    double relative = 0.5;
    /// Absolute part of the test (K); makes a uniform row count as undisturbed.
    double absolute = 1e-9;
};

/// Undisturbed contact temperature (K) of a particle on the spherical grid of resolution `res`
/// with field `temperature` (K) (seed Inv. V L1965, Fig. 3): for each patch in `patches` (indices
/// into the grid's boundary, e.g. from contact_patches), the radial row of nodes with that patch's
/// (theta, phi) is followed from the centre node; the tangent through the centre node (r = 0) and
/// the first-shell node (r = dr) is extrapolated, and the last node i >= 1 that lies on it (within
/// `settings`) gives the row's value, starting the test at the second shell. The rows are
/// averaged with the patch areas as weights (equal weights on a spherical-grid band). Throws
/// InputError for an empty `patches` or a field of the wrong size.
[[nodiscard]] double undisturbed_temperature(const ThermalGrid& grid,
                                             const SphericalResolution& res,
                                             std::span<const double> temperature,
                                             std::span<const int> patches,
                                             const UndisturbedSettings& settings = {});

} // namespace kiln::heat
