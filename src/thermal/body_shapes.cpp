#include "thermal/body_shapes.hpp"

#include "geometry/shape_metrics.hpp"

#include <algorithm>
#include <utility>

namespace kiln::thermal {

/// The heat module's version of a body's shape (body frame, centre of mass at the origin, as the
/// template). A clump carries the template's union volume and exposed area as its references.
heat::Shape heat_shape(const geometry::ShapeTemplate& t) {
    if (const auto* sq = std::get_if<geometry::Superquadric>(&t.shape)) {
        return heat::Superquadric{sq->half_axes, sq->e1, sq->e2};
    }
    if (const auto* sp = std::get_if<geometry::Sphere>(&t.shape)) {
        return heat::Sphere{sp->radius};
    }
    if (const auto* c = std::get_if<geometry::Clump>(&t.shape)) {
        heat::Clump h;
        for (const geometry::ClumpSphere& m : c->spheres) {
            h.centres.push_back(m.centre);
            h.radii.push_back(m.radius);
        }
        h.volume = c->volume;
        h.area = geometry::surface_area(t.shape).value;
        return h;
    }
    const auto& p = std::get<geometry::ConvexPolyhedron>(t.shape);
    return heat::make_convex_polyhedron(p.vertices, p.faces);
}

/// Cartesian grids: when the patches under a contact hold less than half a full cell's heat
/// capacity `full` (J/K), i.e. less than any cell the grid builder merged or kept regular
/// (merge_fraction 0.5): a contact disc smaller than a cell that met a sliver cut cell, which the
/// builder keeps where no neighbour is large enough to merge into (corners of turned polyhedra),
/// adds the nearest facing patches (by centroid distance to the body-frame contact point `x`,
/// normal `n`) until they do. The heat a grid cannot resolve below a cell then spreads over about
/// half a cell or more, and the lag limit dt G / C_patch stays that of such a cell (validation 29
/// met a limit of 1e-14 s otherwise). Contacts on regular cut cells are unchanged.
void widen_to_one_cell(const heat::ThermalGrid& g, const std::vector<double>& capacity, double full,
                       const Vec3& x, const Vec3& n, std::vector<int>& patches) {
    double held = 0.0;
    for (const int b : patches) {
        held += capacity[static_cast<std::size_t>(g.boundary[static_cast<std::size_t>(b)].cell)];
    }
    const double enough = 0.5 * full;
    if (held >= enough) {
        return;
    }
    std::vector<std::pair<double, int>> near; // (squared distance, patch) of facing patches
    for (std::size_t b = 0; b < g.boundary.size(); ++b) {
        const heat::BoundaryFace& f = g.boundary[b];
        if (f.area_normal.dot(n) > 0.0 &&
            std::find(patches.begin(), patches.end(), static_cast<int>(b)) == patches.end()) {
            near.emplace_back((f.centroid - x).squaredNorm(), static_cast<int>(b));
        }
    }
    std::sort(near.begin(), near.end());
    for (const auto& [d2, b] : near) {
        if (held >= enough) {
            break;
        }
        patches.push_back(b);
        held += capacity[static_cast<std::size_t>(g.boundary[static_cast<std::size_t>(b)].cell)];
    }
}

} // namespace kiln::thermal
