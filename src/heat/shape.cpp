#include "heat/shape.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

namespace kiln::heat {

namespace {

template <class... F> struct Overloaded : F... { using F::operator()...; };
/// Deduction guide (implicit for aggregates in C++20, but clang 14 still needs it).
template <class... F> Overloaded(F...) -> Overloaded<F...>;

/// Superquadric radial function f(x) = G(x)^(e1/2), homogeneous of degree one: f(t x) = t f(x),
/// f = 1 on the surface (G is Barr's inside-outside function).
double superquadric_radial(const Superquadric& s, const Vec3& x) {
    const double ex = std::pow(std::abs(x.x() / s.half.x()), 2.0 / s.e2);
    const double ey = std::pow(std::abs(x.y() / s.half.y()), 2.0 / s.e2);
    const double ez = std::pow(std::abs(x.z() / s.half.z()), 2.0 / s.e1);
    const double g = std::pow(ex + ey, s.e2 / s.e1) + ez;
    return std::pow(g, s.e1 / 2.0);
}

double beta(double a, double b) {
    return std::tgamma(a) * std::tgamma(b) / std::tgamma(a + b);
}

/// Cube [-1,1]^3 surface as quads split into triangles, n x n quads per face, outward oriented.
SurfaceMesh unit_cube_mesh(int n) {
    SurfaceMesh m;
    const auto quads = static_cast<std::size_t>(n);
    m.vertices.reserve(6 * (quads + 1) * (quads + 1));
    m.triangles.reserve(12 * quads * quads);
    for (int axis = 0; axis < 3; ++axis) {
        const int u = (axis + 1) % 3;
        const int v = (axis + 2) % 3;
        for (const double side : {-1.0, 1.0}) {
            const int base = static_cast<int>(m.vertices.size());
            for (int j = 0; j <= n; ++j) {
                for (int i = 0; i <= n; ++i) {
                    Vec3 p;
                    p[axis] = side;
                    p[u] = -1.0 + 2.0 * i / n;
                    p[v] = -1.0 + 2.0 * j / n;
                    m.vertices.push_back(p);
                }
            }
            for (int j = 0; j < n; ++j) {
                for (int i = 0; i < n; ++i) {
                    const int a = base + j * (n + 1) + i;
                    const int b = a + 1;
                    const int c = a + (n + 1) + 1;
                    const int d = a + (n + 1);
                    // Each quad is split along the diagonal through the corner nearest the face
                    // centre, so the mesh is mirror-symmetric about the face mid-lines (n even).
                    const bool ac = (2 * i + 1 - n) * (2 * j + 1 - n) > 0;
                    std::array<int, 3> t1 =
                        ac ? std::array<int, 3>{a, b, c} : std::array<int, 3>{a, b, d};
                    std::array<int, 3> t2 =
                        ac ? std::array<int, 3>{a, c, d} : std::array<int, 3>{b, c, d};
                    // (u, v, axis) is right-handed: a-b-c is counter-clockwise seen from +axis.
                    if (side < 0.0) {
                        std::swap(t1[1], t1[2]);
                        std::swap(t2[1], t2[2]);
                    }
                    m.triangles.push_back(t1);
                    m.triangles.push_back(t2);
                }
            }
        }
    }
    return m;
}

int quads_per_face(double extent, double edge) {
    const int n = std::max(2, static_cast<int>(std::ceil(extent / edge)));
    return n + n % 2; // even, for a mirror-symmetric split
}

} // namespace

double SurfaceMesh::area() const {
    double a = 0.0;
    for (const auto& t : triangles) {
        a += 0.5 * (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]).norm();
    }
    return a;
}

double SurfaceMesh::volume() const {
    double v = 0.0;
    for (const auto& t : triangles) {
        v += vertices[t[0]].dot(vertices[t[1]].cross(vertices[t[2]])) / 6.0;
    }
    return v;
}

void validate(const Shape& shape) {
    std::visit(Overloaded{[](const Sphere& s) {
                              if (!(s.radius > 0.0)) {
                                  throw InputError("heat: sphere radius must be > 0 m, got " +
                                                   std::to_string(s.radius));
                              }
                          },
                          [](const Box& b) {
                              if (!(b.half.minCoeff() > 0.0)) {
                                  throw InputError("heat: box half edges must be > 0 m");
                              }
                          },
                          [](const Superquadric& q) {
                              if (!(q.half.minCoeff() > 0.0)) {
                                  throw InputError("heat: superquadric semi-axes must be > 0 m");
                              }
                              if (!(q.e1 >= 0.1 && q.e1 <= 2.0 && q.e2 >= 0.1 && q.e2 <= 2.0)) {
                                  throw InputError("heat: superquadric exponents e1, e2 must lie "
                                                   "in [0.1, 2] (convex range), got " +
                                                   std::to_string(q.e1) + ", " +
                                                   std::to_string(q.e2));
                              }
                          }},
               shape);
}

double level(const Shape& shape, const Vec3& x) {
    return std::visit(
        Overloaded{[&](const Sphere& s) { return x.norm() - s.radius; },
                   [&](const Box& b) {
                       const Vec3 q = x.cwiseAbs() - b.half;
                       return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
                   },
                   [&](const Superquadric& q) {
                       // f is homogeneous of degree 1, so (f - 1)/|grad f| is a
                       // first-order distance; the gradient by central differences.
                       const double f = superquadric_radial(q, x);
                       const double step = 1e-7 * q.half.maxCoeff();
                       Vec3 g;
                       for (int i = 0; i < 3; ++i) {
                           Vec3 e = Vec3::Zero();
                           e[i] = step;
                           g[i] = (superquadric_radial(q, x + e) - superquadric_radial(q, x - e)) /
                                  (2.0 * step);
                       }
                       const double gn = g.norm();
                       return gn > 0.0 ? (f - 1.0) / gn : (f - 1.0) * q.half.minCoeff();
                   }},
        shape);
}

bool inside(const Shape& shape, const Vec3& x) {
    return std::visit(
        Overloaded{[&](const Sphere& s) { return x.squaredNorm() <= s.radius * s.radius; },
                   [&](const Box& b) { return (x.cwiseAbs() - b.half).maxCoeff() <= 0.0; },
                   [&](const Superquadric& q) { return superquadric_radial(q, x) <= 1.0; }},
        shape);
}

Vec3 half_extent(const Shape& shape) {
    return std::visit(Overloaded{[](const Sphere& s) { return Vec3(Vec3::Constant(s.radius)); },
                                 [](const Box& b) { return b.half; },
                                 [](const Superquadric& q) { return q.half; }},
                      shape);
}

double exact_volume(const Shape& shape) {
    return std::visit(Overloaded{[](const Sphere& s) {
                                     return 4.0 / 3.0 * std::numbers::pi * std::pow(s.radius, 3);
                                 },
                                 [](const Box& b) { return 8.0 * b.half.prod(); },
                                 [](const Superquadric& q) {
                                     return 2.0 * q.half.prod() * q.e1 * q.e2 *
                                            beta(q.e1 / 2.0 + 1.0, q.e1) *
                                            beta(q.e2 / 2.0, q.e2 / 2.0);
                                 }},
                      shape);
}

double reference_area(const Shape& shape) {
    return std::visit(
        Overloaded{[](const Sphere& s) { return 4.0 * std::numbers::pi * s.radius * s.radius; },
                   [](const Box& b) {
                       return 8.0 * (b.half.x() * b.half.y() + b.half.y() * b.half.z() +
                                     b.half.z() * b.half.x());
                   },
                   [&](const Superquadric& q) {
                       const double e = q.half.minCoeff() / 50.0;
                       const double coarse = surface_mesh(shape, e).area();
                       const double fine = surface_mesh(shape, e / 2.0).area();
                       return (4.0 * fine - coarse) / 3.0;
                   }},
        shape);
}

SurfaceMesh surface_mesh(const Shape& shape, double edge) {
    KILN_ASSERT(edge > 0.0);
    return std::visit(
        Overloaded{[&](const Sphere& s) {
                       // Radial projection stretches edges by at most sqrt(3) near the cube's
                       // centre of a face; 2 pi R / 4 per face side is the arc length.
                       SurfaceMesh m =
                           unit_cube_mesh(quads_per_face(0.5 * std::numbers::pi * s.radius, edge));
                       for (Vec3& p : m.vertices) {
                           p = s.radius * p.normalized();
                       }
                       return m;
                   },
                   [&](const Box& b) {
                       SurfaceMesh m =
                           unit_cube_mesh(quads_per_face(2.0 * b.half.maxCoeff(), edge));
                       for (Vec3& p : m.vertices) {
                           p = p.cwiseProduct(b.half);
                       }
                       return m;
                   },
                   [&](const Superquadric& q) {
                       // Perimeter-like bound of one face's arc: pi/2 times the largest semi-axis.
                       SurfaceMesh m = unit_cube_mesh(
                           quads_per_face(0.5 * std::numbers::pi * q.half.maxCoeff(), edge));
                       for (Vec3& p : m.vertices) {
                           const Vec3 d = p.cwiseProduct(q.half);
                           p = d / superquadric_radial(q, d);
                       }
                       return m;
                   }},
        shape);
}

} // namespace kiln::heat
