#include "fluid/deposit_body.hpp"

#include "geometry/polyhedron_contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace kiln::fluid {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A face whose normal's x component is at most this is parallel to the rows (docs/theory/fluid.md,
// "Convex polyhedra: rows clipped by the faces").
constexpr double kParallel = 1e-6;

// The polyhedron's planar faces (coplanar triangles merged, as the contact's features have
// them), so the inside test makes one comparison per face.
PlanesBody planes_of(const geometry::ConvexPolyhedron& p) {
    geometry::PolyhedronFeatures f = geometry::polyhedron_features(p);
    return PlanesBody{std::move(f.face_normals), std::move(f.face_offsets), std::move(f.vertices)};
}

struct BodyOf {
    DepositBody operator()(const geometry::Sphere& s) const { return SphereBody{s.radius}; }
    DepositBody operator()(const geometry::ConvexPolyhedron& p) const { return planes_of(p); }
    DepositBody operator()(const geometry::Superquadric& q) const { return SuperquadricBody{q}; }
    DepositBody operator()(const geometry::Clump& c) const { return ClumpBody{c.spheres}; }
};

} // namespace

void pose_planes(const PlanesBody& body, const Mat3& rot, const Vec3& x, double h,
                 PosedPlanes& out) {
    const std::size_t nf = body.normals.size();
    out.normal.resize(nf);
    out.offset.resize(nf);
    out.inv_rate.resize(nf);
    out.to_body = rot.transpose();
    out.centre = x;
    out.step = h * out.to_body.col(0);
    out.h = h;
    for (std::size_t f = 0; f < nf; ++f) {
        const Vec3 n = rot * body.normals[f];
        out.normal[f] = n;
        out.offset[f] = n.dot(x) + body.offsets[f];
        // A face whose plane the rows cross at less than 1e-6 of a step per step is parallel.
        out.inv_rate[f] = std::abs(n.x()) <= kParallel ? 0.0 : 1.0 / (h * n.x());
    }
}

RowRun clip_row(const PlanesBody& body, const PosedPlanes& posed, const Vec3& start, long n) {
    // Face f holds the row's points with a + t b <= 0, a = n . start - e (m), b = h n_x. A face
    // the row crosses bounds t at -a / b. One it runs along (|n_x| <= kParallel) bounds nothing,
    // cuts the whole row, or leaves it to the point tests when the row lies within round-off
    // (1e-9 steps) of its plane.
    const double tol = 1e-9 * posed.h;
    const auto len = static_cast<double>(n);
    double lo = 0.0;
    double hi = len;
    for (std::size_t f = 0; f < posed.normal.size(); ++f) {
        const double a = posed.normal[f].dot(start) - posed.offset[f];
        const double inv = posed.inv_rate[f];
        if (inv == 0.0) {
            const double b = posed.h * posed.normal[f].x();
            const double low = a + std::min(0.0, b * len);
            const double high = a + std::max(0.0, b * len);
            if (low > tol) {
                return {};
            }
            if (high >= -tol) {
                return {0, -1, false};
            }
        } else if (inv > 0.0) {
            hi = std::min(hi, -a * inv);
        } else {
            lo = std::max(lo, -a * inv);
        }
    }
    return detail::settle_row(lo, hi, n, [&](long t) {
        const Vec3 p0 = posed.to_body * (start - posed.centre);
        return body.contains(p0 + static_cast<double>(t) * posed.step);
    });
}

void ClumpBody::rows(std::span<const Vec3> centres, double ox, double h, double y, double z,
                     long lo, long hi, std::vector<RowRun>& out) const {
    out.clear();
    for (std::size_t m = 0; m < spheres.size(); ++m) {
        const Vec3& c = centres[m];
        const double dy = y - c.y();
        const double dz = z - c.z();
        const double r = spheres[m].radius;
        const double w2 = r * r - dy * dy - dz * dz;
        if (w2 < 0.0) {
            continue;
        }
        const RowRun run = chord_run(c.x(), std::sqrt(w2), ox, h, lo, hi);
        if (run.first <= run.last) {
            out.push_back(run);
        }
    }
    std::sort(out.begin(), out.end(),
              [](const RowRun& p, const RowRun& q) { return p.first < q.first; });
    std::size_t k = 0;
    for (std::size_t j = 1; j < out.size(); ++j) {
        if (out[j].first <= out[k].last + 1) {
            out[k].last = std::max(out[k].last, out[j].last);
        } else {
            out[++k] = out[j];
        }
    }
    if (!out.empty()) {
        out.resize(k + 1);
    }
}

DepositTemplate make_deposit_template(const geometry::ShapeTemplate& t) {
    return {std::visit(BodyOf{}, t.shape), t.volume, t.bounding_radius()};
}

Aabb world_box(const DepositBody& b, const Vec3& x, const Mat3& r) {
    struct Box {
        const Vec3& x;
        const Mat3& r;
        Aabb operator()(const SphereBody& s) const {
            return {x.array() - s.radius, x.array() + s.radius};
        }
        Aabb operator()(const SuperquadricBody& s) const {
            // The body box [-a, a] turned into the world: half extents |R| a.
            const Vec3 e = r.cwiseAbs() * s.shape.half_axes;
            return {x - e, x + e};
        }
        Aabb operator()(const PlanesBody& p) const {
            Aabb out{Vec3::Constant(kInf), Vec3::Constant(-kInf)};
            for (const Vec3& v : p.vertices) {
                const Vec3 w = r * v;
                out.lo = out.lo.cwiseMin(w);
                out.hi = out.hi.cwiseMax(w);
            }
            return {x + out.lo, x + out.hi};
        }
        Aabb operator()(const ClumpBody& c) const {
            Aabb out{Vec3::Constant(kInf), Vec3::Constant(-kInf)};
            for (const auto& s : c.spheres) {
                const Vec3 w = r * s.centre;
                out.lo = out.lo.cwiseMin(w - Vec3::Constant(s.radius));
                out.hi = out.hi.cwiseMax(w + Vec3::Constant(s.radius));
            }
            return {x + out.lo, x + out.hi};
        }
    };
    return std::visit(Box{x, r}, b);
}

} // namespace kiln::fluid
