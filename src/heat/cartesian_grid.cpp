// Cut-cell construction (our own design; the seed only remarks that a Cartesian grid gives a
// staircase surface needing an area correction, Oschmann 2019 L1911/L2193). Steps:
//  1. Grid: cubic cells of size h = (largest extent) / cells_across, placed so that the planes
//     x = +-a (and likewise y, z) of the bounding box pass through cell centres, plus one empty
//     layer of cells on every side.
//  2. Surface: a triangulation with edges ~ mesh_edge_fraction * h is clipped against every cell
//     (Sutherland-Hodgman); each cell sums its patch area, integral of n dA and area moments.
//  3. Apertures: the inside part of every cell face next to a cut cell, by m x m sub-squares, each
//     cut by the straight line of the locally linearised level function (exact area of a square
//     below a line).
//  4. Cut-cell volume and centroid by the divergence theorem about the cell centre x0:
//     V = 1/3 (sum_faces (h/2) a_f + integral_patch (x - x0).n dA) and
//     V (x_c - x0)_i = 1/2 closed-surface integral of (x - x0)_i^2 n_i dA.
//     The face terms use the exact implicit surface and the patch terms the triangulation, so
//     the two are consistent only to the triangulation error, O(h^2) with edges ~ h/4.
//  5. Cut cells with volume fraction below merge_fraction join the neighbour with the largest
//     shared aperture (volumes, patches and links are summed), which keeps the conditioning
//     of the implicit matrix moderate.
// Conduction geometry: aperture / d between face neighbours, d the distance of the two nodes
// (cell centroids) along the face normal, floored at h/2; node-to-surface distance: from the
// cell's node to its patch plane along the patch normal. (A first version used d = h for every
// face; that made the cube of validation 21 converge at first order only.)

#include "heat/cartesian_grid.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace kiln::heat {

namespace {

struct Polygon {
    std::array<Vec3, 16> p;
    int n = 0;
};

/// Keeps the part of `in` with x[axis] <= plane (below) or >= plane (!below).
void clip(const Polygon& in, int axis, double plane, bool below, Polygon& out) {
    out.n = 0;
    for (int k = 0; k < in.n; ++k) {
        const Vec3& a = in.p[k];
        const Vec3& b = in.p[(k + 1) % in.n];
        const double da = below ? plane - a[axis] : a[axis] - plane;
        const double db = below ? plane - b[axis] : b[axis] - plane;
        if (da >= 0.0) {
            out.p[out.n++] = a;
        }
        if ((da >= 0.0) != (db >= 0.0)) {
            out.p[out.n++] = a + da / (da - db) * (b - a);
        }
    }
}

/// Area fraction of the unit square [0,1]^2 where a X + b Y < t (a, b >= 0).
double square_fraction_below(double a, double b, double t) {
    if (a < b) {
        std::swap(a, b);
    }
    if (b < 1e-12) {
        return std::clamp(t / a, 0.0, 1.0);
    }
    const auto sq = [](double x) { return x > 0.0 ? x * x : 0.0; };
    const double f = (sq(t) - sq(t - a) - sq(t - b) + sq(t - a - b)) / (2.0 * a * b);
    return std::clamp(f, 0.0, 1.0);
}

struct Patch {
    double area = 0.0;
    Vec3 area_normal = Vec3::Zero();
    Vec3 moment = Vec3::Zero(); // integral of x dA
    double flux = 0.0;          // integral of (x - x0).n dA
    Vec3 second = Vec3::Zero(); // integral of (x - x0)_i^2 n_i dA
};

struct Layout {
    double h = 0.0;
    Vec3 lo;
    std::array<int, 3> n{};
    [[nodiscard]] int index(int i, int j, int k) const { return (k * n[1] + j) * n[0] + i; }
    [[nodiscard]] Vec3 centre(int i, int j, int k) const {
        return lo + h * Vec3(i + 0.5, j + 0.5, k + 0.5);
    }
    [[nodiscard]] int count() const { return n[0] * n[1] * n[2]; }
};

/// Aperture (m^2) of the face with normal `axis` whose lower corner is `corner`.
double aperture(const Shape& shape, const Layout& g, int axis, const Vec3& corner, int m) {
    const int u = (axis + 1) % 3;
    const int v = (axis + 2) % 3;
    const double s = g.h / m;
    const double eps = 1e-3 * s;
    double inside_area = 0.0;
    for (int b = 0; b < m; ++b) {
        for (int a = 0; a < m; ++a) {
            Vec3 q = corner;
            q[u] += (a + 0.5) * s;
            q[v] += (b + 0.5) * s;
            const double d = level(shape, q);
            if (d <= -s) {
                inside_area += 1.0;
                continue;
            }
            if (d >= s) {
                continue;
            }
            Vec3 du = Vec3::Zero();
            Vec3 dv = Vec3::Zero();
            du[u] = eps;
            dv[v] = eps;
            const double gu = (level(shape, q + du) - level(shape, q - du)) / (2.0 * eps);
            const double gv = (level(shape, q + dv) - level(shape, q - dv)) / (2.0 * eps);
            const double gn = std::hypot(gu, gv);
            if (gn < 1e-8) {
                inside_area += d < 0.0 ? 1.0 : 0.0;
                continue;
            }
            // Inside where gu x + gv y < -d (x, y in units of s about the sub-square centre).
            const double ua = std::abs(gu) / gn;
            const double vb = std::abs(gv) / gn;
            inside_area += square_fraction_below(ua, vb, -d / (s * gn) + 0.5 * (ua + vb));
        }
    }
    return inside_area * s * s;
}

using CellFlags = std::vector<char>;

/// Grid placement: centres on -half + i h, one empty layer beyond each side (step 1).
Layout make_layout(const Shape& shape, const CartesianResolution& res) {
    const Vec3 half = half_extent(shape);
    Layout g;
    g.h = 2.0 * half.maxCoeff() / res.cells_across;
    for (int a = 0; a < 3; ++a) {
        g.n[a] = static_cast<int>(std::ceil(2.0 * half[a] / g.h - 1e-9)) + 3;
        g.lo[a] = -half[a] - 1.5 * g.h;
    }
    return g;
}

/// Adds the clipped polygon `poly` (fan-triangulated) to the patch sums of a cell centred at x0.
void add_polygon(const Polygon& poly, const Vec3& x0, Patch& pc) {
    for (int f = 1; f + 1 < poly.n; ++f) {
        const Vec3& a = poly.p[0];
        const Vec3& b = poly.p[f];
        const Vec3& c = poly.p[f + 1];
        const Vec3 an = 0.5 * (b - a).cross(c - a);
        const double area = an.norm();
        pc.area += area;
        pc.area_normal += an;
        pc.moment += area * (a + b + c) / 3.0;
        pc.flux += (a - x0).dot(an);
        // Edge-midpoint rule: exact for the quadratic integrand over each triangle.
        const Vec3 m1 = 0.5 * (a + b) - x0;
        const Vec3 m2 = 0.5 * (b + c) - x0;
        const Vec3 m3 = 0.5 * (c + a) - x0;
        pc.second += an.cwiseProduct(m1.cwiseAbs2() + m2.cwiseAbs2() + m3.cwiseAbs2()) / 3.0;
    }
}

/// Step 2: the surface triangulation clipped against every cell it overlaps.
std::vector<Patch> clip_surface(const Shape& shape, const Layout& g, double mesh_edge) {
    std::vector<Patch> patch(static_cast<std::size_t>(g.count()));
    const SurfaceMesh mesh = surface_mesh(shape, mesh_edge);
    Polygon poly;
    Polygon tmp;
    for (const auto& t : mesh.triangles) {
        const Vec3& p0 = mesh.vertices[t[0]];
        const Vec3& p1 = mesh.vertices[t[1]];
        const Vec3& p2 = mesh.vertices[t[2]];
        const Vec3 bmin = p0.cwiseMin(p1).cwiseMin(p2);
        const Vec3 bmax = p0.cwiseMax(p1).cwiseMax(p2);
        std::array<int, 3> i0{};
        std::array<int, 3> i1{};
        for (int a = 0; a < 3; ++a) {
            i0[a] =
                std::clamp(static_cast<int>(std::floor((bmin[a] - g.lo[a]) / g.h)), 0, g.n[a] - 1);
            i1[a] =
                std::clamp(static_cast<int>(std::floor((bmax[a] - g.lo[a]) / g.h)), 0, g.n[a] - 1);
        }
        for (int k = i0[2]; k <= i1[2]; ++k) {
            for (int j = i0[1]; j <= i1[1]; ++j) {
                for (int i = i0[0]; i <= i1[0]; ++i) {
                    poly.n = 3;
                    poly.p[0] = p0;
                    poly.p[1] = p1;
                    poly.p[2] = p2;
                    const std::array<int, 3> ijk{i, j, k};
                    for (int a = 0; a < 3 && poly.n >= 3; ++a) {
                        const double lo = g.lo[a] + ijk[a] * g.h;
                        clip(poly, a, lo, false, tmp);
                        clip(tmp, a, lo + g.h, true, poly);
                    }
                    if (poly.n >= 3) {
                        add_polygon(poly, g.centre(i, j, k),
                                    patch[static_cast<std::size_t>(g.index(i, j, k))]);
                    }
                }
            }
        }
    }
    return patch;
}

/// Apertures: ap[a][c] is the inside area of the face between cell c and its +a neighbour (m^2).
struct Apertures {
    std::array<std::vector<double>, 3> ap;
    std::array<int, 3> stride{};
    /// Aperture of the upper (+a) or lower (-a) face of cell c.
    [[nodiscard]] double face(int a, int c, bool upper) const {
        if (upper) {
            return ap[a][static_cast<std::size_t>(c)];
        }
        const int d = c - stride[a];
        return d >= 0 ? ap[a][static_cast<std::size_t>(d)] : 0.0;
    }
};

/// Step 3: apertures of every face next to a cut cell; h^2 between full cells.
Apertures compute_apertures(const Shape& shape, const Layout& g, const CellFlags& cut,
                            const CellFlags& full, int samples) {
    Apertures out;
    out.stride = {1, g.n[0], g.n[0] * g.n[1]};
    for (int a = 0; a < 3; ++a) {
        out.ap[a].assign(static_cast<std::size_t>(g.count()), 0.0);
        for (int k = 0; k < g.n[2]; ++k) {
            for (int j = 0; j < g.n[1]; ++j) {
                for (int i = 0; i < g.n[0]; ++i) {
                    const std::array<int, 3> ijk{i, j, k};
                    if (ijk[a] + 1 >= g.n[a]) {
                        continue;
                    }
                    const auto c = static_cast<std::size_t>(g.index(i, j, k));
                    const auto d = c + static_cast<std::size_t>(out.stride[a]);
                    if (cut[c] || cut[d]) {
                        Vec3 corner = g.lo + g.h * Vec3(i, j, k);
                        corner[a] += g.h;
                        out.ap[a][c] = aperture(shape, g, a, corner, samples);
                    } else if (full[c] && full[d]) {
                        out.ap[a][c] = g.h * g.h;
                    }
                }
            }
        }
    }
    return out;
}

/// Step 4: volumes and nodes (centroids) of full and cut cells; zero elsewhere.
void volumes_and_nodes(const Layout& g, const CellFlags& cut, const CellFlags& full,
                       const std::vector<Patch>& patch, const Apertures& ap,
                       std::vector<double>& vol, std::vector<Vec3>& node) {
    const double h = g.h;
    vol.assign(static_cast<std::size_t>(g.count()), 0.0);
    node.assign(static_cast<std::size_t>(g.count()), Vec3::Zero());
    for (int k = 0; k < g.n[2]; ++k) {
        for (int j = 0; j < g.n[1]; ++j) {
            for (int i = 0; i < g.n[0]; ++i) {
                const int c = g.index(i, j, k);
                const auto cs = static_cast<std::size_t>(c);
                const Vec3 x0 = g.centre(i, j, k);
                if (full[cs]) {
                    vol[cs] = h * h * h;
                    node[cs] = x0;
                } else if (cut[cs]) {
                    double sum = 0.0;
                    Vec3 offset = 0.5 * patch[cs].second;
                    for (int a = 0; a < 3; ++a) {
                        const double up = ap.face(a, c, true);
                        const double down = ap.face(a, c, false);
                        sum += up + down;
                        offset[a] += h * h / 8.0 * (up - down);
                    }
                    const double v = (0.5 * h * sum + patch[cs].flux) / 3.0;
                    vol[cs] = v;
                    node[cs] = v > 1e-9 * h * h * h ? Vec3(x0 + offset / v) : x0;
                }
            }
        }
    }
}

/// Step 5: for each cut cell below `v_small`, the regular face neighbour with the largest shared
/// aperture it joins (-1: keep).
std::vector<int> merge_targets(const Layout& g, const CellFlags& cut, const CellFlags& full,
                               const std::vector<double>& vol, const Apertures& ap,
                               double v_small) {
    const int total = g.count();
    std::vector<int> target(static_cast<std::size_t>(total), -1);
    for (int c = 0; c < total; ++c) {
        const auto cs = static_cast<std::size_t>(c);
        if (!cut[cs] || vol[cs] >= v_small) {
            continue;
        }
        double best = -1.0;
        for (int a = 0; a < 3; ++a) {
            for (const bool upper : {false, true}) {
                const int d = upper ? c + ap.stride[a] : c - ap.stride[a];
                if (d < 0 || d >= total) {
                    continue;
                }
                const auto ds = static_cast<std::size_t>(d);
                const bool regular = full[ds] || (cut[ds] && vol[ds] >= v_small);
                const double w = ap.face(a, c, upper);
                // Apertures equal to rounding (mirror images) keep the first axis in x, y, z order,
                // so the choice does not depend on round-off and mirror-symmetric shapes get
                // mirror-symmetric grids.
                if (regular && w > best * (1.0 + 1e-9) + 1e-300) {
                    best = w;
                    target[cs] = d;
                }
            }
        }
    }
    return target;
}

/// Step 6: the compact grid: summed volumes, nodes and patches per compact cell, links, patches.
ThermalGrid assemble(const Layout& g, const std::vector<int>& id, int count,
                     const std::vector<double>& vol, const std::vector<Vec3>& node,
                     const std::vector<Patch>& patch, const Apertures& ap) {
    const double h = g.h;
    const int total = g.count();
    ThermalGrid out;
    out.kind = "cartesian";
    out.volume.assign(static_cast<std::size_t>(count), 0.0);
    out.node.assign(static_cast<std::size_t>(count), Vec3::Zero());
    std::vector<Patch> cell_patch(static_cast<std::size_t>(count));
    for (int c = 0; c < total; ++c) {
        const auto cs = static_cast<std::size_t>(c);
        if (id[cs] < 0) {
            continue;
        }
        const auto o = static_cast<std::size_t>(id[cs]);
        out.volume[o] += vol[cs];
        out.node[o] += vol[cs] * node[cs];
        cell_patch[o].area += patch[cs].area;
        cell_patch[o].area_normal += patch[cs].area_normal;
        cell_patch[o].moment += patch[cs].moment;
    }
    out.volume_fraction.resize(static_cast<std::size_t>(count));
    for (std::size_t o = 0; o < out.volume.size(); ++o) {
        out.node[o] /= std::max(out.volume[o], 1e-300);
        out.volume_fraction[o] = out.volume[o] / (h * h * h);
    }
    for (int a = 0; a < 3; ++a) {
        for (int c = 0; c < total; ++c) {
            const auto cs = static_cast<std::size_t>(c);
            const double w = ap.ap[a][cs];
            const int d = c + ap.stride[a];
            if (w <= 0.0 || d >= total) {
                continue;
            }
            const int ia = id[cs];
            const int ib = id[static_cast<std::size_t>(d)];
            if (ia >= 0 && ib >= 0 && ia != ib) {
                // Node distance along the face normal: h between regular cells, less next to a
                // cut cell whose node (centroid) moved towards the face; floored at h/2.
                const double dist =
                    std::max(0.5 * h, std::abs(out.node[static_cast<std::size_t>(ib)][a] -
                                               out.node[static_cast<std::size_t>(ia)][a]));
                out.links.push_back({ia, ib, w / dist});
            }
        }
    }
    for (int o = 0; o < count; ++o) {
        const Patch& p = cell_patch[static_cast<std::size_t>(o)];
        if (p.area <= 0.0) {
            continue;
        }
        BoundaryFace f;
        f.cell = o;
        f.area = p.area;
        f.area_normal = p.area_normal;
        f.centroid = p.moment / p.area;
        const double nn = p.area_normal.norm();
        f.distance = nn > 0.0
                         ? std::max(0.0, p.area_normal.dot(f.centroid -
                                                           out.node[static_cast<std::size_t>(o)]) /
                                             nn)
                         : 0.0;
        out.boundary.push_back(f);
    }
    // The cell holding the origin.
    const Vec3 rel = -g.lo / h;
    const int c0 =
        g.index(static_cast<int>(rel.x()), static_cast<int>(rel.y()), static_cast<int>(rel.z()));
    out.centre_cell = std::max(0, id[static_cast<std::size_t>(c0)]);
    return out;
}

} // namespace

double cartesian_cell_size(const Shape& shape, const CartesianResolution& res) {
    return 2.0 * half_extent(shape).maxCoeff() / res.cells_across;
}

ThermalGrid make_cartesian_grid(const Shape& shape, const CartesianResolution& res) {
    validate(shape);
    if (res.cells_across < 2 || res.aperture_samples < 1 || !(res.mesh_edge_fraction > 0.0) ||
        !(res.merge_fraction >= 0.0 && res.merge_fraction < 1.0)) {
        throw InputError("heat: Cartesian grid needs cells_across >= 2, aperture_samples >= 1, "
                         "mesh_edge_fraction > 0 and 0 <= merge_fraction < 1");
    }
    const Layout g = make_layout(shape, res);
    const double h = g.h;
    const int total = g.count();
    const std::vector<Patch> patch = clip_surface(shape, g, res.mesh_edge_fraction * h);

    // Classification: cut (carries surface), inside, outside.
    CellFlags cut(static_cast<std::size_t>(total), 0);
    CellFlags full(static_cast<std::size_t>(total), 0);
    for (int k = 0; k < g.n[2]; ++k) {
        for (int j = 0; j < g.n[1]; ++j) {
            for (int i = 0; i < g.n[0]; ++i) {
                const auto c = static_cast<std::size_t>(g.index(i, j, k));
                if (patch[c].area > 0.0) {
                    cut[c] = 1;
                } else if (inside(shape, g.centre(i, j, k))) {
                    full[c] = 1;
                }
            }
        }
    }
    const Apertures ap = compute_apertures(shape, g, cut, full, res.aperture_samples);
    std::vector<double> vol;
    std::vector<Vec3> node;
    volumes_and_nodes(g, cut, full, patch, ap, vol, node);
    const std::vector<int> target =
        merge_targets(g, cut, full, vol, ap, res.merge_fraction * h * h * h);

    // Compact numbering: regular cells first, merged cells share their target's number.
    std::vector<int> id(static_cast<std::size_t>(total), -1);
    int count = 0;
    for (std::size_t c = 0; c < id.size(); ++c) {
        if ((full[c] || cut[c]) && target[c] < 0) {
            id[c] = count++;
        }
    }
    for (std::size_t c = 0; c < id.size(); ++c) {
        if (target[c] >= 0) {
            id[c] = id[static_cast<std::size_t>(target[c])];
        }
    }
    return assemble(g, id, count, vol, node, patch, ap);
}

} // namespace kiln::heat
