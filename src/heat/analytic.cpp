#include "heat/analytic.hpp"

#include "core/error.hpp"

#include <cmath>
#include <functional>
#include <numbers>

namespace kiln::heat::analytic {

namespace {

/// Bisection for a sign change of f on [lo, hi] down to adjacent doubles.
double bisect(const std::function<double(double)>& f, double lo, double hi) {
    double flo = f(lo);
    for (int it = 0; it < 200; ++it) {
        const double mid = 0.5 * (lo + hi);
        if (mid <= lo || mid >= hi) {
            break;
        }
        const double fm = f(mid);
        if ((fm > 0.0) == (flo > 0.0)) {
            lo = mid;
            flo = fm;
        } else {
            hi = mid;
        }
    }
    return 0.5 * (lo + hi);
}

} // namespace

std::vector<double> sphere_eigenvalues(double biot, int count) {
    KILN_ASSERT(biot > 0.0 && count > 0);
    const double pi = std::numbers::pi;
    // lambda cos(lambda) + (Bi - 1) sin(lambda) changes sign once on each ((n-1) pi, n pi):
    // it is Bi*lambda > 0 near 0 and (n pi)(-1)^n at n pi.
    const auto f = [biot](double x) { return x * std::cos(x) + (biot - 1.0) * std::sin(x); };
    std::vector<double> roots;
    for (int n = 1; n <= count; ++n) {
        const double lo = (n == 1) ? 1e-12 : (n - 1) * pi;
        roots.push_back(bisect(f, lo, n * pi));
    }
    return roots;
}

std::vector<double> slab_eigenvalues(double biot, int count) {
    KILN_ASSERT(biot > 0.0 && count > 0);
    const double pi = std::numbers::pi;
    // lambda sin(lambda) - Bi cos(lambda): -Bi (-1)^(n-1) at (n-1) pi, (n-1/2) pi (-1)^(n-1) at
    // (n - 1/2) pi.
    const auto f = [biot](double x) { return x * std::sin(x) - biot * std::cos(x); };
    std::vector<double> roots;
    for (int n = 1; n <= count; ++n) {
        roots.push_back(bisect(f, (n - 1) * pi, (n - 0.5) * pi));
    }
    return roots;
}

double sphere_theta(const std::vector<double>& lambda, double r_over_r, double fo) {
    double sum = 0.0;
    for (const double l : lambda) {
        const double c = 4.0 * (std::sin(l) - l * std::cos(l)) / (2.0 * l - std::sin(2.0 * l));
        const double x = l * r_over_r;
        const double shape = x > 1e-12 ? std::sin(x) / x : 1.0;
        sum += c * std::exp(-l * l * fo) * shape;
    }
    return sum;
}

double sphere_mean_theta(const std::vector<double>& lambda, double fo) {
    double sum = 0.0;
    for (const double l : lambda) {
        const double s = std::sin(l) - l * std::cos(l);
        const double c = 4.0 * s / (2.0 * l - std::sin(2.0 * l));
        sum += 3.0 * c * s / (l * l * l) * std::exp(-l * l * fo);
    }
    return sum;
}

double slab_theta(const std::vector<double>& lambda, double x_over_l, double fo) {
    double sum = 0.0;
    for (const double l : lambda) {
        const double c = 4.0 * std::sin(l) / (2.0 * l + std::sin(2.0 * l));
        sum += c * std::exp(-l * l * fo) * std::cos(l * x_over_l);
    }
    return sum;
}

double slab_mean_theta(const std::vector<double>& lambda, double fo) {
    double sum = 0.0;
    for (const double l : lambda) {
        const double c = 4.0 * std::sin(l) / (2.0 * l + std::sin(2.0 * l));
        sum += c * std::sin(l) / l * std::exp(-l * l * fo);
    }
    return sum;
}

} // namespace kiln::heat::analytic
