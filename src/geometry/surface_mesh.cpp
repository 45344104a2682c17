// Triangulated shape surfaces; see surface_mesh.hpp.

#include "geometry/surface_mesh.hpp"

#include <numbers>

namespace kiln::geometry {

double SurfaceMesh::volume() const {
    double v = 0.0;
    for (const auto& t : triangles) {
        v += vertices[static_cast<std::size_t>(t[0])].dot(
            vertices[static_cast<std::size_t>(t[1])].cross(
                vertices[static_cast<std::size_t>(t[2])]));
    }
    return v / 6.0;
}

namespace {

/// Appends the parametric surface of q shifted by `offset`: south pole, n-1 rings of m = 4 n
/// vertices, north pole.
void append_superquadric(SurfaceMesh& mesh, const Superquadric& q, const Vec3& offset, int n) {
    const int m = 4 * n;
    const int base = static_cast<int>(mesh.vertices.size());
    constexpr double kPi = std::numbers::pi;
    mesh.vertices.push_back(offset + q.parametric_point(-0.5 * kPi, 0.0));
    for (int i = 1; i < n; ++i) {
        const double eta = -0.5 * kPi + kPi * i / n;
        for (int j = 0; j < m; ++j) {
            mesh.vertices.push_back(offset + q.parametric_point(eta, -kPi + 2.0 * kPi * j / m));
        }
    }
    mesh.vertices.push_back(offset + q.parametric_point(0.5 * kPi, 0.0));
    const int south = base;
    const int north = base + 1 + (n - 1) * m;
    const auto ring = [&](int i, int j) { return base + 1 + (i - 1) * m + (j % m); };
    // Longitude increases counter-clockwise seen from +z and latitude upwards, so (lower-left,
    // lower-right, upper-right) is counter-clockwise seen from outside.
    for (int j = 0; j < m; ++j) {
        mesh.triangles.push_back({south, ring(1, j + 1), ring(1, j)});
        mesh.triangles.push_back({north, ring(n - 1, j), ring(n - 1, j + 1)});
    }
    for (int i = 1; i < n - 1; ++i) {
        for (int j = 0; j < m; ++j) {
            mesh.triangles.push_back({ring(i, j), ring(i, j + 1), ring(i + 1, j + 1)});
            mesh.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i + 1, j)});
        }
    }
}

Superquadric ball(double r) {
    Superquadric q;
    q.half_axes = Vec3::Constant(r);
    return q;
}

template <class... Ts> struct Overloaded : Ts... { using Ts::operator()...; };

} // namespace

SurfaceMesh surface_mesh(const Shape& s, int n) {
    SurfaceMesh mesh;
    std::visit(
        Overloaded{
            [&](const Sphere& sp) { append_superquadric(mesh, ball(sp.radius), Vec3::Zero(), n); },
            [&](const Clump& c) {
                for (const ClumpSphere& m : c.spheres) {
                    append_superquadric(mesh, ball(m.radius), m.centre, n);
                }
            },
            [&](const Superquadric& q) { append_superquadric(mesh, q, Vec3::Zero(), n); },
            [&](const ConvexPolyhedron& p) {
                mesh.vertices = p.vertices;
                mesh.triangles = p.faces;
            }},
        s);
    return mesh;
}

SurfaceMesh posed(const SurfaceMesh& mesh, const Vec3& x, const Quat& q) {
    SurfaceMesh out = mesh;
    const Mat3 r = q.toRotationMatrix();
    for (Vec3& v : out.vertices) {
        v = x + r * v;
    }
    return out;
}

} // namespace kiln::geometry
