// Superquadric geometry and mass properties. References: Barr, IEEE CG&A 1 (1981) 11-23;
// Jaklic, Leonardis & Solina, "Segmentation and Recovery of Superquadrics", Springer 2000, Ch. 2
// (volume Eq. 2.60, moments of inertia Eqs. 2.62-2.64). Derivations in docs/theory/shapes.md.

#include "geometry/superquadric.hpp"

#include "core/error.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <fmt/format.h>
#include <limits>
#include <numbers>

namespace kiln::geometry {

double beta_function(double x, double y) {
    return std::exp(std::lgamma(x) + std::lgamma(y) - std::lgamma(x + y));
}

void Superquadric::validate(const std::string& where) const {
    if (!(half_axes.array() > 0.0).all() || !half_axes.allFinite()) {
        throw InputError(where + ": half_axes: every half-axis must be > 0 m");
    }
    for (const double e : {e1, e2}) {
        if (!(e >= kMinExponent && e <= kMaxExponent)) {
            throw InputError(fmt::format(
                "{}: exponents: {:g} is out of range; allowed: {:g} <= e <= {:g} (convex and "
                "smooth enough for support map and curvature)",
                where, e, kMinExponent, kMaxExponent));
        }
    }
}

namespace {
/// |v|^p for p > 0 (0 at 0).
double apow(double v, double p) {
    return std::pow(std::abs(v), p);
}
double sgn(double v) {
    return v < 0.0 ? -1.0 : 1.0;
}
} // namespace

double Superquadric::inside_outside(const Vec3& p) const {
    const double n1 = 2.0 / e2;
    const double n2 = 2.0 / e1;
    const double s = apow(p.x() / half_axes.x(), n1) + apow(p.y() / half_axes.y(), n1);
    return std::pow(s, n2 / n1) + apow(p.z() / half_axes.z(), n2) - 1.0;
}

Vec3 Superquadric::gradient(const Vec3& p) const {
    const double n1 = 2.0 / e2;
    const double n2 = 2.0 / e1;
    const double u = std::abs(p.x()) / half_axes.x();
    const double v = std::abs(p.y()) / half_axes.y();
    const double w = std::abs(p.z()) / half_axes.z();
    const double s = std::pow(u, n1) + std::pow(v, n1);
    const double sm = s > 0.0 ? std::pow(s, n2 / n1 - 1.0) : 0.0;
    return {n2 * sm * std::pow(u, n1 - 1.0) * sgn(p.x()) / half_axes.x(),
            n2 * sm * std::pow(v, n1 - 1.0) * sgn(p.y()) / half_axes.y(),
            n2 * std::pow(w, n2 - 1.0) * sgn(p.z()) / half_axes.z()};
}

Mat3 Superquadric::hessian(const Vec3& p) const {
    // F = S^m + w^n2, S = u^n1 + v^n1, m = n2/n1, u = |x|/a, v = |y|/b, w = |z|/c.
    const double n1 = 2.0 / e2;
    const double n2 = 2.0 / e1;
    const double m = n2 / n1;
    const Vec3& h = half_axes;
    const double u = std::abs(p.x()) / h.x();
    const double v = std::abs(p.y()) / h.y();
    const double w = std::abs(p.z()) / h.z();
    const double s = std::pow(u, n1) + std::pow(v, n1);
    Mat3 hess = Mat3::Zero();
    if (s > 0.0) {
        const double s1 = std::pow(s, m - 1.0);
        const double s2 = std::pow(s, m - 2.0);
        const double du = std::pow(u, n1 - 1.0);
        const double dv = std::pow(v, n1 - 1.0);
        hess(0, 0) = n2 *
                     ((m - 1.0) * n1 * s2 * du * du + (n1 - 1.0) * s1 * std::pow(u, n1 - 2.0)) /
                     (h.x() * h.x());
        hess(1, 1) = n2 *
                     ((m - 1.0) * n1 * s2 * dv * dv + (n1 - 1.0) * s1 * std::pow(v, n1 - 2.0)) /
                     (h.y() * h.y());
        hess(0, 1) = n2 * (m - 1.0) * n1 * s2 * du * dv * sgn(p.x()) * sgn(p.y()) / (h.x() * h.y());
        hess(1, 0) = hess(0, 1);
    } else {
        // On the z axis: the surface near the pole drops as rho^n2, so the x-y curvature is 0
        // for n2 > 2 (e1 < 1), infinite for n2 < 2 (e1 > 1) and 2/a^2, 2/b^2 for n2 = 2 (exact
        // along the axes when n1 != 2).
        const double k =
            n2 < 2.0 ? std::numeric_limits<double>::infinity() : (n2 > 2.0 ? 0.0 : 2.0);
        hess(0, 0) = k / (h.x() * h.x());
        hess(1, 1) = k / (h.y() * h.y());
    }
    hess(2, 2) = n2 * (n2 - 1.0) * std::pow(w, n2 - 2.0) / (h.z() * h.z());
    return hess;
}

Vec3 Superquadric::radial_surface_point(const Vec3& u_body) const {
    // F + 1 is homogeneous of degree 2/e1 in p, so F(lambda u) = 0 gives lambda = (F(u)+1)^(-e1/2).
    const double f = inside_outside(u_body) + 1.0;
    return std::pow(f, -0.5 * e1) * u_body;
}

Vec3 Superquadric::parametric_point(double eta, double omega) const {
    const auto spow = [](double v, double e) { return sgn(v) * std::pow(std::abs(v), e); };
    const double ce = spow(std::cos(eta), e1);
    return {half_axes.x() * ce * spow(std::cos(omega), e2),
            half_axes.y() * ce * spow(std::sin(omega), e2),
            half_axes.z() * spow(std::sin(eta), e1)};
}

namespace detail {
// Without libm's cbrt, which rebuilds the exponent through out-of-line calls (cbrt, frexp and
// scalbn were ~30 % of the profile of the e = 0.8 superquadric scene) and is up to 3 ulp off.
// Start: the bits of x divided by 3 plus a constant (Kahan's estimate: the biased exponent
// divided by 3, a few per cent off), then two Halley steps (cubic convergence: 3e-2 -> 1e-14)
// and one Newton step with a fused residual; within 1 ulp of the exact root
// (Superquadric.CubeRootMatchesLibm). Subnormal and huge arguments are scaled by 2^(+-300)
// first.
double cube_root(double x) {
    if (!(x > 0.0) || x == std::numeric_limits<double>::infinity()) {
        return x;
    }
    double post = 1.0;
    if (x < 0x1p-900) {
        x *= 0x1p300;
        post = 0x1p-100;
    } else if (x > 0x1p900) {
        x *= 0x1p-300;
        post = 0x1p100;
    }
    double y = std::bit_cast<double>(std::bit_cast<std::uint64_t>(x) / 3 + 0x2A9F7893782DA1CEULL);
    for (int i = 0; i < 2; ++i) {
        const double y3 = y * y * y;
        y *= (y3 + 2.0 * x) / (2.0 * y3 + x);
    }
    // Newton step on y^3 - x with the residual from fused products (the square's rounding error
    // e2 included), so the result is the correctly rounded root in all but ~1e-4 of the cases.
    const double y2 = y * y;
    const double e2 = std::fma(y, y, -y2);
    const double residual = std::fma(y2, y, -x) + e2 * y;
    y -= residual / (3.0 * y2);
    return y * post;
}

} // namespace detail

namespace {
using detail::cube_root;

/// x^a for x >= 0 and the exponents a = 1/(n - 1) and -1/n of a support point (n = 2/e): roots the
/// common exponents take without libm's pow (e = 1, 2/3, 0.5, 0.8, 0.2 give a = 1, 1/2, 1/3,
/// 2/3, 1/9; -1/n = -1/4 for e = 0.5), exp2 and log2 otherwise. An exponent within 1e-14 of a
/// special value counts as that value (2/e is not exact in binary): the relative change of x^a, |da
/// ln x|, stays below 1e-12 for every x >= 1e-308.
double support_pow(double x, double a) {
    constexpr double kSame = 1e-15;
    if (std::abs(a - 1.0) < kSame) {
        return x;
    }
    if (std::abs(a - 0.5) < kSame) {
        return std::sqrt(x);
    }
    if (std::abs(a - 1.0 / 3.0) < kSame) {
        return cube_root(x);
    }
    if (std::abs(a - 2.0 / 3.0) < kSame) {
        const double c = cube_root(x);
        return c * c;
    }
    if (std::abs(a - 1.0 / 9.0) < kSame) {
        return cube_root(cube_root(x));
    }
    if (std::abs(a + 0.25) < kSame) {
        return 1.0 / std::sqrt(std::sqrt(x));
    }
    if (std::abs(a + 0.5) < kSame) {
        return 1.0 / std::sqrt(x);
    }
    // Other exponents: 2^(a log2 x), about a quarter cheaper than libm's pow (which keeps extra
    // precision for every base and exponent). Error: that of log2 scaled by |a log2 x|, i.e.
    // below 1.6e-13 relative for any result above the underflow limit (|a log2 x| < 1075).
    return std::exp2(a * std::log2(x));
}
} // namespace

Vec3 Superquadric::support(const Vec3& d) const {
    // grad F parallel to d in the first octant (signs restored at the end); with n1 = 2/e2,
    // n2 = 2/e1 and lengths scaled by the largest half-axis (the support point scales linearly):
    //   u = t p, v = t q, w = s r, p = (a dx)^(1/(n1-1)), q = (b dy)^(1/(n1-1)),
    //   r = (c dz)^(1/(n2-1)), t = s P^(-(n2/n1-1)/(n2-1)), P = p^n1 + q^n1,
    //   s = (P^(n2 (n1-1) / (n1 (n2-1))) + r^n2)^(-1/n2).
    // Fewer powers by exact identities: p^n1 = p (a dx) (as n1/(n1-1) = 1 + 1/(n1-1)), likewise
    // q^n1 and r^n2, and P^(n2 (n1-1) / (n1 (n2-1))) = P P^kappa with kappa = -(n2/n1-1)/(n2-1)
    // (the two exponents differ by exactly 1); kappa = 0 when e1 = e2. Five powers instead of
    // nine, and support_pow takes the common exponents as roots (docs/performance.md).
    KILN_ASSERT(d.squaredNorm() > 0.0);
    if (e1 == 1.0 && e2 == 1.0) {
        // Ellipsoid (and sphere): A^2 d / |A d| with A = diag(a, b, c), no powers needed.
        const Vec3 ad = half_axes.cwiseProduct(d);
        return half_axes.cwiseProduct(ad) / ad.norm();
    }
    const double scale = half_axes.maxCoeff();
    const Vec3 h = half_axes / scale;
    const Vec3 dn = d.cwiseAbs() / d.cwiseAbs().maxCoeff();
    const double n1 = 2.0 / e2;
    const double n2 = 2.0 / e1;
    const double a1 = 1.0 / (n1 - 1.0);
    const double a2 = 1.0 / (n2 - 1.0);
    const double hx = h.x() * dn.x();
    const double hy = h.y() * dn.y();
    const double hz = h.z() * dn.z();
    const double p = support_pow(hx, a1);
    const double q = support_pow(hy, a1);
    const double r = support_pow(hz, a2);
    const double big_p = p * hx + q * hy;
    const double kappa = -(n2 / n1 - 1.0) * a2;
    const double pk = big_p > 0.0 && kappa != 0.0 ? support_pow(big_p, kappa) : 1.0;
    const double g = (big_p > 0.0 ? big_p * pk : 0.0) + r * hz;
    const double s = support_pow(g, -1.0 / n2);
    const double t = big_p > 0.0 ? s * pk : 0.0;
    return scale *
           Vec3(sgn(d.x()) * h.x() * t * p, sgn(d.y()) * h.y() * t * q, sgn(d.z()) * h.z() * s * r);
}

namespace {
/// x^a for x >= 0 and a >= 0: integer and half-integer exponents up to 16 (e = 0.8 gives
/// 2/e - 1 = 1.5 and 2/e - 2 = 0.5; e = 0.5 and 1 integers) by products and one square root,
/// within a few ulp of pow; std::pow otherwise. An exponent within 1e-14 of such a value counts as
/// it (2/e is not exact in binary): a relative change of |da ln x| < 1e-11 for x >= 1e-308.
double curvature_pow(double x, double a) {
    const double twice = 2.0 * a;
    const double k = std::round(twice);
    if (!(std::abs(twice - k) < 2e-14 && k >= 0.0 && k <= 32.0)) {
        return std::pow(x, a);
    }
    const int whole = static_cast<int>(k) / 2;
    double r = (static_cast<int>(k) % 2 != 0) ? std::sqrt(x) : 1.0;
    double base = x;
    for (int e = whole; e > 0; e >>= 1) { // x^whole by squaring
        if ((e & 1) != 0) {
            r *= base;
        }
        base *= base;
    }
    return r;
}
} // namespace

Mat3 Superquadric::curvature_tensor(const Vec3& p, Vec3* normal_out) const {
    // Shape operator of an implicit surface: restricted to the tangent plane, the curvature tensor
    // is P H P / |grad F| with P = I - n n^T (e.g. Goldman, CAGD 22 (2005) 632, Sec. 4). Gradient
    // and Hessian as in gradient() and hessian(), with their powers shared: u^(n1-2) =
    // u^(n1-1) / u, S = u u^(n1-1) + v v^(n1-1), S^(m-2) = S^(m-1) / S, and S^(m-1) = 1 when
    // e1 = e2 (m = 1): three powers instead of fourteen (none for e = 0.5, 0.8, 1; round-off
    // differences only, Superquadric.CurvatureTensorSharesThePowers).
    const double n1 = 2.0 / e2;
    const double n2 = 2.0 / e1;
    const double m = n2 / n1;
    const Vec3& h = half_axes;
    const double u = std::abs(p.x()) / h.x();
    const double v = std::abs(p.y()) / h.y();
    const double w = std::abs(p.z()) / h.z();
    const double du = curvature_pow(u, n1 - 1.0);
    const double dv = curvature_pow(v, n1 - 1.0);
    const double dw = curvature_pow(w, n2 - 1.0);
    const double s = u * du + v * dv;
    Vec3 g(0.0, 0.0, n2 * dw * sgn(p.z()) / h.z());
    Mat3 hess = Mat3::Zero();
    if (s > 0.0) {
        const double s1 = m == 1.0 ? 1.0 : curvature_pow(s, m - 1.0);
        const double s2 = s1 / s;
        g.x() = n2 * s1 * du * sgn(p.x()) / h.x();
        g.y() = n2 * s1 * dv * sgn(p.y()) / h.y();
        const double ddu = u > 0.0 ? du / u : std::pow(u, n1 - 2.0);
        const double ddv = v > 0.0 ? dv / v : std::pow(v, n1 - 2.0);
        hess(0, 0) = n2 * ((m - 1.0) * n1 * s2 * du * du + (n1 - 1.0) * s1 * ddu) / (h.x() * h.x());
        hess(1, 1) = n2 * ((m - 1.0) * n1 * s2 * dv * dv + (n1 - 1.0) * s1 * ddv) / (h.y() * h.y());
        hess(0, 1) = n2 * (m - 1.0) * n1 * s2 * du * dv * sgn(p.x()) * sgn(p.y()) / (h.x() * h.y());
        hess(1, 0) = hess(0, 1);
    } else {
        // On the z axis (hessian() explains the limits).
        const double k =
            n2 < 2.0 ? std::numeric_limits<double>::infinity() : (n2 > 2.0 ? 0.0 : 2.0);
        hess(0, 0) = k / (h.x() * h.x());
        hess(1, 1) = k / (h.y() * h.y());
    }
    const double ddw = w > 0.0 ? dw / w : std::pow(w, n2 - 2.0);
    hess(2, 2) = n2 * (n2 - 1.0) * ddw / (h.z() * h.z());
    const double gn = g.norm();
    KILN_ASSERT(gn > 0.0);
    const Vec3 n = g / gn;
    if (normal_out != nullptr) {
        *normal_out = n;
    }
    const Mat3 proj = Mat3::Identity() - n * n.transpose();
    return proj * hess * proj / gn;
}

std::array<double, 2> Superquadric::principal_curvatures(const Vec3& p) const {
    Vec3 n;
    const Mat3 tensor = curvature_tensor(p, &n);
    if (!tensor.allFinite()) {
        // A tip or crease (exponent > 1 at a pole or an axis): zero radius.
        return {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    }
    const Eigen::SelfAdjointEigenSolver<Mat3> es(tensor);
    // One eigenvalue belongs to the normal (0); drop the one whose vector is most parallel to n.
    int drop = 0;
    for (int i = 1; i < 3; ++i) {
        if (std::abs(es.eigenvectors().col(i).dot(n)) >
            std::abs(es.eigenvectors().col(drop).dot(n))) {
            drop = i;
        }
    }
    std::array<double, 2> out{};
    int j = 0;
    for (int i = 0; i < 3; ++i) {
        if (i != drop) {
            out[static_cast<std::size_t>(j++)] = std::max(0.0, es.eigenvalues()[i]);
        }
    }
    if (out[0] > out[1]) {
        std::swap(out[0], out[1]);
    }
    return out;
}

double Superquadric::volume() const {
    return 2.0 * half_axes.prod() * e1 * e2 * beta_function(0.5 * e1 + 1.0, e1) *
           beta_function(0.5 * e2, 0.5 * e2);
}

Vec3 Superquadric::inertia_unit_density() const {
    // With A = B(3 e2/2, e2/2) B(e1/2, 2 e1 + 1) (x-y second moments) and
    // C = B(e2/2, e2/2 + 1) B(3 e1/2, e1 + 1) (z second moment):
    //   int x^2 dV = a^3 b c e1 e2 A / 2, int y^2 dV = a b^3 c e1 e2 A / 2,
    //   int z^2 dV = 2 a b c^3 e1 e2 C.
    const double a = half_axes.x();
    const double b = half_axes.y();
    const double c = half_axes.z();
    const double abc = a * b * c;
    const double big_a =
        beta_function(1.5 * e2, 0.5 * e2) * beta_function(0.5 * e1, 2.0 * e1 + 1.0);
    const double big_c =
        beta_function(0.5 * e2, 0.5 * e2 + 1.0) * beta_function(1.5 * e1, e1 + 1.0);
    const double xx = 0.5 * abc * a * a * e1 * e2 * big_a;
    const double yy = 0.5 * abc * b * b * e1 * e2 * big_a;
    const double zz = 2.0 * abc * c * c * e1 * e2 * big_c;
    return {yy + zz, xx + zz, xx + yy};
}

double Superquadric::bounding_radius() const {
    // The farthest surface point lies on a direction maximising |x|; sample the parametric form
    // and bound it from above by the box diagonal when the shape is blocky.
    double r = 0.0;
    constexpr int kN = 64;
    for (int i = 0; i <= kN; ++i) {
        const double eta = 0.5 * std::numbers::pi * i / kN;
        for (int j = 0; j <= kN; ++j) {
            r = std::max(r, parametric_point(eta, 0.5 * std::numbers::pi * j / kN).norm());
        }
    }
    return std::min(r * (1.0 + 1e-3), half_axes.norm());
}

} // namespace kiln::geometry
