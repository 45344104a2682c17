// Finite-volume form of the spherical heat equation of Oschmann (2019), Ch. 4 eq. 42 (the seed's
// eq. 40 / Inv. V eq. 7 print (1/r) dT/dr, a typo for (2/r) dT/dr; integrating the divergence
// form over each cell, as here, cannot carry that error). Control volumes:
//   centre cell: ball of radius dr/2 (node at r = 0), replacing the seed's centre-node Laplacian
//     (Ch. 4 eq. 48, printed without its 6/N normalisation): its faces are the inner faces of the
//     first shell, so every first-shell cell couples to it with its own face area;
//   shells: r in [dr/2 + (i-1) dr, dr/2 + i dr], i = 1..n_r, dr = R / (n_r + 1/2), nodes at
//     r_i = i dr, so the outer node sits dr/2 below the surface;
//   poles: the polar faces at theta = 0 and pi have zero area, so no pole singularity appears (the
//     seed does not discuss the poles).
// Conduction geometry (area / distance, times k gives W/K):
//   radial between nodes r_a < r_b: exact shell conductance Omega r_a r_b / (r_b - r_a), where
//     Omega = (cos theta_j - cos theta_{j+1}) dphi is the solid angle of the column;
//   polar across theta_f: sin(theta_f) (r_o^2 - r_i^2)/2 dphi over r_node dtheta;
//   azimuthal: dtheta (r_o^2 - r_i^2)/2 over r_node sin(theta_mid) dphi.

#include "heat/spherical_grid.hpp"

#include "core/error.hpp"

#include <cmath>
#include <numbers>
#include <string>

namespace kiln::heat {

namespace {

Vec3 spherical_point(double r, double theta, double phi) {
    return r *
           Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
}

/// Integral of the unit normal over the patch [t0, t1] x [p0, p1] of the unit sphere.
Vec3 unit_patch_normal(double t0, double t1, double p0, double p1) {
    const double s2 = (t1 - t0) / 2.0 - (std::sin(2.0 * t1) - std::sin(2.0 * t0)) / 4.0;
    const double sc = (std::sin(t1) * std::sin(t1) - std::sin(t0) * std::sin(t0)) / 2.0;
    return {s2 * (std::sin(p1) - std::sin(p0)), s2 * (std::cos(p0) - std::cos(p1)), sc * (p1 - p0)};
}

} // namespace

ThermalGrid make_spherical_grid(double radius, const SphericalResolution& res) {
    if (!(radius > 0.0)) {
        throw InputError("heat: spherical grid radius must be > 0 m, got " +
                         std::to_string(radius));
    }
    if (res.n_r < 1 || res.n_theta < 1 || res.n_phi < 1) {
        throw InputError("heat: spherical grid needs n_r, n_theta, n_phi >= 1");
    }
    const double pi = std::numbers::pi;
    const double dr = radius / (res.n_r + 0.5);
    const double dtheta = pi / res.n_theta;
    const double dphi = 2.0 * pi / res.n_phi;
    const int n = 1 + res.n_r * res.n_theta * res.n_phi;

    ThermalGrid g;
    g.kind = "spherical";
    g.volume.assign(static_cast<std::size_t>(n), 0.0);
    g.volume_fraction.assign(static_cast<std::size_t>(n), 1.0);
    g.node.assign(static_cast<std::size_t>(n), Vec3::Zero());
    g.centre_cell = 0;
    g.volume[0] = 4.0 / 3.0 * pi * std::pow(dr / 2.0, 3);

    const auto r_inner = [&](int i) { return dr / 2.0 + (i - 1) * dr; };
    for (int i = 1; i <= res.n_r; ++i) {
        const double ri = r_inner(i);
        const double ro = (i == res.n_r) ? radius : ri + dr;
        const double rn = i * dr;
        const double annulus = (ro * ro - ri * ri) / 2.0; // integral of r dr
        for (int j = 0; j < res.n_theta; ++j) {
            const double t0 = j * dtheta;
            const double t1 = t0 + dtheta;
            const double tm = t0 + dtheta / 2.0;
            const double omega = (std::cos(t0) - std::cos(t1)) * dphi;
            for (int k = 0; k < res.n_phi; ++k) {
                const int c = spherical_index(res, i, j, k);
                g.volume[c] = (ro * ro * ro - ri * ri * ri) / 3.0 * omega;
                g.node[c] = spherical_point(rn, tm, (k + 0.5) * dphi);
                // Radial link inwards (to the centre cell or the previous shell).
                if (i == 1) {
                    g.links.push_back({0, c, omega * ri * ri / rn});
                } else {
                    const double rp = (i - 1) * dr;
                    g.links.push_back(
                        {spherical_index(res, i - 1, j, k), c, omega * rp * rn / (rn - rp)});
                }
                // Polar link to the next band.
                if (j + 1 < res.n_theta) {
                    g.links.push_back({c, spherical_index(res, i, j + 1, k),
                                       std::sin(t1) * annulus * dphi / (rn * dtheta)});
                }
                // Azimuthal link to the next sector (periodic); one sector has no such face.
                if (res.n_phi > 1) {
                    g.links.push_back({c, spherical_index(res, i, j, (k + 1) % res.n_phi),
                                       dtheta * annulus / (rn * std::sin(tm) * dphi)});
                }
                if (i == res.n_r) {
                    BoundaryFace f;
                    f.cell = c;
                    f.area = radius * radius * omega;
                    f.area_normal =
                        radius * radius * unit_patch_normal(t0, t1, k * dphi, (k + 1) * dphi);
                    f.centroid = spherical_point(radius, tm, (k + 0.5) * dphi);
                    // Exact shell conductance node -> surface: k omega rn R / (R - rn).
                    f.distance = radius * (radius - rn) / rn;
                    g.boundary.push_back(f);
                }
            }
        }
    }
    return g;
}

} // namespace kiln::heat
