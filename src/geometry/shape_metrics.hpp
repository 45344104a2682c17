#pragma once
// Surface area, projected area and the shape factors of drag correlations (sphericity and
// crosswise sphericity after Hoelzer & Sommerfeld, Powder Technol. 184 (2008) 361, Sec. 2).

#include "core/types.hpp"
#include "geometry/shape.hpp"

namespace kiln::geometry {

/// A numerically computed quantity with its estimated absolute error (0 when analytic).
struct Estimate {
    double value = 0.0; ///< value (unit of the quantity)
    double error = 0.0; ///< estimated absolute error (same unit)
};

/// Surface area (m^2): analytic for spheres; superquadrics by a triangulation of the parametric
/// surface (Richardson-extrapolated from two resolutions, error = their difference); clumps by
/// the exposed area of each member (exact arcs along latitude bands, midpoint rule in latitude);
/// polyhedra exactly (sum of the faces).
[[nodiscard]] Estimate surface_area(const Shape& s);

/// Area (m^2) of the shadow of the shape on a plane normal to the body-frame direction u.
/// Spheres: analytic; superquadrics: 1/2 sum |n . u| dA over the triangulation (convex body);
/// clumps: union of the member discs, exact chords along rows of a fine grid; polyhedra exactly,
/// 1/2 sum |n . u| A over the faces.
[[nodiscard]] Estimate projected_area(const Shape& s, const Vec3& u_body);

/// Shape factors of a template (see docs/theory/shapes.md for the definitions).
struct ShapeFactors {
    double volume = 0.0;           ///< solid volume V (m^3)
    Estimate surface;              ///< surface area S (m^2)
    double d_volume = 0.0;         ///< equivalent-volume diameter (6 V / pi)^(1/3) (m)
    double d_surface = 0.0;        ///< equivalent-surface diameter sqrt(S / pi) (m)
    double sphericity = 0.0;       ///< pi d_v^2 / S (-)
    Vec3 projected = Vec3::Zero(); ///< shadow area for flow along body x, y, z (m^2)
    Vec3 crosswise = Vec3::Zero(); ///< crosswise sphericity (pi d_v^2 / 4) / A_perp, flow along
                                   ///< body x, y, z (-)
};

/// Shape factors of a template.
[[nodiscard]] ShapeFactors shape_factors(const ShapeTemplate& t);

} // namespace kiln::geometry
