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
        return support_newton_contact(a, b, nullptr);
    }
    return {};
}

ContactCurvature contact_curvature(const PosedSuperquadric& a, const PosedSuperquadric& b,
                                   const ConvexContact& c) {
    // Deepest points: A's support against the normal, B's along it. Each body's curvature tensor
    // is rotated to the world frame; near the contact the gap between the surfaces is
    // 1/2 x^T (K_A + K_B) x in the common tangent plane (Johnson 1985, Sec. 4.1).
    const Vec3 pa =
        a.q.conjugate() * ((c.deepest_known ? c.deepest_a : a.support(-c.normal)) - a.x);
    const Vec3 pb = b.q.conjugate() * ((c.deepest_known ? c.deepest_b : b.support(c.normal)) - b.x);
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
constexpr double kMaxTurn = 0.5;  // largest Newton step (rad)
// Below this exponent the Hessian comes from differences even with analytic_hessian: the
// curvature of a blocky body changes within far less than a Newton step near its flat faces, and
// the point value made e = 0.3 searches slower (docs/performance.md, session 11).
constexpr double kBlockyHessian = 0.5;
constexpr double kFNoise = 1e-14; // round-off of f relative to the summed |coordinates| of s_A, s_B

/// f(n) = h_A(n) + h_B(-n), its Euclidean gradient p = s_A(n) - s_B(-n) (Danskin) and the two
/// support points (m, world frame), kept so that the contact point and the curvature reuse them.
struct Eval {
    double f;
    Vec3 p;
    Vec3 sa; ///< s_A(n)
    Vec3 sb; ///< s_B(-n)
};

/// End of a Newton run: the final direction, whether it converged, and f there.
struct NewtonEnd {
    Vec3 n;
    bool ok;
    Eval e;
};

class SupportMinimiser {
  public:
    SupportMinimiser(const PosedSuperquadric& a, const PosedSuperquadric& b,
                     const NewtonSettings& settings)
        : a_(a), b_(b), settings_(settings) {
        length_ = a.length_scale() + b.length_scale();
        blocky_ = std::min({a.shape->e1, a.shape->e2, b.shape->e1, b.shape->e2}) < kBlockyHessian;
    }

    [[nodiscard]] Eval eval(const Vec3& n) const {
        return eval_from(n, a_.support(n), b_.support(-n));
    }

    /// The evaluation at n from the supports s_A(n) and s_B(-n).
    [[nodiscard]] static Eval eval_from(const Vec3& n, const Vec3& sa, const Vec3& sb) {
        const Vec3 p = sa - sb;
        return {n.dot(p), p, sa, sb};
    }

    /// Newton on the sphere from n0; returns the final direction, whether it converged and f
    /// there. The accepted trial's evaluation serves the next iteration (it is f at the new n).
    NewtonEnd newton(const Vec3& n0, int& iterations) const {
        return newton(n0, eval(n0), iterations);
    }

    /// The same with f already evaluated at n0 (e0 = eval(n0)).
    NewtonEnd newton(Vec3 n, Eval e, int& iterations) const {
        // dp/dn as a world-frame matrix acting on tangent vectors: from finite differences, then
        // (secant_updates) carried to the next iterate by Broyden's update after a full step.
        Mat3 jac = Mat3::Zero();
        bool have_jac = false;
        for (int it = 0; it < kMaxNewton; ++it) {
            ++iterations;
            const Vec3 g = e.p - e.f * n; // tangential (Riemannian) gradient
            if (g.norm() < kGradTol * length_) {
                return {n, true, e};
            }
            const Vec3 e1 = n.unitOrthogonal();
            const Vec3 e2 = n.cross(e1);
            // Riemannian Hessian: P (dp/dn) P - f I on the tangent plane; dp/dn (the summed
            // curvature-radius tensors of A and B) by finite differences: central ones (four
            // evaluations) by default, forward ones from e.p (two) on request.
            std::array<Vec3, 2> dp;
            const std::array<Vec3, 2> basis{e1, e2};
            if (!have_jac && settings_.analytic_hessian && !blocky_) {
                have_jac = radius_tensors(e, e1, e2, dp);
                if (have_jac) {
                    jac = dp[0] * e1.transpose() + dp[1] * e2.transpose();
                }
            } else if (have_jac) {
                dp[0] = jac * e1;
                dp[1] = jac * e2;
            }
            if (!have_jac) {
                const double h_fd = settings_.fd_step;
                for (std::size_t j = 0; j < 2; ++j) {
                    const Vec3 pp = eval((n + h_fd * basis[j]).normalized()).p;
                    if (settings_.central_differences) {
                        const Vec3 pm = eval((n - h_fd * basis[j]).normalized()).p;
                        dp[j] = (pp - pm) / (2.0 * h_fd);
                    } else {
                        dp[j] = (pp - e.p) / h_fd;
                    }
                }
                jac = dp[0] * e1.transpose() + dp[1] * e2.transpose();
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
            // Backtracking until f decreases (Armijo with a small constant). Near the minimum the
            // decrease a step promises, -t slope, falls below the round-off of f (a difference of
            // world coordinates): f cannot judge the step there, so a step that leaves f within
            // its round-off is taken when it shrinks the gradient, the quantity of the convergence
            // test (otherwise the search halved t 20 times and stopped on the looser test below).
            const double slope = -rhs.dot(step);
            const double f_noise = kFNoise * (e.sa.cwiseAbs().sum() + e.sb.cwiseAbs().sum());
            const double g_norm = g.norm();
            double t = 1.0;
            Vec3 trial = n;
            bool moved = false;
            Eval et{};
            for (int ls = 0; ls < 20; ++ls) { // t >= 2e-6: shorter steps are round-off
                trial = (n + t * (step.x() * e1 + step.y() * e2)).normalized();
                et = eval(trial);
                if (et.f <= e.f + 1e-4 * t * slope) {
                    moved = true;
                    break;
                }
                if (settings_.roundoff_steps && -t * slope < f_noise && et.f <= e.f + f_noise &&
                    (et.p - et.f * trial).norm() < g_norm) {
                    moved = true;
                    break;
                }
                t *= 0.5;
            }
            if (!moved) {
                // No decrease possible: f is flat to round-off here. Converged when the gradient
                // is small (the depth error is then about |g|^2 / curvature, negligible).
                return {n, g.norm() < 1e-7 * length_, e};
            }
            // A full step means the model held: update dp/dn along it (Broyden: the least change
            // with jac s = y) instead of new differences; after a shortened step, differences.
            have_jac = settings_.secant_updates && t == 1.0;
            if (have_jac) {
                const Vec3 s = trial - n;
                const Vec3 y = et.p - e.p;
                const double ss = s.squaredNorm();
                if (ss > 0.0) {
                    jac += (y - jac * s) * s.transpose() / ss;
                } else {
                    have_jac = false;
                }
            }
            n = trial;
            e = et;
        }
        return {n, false, e};
    }

    /// dp/dn e1 and dp/dn e2 from the curvature: dp/dn on the tangent plane is the sum of the
    /// two bodies' curvature-radius tensors, the inverses of their curvature tensors (the support
    /// map inverts the Gauss map) at s_A(n) and s_B(-n). False (use differences) where a tensor
    /// is not finite or not safely invertible (flat points, tips).
    bool radius_tensors(const Eval& e, const Vec3& e1, const Vec3& e2,
                        std::array<Vec3, 2>& dp) const {
        Eigen::Matrix2d sum = Eigen::Matrix2d::Zero();
        for (const auto& [body, point] : {std::pair{&a_, &e.sa}, std::pair{&b_, &e.sb}}) {
            const Vec3 local = body->q.conjugate() * (*point - body->x);
            const Mat3 k_body = body->shape->curvature_tensor(local);
            const Vec3 t1 = body->q.conjugate() * e1;
            const Vec3 t2 = body->q.conjugate() * e2;
            const double k11 = t1.dot(k_body * t1);
            const double k22 = t2.dot(k_body * t2);
            const double k12 = 0.5 * (t1.dot(k_body * t2) + t2.dot(k_body * t1));
            const double det = k11 * k22 - k12 * k12;
            const double scale = body->length_scale();
            // Curvature radii above 1e6 of the body's size (nearly flat) or a non-finite tensor:
            // leave it to the differences.
            if (!std::isfinite(det) || !(k11 > 0.0) || !(k22 > 0.0) ||
                !(det > 1e-12 / (scale * scale) * (k11 + k22) * (k11 + k22))) {
                return false;
            }
            sum(0, 0) += k22 / det;
            sum(1, 1) += k11 / det;
            sum(0, 1) -= k12 / det;
        }
        sum(1, 0) = sum(0, 1);
        dp[0] = sum(0, 0) * e1 + sum(1, 0) * e2;
        dp[1] = sum(0, 1) * e1 + sum(1, 1) * e2;
        return true;
    }

    [[nodiscard]] double length() const { return length_; }

  private:
    const PosedSuperquadric& a_;
    const PosedSuperquadric& b_;
    const NewtonSettings& settings_;
    double length_ = 0.0;
    bool blocky_ = false; ///< an exponent below kBlockyHessian: differences, not curvature
};

} // namespace

ConvexContact support_newton_contact(const PosedSuperquadric& a, const PosedSuperquadric& b,
                                     const Vec3* warm_normal, const NewtonSettings& settings,
                                     const std::array<Vec3, 2>* warm_supports) {
    const SupportMinimiser m(a, b, settings);
    // A run that ends more than this (of the bodies' length scales) above a start it began at or
    // that another run reached has crossed to another minimum; below it, the difference is the
    // round-off that Newton's accepted steps may leave (roundoff_steps), and the run stands.
    constexpr double kCrossedRun = 1e-6;
    const double scale = a.length_scale() + b.length_scale();
    if (warm_normal != nullptr) {
        int iterations = 0;
        const Vec3 n0 = -*warm_normal;
        const Eval e0 = warm_supports != nullptr
                            ? m.eval_from(n0, (*warm_supports)[0], (*warm_supports)[1])
                            : m.eval(n0);
        NewtonEnd end = m.newton(n0, e0, iterations);
        // A run that ends above its start has left the minimum it started at (on thin blocky
        // shapes, e = 0.2 plates 1 mm thick, a run from the right side of a stacked pair crossed
        // to the other face, 2 mm deep: docs/performance.md, "Session 34"). f at any direction is
        // an upper bound of the MTD, so the start is the better answer: returned as a stalled run
        // (the caller finishes it), or left to the cold start.
        if (end.e.f > e0.f + kCrossedRun * scale) {
            end = {n0, false, e0};
        }
        if (end.ok || !settings.cold_after_warm) {
            ConvexContact c;
            c.depth = end.e.f;
            c.normal = -end.n;
            c.converged = end.ok;
            c.iterations = iterations;
            c.touching = c.depth > 0.0;
            c.set_deepest(end.e.sa, end.e.sb);
            return c;
        }
    }
    // Candidate directions: the 26 directions to the faces, edges and corners of a cube, and the
    // centre line (n points from A towards B at the minimum when they overlap).
    std::vector<std::pair<Eval, Vec3>> cand;
    for (int i = -1; i <= 1; ++i) {
        for (int j = -1; j <= 1; ++j) {
            for (int k = -1; k <= 1; ++k) {
                if (i != 0 || j != 0 || k != 0) {
                    const Vec3 n = Vec3(i, j, k).normalized();
                    cand.emplace_back(m.eval(n), n);
                }
            }
        }
    }
    if ((b.x - a.x).norm() > 0.0) {
        const Vec3 n = (b.x - a.x).normalized();
        cand.emplace_back(m.eval(n), n);
    }
    std::partial_sort(cand.begin(), cand.begin() + kStarts, cand.end(),
                      [](const auto& l, const auto& r) { return l.first.f < r.first.f; });
    // Smallest f among the starts that converged (a start may stall near a maximum of f), but a
    // run that ends above the best start's f has crossed to another minimum, and a stalled run
    // below every converged one is the better bound: then the smallest f found is returned as
    // a stalled run, for the caller to finish (f at any direction bounds the MTD from above).
    ConvexContact best;
    best.depth = 1e300;
    best.converged = false;
    int iterations = 0;
    Vec3 best_sa = Vec3::Zero();
    Vec3 best_sb = Vec3::Zero();
    NewtonEnd lowest{cand.front().second, false, cand.front().first}; // smallest f seen
    for (int s = 0; s < kStarts; ++s) {
        const auto& start = cand[static_cast<std::size_t>(s)];
        const NewtonEnd end = m.newton(start.second, start.first, iterations);
        const double f = end.e.f;
        if (f < lowest.e.f) {
            lowest = end;
        }
        if ((end.ok && !best.converged) || (end.ok == best.converged && f < best.depth)) {
            best.depth = f;
            best.normal = -end.n;
            best.converged = end.ok;
            best_sa = end.e.sa;
            best_sb = end.e.sb;
        }
    }
    if (lowest.e.f < best.depth - kCrossedRun * scale) {
        best.depth = lowest.e.f;
        best.normal = -lowest.n;
        best.converged = false;
        best_sa = lowest.e.sa;
        best_sb = lowest.e.sb;
    }
    best.iterations = iterations;
    best.touching = best.depth > 0.0;
    best.set_deepest(best_sa, best_sb);
    return best;
}

} // namespace kiln::geometry
