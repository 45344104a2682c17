#pragma once
// The finite-volume conduction graph of one particle template at one resolution, in the body
// frame. Built once per (shape, resolution) and shared by every particle of that template: only
// geometry is stored here; material, time step and boundary data come later (resolved_model.hpp).

#include "core/types.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace kiln::heat {

/// Conduction between two cells: heat rate k * geometry * (T_b - T_a) from b into a.
struct CellLink {
    int a = 0;           ///< first cell index
    int b = 0;           ///< second cell index
    double geometry = 0; ///< face area / node distance (m); times k gives W/K
};

/// The surface part of one boundary cell.
struct BoundaryFace {
    int cell = 0;        ///< owning cell index
    double area = 0;     ///< surface area inside the cell (m^2)
    Vec3 area_normal;    ///< area-weighted outward normal: integral of n dA (m^2), body frame
    Vec3 centroid;       ///< area centroid of the surface patch (m), body frame
    double distance = 0; ///< conduction distance cell node -> surface (m): k area / distance
                         ///< is the node-to-surface conductance (W/K)
};

/// Boundary patches grouped by position: a ball (body frame) holding the centroids of the group,
/// and the group's patch indices, ascending. Lets a query near one point of the surface
/// (contact_patches) pass over the groups far from it.
struct BoundaryCluster {
    Vec3 centre = Vec3::Zero(); ///< centre of the ball (m), body frame
    double radius = 0;          ///< radius of the ball holding the group's centroids (m)
    std::vector<int> faces;     ///< indices into ThermalGrid::boundary, ascending
};

/// Geometry of a template grid; all vectors in the body frame, centre of mass at the origin.
struct ThermalGrid {
    std::string kind;                    ///< "spherical" or "cartesian" (for reports)
    std::vector<double> volume;          ///< cell volumes (m^3)
    std::vector<double> volume_fraction; ///< cell volume / full cell volume (-); 1 off the surface
    std::vector<Vec3> node;              ///< node (temperature) position of each cell (m)
    std::vector<CellLink> links;         ///< conduction links, each pair once (or once per face)
    std::vector<BoundaryFace> boundary;  ///< surface patches, at most one per boundary cell
    std::vector<BoundaryCluster> clusters; ///< the patches grouped in space (index_boundary);
                                           ///< empty: not grouped (queries scan every patch)
    int centre_cell = 0;                 ///< the cell containing the origin (the "core" node)

    /// Number of cells (unknowns).
    [[nodiscard]] int size() const { return static_cast<int>(volume.size()); }
    /// Sum of cell volumes (m^3).
    [[nodiscard]] double total_volume() const;
    /// Sum of boundary patch areas (m^2).
    [[nodiscard]] double total_area() const;
    /// Sum of area-weighted normals (m^2); zero for a closed surface.
    [[nodiscard]] Vec3 total_area_normal() const;
};

inline double ThermalGrid::total_volume() const {
    double v = 0.0;
    for (const double x : volume) {
        v += x;
    }
    return v;
}

inline double ThermalGrid::total_area() const {
    double a = 0.0;
    for (const BoundaryFace& f : boundary) {
        a += f.area;
    }
    return a;
}

inline Vec3 ThermalGrid::total_area_normal() const {
    Vec3 n = Vec3::Zero();
    for (const BoundaryFace& f : boundary) {
        n += f.area_normal;
    }
    return n;
}

/// Groups g.boundary into g.clusters: the boxes of a `per_axis`^3 lattice over the bounding box of
/// the centroids, each non-empty box one group (its ball centred on its centroids' bounding box).
/// The grid builders call it; a grid assembled by hand works without it.
inline void index_boundary(ThermalGrid& g, int per_axis = 4) {
    g.clusters.clear();
    if (g.boundary.empty() || per_axis < 1) {
        return;
    }
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
    Vec3 hi = -lo;
    for (const BoundaryFace& f : g.boundary) {
        lo = lo.cwiseMin(f.centroid);
        hi = hi.cwiseMax(f.centroid);
    }
    const Vec3 span = hi - lo;
    std::vector<std::vector<int>> boxes(static_cast<std::size_t>(per_axis * per_axis * per_axis));
    for (std::size_t b = 0; b < g.boundary.size(); ++b) {
        int key = 0;
        for (int d = 0; d < 3; ++d) {
            const double t = span[d] > 0.0 ? (g.boundary[b].centroid[d] - lo[d]) / span[d] : 0.0;
            const int i = std::clamp(static_cast<int>(std::floor(t * per_axis)), 0, per_axis - 1);
            key = key * per_axis + i;
        }
        boxes[static_cast<std::size_t>(key)].push_back(static_cast<int>(b));
    }
    for (std::vector<int>& faces : boxes) {
        if (faces.empty()) {
            continue;
        }
        Vec3 blo = Vec3::Constant(std::numeric_limits<double>::infinity());
        Vec3 bhi = -blo;
        for (const int b : faces) {
            blo = blo.cwiseMin(g.boundary[static_cast<std::size_t>(b)].centroid);
            bhi = bhi.cwiseMax(g.boundary[static_cast<std::size_t>(b)].centroid);
        }
        BoundaryCluster c;
        c.centre = 0.5 * (blo + bhi);
        for (const int b : faces) {
            c.radius = std::max(
                c.radius, (g.boundary[static_cast<std::size_t>(b)].centroid - c.centre).norm());
        }
        c.faces = std::move(faces);
        g.clusters.push_back(std::move(c));
    }
}

} // namespace kiln::heat
