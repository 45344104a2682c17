#pragma once
// The closed set of particle shapes and the named templates built from them.
//
// A template is a shape in its body frame (principal axes, origin at the centre of mass) with its
// mass properties computed from the geometry (never typed in).

#include "core/types.hpp"
#include "geometry/clump.hpp"
#include "geometry/polyhedron.hpp"
#include "geometry/superquadric.hpp"

#include <map>
#include <string>
#include <variant>
#include <vector>

namespace kiln::geometry {

/// Sphere of a given radius (m), centred at the body origin.
struct Sphere {
    double radius = 0.0; ///< radius (m)
};

/// Every shape kiln knows; dispatch with std::visit.
using Shape = std::variant<Sphere, Clump, Superquadric, ConvexPolyhedron>;

/// Kind name of a shape ("sphere", "clump", "superquadric", "polyhedron").
[[nodiscard]] const char* kind_name(const Shape& s);

/// A solid a template approximates (for the captured volume fraction and density correction).
struct ReferenceSolid {
    std::string kind; ///< "none", "sphere", "cylinder" (axis = template z) or "box"
    Vec3 size =
        Vec3::Zero(); ///< sphere: (radius, -, -); cylinder: (radius, length, -); box: edges (m)
    /// Volume of the reference solid (m^3); 0 for "none".
    [[nodiscard]] double volume() const;
};

/// A named shape with its mass properties in the principal body frame.
struct ShapeTemplate {
    std::string name;    ///< registry name, e.g. "cylinder_36"
    std::string source;  ///< file it was read from ("" when built in code)
    Shape shape;         ///< geometry, body frame (principal axes at the centre of mass)
    double volume = 0.0; ///< solid volume (m^3)
    Vec3 inertia_unit_density = Vec3::Zero(); ///< principal moments per unit density (m^5)
    ReferenceSolid reference;                 ///< solid it approximates, kind "none" if any
    bool density_correction = false;   ///< scale the density so mass = rho * reference volume
    std::vector<std::string> warnings; ///< reader notes, e.g. non-convex input replaced by its hull

    /// Factor applied to the material density: reference.volume() / volume with the density
    /// correction (the seed's 1380 -> 1691 kg/m^3 for the 36-sphere cylinder), else 1.
    [[nodiscard]] double density_factor() const;
    /// Mass (kg) for a material density (kg/m^3).
    [[nodiscard]] double mass(double density) const { return density * density_factor() * volume; }
    /// Principal moments of inertia (kg m^2), body frame, for a material density (kg/m^3).
    [[nodiscard]] Vec3 inertia(double density) const {
        return density * density_factor() * inertia_unit_density;
    }
    /// Radius of a centred sphere enclosing the shape (m).
    [[nodiscard]] double bounding_radius() const;
};

/// Template of a shape whose mass properties follow from its geometry. Clumps must already be
/// built by make_clump and polyhedra by make_polyhedron (principal frame); spheres and
/// superquadrics are centred by definition.
[[nodiscard]] ShapeTemplate make_template(std::string name, Shape shape);

/// Named templates. Lookup of an unknown name is an input error listing the known names.
class ShapeRegistry {
  public:
    /// Adds (or replaces) a template under its name.
    void add(ShapeTemplate t);
    /// True when a template of this name is present.
    [[nodiscard]] bool contains(const std::string& name) const { return templates_.contains(name); }
    /// The template of this name; throws kiln::InputError when unknown.
    [[nodiscard]] const ShapeTemplate& get(const std::string& name) const;
    /// Names of all templates, sorted.
    [[nodiscard]] std::vector<std::string> names() const;

  private:
    std::map<std::string, ShapeTemplate> templates_;
};

} // namespace kiln::geometry
