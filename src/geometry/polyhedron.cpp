// Convex polyhedra: mass properties by signed tetrahedra, principal frame, support map.

#include "geometry/polyhedron.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <map>

namespace kiln::geometry {

Vec3 farthest_vertex(const std::vector<Vec3>& vertices, const Vec3& d_body) {
    KILN_ASSERT(!vertices.empty());
    std::size_t best = 0;
    double best_dot = vertices[0].dot(d_body);
    for (std::size_t i = 1; i < vertices.size(); ++i) {
        const double s = vertices[i].dot(d_body);
        if (s > best_dot) {
            best_dot = s;
            best = i;
        }
    }
    return vertices[best];
}

Vec3 ConvexPolyhedron::support(const Vec3& d_body) const {
    return farthest_vertex(vertices, d_body);
}

namespace {

/// Twice the vector area of a triangle (outward normal times twice its area) (m^2).
Vec3 twice_area(const std::vector<Vec3>& v, const std::array<int, 3>& f) {
    const Vec3& a = v[static_cast<std::size_t>(f[0])];
    const Vec3& b = v[static_cast<std::size_t>(f[1])];
    const Vec3& c = v[static_cast<std::size_t>(f[2])];
    return (b - a).cross(c - a);
}

} // namespace

double ConvexPolyhedron::surface_area() const {
    double a = 0.0;
    for (const auto& f : faces) {
        a += 0.5 * twice_area(vertices, f).norm();
    }
    return a;
}

double ConvexPolyhedron::projected_area(const Vec3& u_body) const {
    const Vec3 u = u_body.normalized();
    double a = 0.0;
    for (const auto& f : faces) {
        a += std::abs(twice_area(vertices, f).dot(u));
    }
    return 0.25 * a; // 1/2 (both sides) of 1/2 (triangle = half the cross product)
}

double ConvexPolyhedron::bounding_radius() const {
    double r = 0.0;
    for (const Vec3& v : vertices) {
        r = std::max(r, v.norm());
    }
    return r;
}

MassProperties polyhedron_mass_properties(const std::vector<Vec3>& vertices,
                                          const std::vector<std::array<int, 3>>& faces) {
    // Reference point at the vertex mean: the tetrahedra stay small, which keeps the round-off of
    // the second moments relative to the body size rather than to its distance from the origin.
    Vec3 o = Vec3::Zero();
    for (const Vec3& v : vertices) {
        o += v;
    }
    o /= static_cast<double>(std::max<std::size_t>(vertices.size(), 1));
    double vol6 = 0.0;             // 6 V
    Vec3 first24 = Vec3::Zero();   // 24 int x dV
    Mat3 second120 = Mat3::Zero(); // 120 int x x^T dV
    for (const auto& f : faces) {
        const Vec3 a = vertices[static_cast<std::size_t>(f[0])] - o;
        const Vec3 b = vertices[static_cast<std::size_t>(f[1])] - o;
        const Vec3 c = vertices[static_cast<std::size_t>(f[2])] - o;
        const double det = a.dot(b.cross(c)); // 6 x signed volume of the tetrahedron (o, a, b, c)
        const Vec3 s = a + b + c;
        vol6 += det;
        first24 += det * s;
        // Tonon (2004): int x x^T over the tetrahedron with one vertex at the origin is
        // det/120 (a a^T + b b^T + c c^T + s s^T).
        second120 +=
            det * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
    }
    MassProperties m;
    m.volume = vol6 / 6.0;
    if (m.volume == 0.0) {
        return m;
    }
    const Vec3 c_local = first24 / 24.0 / m.volume;
    const Mat3 cov = second120 / 120.0 - m.volume * c_local * c_local.transpose();
    m.centroid = o + c_local;
    m.inertia_centroid = cov.trace() * Mat3::Identity() - cov;
    return m;
}

ConvexPolyhedron make_polyhedron(const std::vector<Vec3>& vertices,
                                 const std::vector<std::array<int, 3>>& faces,
                                 const std::string& where) {
    const int nv = static_cast<int>(vertices.size());
    if (faces.size() < 4) {
        throw InputError(
            fmt::format("{}: a polyhedron needs at least 4 faces, got {}", where, faces.size()));
    }
    // Closed and consistently oriented: every directed edge once, and its reverse once.
    std::map<std::array<int, 2>, int> directed;
    for (const auto& f : faces) {
        for (int k = 0; k < 3; ++k) {
            const int i = f[static_cast<std::size_t>(k)];
            const int j = f[static_cast<std::size_t>((k + 1) % 3)];
            if (i < 0 || i >= nv || j < 0 || j >= nv || i == j) {
                throw InputError(fmt::format("{}: face with an invalid vertex index", where));
            }
            ++directed[{i, j}];
        }
    }
    ConvexPolyhedron p;
    for (const auto& [e, n] : directed) {
        const auto rev = directed.find({e[1], e[0]});
        if (n != 1 || rev == directed.end() || rev->second != 1) {
            throw InputError(fmt::format("{}: the surface is not closed (edge {}-{} is not shared "
                                         "by exactly two oppositely oriented faces)",
                                         where, e[0], e[1]));
        }
        if (e[0] < e[1]) {
            p.edges.push_back(e);
        }
    }
    // Every vertex on a face: a stray point would enter the support map but not the volume.
    std::vector<bool> used(vertices.size(), false);
    for (const auto& f : faces) {
        for (const int k : f) {
            used[static_cast<std::size_t>(k)] = true;
        }
    }
    if (const auto it = std::find(used.begin(), used.end(), false); it != used.end()) {
        throw InputError(fmt::format("{}: vertex {} belongs to no face", where, it - used.begin()));
    }
    const MassProperties m = polyhedron_mass_properties(vertices, faces);
    if (!(m.volume > 0.0)) {
        throw InputError(
            fmt::format("{}: the surface encloses no positive volume ({:g} m^3)", where, m.volume));
    }
    const PrincipalFrame pf = principal_frame(m.inertia_centroid);
    p.volume = m.volume;
    p.inertia_unit_density = pf.moments;
    p.template_axes = pf.axes;
    p.template_centroid = m.centroid;
    p.faces = faces;
    p.vertices.reserve(vertices.size());
    for (const Vec3& v : vertices) {
        p.vertices.push_back(pf.axes.transpose() * (v - m.centroid));
    }
    return p;
}

} // namespace kiln::geometry
