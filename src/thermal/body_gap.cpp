#include "thermal/body_gap.hpp"

#include "geometry/clump.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace kiln::thermal {

namespace {

/// Most GJK iterations; smooth cores (superquadrics) converge linearly, polytopes finitely.
constexpr int max_gjk_iterations = 128;
/// Distance tolerance of body_gap relative to the larger bounding radius (-).
constexpr double relative_gap_tolerance = 1e-9;

/// A vertex of the GJK simplex: the Minkowski point w = a - b and the two support points.
struct SimplexPoint {
    Vec3 w;
    Vec3 a;
    Vec3 b;
};

/// A GJK simplex in fixed storage (at most four points; a heap vector per iteration was a tenth
/// of the query), with the squared distance of its nearest point as the last closest_on_simplex
/// found it (infinity: none yet).
struct Simplex {
    std::array<SimplexPoint, 4> p{};
    int n = 0;
    double d2 = std::numeric_limits<double>::infinity();
    [[nodiscard]] const SimplexPoint& operator[](std::size_t k) const { return p[k]; }
};

/// Closest point to the origin of the simplex `s` (1-4 points): tries every sub-simplex, takes
/// the affine minimiser of each whose barycentric weights are all >= 0, keeps the nearest
/// (the true closest point lies in the relative interior of one face, where it is that face's
/// affine minimiser; the first in mask order of equal ones). Reduces `s` to the supporting face;
/// `lambda` gets its weights (on entry: the last call's, which it set). Returns false when no
/// sub-simplex qualifies (numerically degenerate).
///
/// Only the sub-simplices with the newest point (the last) are evaluated: the others are faces of
/// the simplex of the last call, which that call reduced to its winner, and they come first in
/// mask order, in the same order and with the same arithmetic as then. So the best of them is
/// that winner (the whole old simplex, mask 2^(n-1) - 1) with its stored distance and the weights
/// in `lambda`, exactly as an evaluation of all of them would find.
bool closest_on_simplex(Simplex& s, std::array<double, 4>& lambda) {
    const int n = s.n;
    double best = std::numeric_limits<double>::infinity();
    int best_mask = 0;
    std::array<double, 4> best_l{};
    if (n > 1 && s.d2 < std::numeric_limits<double>::infinity()) {
        best = s.d2;
        best_mask = (1 << (n - 1)) - 1;
        best_l = lambda;
    }
    for (int mask = best_mask != 0 ? 1 << (n - 1) : 1; mask < (1 << n); ++mask) {
        std::array<int, 4> idx{};
        int k = 0;
        for (int v = 0; v < n; ++v) {
            if ((mask >> v) & 1) {
                idx[static_cast<std::size_t>(k++)] = v;
            }
        }
        std::array<double, 4> l{};
        const Vec3& p0 = s[static_cast<std::size_t>(idx[0])].w;
        if (k == 1) {
            l[0] = 1.0;
        } else {
            // Minimise |p0 + D mu|^2 with D = [p_m - p0]: (D^T D) mu = -D^T p0, the m x m block
            // of a 3 x 3 system padded with the identity (block diagonal: same determinant).
            const int m_used = k - 1;
            Mat3 g = Mat3::Identity();
            Vec3 rhs = Vec3::Zero();
            double scale = 1.0;
            for (int r = 0; r < m_used; ++r) {
                const Vec3 dr =
                    s[static_cast<std::size_t>(idx[static_cast<std::size_t>(r + 1)])].w - p0;
                rhs[r] = -dr.dot(p0);
                for (int c = 0; c < m_used; ++c) {
                    g(r, c) = dr.dot(
                        s[static_cast<std::size_t>(idx[static_cast<std::size_t>(c + 1)])].w - p0);
                }
                scale *= g(r, r);
            }
            const double det = g.determinant();
            if (!(std::abs(det) > 1e-12 * scale)) {
                continue; // a degenerate face: its lower faces cover it
            }
            const Vec3 mu = g.inverse() * rhs;
            l[0] = 1.0;
            for (int m = 1; m < k; ++m) {
                l[static_cast<std::size_t>(m)] = mu[m - 1];
                l[0] -= mu[m - 1];
            }
        }
        bool inside = true;
        Vec3 v = Vec3::Zero();
        for (int m = 0; m < k; ++m) {
            inside = inside && l[static_cast<std::size_t>(m)] >= 0.0;
            v += l[static_cast<std::size_t>(m)] *
                 s[static_cast<std::size_t>(idx[static_cast<std::size_t>(m)])].w;
        }
        const double d2 = v.squaredNorm();
        if (inside && d2 < best) {
            best = d2;
            best_mask = mask;
            best_l = l;
        }
    }
    if (best_mask == 0) {
        return false;
    }
    int k = 0;
    for (int v = 0; v < n; ++v) {
        if ((best_mask >> v) & 1) {
            s.p[static_cast<std::size_t>(k)] = s.p[static_cast<std::size_t>(v)]; // k <= v
            lambda[static_cast<std::size_t>(k)] = best_l[static_cast<std::size_t>(k)];
            ++k;
        }
    }
    s.n = k;
    s.d2 = best;
    return true;
}

/// The convex cores of particle index i with their margins (m).
void cores_of(const dynamics::System& sys, std::size_t i, std::vector<Core>& cores,
              std::vector<double>& margins) {
    cores.clear();
    margins.clear();
    const ParticleStore& p = sys.particles();
    const int s = p.shape[i];
    Core c;
    c.x = p.x[i];
    c.q = p.q[i];
    if (s < 0) {
        cores.push_back(c);
        margins.push_back(p.radius[i]);
        return;
    }
    const geometry::Shape& shape = sys.spec().shapes[static_cast<std::size_t>(s)].shape;
    if (const auto* clump = std::get_if<geometry::Clump>(&shape)) {
        for (const geometry::ClumpSphere& m : clump->spheres) {
            Core mc;
            mc.x = p.x[i] + p.q[i] * m.centre;
            cores.push_back(mc);
            margins.push_back(m.radius);
        }
        return;
    }
    if (const auto* sq = std::get_if<geometry::Superquadric>(&shape)) {
        c.superquadric = sq;
    } else if (const auto* poly = std::get_if<geometry::ConvexPolyhedron>(&shape)) {
        c.polyhedron = poly;
    } else {
        // A sphere template: its centre with the radius as margin.
        cores.push_back(c);
        margins.push_back(std::get<geometry::Sphere>(shape).radius);
        return;
    }
    cores.push_back(c);
    margins.push_back(0.0);
}

/// True for a core with a support map (no margin), false for a point.
bool is_convex(const Core& c) {
    return c.superquadric != nullptr || c.polyhedron != nullptr;
}

} // namespace

Vec3 Core::support(const Vec3& d) const {
    if (superquadric != nullptr) {
        return x + q * superquadric->support(q.conjugate() * d);
    }
    if (polyhedron != nullptr) {
        return x + q * polyhedron->support(q.conjugate() * d);
    }
    return x;
}

CoreDistance core_distance(const Core& a, const Core& b, double tolerance, double beyond) {
    CoreDistance out;
    if (!is_convex(a) && !is_convex(b)) {
        out.a = a.x;
        out.b = b.x;
        out.distance = (a.x - b.x).norm();
        out.overlap = !(out.distance > 0.0);
        return out;
    }
    Simplex simplex;
    std::array<double, 4> lambda{};
    Vec3 v = a.x - b.x; // a point of A - B (both centres are inside their cores)
    if (!(v.squaredNorm() > 0.0)) {
        out.overlap = true;
        return out;
    }
    for (int it = 0; it < max_gjk_iterations; ++it) {
        out.iterations = it + 1;
        SimplexPoint sp;
        sp.a = a.support(-v);
        sp.b = b.support(v);
        sp.w = sp.a - sp.b;
        const double vn = v.norm();
        // |v| is an upper bound of the distance, v.w / |v| a lower bound.
        const double lower = v.dot(sp.w) / vn;
        if (lower > beyond) {
            out.beyond = true;
            out.distance = lower;
            return out;
        }
        if (simplex.n > 0 && vn - lower <= tolerance) {
            break;
        }
        const bool repeated =
            std::any_of(simplex.p.begin(), simplex.p.begin() + simplex.n,
                        [&](const auto& q) { return (q.w - sp.w).squaredNorm() == 0.0; });
        if (repeated) {
            break; // no new support point: v is as near as the supports allow
        }
        simplex.p[static_cast<std::size_t>(simplex.n++)] = sp;
        if (!closest_on_simplex(simplex, lambda)) {
            // The new point left no usable face: the nearest points come from the simplex and
            // weights before it (which still give v), not from weights of another simplex.
            --simplex.n;
            out.converged = false;
            break;
        }
        v = Vec3::Zero();
        for (std::size_t k = 0; k < static_cast<std::size_t>(simplex.n); ++k) {
            v += lambda[k] * simplex[k].w;
        }
        if (simplex.n == 4 || v.norm() <= tolerance) {
            out.overlap = true; // the origin is in A - B (to the tolerance)
            return out;
        }
        if (it + 1 == max_gjk_iterations) {
            out.converged = false;
        }
    }
    out.a = Vec3::Zero();
    out.b = Vec3::Zero();
    for (std::size_t k = 0; k < static_cast<std::size_t>(simplex.n); ++k) {
        out.a += lambda[k] * simplex[k].a;
        out.b += lambda[k] * simplex[k].b;
    }
    out.distance = v.norm();
    return out;
}

std::vector<BodyGap> element_gaps(const dynamics::System& sys, std::size_t i, std::size_t j,
                                  double cutoff) {
    const ParticleStore& p = sys.particles();
    std::vector<Core> ci;
    std::vector<Core> cj;
    std::vector<double> mi;
    std::vector<double> mj;
    cores_of(sys, i, ci, mi);
    cores_of(sys, j, cj, mj);
    const double tol = relative_gap_tolerance * std::max(p.radius[i], p.radius[j]);
    std::vector<BodyGap> out;
    out.reserve(ci.size() * cj.size());
    for (std::size_t a = 0; a < ci.size(); ++a) {
        for (std::size_t b = 0; b < cj.size(); ++b) {
            // The largest distance of the cores at which the pair can be kept: both margins and
            // the reach of the largest equivalent spheres (a sphere element: its radius; a convex
            // body: its bounding radius, above its volume-equivalent radius and its gas-gap
            // radius), plus the GJK tolerance against the support maps' round-off.
            double beyond = std::numeric_limits<double>::infinity();
            if (std::isfinite(cutoff)) {
                const double r_a = is_convex(ci[a]) ? p.radius[i] : mi[a];
                const double r_b = is_convex(cj[b]) ? p.radius[j] : mj[b];
                beyond = mi[a] + mj[b] + 2.0 * cutoff * (2.0 * r_a * r_b) / (r_a + r_b) + tol;
            }
            const CoreDistance d = core_distance(ci[a], cj[b], tol, beyond);
            if (d.beyond || (!d.overlap && d.distance > beyond)) {
                continue;
            }
            BodyGap g;
            g.member_radius_i = is_convex(ci[a]) ? 0.0 : mi[a];
            g.member_radius_j = is_convex(cj[b]) ? 0.0 : mj[b];
            if (d.overlap) {
                // Convex cores in contact: gap 0, normal along the line of centres.
                Vec3 n = cj[b].x - ci[a].x;
                n = n.squaredNorm() > 0.0 ? n.normalized() : Vec3::UnitX();
                g.gap = 0.0;
                g.normal = n;
                g.point_i = ci[a].support(n) + mi[a] * n;
                g.point_j = cj[b].support(-n) - mj[b] * n;
            } else {
                Vec3 n = d.b - d.a;
                n = n.squaredNorm() > 0.0 ? n.normalized() : (p.x[j] - p.x[i]).normalized();
                g.gap = d.distance - mi[a] - mj[b];
                g.normal = n;
                g.point_i = d.a + mi[a] * n;
                g.point_j = d.b - mj[b] * n;
                g.converged = d.converged;
            }
            out.push_back(g);
        }
    }
    return out;
}

std::vector<PlaneGap> plane_gaps(const dynamics::System& sys, std::size_t i, const Vec3& point,
                                 const Vec3& normal) {
    std::vector<Core> cores;
    std::vector<double> margins;
    cores_of(sys, i, cores, margins);
    std::vector<PlaneGap> out(cores.size());
    for (std::size_t a = 0; a < cores.size(); ++a) {
        PlaneGap& g = out[a];
        if (is_convex(cores[a])) {
            // The support along -n is the body's point nearest the plane (a convex body).
            g.point = cores[a].support(-normal);
            g.gap = (g.point - point).dot(normal);
        } else {
            g.member_radius = margins[a];
            g.point = cores[a].x - margins[a] * normal;
            g.gap = (cores[a].x - point).dot(normal) - margins[a];
        }
    }
    return out;
}

BodyGap body_gap(const dynamics::System& sys, std::size_t i, std::size_t j) {
    const std::vector<BodyGap> all = element_gaps(sys, i, j);
    return *std::min_element(all.begin(), all.end(), [](const BodyGap& x, const BodyGap& y) {
        return x.gap < y.gap; // the first of equal ones
    });
}

} // namespace kiln::thermal
