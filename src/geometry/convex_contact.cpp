// Narrow phase on support maps: dispatch, and the Newton method on the sphere of directions.
// See convex_contact.hpp and docs/theory/shapes.md ("Contact detection").

#include "geometry/convex_contact.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace kiln::geometry {

ConvexContact convex_contact(const PosedSuperquadric& a, const PosedSuperquadric& b,
                             ConvexMethod method) {
    switch (method) {
    case ConvexMethod::kCcdEpa:
        return ccd_contact(a, b, false);
    case ConvexMethod::kCcdMpr:
        return ccd_contact(a, b, true);
    case ConvexMethod::kSupportNewton:
        return support_newton_contact(a, b);
    }
    return {};
}

ContactCurvature contact_curvature(const PosedSuperquadric& a, const PosedSuperquadric& b,
                                   const ConvexContact& c) {
    // Deepest points: A's support against the normal, B's along it. Each body's curvature tensor
    // is rotated to the world frame; near the contact the gap between the surfaces is
    // 1/2 x^T (K_A + K_B) x in the common tangent plane (Johnson 1985, Sec. 4.1).
    const Vec3 pa = a.q.conjugate() * (a.support(-c.normal) - a.x);
    const Vec3 pb = b.q.conjugate() * (b.support(c.normal) - b.x);
    const Mat3 ra = a.q.toRotationMatrix();
    const Mat3 rb = b.q.toRotationMatrix();
    const Mat3 k = ra * a.shape->curvature_tensor(pa) * ra.transpose() +
                   rb * b.shape->curvature_tensor(pb) * rb.transpose();
    const Vec3 e1 = c.normal.unitOrthogonal();
    const Vec3 e2 = c.normal.cross(e1);
    const double k11 = e1.dot(k * e1);
    const double k22 = e2.dot(k * e2);
    const double k12 = 0.5 * (e1.dot(k * e2) + e2.dot(k * e1));
    const double mean = 0.5 * (k11 + k22);
    const double diff = std::sqrt(0.25 * (k11 - k22) * (k11 - k22) + k12 * k12);
    ContactCurvature out;
    out.k_min = std::max(0.0, mean - diff);
    out.k_max = std::max(0.0, mean + diff);
    const double gauss = out.k_min * out.k_max;
    out.effective_radius =
        gauss > 0.0 ? 1.0 / std::sqrt(gauss) : std::numeric_limits<double>::infinity();
    out.hertz_area = std::numbers::pi * out.effective_radius * std::max(0.0, c.depth);
    return out;
}

namespace {

constexpr int kMaxNewton = 100;   // Newton iterations per start
constexpr int kStarts = 4;        // Newton runs from the best sampled directions
constexpr double kGradTol = 1e-9; // |tangential gradient| / L; the support round-off is ~1e-10
constexpr double kFdStep = 1e-6;  // finite-difference step (rad) of the Hessian
constexpr double kMaxTurn = 0.5;  // largest Newton step (rad)

/// f(n) = h_A(n) + h_B(-n) and its Euclidean gradient p = s_A(n) - s_B(-n) (Danskin).
struct Eval {
    double f;
    Vec3 p;
};

class SupportMinimiser {
  public:
    SupportMinimiser(const PosedSuperquadric& a, const PosedSuperquadric& b) : a_(a), b_(b) {
        length_ = a.length_scale() + b.length_scale();
    }

    [[nodiscard]] Eval eval(const Vec3& n) const {
        const Vec3 p = a_.support(n) - b_.support(-n);
        return {n.dot(p), p};
    }

    /// Newton on the sphere from n0; returns the final direction and whether it converged.
    std::pair<Vec3, bool> newton(Vec3 n, int& iterations) const {
        for (int it = 0; it < kMaxNewton; ++it) {
            ++iterations;
            const Eval e = eval(n);
            const Vec3 g = e.p - e.f * n; // tangential (Riemannian) gradient
            if (g.norm() < kGradTol * length_) {
                return {n, true};
            }
            const Vec3 e1 = n.unitOrthogonal();
            const Vec3 e2 = n.cross(e1);
            // Riemannian Hessian: P (dp/dn) P - f I on the tangent plane; dp/dn (the summed
            // curvature-radius tensors of A and B) by central differences.
            std::array<Vec3, 2> dp;
            const std::array<Vec3, 2> basis{e1, e2};
            for (std::size_t j = 0; j < 2; ++j) {
                const Vec3 pp = eval((n + kFdStep * basis[j]).normalized()).p;
                const Vec3 pm = eval((n - kFdStep * basis[j]).normalized()).p;
                dp[j] = (pp - pm) / (2.0 * kFdStep);
            }
            Eigen::Matrix2d h;
            h << e1.dot(dp[0]), e1.dot(dp[1]), e2.dot(dp[0]), e2.dot(dp[1]);
            h = 0.5 * (h + h.transpose());
            h -= e.f * Eigen::Matrix2d::Identity();
            const Eigen::Vector2d rhs(-e1.dot(g), -e2.dot(g));
            Eigen::Vector2d step;
            // Where f is not convex (deep overlap against a sharp tip) shift the Hessian to
            // positive definite: a damped Newton step, still a descent direction.
            const double half_trace = 0.5 * h.trace();
            const double lambda_min =
                half_trace - std::sqrt(std::max(0.0, half_trace * half_trace - h.determinant()));
            const double floor = 1e-9 * length_;
            if (lambda_min < floor) {
                h += (floor - lambda_min) * Eigen::Matrix2d::Identity();
            }
            // 2 x 2 solve by Cramer's rule (h is positive definite after the shift).
            const double det = h(0, 0) * h(1, 1) - h(0, 1) * h(1, 0);
            step = Eigen::Vector2d((h(1, 1) * rhs.x() - h(0, 1) * rhs.y()) / det,
                                   (h(0, 0) * rhs.y() - h(1, 0) * rhs.x()) / det);
            if (step.norm() > kMaxTurn) {
                step *= kMaxTurn / step.norm();
            }
            // Backtracking until f decreases (Armijo with a small constant).
            const double slope = -rhs.dot(step);
            double t = 1.0;
            Vec3 trial = n;
            bool moved = false;
            for (int ls = 0; ls < 20; ++ls) { // t >= 2e-6: shorter steps are round-off
                trial = (n + t * (step.x() * e1 + step.y() * e2)).normalized();
                if (eval(trial).f <= e.f + 1e-4 * t * slope) {
                    moved = true;
                    break;
                }
                t *= 0.5;
            }
            if (!moved) {
                // No decrease possible: f is flat to round-off here. Converged when the gradient
                // is small (the depth error is then about |g|^2 / curvature, negligible).
                return {n, g.norm() < 1e-7 * length_};
            }
            n = trial;
        }
        return {n, false};
    }

    [[nodiscard]] double length() const { return length_; }

  private:
    const PosedSuperquadric& a_;
    const PosedSuperquadric& b_;
    double length_ = 0.0;
};

} // namespace

ConvexContact support_newton_contact(const PosedSuperquadric& a, const PosedSuperquadric& b,
                                     const Vec3* warm_normal) {
    const SupportMinimiser m(a, b);
    if (warm_normal != nullptr) {
        int iterations = 0;
        const auto [n, ok] = m.newton(-*warm_normal, iterations);
        if (ok) {
            ConvexContact c;
            c.depth = m.eval(n).f;
            c.normal = -n;
            c.converged = true;
            c.iterations = iterations;
            c.touching = c.depth > 0.0;
            c.point = 0.5 * (a.support(-c.normal) + b.support(c.normal));
            return c;
        }
    }
    // Candidate directions: the 26 directions to the faces, edges and corners of a cube, and the
    // centre line (n points from A towards B at the minimum when they overlap).
    std::vector<std::pair<double, Vec3>> cand;
    for (int i = -1; i <= 1; ++i) {
        for (int j = -1; j <= 1; ++j) {
            for (int k = -1; k <= 1; ++k) {
                if (i != 0 || j != 0 || k != 0) {
                    const Vec3 n = Vec3(i, j, k).normalized();
                    cand.emplace_back(m.eval(n).f, n);
                }
            }
        }
    }
    if ((b.x - a.x).norm() > 0.0) {
        const Vec3 n = (b.x - a.x).normalized();
        cand.emplace_back(m.eval(n).f, n);
    }
    std::partial_sort(cand.begin(), cand.begin() + kStarts, cand.end(),
                      [](const auto& l, const auto& r) { return l.first < r.first; });
    // Smallest f among the starts that converged (a start may stall near a maximum of f).
    ConvexContact best;
    best.depth = 1e300;
    best.converged = false;
    int iterations = 0;
    for (int s = 0; s < kStarts; ++s) {
        const auto [n, ok] = m.newton(cand[static_cast<std::size_t>(s)].second, iterations);
        const double f = m.eval(n).f;
        if ((ok && !best.converged) || (ok == best.converged && f < best.depth)) {
            best.depth = f;
            best.normal = -n;
            best.converged = ok;
        }
    }
    best.iterations = iterations;
    best.touching = best.depth > 0.0;
    best.point = 0.5 * (a.support(-best.normal) + b.support(best.normal));
    return best;
}

} // namespace kiln::geometry
