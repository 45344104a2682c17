#pragma once
// Resolved bodies in the run loop: the heat module's shape of a geometry template, and the patch
// set of a contact on a Cartesian grid widened past sliver cut cells.

#include "core/types.hpp"
#include "geometry/shape.hpp"
#include "heat/shape.hpp"
#include "heat/thermal_grid.hpp"

#include <vector>

namespace kiln::thermal {

/// The heat module's version of a template's shape (body frame, centre of mass at the origin, as
/// the template). A clump carries the template's union volume and exposed area as references.
[[nodiscard]] heat::Shape heat_shape(const geometry::ShapeTemplate& t);

/// Cartesian grids: adds the nearest facing patches (by centroid distance to the body-frame
/// contact point `x` (m), body-frame normal `n`) to `patches` until they hold at least half of
/// `full`, the capacity of a full cell (J/K); `capacity` per cell (J/K). See body_shapes.cpp.
void widen_to_one_cell(const heat::ThermalGrid& g, const std::vector<double>& capacity, double full,
                       const Vec3& x, const Vec3& n, std::vector<int>& patches);

} // namespace kiln::thermal
