#pragma once
// Spherical-coordinate finite-volume grid of a sphere (after Oschmann et al. 2016, Powder
// Technol. 291, Investigation V of the seed, eq. 7 and Ch. 4 eq. 42): one centre cell plus
// n_r shells x n_theta polar bands x n_phi azimuthal sectors, equidistant in r, theta and phi.

#include "heat/thermal_grid.hpp"

namespace kiln::heat {

/// Resolution of a spherical grid.
struct SphericalResolution {
    int n_r = 10;    ///< shells outside the centre cell (-)
    int n_theta = 8; ///< polar bands, theta in [0, pi] (-)
    int n_phi = 16;  ///< azimuthal sectors, phi in [0, 2 pi) (-)
};

/// Builds the grid of a sphere of radius `radius` (m). Throws InputError for a non-positive
/// radius or resolution.
[[nodiscard]] ThermalGrid make_spherical_grid(double radius, const SphericalResolution& res);

/// Index of cell (shell i in 1..n_r, band j, sector k); the centre cell is 0.
[[nodiscard]] inline int spherical_index(const SphericalResolution& res, int i, int j, int k) {
    return 1 + ((i - 1) * res.n_theta + j) * res.n_phi + k;
}

} // namespace kiln::heat
