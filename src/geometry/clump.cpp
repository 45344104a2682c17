// Multi-sphere clump mass properties over the union of the member spheres (see clump.hpp).

#include "geometry/clump.hpp"

#include "core/error.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <numbers>

namespace kiln::geometry {

double Clump::bounding_radius() const {
    double r = 0.0;
    for (const ClumpSphere& s : spheres) {
        r = std::max(r, s.centre.norm() + s.radius);
    }
    return r;
}

bool Clump::contains(const Vec3& p) const {
    return std::any_of(spheres.begin(), spheres.end(), [&](const ClumpSphere& s) {
        return (p - s.centre).squaredNorm() <= s.radius * s.radius;
    });
}

MassProperties union_mass_properties(const std::vector<ClumpSphere>& spheres, int n) {
    KILN_ASSERT(!spheres.empty() && n > 0);
    Vec3 lo = Vec3::Constant(1e300);
    Vec3 hi = Vec3::Constant(-1e300);
    for (const ClumpSphere& s : spheres) {
        lo = lo.cwiseMin(s.centre - Vec3::Constant(s.radius));
        hi = hi.cwiseMax(s.centre + Vec3::Constant(s.radius));
    }
    const double hx = (hi.x() - lo.x()) / n;
    const double hy = (hi.y() - lo.y()) / n;
    const double cell = hx * hy;
    // Moments: 1, x, y, z, xx, yy, zz, xy, xz, yz.
    double m0 = 0;
    double mx = 0;
    double my = 0;
    double mz = 0;
    double mxx = 0;
    double myy = 0;
    double mzz = 0;
    double mxy = 0;
    double mxz = 0;
    double myz = 0;
    std::vector<const ClumpSphere*> row;
    std::vector<std::pair<double, double>> iv;
    for (int i = 0; i < n; ++i) {
        const double x = lo.x() + (i + 0.5) * hx;
        row.clear();
        for (const ClumpSphere& s : spheres) {
            if (std::abs(x - s.centre.x()) < s.radius) {
                row.push_back(&s);
            }
        }
        for (int j = 0; j < n; ++j) {
            const double y = lo.y() + (j + 0.5) * hy;
            iv.clear();
            for (const ClumpSphere* s : row) {
                const double rho2 = (x - s->centre.x()) * (x - s->centre.x()) +
                                    (y - s->centre.y()) * (y - s->centre.y());
                if (rho2 < s->radius * s->radius) {
                    const double h = std::sqrt(s->radius * s->radius - rho2);
                    iv.emplace_back(s->centre.z() - h, s->centre.z() + h);
                }
            }
            if (iv.empty()) {
                continue;
            }
            std::sort(iv.begin(), iv.end());
            double len = 0;
            double z1 = 0;
            double z2 = 0;
            double a = iv[0].first;
            double b = iv[0].second;
            const auto close = [&] {
                len += b - a;
                z1 += 0.5 * (b * b - a * a);
                z2 += (b * b * b - a * a * a) / 3.0;
            };
            for (std::size_t k = 1; k < iv.size(); ++k) {
                if (iv[k].first > b) {
                    close();
                    a = iv[k].first;
                    b = iv[k].second;
                } else {
                    b = std::max(b, iv[k].second);
                }
            }
            close();
            m0 += len;
            mx += x * len;
            my += y * len;
            mz += z1;
            mxx += x * x * len;
            myy += y * y * len;
            mzz += z2;
            mxy += x * y * len;
            mxz += x * z1;
            myz += y * z1;
        }
    }
    MassProperties mp;
    mp.volume = m0 * cell;
    const Vec3 c = Vec3(mx, my, mz) / m0;
    mp.centroid = c;
    Mat3 second; // int r r^T dV about the origin
    second << mxx, mxy, mxz, mxy, myy, myz, mxz, myz, mzz;
    second *= cell;
    const Mat3 inertia_origin = second.trace() * Mat3::Identity() - second;
    mp.inertia_centroid =
        inertia_origin - mp.volume * (c.squaredNorm() * Mat3::Identity() - c * c.transpose());
    return mp;
}

Vec3 equal_within(const Vec3& moments, double tol) {
    // The three moments, then the closest two: set to their mean where they differ by no more
    // than tol of the largest moment (none with tol 0: a one-sphere clump's are exact).
    if (!(tol > 0.0)) {
        return moments;
    }
    const double bar = tol * moments.maxCoeff();
    if (moments.maxCoeff() - moments.minCoeff() <= bar) {
        return Vec3::Constant(moments.sum() / 3.0);
    }
    int s = 0; // the moment left out of the closest pair
    for (int k = 1; k < 3; ++k) {
        const double gap_k = std::abs(moments[(k + 1) % 3] - moments[(k + 2) % 3]);
        const double gap_s = std::abs(moments[(s + 1) % 3] - moments[(s + 2) % 3]);
        s = gap_k < gap_s ? k : s;
    }
    const int a = (s + 1) % 3;
    const int b = (s + 2) % 3;
    Vec3 out = moments;
    if (std::abs(moments[a] - moments[b]) <= bar) {
        out[a] = out[b] = 0.5 * (moments[a] + moments[b]);
    }
    return out;
}

Clump make_clump(const std::vector<ClumpSphere>& spheres, const std::string& where, int n) {
    if (spheres.empty()) {
        throw InputError(where + ": a clump needs at least one sphere");
    }
    for (const ClumpSphere& s : spheres) {
        if (!(s.radius > 0.0) || !s.centre.allFinite()) {
            throw InputError(fmt::format("{}: sphere radius {:g} m: every radius must be > 0 m",
                                         where, s.radius));
        }
    }
    Clump c;
    MassProperties mp;
    if (spheres.size() == 1) {
        // One sphere: exact, no quadrature.
        const double r = spheres[0].radius;
        mp.volume = 4.0 / 3.0 * std::numbers::pi * r * r * r;
        mp.centroid = spheres[0].centre;
        mp.inertia_centroid = Mat3::Identity() * 0.4 * mp.volume * r * r;
        c.volume_error = 0.0;
    } else {
        mp = union_mass_properties(spheres, n);
        const MassProperties coarse = union_mass_properties(spheres, n / 2);
        c.volume_error = std::abs(mp.volume - coarse.volume);
    }
    const PrincipalFrame pf = principal_frame(mp.inertia_centroid);
    c.volume = mp.volume;
    c.inertia_unit_density = equal_within(pf.moments, c.volume_error / c.volume);
    c.template_axes = pf.axes;
    c.template_centroid = mp.centroid;
    for (const ClumpSphere& s : spheres) {
        c.spheres.push_back({pf.axes.transpose() * (s.centre - mp.centroid), s.radius});
    }
    return c;
}

double lens_volume(double r1, double r2, double d) {
    if (d >= r1 + r2) {
        return 0.0;
    }
    const double rmin = std::min(r1, r2);
    if (d <= std::abs(r1 - r2)) {
        return 4.0 / 3.0 * std::numbers::pi * rmin * rmin * rmin;
    }
    // Two spherical caps; e.g. Weisstein, MathWorld "Sphere-Sphere Intersection", Eq. 16.
    const double s = r1 + r2 - d;
    return std::numbers::pi * s * s * (d * d + 2.0 * d * (r1 + r2) - 3.0 * (r1 - r2) * (r1 - r2)) /
           (12.0 * d);
}

} // namespace kiln::geometry
