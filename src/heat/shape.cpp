#include "heat/shape.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
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

/// Largest |coordinate| of the polyhedron's vertices (m): its length scale for tolerances.
double polyhedron_scale(const ConvexPolyhedron& p) {
    double s = 0.0;
    for (const Vec3& v : p.vertices) {
        s = std::max(s, v.cwiseAbs().maxCoeff());
    }
    return s;
}

/// Keeps the part of the polygon `poly` where w . x >= t (Sutherland-Hodgman against one plane).
std::vector<Vec3> clip_half_space(const std::vector<Vec3>& poly, const Vec3& w, double t) {
    std::vector<Vec3> out;
    out.reserve(poly.size() + 1);
    for (std::size_t k = 0; k < poly.size(); ++k) {
        const Vec3& a = poly[k];
        const Vec3& b = poly[(k + 1) % poly.size()];
        const double da = w.dot(a) - t;
        const double db = w.dot(b) - t;
        if (da >= 0.0) {
            out.push_back(a);
        }
        if ((da >= 0.0) != (db >= 0.0)) {
            out.push_back(a + da / (da - db) * (b - a));
        }
    }
    return out;
}

/// Polyhedron faces split into n x n similar triangles with edges <= `edge` (orientation kept).
SurfaceMesh polyhedron_mesh(const ConvexPolyhedron& p, double edge) {
    SurfaceMesh m;
    for (const auto& f : p.faces) {
        const Vec3& a = p.vertices[static_cast<std::size_t>(f[0])];
        const Vec3& b = p.vertices[static_cast<std::size_t>(f[1])];
        const Vec3& c = p.vertices[static_cast<std::size_t>(f[2])];
        const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
        const int n = std::max(1, static_cast<int>(std::ceil(longest / edge)));
        const int base = static_cast<int>(m.vertices.size());
        // Vertex (i, j), i + j <= n, at a + (i/n)(b - a) + (j/n)(c - a); row j holds n + 1 - j.
        std::vector<int> row_start(static_cast<std::size_t>(n) + 2, 0);
        for (int j = 0; j <= n; ++j) {
            row_start[static_cast<std::size_t>(j) + 1] =
                row_start[static_cast<std::size_t>(j)] + n + 1 - j;
            for (int i = 0; i + j <= n; ++i) {
                m.vertices.push_back(a + (static_cast<double>(i) / n) * (b - a) +
                                     (static_cast<double>(j) / n) * (c - a));
            }
        }
        const auto id = [&](int i, int j) {
            return base + row_start[static_cast<std::size_t>(j)] + i;
        };
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i + j < n; ++i) {
                m.triangles.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
                if (i + j + 1 < n) {
                    m.triangles.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
                }
            }
        }
    }
    return m;
}

/// Outer surface of a union of spheres: member meshes clipped against the radical planes of the
/// overlapping members (see surface_mesh in shape.hpp).
SurfaceMesh clump_mesh(const Clump& c, double edge) {
    SurfaceMesh m;
    const std::size_t members = c.radii.size();
    for (std::size_t i = 0; i < members; ++i) {
        const double ri = c.radii[i];
        // Planes y . d >= t (y = x - c_i) that keep the part of sphere i outside member j.
        std::vector<std::pair<Vec3, double>> planes;
        bool hidden = false;
        for (std::size_t j = 0; j < members && !hidden; ++j) {
            if (j == i) {
                continue;
            }
            const double rj = c.radii[j];
            const Vec3 d = c.centres[i] - c.centres[j];
            const double dist = d.norm();
            if (dist >= ri + rj) {
                continue; // apart or touching: nothing of i is inside j
            }
            if (dist + ri <= rj && !(dist == 0.0 && ri == rj && i < j)) {
                hidden = true; // i lies inside j (of an identical pair the lower index stays)
            } else if (dist > 0.0) {
                // |y + d|^2 < rj^2 with |y| = ri  <=>  y . d < (rj^2 - ri^2 - |d|^2) / 2.
                planes.emplace_back(d, 0.5 * (rj * rj - ri * ri - dist * dist));
            }
        }
        if (hidden) {
            continue;
        }
        const SurfaceMesh sphere = surface_mesh(Sphere{ri}, edge);
        std::vector<Vec3> poly;
        for (const auto& t : sphere.triangles) {
            poly = {sphere.vertices[static_cast<std::size_t>(t[0])],
                    sphere.vertices[static_cast<std::size_t>(t[1])],
                    sphere.vertices[static_cast<std::size_t>(t[2])]};
            for (const auto& [w, off] : planes) {
                if (poly.size() < 3) {
                    break;
                }
                poly = clip_half_space(poly, w, off);
            }
            if (poly.size() < 3) {
                continue;
            }
            const int base = static_cast<int>(m.vertices.size());
            for (const Vec3& y : poly) {
                m.vertices.push_back(c.centres[i] + y);
            }
            for (int f = 1; f + 1 < static_cast<int>(poly.size()); ++f) {
                m.triangles.push_back({base, base + f, base + f + 1});
            }
        }
    }
    return m;
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

ConvexPolyhedron make_convex_polyhedron(std::vector<Vec3> vertices,
                                        std::vector<std::array<int, 3>> faces) {
    ConvexPolyhedron p;
    p.vertices = std::move(vertices);
    p.faces = std::move(faces);
    if (p.faces.size() < 4) {
        throw InputError("heat: a polyhedron needs at least 4 triangles, got " +
                         std::to_string(p.faces.size()));
    }
    const double scale = polyhedron_scale(p);
    const double tol = 1e-9 * scale;
    for (const auto& f : p.faces) {
        for (const int v : f) {
            if (v < 0 || static_cast<std::size_t>(v) >= p.vertices.size()) {
                throw InputError("heat: polyhedron triangle refers to a missing vertex");
            }
        }
        const Vec3& a = p.vertices[static_cast<std::size_t>(f[0])];
        const Vec3 an = (p.vertices[static_cast<std::size_t>(f[1])] - a)
                            .cross(p.vertices[static_cast<std::size_t>(f[2])] - a);
        if (!(an.norm() > 1e-12 * scale * scale)) {
            throw InputError("heat: polyhedron has a degenerate (zero-area) triangle");
        }
        const Vec3 n = an.normalized();
        const double off = n.dot(a);
        bool known = false;
        for (std::size_t k = 0; k < p.normals.size() && !known; ++k) {
            known = p.normals[k].dot(n) > 1.0 - 1e-9 && std::abs(p.offsets[k] - off) <= tol;
        }
        if (!known) {
            p.normals.push_back(n);
            p.offsets.push_back(off);
        }
    }
    for (std::size_t k = 0; k < p.normals.size(); ++k) {
        for (const Vec3& v : p.vertices) {
            if (p.normals[k].dot(v) - p.offsets[k] > tol) {
                throw InputError("heat: polyhedron is not convex (a vertex lies outside a face "
                                 "plane) or its triangles are not outward oriented");
            }
        }
    }
    return p;
}

void validate(const Shape& shape) {
    std::visit(
        Overloaded{[](const Sphere& s) {
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
                                            std::to_string(q.e1) + ", " + std::to_string(q.e2));
                       }
                   },
                   [](const ConvexPolyhedron& p) {
                       if (p.faces.size() < 4 || p.normals.size() < 4 ||
                           p.normals.size() != p.offsets.size()) {
                           throw InputError("heat: polyhedron without its face planes "
                                            "(build it with make_convex_polyhedron)");
                       }
                   },
                   [](const Clump& c) {
                       if (c.radii.empty() || c.radii.size() != c.centres.size()) {
                           throw InputError("heat: a clump needs one radius per centre "
                                            "and at least one member");
                       }
                       for (const double r : c.radii) {
                           if (!(r > 0.0)) {
                               throw InputError("heat: clump member radii must be > 0 m, got " +
                                                std::to_string(r));
                           }
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
                   },
                   [&](const ConvexPolyhedron& p) {
                       double d = -std::numeric_limits<double>::infinity();
                       for (std::size_t k = 0; k < p.normals.size(); ++k) {
                           d = std::max(d, p.normals[k].dot(x) - p.offsets[k]);
                       }
                       return d;
                   },
                   [&](const Clump& c) {
                       double d = std::numeric_limits<double>::infinity();
                       for (std::size_t k = 0; k < c.radii.size(); ++k) {
                           d = std::min(d, (x - c.centres[k]).norm() - c.radii[k]);
                       }
                       return d;
                   }},
        shape);
}

bool inside(const Shape& shape, const Vec3& x) {
    return std::visit(
        Overloaded{[&](const Sphere& s) { return x.squaredNorm() <= s.radius * s.radius; },
                   [&](const Box& b) { return (x.cwiseAbs() - b.half).maxCoeff() <= 0.0; },
                   [&](const Superquadric& q) { return superquadric_radial(q, x) <= 1.0; },
                   [&](const ConvexPolyhedron& p) {
                       for (std::size_t k = 0; k < p.normals.size(); ++k) {
                           if (p.normals[k].dot(x) > p.offsets[k]) {
                               return false;
                           }
                       }
                       return true;
                   },
                   [&](const Clump& c) {
                       for (std::size_t k = 0; k < c.radii.size(); ++k) {
                           if ((x - c.centres[k]).squaredNorm() <= c.radii[k] * c.radii[k]) {
                               return true;
                           }
                       }
                       return false;
                   }},
        shape);
}

Vec3 half_extent(const Shape& shape) {
    return std::visit(Overloaded{[](const Sphere& s) { return Vec3(Vec3::Constant(s.radius)); },
                                 [](const Box& b) { return b.half; },
                                 [](const Superquadric& q) { return q.half; },
                                 [](const ConvexPolyhedron& p) {
                                     Vec3 h = Vec3::Zero();
                                     for (const Vec3& v : p.vertices) {
                                         h = h.cwiseMax(v.cwiseAbs());
                                     }
                                     return h;
                                 },
                                 [](const Clump& c) {
                                     Vec3 h = Vec3::Zero();
                                     for (std::size_t k = 0; k < c.radii.size(); ++k) {
                                         h = h.cwiseMax(c.centres[k].cwiseAbs() +
                                                        Vec3::Constant(c.radii[k]));
                                     }
                                     return h;
                                 }},
                      shape);
}

double exact_volume(const Shape& shape) {
    return std::visit(
        Overloaded{
            [](const Sphere& s) { return 4.0 / 3.0 * std::numbers::pi * std::pow(s.radius, 3); },
            [](const Box& b) { return 8.0 * b.half.prod(); },
            [](const Superquadric& q) {
                return 2.0 * q.half.prod() * q.e1 * q.e2 * beta(q.e1 / 2.0 + 1.0, q.e1) *
                       beta(q.e2 / 2.0, q.e2 / 2.0);
            },
            [](const ConvexPolyhedron& p) { return polyhedron_mesh(p, 1e300).volume(); },
            [](const Clump& c) {
                if (!(c.volume > 0.0)) {
                    throw InputError("heat: clump without a reference volume");
                }
                return c.volume;
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
                   },
                   [](const ConvexPolyhedron& p) { return polyhedron_mesh(p, 1e300).area(); },
                   [](const Clump& c) {
                       if (!(c.area > 0.0)) {
                           throw InputError("heat: clump without a reference area");
                       }
                       return c.area;
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
                   },
                   [&](const ConvexPolyhedron& p) { return polyhedron_mesh(p, edge); },
                   [&](const Clump& c) { return clump_mesh(c, edge); }},
        shape);
}

} // namespace kiln::heat
