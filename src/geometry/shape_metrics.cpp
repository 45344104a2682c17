// Surface area, projected area and shape factors; see shape_metrics.hpp.

#include "geometry/shape_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace kiln::geometry {

namespace {

template <class... Ts> struct Overloaded : Ts... { using Ts::operator()...; };

constexpr double kPi = std::numbers::pi;

/// Calls f(area vector = normal times area) for each triangle of the parametric triangulation of
/// the superquadric: n latitude bands from pole to pole, 4 n longitude steps around.
template <class F> void for_each_triangle(const Superquadric& q, int n, F&& f) {
    const int m = 4 * n;
    std::vector<Vec3> ring0(static_cast<std::size_t>(m + 1));
    std::vector<Vec3> ring1(static_cast<std::size_t>(m + 1));
    const auto fill = [&](std::vector<Vec3>& ring, int i) {
        const double eta = -0.5 * kPi + kPi * i / n;
        for (int j = 0; j <= m; ++j) {
            ring[static_cast<std::size_t>(j)] = q.parametric_point(eta, -kPi + 2.0 * kPi * j / m);
        }
    };
    fill(ring0, 0);
    for (int i = 1; i <= n; ++i) {
        fill(ring1, i);
        for (std::size_t j = 0; j < static_cast<std::size_t>(m); ++j) {
            const Vec3& a = ring0[j];
            const Vec3& b = ring0[j + 1];
            const Vec3& c = ring1[j + 1];
            const Vec3& d = ring1[j];
            f(0.5 * (b - a).cross(c - a));
            f(0.5 * (c - a).cross(d - a));
        }
        std::swap(ring0, ring1);
    }
}

double superquadric_area(const Superquadric& q, int n) {
    double s = 0.0;
    for_each_triangle(q, n, [&](const Vec3& an) { s += an.norm(); });
    return s;
}

double superquadric_shadow(const Superquadric& q, int n, const Vec3& u) {
    double s = 0.0;
    for_each_triangle(q, n, [&](const Vec3& an) { s += std::abs(an.dot(u)); });
    return 0.5 * s;
}

/// Richardson extrapolation of a second-order quantity from resolutions n and 2n.
Estimate richardson(double coarse, double fine) {
    return {fine + (fine - coarse) / 3.0, std::abs(fine - coarse)};
}

/// Length (rad) of the union of arcs [lo, hi] on a circle, each of length < 2 pi.
double arc_union(std::vector<std::pair<double, double>>& arcs) {
    std::vector<std::pair<double, double>> flat;
    for (const auto& [lo0, hi0] : arcs) {
        double lo = std::fmod(lo0, 2.0 * kPi);
        if (lo < 0.0) {
            lo += 2.0 * kPi;
        }
        const double hi = lo + (hi0 - lo0);
        if (hi > 2.0 * kPi) {
            flat.emplace_back(lo, 2.0 * kPi);
            flat.emplace_back(0.0, hi - 2.0 * kPi);
        } else {
            flat.emplace_back(lo, hi);
        }
    }
    std::sort(flat.begin(), flat.end());
    double total = 0.0;
    double a = flat[0].first;
    double b = flat[0].second;
    for (std::size_t k = 1; k < flat.size(); ++k) {
        if (flat[k].first > b) {
            total += b - a;
            a = flat[k].first;
            b = flat[k].second;
        } else {
            b = std::max(b, flat[k].second);
        }
    }
    return std::min(2.0 * kPi, total + (b - a));
}

/// Exposed area of a union of spheres with nt latitude bands per sphere. On sphere i, the band at
/// height t = z/r_i (uniform in t means uniform in area, Archimedes) is a circle; sphere j covers
/// the arc |phi - psi| < acos(K / (rho D)) of it, computed exactly.
double clump_area(const Clump& c, int nt) {
    double area = 0.0;
    std::vector<std::pair<double, double>> arcs;
    for (std::size_t i = 0; i < c.spheres.size(); ++i) {
        const ClumpSphere& si = c.spheres[i];
        double exposed = 0.0;
        for (int k = 0; k < nt; ++k) {
            const double t = -1.0 + (k + 0.5) * 2.0 / nt;
            const double rho = std::sqrt(1.0 - t * t);
            arcs.clear();
            bool full = false;
            for (std::size_t j = 0; j < c.spheres.size() && !full; ++j) {
                if (j == i) {
                    continue;
                }
                const ClumpSphere& sj = c.spheres[j];
                const Vec3 d = sj.centre - si.centre;
                const double kk =
                    (si.radius * si.radius + d.squaredNorm() - sj.radius * sj.radius) /
                        (2.0 * si.radius) -
                    t * d.z();
                const double dd = rho * std::hypot(d.x(), d.y());
                if (kk < -dd) {
                    full = true;
                } else if (kk < dd) {
                    const double half = std::acos(kk / dd);
                    const double psi = std::atan2(d.y(), d.x());
                    arcs.emplace_back(psi - half, psi + half);
                }
            }
            if (full) {
                continue;
            }
            exposed += arcs.empty() ? 2.0 * kPi : 2.0 * kPi - arc_union(arcs);
        }
        area += si.radius * si.radius * exposed * 2.0 / nt;
    }
    return area;
}

/// Shadow of a union of spheres on the plane normal to u: union of discs, exact chords per row.
double clump_shadow(const Clump& c, const Vec3& u, int n) {
    const Vec3 w = u.normalized();
    const Vec3 e1 = w.unitOrthogonal();
    const Vec3 e2 = w.cross(e1);
    struct Disc {
        double x, y, r;
    };
    std::vector<Disc> discs;
    double lo = 1e300;
    double hi = -1e300;
    for (const ClumpSphere& s : c.spheres) {
        discs.push_back({s.centre.dot(e1), s.centre.dot(e2), s.radius});
        lo = std::min(lo, s.centre.dot(e2) - s.radius);
        hi = std::max(hi, s.centre.dot(e2) + s.radius);
    }
    const double h = (hi - lo) / n;
    double area = 0.0;
    std::vector<std::pair<double, double>> iv;
    for (int j = 0; j < n; ++j) {
        const double y = lo + (j + 0.5) * h;
        iv.clear();
        for (const Disc& d : discs) {
            const double dy = y - d.y;
            if (dy * dy < d.r * d.r) {
                const double half = std::sqrt(d.r * d.r - dy * dy);
                iv.emplace_back(d.x - half, d.x + half);
            }
        }
        if (iv.empty()) {
            continue;
        }
        std::sort(iv.begin(), iv.end());
        double a = iv[0].first;
        double b = iv[0].second;
        double len = 0.0;
        for (std::size_t k = 1; k < iv.size(); ++k) {
            if (iv[k].first > b) {
                len += b - a;
                a = iv[k].first;
                b = iv[k].second;
            } else {
                b = std::max(b, iv[k].second);
            }
        }
        area += (len + b - a) * h;
    }
    return area;
}

} // namespace

Estimate surface_area(const Shape& s) {
    return std::visit(Overloaded{[](const Sphere& sp) {
                                     return Estimate{4.0 * kPi * sp.radius * sp.radius, 0.0};
                                 },
                                 [](const Clump& c) {
                                     const double fine = clump_area(c, 8000);
                                     const double coarse = clump_area(c, 4000);
                                     return Estimate{fine, std::abs(fine - coarse)};
                                 },
                                 [](const Superquadric& q) {
                                     return richardson(superquadric_area(q, 200),
                                                       superquadric_area(q, 400));
                                 },
                                 [](const ConvexPolyhedron& p) {
                                     return Estimate{p.surface_area(), 0.0};
                                 }},
                      s);
}

Estimate projected_area(const Shape& s, const Vec3& u_body) {
    const Vec3 u = u_body.normalized();
    return std::visit(Overloaded{[](const Sphere& sp) {
                                     return Estimate{kPi * sp.radius * sp.radius, 0.0};
                                 },
                                 [&](const Clump& c) {
                                     const double fine = clump_shadow(c, u, 4000);
                                     const double coarse = clump_shadow(c, u, 2000);
                                     return Estimate{fine, std::abs(fine - coarse)};
                                 },
                                 [&](const Superquadric& q) {
                                     return richardson(superquadric_shadow(q, 200, u),
                                                       superquadric_shadow(q, 400, u));
                                 },
                                 [&](const ConvexPolyhedron& p) {
                                     return Estimate{p.projected_area(u), 0.0};
                                 }},
                      s);
}

ShapeFactors shape_factors(const ShapeTemplate& t) {
    ShapeFactors f;
    f.volume = t.volume;
    f.surface = surface_area(t.shape);
    f.d_volume = std::cbrt(6.0 * t.volume / kPi);
    f.d_surface = std::sqrt(f.surface.value / kPi);
    f.sphericity = kPi * f.d_volume * f.d_volume / f.surface.value;
    for (int k = 0; k < 3; ++k) {
        f.projected[k] = projected_area(t.shape, Vec3::Unit(k)).value;
        f.crosswise[k] = 0.25 * kPi * f.d_volume * f.d_volume / f.projected[k];
    }
    return f;
}

} // namespace kiln::geometry
