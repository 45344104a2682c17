// Superquadric geometry and beta-function mass properties (geometry/superquadric.hpp).

#include "core/error.hpp"
#include "geometry/shape_metrics.hpp"
#include "geometry/superquadric.hpp"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <gtest/gtest.h>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

using kiln::Mat3;
using kiln::Vec3;
namespace g = kiln::geometry;

namespace {
constexpr double kPi = std::numbers::pi;
constexpr double kExact = 1e-13; // closed forms evaluated through lgamma: round-off only

g::Superquadric make(Vec3 h, double e1, double e2) {
    g::Superquadric q;
    q.half_axes = h;
    q.e1 = e1;
    q.e2 = e2;
    return q;
}

/// Monte Carlo volume and int x_k^2 dV over the bounding box, with standard errors.
struct McResult {
    double volume, volume_sigma;
    Vec3 second, second_sigma;
};
McResult monte_carlo(const g::Superquadric& q, int n, unsigned seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const double box = 8.0 * q.half_axes.prod();
    double hits = 0;
    Vec3 s = Vec3::Zero();
    Vec3 s2 = Vec3::Zero();
    for (int i = 0; i < n; ++i) {
        const Vec3 p = Vec3(u(rng), u(rng), u(rng)).cwiseProduct(q.half_axes);
        if (q.inside_outside(p) < 0.0) {
            hits += 1;
            const Vec3 p2 = p.cwiseProduct(p);
            s += p2;
            s2 += p2.cwiseProduct(p2);
        }
    }
    McResult r{};
    const double nn = n;
    r.volume = box * hits / nn;
    r.volume_sigma = box * std::sqrt(hits / nn * (1 - hits / nn) / nn);
    r.second = box * s / nn;
    for (int k = 0; k < 3; ++k) {
        const double mean = s[k] / nn;
        r.second_sigma[k] = box * std::sqrt((s2[k] / nn - mean * mean) / nn);
    }
    return r;
}
} // namespace

TEST(Superquadric, SphereLimitIsExact) {
    const double r = 0.7;
    const g::Superquadric q = make(Vec3::Constant(r), 1.0, 1.0);
    const double v = 4.0 / 3.0 * kPi * r * r * r;
    EXPECT_NEAR(q.volume() / v, 1.0, kExact);
    const Vec3 inertia = q.inertia_unit_density();
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(inertia[k] / (0.4 * v * r * r), 1.0, kExact);
    }
}

TEST(Superquadric, EllipsoidIsExact) {
    const Vec3 h(1.0, 2.0, 3.0);
    const g::Superquadric q = make(h, 1.0, 1.0);
    const double v = 4.0 / 3.0 * kPi * h.prod();
    EXPECT_NEAR(q.volume() / v, 1.0, kExact);
    const Vec3 inertia = q.inertia_unit_density();
    EXPECT_NEAR(inertia.x() / (v * (4 + 9) / 5.0), 1.0, kExact);
    EXPECT_NEAR(inertia.y() / (v * (1 + 9) / 5.0), 1.0, kExact);
    EXPECT_NEAR(inertia.z() / (v * (1 + 4) / 5.0), 1.0, kExact);
}

TEST(Superquadric, BlockyLimitApproachesTheBox) {
    // e1, e2 -> 0 is the box 2a x 2b x 2c: volume 8abc, I_x = V (b^2 + c^2) / 3. The deficit
    // shrinks monotonically with e; at e = 0.1 the corners are rounded by a few per cent.
    const Vec3 h(1.0, 1.5, 0.5);
    double prev = 1.0;
    for (const double e : {0.4, 0.2, 0.1}) {
        const g::Superquadric q = make(h, e, e);
        const double deficit = 1.0 - q.volume() / (8.0 * h.prod());
        EXPECT_GT(deficit, 0.0);
        EXPECT_LT(deficit, prev);
        prev = deficit;
    }
    constexpr double kBoxTol = 0.03; // rounding of edges and corners at e = 0.1
    const g::Superquadric q = make(h, 0.1, 0.1);
    const double v = 8.0 * h.prod();
    EXPECT_NEAR(q.volume() / v, 1.0, kBoxTol);
    EXPECT_NEAR(q.inertia_unit_density().x() / (v * (h.y() * h.y() + h.z() * h.z()) / 3.0), 1.0,
                kBoxTol);
}

TEST(Superquadric, MassPropertiesAgreeWithMonteCarlo) {
    const int n = 2000000;
    unsigned seed = 1;
    for (const auto& [e1, e2] :
         {std::pair{0.3, 0.6}, std::pair{1.5, 0.4}, std::pair{0.8, 1.8}, std::pair{0.1, 1.0}}) {
        const g::Superquadric q = make(Vec3(1.0, 0.6, 1.4), e1, e2);
        const McResult mc = monte_carlo(q, n, seed++);
        constexpr double kSigmas = 4.5; // passes by chance with probability 1 - 7e-6 per value
        EXPECT_NEAR(q.volume(), mc.volume, kSigmas * mc.volume_sigma) << e1 << " " << e2;
        const Vec3 in = q.inertia_unit_density();
        // Recover the second moments int x_k^2 dV from the principal moments.
        const double tr = 0.5 * in.sum();
        const Vec3 second(tr - in.x(), tr - in.y(), tr - in.z());
        for (int k = 0; k < 3; ++k) {
            EXPECT_NEAR(second[k], mc.second[k], kSigmas * mc.second_sigma[k]) << e1 << " " << e2;
        }
    }
}

TEST(Superquadric, SupportMapBeatsBruteForceOverSurfaceSamples) {
    std::mt19937_64 rng(3);
    std::normal_distribution<double> nd;
    for (const auto& [e1, e2] : {std::pair{1.0, 1.0}, std::pair{0.2, 0.2}, std::pair{0.3, 1.0},
                                 std::pair{1.6, 0.5}, std::pair{0.1, 1.9}}) {
        const g::Superquadric q = make(Vec3(1.0, 2.0, 0.5), e1, e2);
        std::vector<Vec3> samples;
        const int n = 300;
        for (int i = 0; i <= n; ++i) {
            for (int j = 0; j < 2 * n; ++j) {
                samples.push_back(q.parametric_point(-0.5 * kPi + kPi * i / n, -kPi + kPi * j / n));
            }
        }
        for (int t = 0; t < 50; ++t) {
            const Vec3 d = Vec3(nd(rng), nd(rng), nd(rng)).normalized();
            const Vec3 s = q.support(d);
            double brute = -1e300;
            for (const Vec3& p : samples) {
                brute = std::max(brute, d.dot(p));
            }
            constexpr double kOnSurface = 1e-9; // F(support) = 0 up to pow() round-off
            EXPECT_NEAR(q.inside_outside(s), 0.0, kOnSurface) << e1 << " " << e2;
            // The support value is the maximum: never below the samples, and above them only by
            // the sampling gap (samples are 1/300 of a half-turn apart).
            EXPECT_GE(d.dot(s), brute - 1e-12) << e1 << " " << e2;
            constexpr double kSamplingGap = 2e-3; // O(spacing^2 / radius) for pi/300 spacing
            EXPECT_LT(d.dot(s) - brute, kSamplingGap) << e1 << " " << e2;
        }
    }
}

/// The support point by the closed form with nine std::pow calls (the form before the fast path).
Vec3 support_by_pow(const g::Superquadric& sq, const Vec3& d) {
    const double scale = sq.half_axes.maxCoeff();
    const Vec3 h = sq.half_axes / scale;
    const Vec3 dn = d.cwiseAbs() / d.cwiseAbs().maxCoeff();
    const double n1 = 2.0 / sq.e2;
    const double n2 = 2.0 / sq.e1;
    const double p = std::pow(h.x() * dn.x(), 1.0 / (n1 - 1.0));
    const double q = std::pow(h.y() * dn.y(), 1.0 / (n1 - 1.0));
    const double r = std::pow(h.z() * dn.z(), 1.0 / (n2 - 1.0));
    const double big_p = std::pow(p, n1) + std::pow(q, n1);
    const double gg = (big_p > 0.0 ? std::pow(big_p, n2 * (n1 - 1.0) / (n1 * (n2 - 1.0))) : 0.0) +
                      std::pow(r, n2);
    const double s = std::pow(gg, -1.0 / n2);
    const double t = big_p > 0.0 ? s * std::pow(big_p, -(n2 / n1 - 1.0) / (n2 - 1.0)) : 0.0;
    const auto sg = [](double v) { return v < 0.0 ? -1.0 : 1.0; };
    return scale *
           Vec3(sg(d.x()) * h.x() * t * p, sg(d.y()) * h.y() * t * q, sg(d.z()) * h.z() * s * r);
}

TEST(Superquadric, SupportFastPathMatchesThePowForm) {
    // The support map saves powers by exact identities and takes the common exponents as roots;
    // it must agree with the plain closed form to round-off (issue 6: results unchanged beyond
    // 1e-12 relative). Exponents with fast paths (1, 2/3, 0.5, 0.8, 0.2 and pairs) and without,
    // directions at random and along axes, faces and edges (components 0 and tiny).
    std::mt19937_64 rng(17);
    std::normal_distribution<double> nd;
    std::vector<Vec3> dirs{Vec3(1, 0, 0),  Vec3(0, 1, 0),          Vec3(0, 0, -1),   Vec3(1, 1, 0),
                           Vec3(0, -1, 1), Vec3(1, 1e-200, 1e-30), Vec3(1e-9, 1, -1)};
    for (int t = 0; t < 400; ++t) {
        dirs.emplace_back(nd(rng), nd(rng), nd(rng));
    }
    constexpr double kRoundOff = 1e-12; // relative to the largest half-axis
    for (const auto& [e1, e2] :
         {std::pair{0.5, 0.5}, std::pair{2.0 / 3.0, 2.0 / 3.0}, std::pair{0.2, 1.0},
          std::pair{0.8, 0.8}, std::pair{0.3, 0.3}, std::pair{0.2, 0.2}, std::pair{1.0, 0.5},
          std::pair{0.5, 1.0}, std::pair{0.1, 1.9}, std::pair{1.6, 0.5}, std::pair{0.7, 0.4}}) {
        const g::Superquadric q = make(Vec3(1.0e-3, 2.0e-3, 0.5e-3), e1, e2);
        for (const Vec3& d : dirs) {
            const Vec3 fast = q.support(d);
            const Vec3 ref = support_by_pow(q, d);
            EXPECT_LT((fast - ref).norm() / 2.0e-3, kRoundOff)
                << "e1 " << e1 << " e2 " << e2 << " d " << d.transpose();
        }
    }
}

TEST(Superquadric, CubeRootMatchesLibm) {
    // The support map's own cube root (no libm call): within 1 ulp of the exact root (the long
    // double root, rounded) and within 4 ulp of std::cbrt (glibc's is itself up to 3 ulp off),
    // over the normal range, subnormals and huge arguments; 0, infinity and NaN pass through.
    std::mt19937_64 rng(23);
    std::uniform_real_distribution<double> mant(1.0, 2.0);
    std::uniform_int_distribution<int> expo(-1074, 1023);
    std::vector<double> xs{1.0, 2.0, 8.0, 27.0, 0.125, 1e-300, 4.9e-324, 1e-310, 1e300, 1.7e308};
    for (int t = 0; t < 200000; ++t) {
        xs.push_back(std::ldexp(mant(rng), expo(rng)));
    }
    // Distance in units in the last place (positive doubles order like their bit patterns).
    const auto ulps = [](double a, double b) {
        return std::abs(std::bit_cast<std::int64_t>(a) - std::bit_cast<std::int64_t>(b));
    };
    int exact = 0;
    for (const double x : xs) {
        const double y = g::detail::cube_root(x);
        const auto truth = static_cast<double>(std::cbrt(static_cast<long double>(x)));
        ASSERT_LE(ulps(y, truth), 1) << "x " << x << " truth " << truth << " cube_root " << y;
        ASSERT_LE(ulps(y, std::cbrt(x)), 4) << "x " << x;
        exact += y == truth ? 1 : 0;
    }
    EXPECT_GT(exact, 0.99 * static_cast<double>(xs.size())); // nearly always correctly rounded
    EXPECT_EQ(g::detail::cube_root(0.0), 0.0);
    EXPECT_EQ(g::detail::cube_root(std::numeric_limits<double>::infinity()),
              std::numeric_limits<double>::infinity());
    EXPECT_TRUE(std::isnan(g::detail::cube_root(std::numeric_limits<double>::quiet_NaN())));
}

TEST(Superquadric, NormalAtTheSupportPointIsTheDirection) {
    const g::Superquadric q = make(Vec3(1.0, 0.5, 2.0), 0.6, 1.2);
    std::mt19937_64 rng(5);
    std::normal_distribution<double> nd;
    for (int t = 0; t < 100; ++t) {
        const Vec3 d = Vec3(nd(rng), nd(rng), nd(rng)).normalized();
        EXPECT_GT(q.normal(q.support(d)).dot(d), 1.0 - 1e-10);
    }
}

TEST(Superquadric, CurvatureOfSphereAndEllipsoidTips) {
    const g::Superquadric s = make(Vec3::Constant(2.0), 1.0, 1.0);
    const auto ks = s.principal_curvatures(s.radial_surface_point(Vec3(1, 2, -0.5)));
    EXPECT_NEAR(ks[0], 0.5, 1e-12);
    EXPECT_NEAR(ks[1], 0.5, 1e-12);
    // Ellipsoid tip (a, 0, 0): radii of curvature b^2/a and c^2/a.
    const g::Superquadric e = make(Vec3(1.0, 2.0, 3.0), 1.0, 1.0);
    const auto ke = e.principal_curvatures(Vec3(1.0, 0.0, 0.0));
    EXPECT_NEAR(1.0 / ke[0], 9.0, 1e-10);
    EXPECT_NEAR(1.0 / ke[1], 4.0, 1e-10);
    // Side of a cylinder-like superquadric at mid-height: radius a around, flat along the axis.
    const g::Superquadric c = make(Vec3(1.5, 1.5, 2.0), 0.2, 1.0);
    const auto kc = c.principal_curvatures(Vec3(1.5, 0.0, 0.0));
    EXPECT_NEAR(kc[0], 0.0, 1e-12);
    EXPECT_NEAR(1.0 / kc[1], 1.5, 1e-10);
}

// curvature_tensor shares its powers between gradient and Hessian (u^(n1-2) = u^(n1-1) / u, ...)
// and takes integer and half-integer exponents by products and square roots: against P H P / |g|
// from gradient() and hessian() (the plain pow forms) at support points in 300 directions (axes,
// faces and near-zero components included) of seven exponent pairs, e = 0.8 and 0.3 among them.
// Round-off only: the entries agree to 1e-11 of the largest, and the normal to 1e-13.
TEST(Superquadric, CurvatureTensorSharesThePowers) {
    const std::vector<g::Superquadric> shapes = {
        make(Vec3(1.0, 2.0, 3.0), 0.8, 0.8), make(Vec3(1.0, 1.0, 1.0), 0.3, 0.3),
        make(Vec3(1.0, 1.5, 0.7), 0.5, 0.5), make(Vec3(1.0, 1.0, 1.5), 0.2, 1.0),
        make(Vec3(2.0, 1.0, 1.0), 1.0, 0.4), make(Vec3(1.0, 1.0, 1.0), 1.5, 1.2),
        make(Vec3(1.0, 2.0, 3.0), 1.0, 1.0)};
    std::mt19937_64 rng(311);
    std::normal_distribution<double> nd;
    std::vector<Vec3> dirs = {Vec3(1, 0, 0),      Vec3(0, 1, 0),     Vec3(0, 0, -1),
                              Vec3(1, 1e-9, 0.3), Vec3(1e-12, 1, 1), Vec3(0.2, -0.7, 1e-7)};
    while (dirs.size() < 300) {
        dirs.emplace_back(nd(rng), nd(rng), nd(rng));
    }
    double worst = 0.0;
    double worst_normal = 0.0;
    for (const auto& q : shapes) {
        for (const Vec3& d : dirs) {
            const Vec3 p = q.support(d.normalized());
            const Vec3 grad = q.gradient(p);
            const Vec3 n = grad.normalized();
            const Mat3 proj = Mat3::Identity() - n * n.transpose();
            const Mat3 plain = proj * q.hessian(p) * proj / grad.norm();
            Vec3 shared_n;
            const Mat3 shared = q.curvature_tensor(p, &shared_n);
            if (!plain.allFinite()) { // a tip: both infinite or undefined
                EXPECT_FALSE(shared.allFinite());
                continue;
            }
            const double scale = plain.cwiseAbs().maxCoeff() + 1e-300;
            worst = std::max(worst, (shared - plain).cwiseAbs().maxCoeff() / scale);
            worst_normal = std::max(worst_normal, (shared_n - n).norm());
        }
    }
    std::printf("shared powers: worst entry difference %.3g (relative), normal %.3g\n", worst,
                worst_normal);
    EXPECT_LT(worst, 1e-11);
    EXPECT_LT(worst_normal, 1e-13);
}

TEST(Superquadric, PoleCurvatureJumpsAtExponentOne) {
    // At the pole (0, 0, c) the surface drops as rho^(2/e1): flat for e1 < 1, a tip for e1 > 1,
    // and the sphere's 1/r only at e1 = 1.
    for (const double e : {0.95, 1.0, 1.05}) {
        const g::Superquadric q = make(Vec3::Constant(2.0), e, e);
        const auto k = q.principal_curvatures(Vec3(0.0, 0.0, 2.0));
        if (e < 1.0) {
            EXPECT_EQ(k[1], 0.0);
        } else if (e > 1.0) {
            EXPECT_TRUE(std::isinf(k[0]));
        } else {
            EXPECT_NEAR(k[0], 0.5, 1e-12);
            EXPECT_NEAR(k[1], 0.5, 1e-12);
        }
    }
}

TEST(Superquadric, ExponentsOutsideTheSupportedRangeAreInputErrors) {
    EXPECT_THROW(make(Vec3::Ones(), 2.5, 1.0).validate("x"), kiln::InputError);
    EXPECT_THROW(make(Vec3::Ones(), 1.0, 0.05).validate("x"), kiln::InputError);
    EXPECT_THROW(make(Vec3(1, 0, 1), 1.0, 1.0).validate("x"), kiln::InputError);
    EXPECT_NO_THROW(make(Vec3::Ones(), 0.1, 1.9).validate("x"));
}

TEST(Superquadric, SurfaceAndShadowOfASpheroid) {
    // Prolate spheroid a = b < c: S = 2 pi a^2 (1 + c / (a e) asin e), e^2 = 1 - a^2/c^2.
    const double a = 1.0;
    const double c = 2.5;
    const g::Shape s = make(Vec3(a, a, c), 1.0, 1.0);
    const double ecc = std::sqrt(1.0 - a * a / (c * c));
    const double area = 2.0 * kPi * a * a * (1.0 + c / (a * ecc) * std::asin(ecc));
    const g::Estimate est = g::surface_area(s);
    constexpr double kArea = 1e-6; // Richardson-extrapolated triangulation, relative
    EXPECT_NEAR(est.value / area, 1.0, kArea);
    EXPECT_LT(std::abs(est.value - area), est.error); // the error estimate is conservative
    EXPECT_NEAR(g::projected_area(s, Vec3::UnitZ()).value / (kPi * a * a), 1.0, kArea);
    EXPECT_NEAR(g::projected_area(s, Vec3::UnitX()).value / (kPi * a * c), 1.0, kArea);
}
