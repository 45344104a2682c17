#pragma once
// The finite-volume conduction graph of one particle template at one resolution, in the body
// frame. Built once per (shape, resolution) and shared by every particle of that template: only
// geometry is stored here; material, time step and boundary data come later (resolved_model.hpp).

#include "core/types.hpp"

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

/// Geometry of a template grid; all vectors in the body frame, centre of mass at the origin.
struct ThermalGrid {
    std::string kind;                    ///< "spherical" or "cartesian" (for reports)
    std::vector<double> volume;          ///< cell volumes (m^3)
    std::vector<double> volume_fraction; ///< cell volume / full cell volume (-); 1 off the surface
    std::vector<Vec3> node;              ///< node (temperature) position of each cell (m)
    std::vector<CellLink> links;         ///< conduction links, each pair once (or once per face)
    std::vector<BoundaryFace> boundary;  ///< surface patches, at most one per boundary cell
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

} // namespace kiln::heat
