#pragma once
// The heat part of a scene as plain data (what the [heat] section, the per-material heat tables,
// wall temperatures and particle temperatures of a case file say), validated and with defaults
// filled in. A scene without heat has `enabled == false` and costs nothing.

#include "core/types.hpp"
#include "heat/gas_conduction.hpp"
#include "heat/heat_model.hpp"
#include "heat/resolved_model.hpp"
#include "heat/spherical_grid.hpp"

#include <limits>
#include <vector>

namespace kiln::thermal {

/// Grid of a resolved particle type.
enum class GridKind {
    spherical, ///< spherical-coordinate grid (spheres only)
    cartesian, ///< body-fixed cut-cell Cartesian grid (any shape)
};

/// How the contact radius is derived from the overlap.
enum class ContactRadius {
    hertz, ///< sqrt(R* delta) (consistent with the Hertz contact mechanics)
    lens,  ///< radius of the intersection circle of the undeformed spheres (the seed's r_c)
};

/// Heat properties of one material; `enabled` is false for a material without a heat table.
struct MaterialHeat {
    bool enabled = false;                            ///< the material has heat properties
    double conductivity = 0;                         ///< k (W/(m K))
    double specific_heat = 0;                        ///< c_p (J/(kg K))
    double initial_temperature = 293.15;             ///< initial particle temperature (K)
    heat::HeatModel model = heat::HeatModel::lumped; ///< requested heat model
    GridKind grid = GridKind::spherical;             ///< grid of resolved particles
    heat::SphericalResolution spherical;             ///< resolution of spherical grids
    int cells_across = 10;                           ///< Cartesian cells across the diameter (-)
    double real_youngs_modulus = 0; ///< E_real (Pa) for the contact-radius correction
                                    ///< c = (E_sim / E_real)^(1/5); 0 = c = 1
    double emissivity = 0;          ///< grey emissivity of the surface for radiation (-); 0 = none
};

/// The heat coupling of a run.
struct HeatSpec {
    bool enabled = false;        ///< true when the case has a [heat] section
    int step_multiple = 100;     ///< thermal step = step_multiple mechanical steps (-)
    heat::SolverSettings solver; ///< linear solver of resolved particles
    /// Initial guess of the iterative solvers: extrapolated linearly in time from the last two
    /// fields (2 T^n - T^{n-1}; keeps a second field per resolved particle, 8 bytes per cell)
    /// when true, the last field when false. Unused by CHOLMOD.
    bool extrapolated_guess = true;
    double ambient_temperature = 293.15;  ///< fluid temperature for convection (K)
    double heat_transfer_coefficient = 0; ///< mean h to the ambient (W/(m^2 K)); 0 = insulated
    bool stagnation = false; ///< distribute h around the stagnation point with the seed's f(theta)
    Vec3 flow_direction = Vec3::UnitZ(); ///< direction the fluid flows (unit, world)
    double flux = 0;                     ///< prescribed heat flux into every particle (W/m^2)
    double biot_threshold = 0.1;         ///< model "auto": lumped below this Biot number (-)
    ContactRadius contact_radius = ContactRadius::hertz; ///< contact-radius rule
    int max_substeps = 1024; ///< most sub-steps per thermal step allowed by the lag limit (-)
    /// Gas in the gaps between spheres (Cheng et al. 1999); conductivity 0 = none.
    heat::GasGap gas;
    /// Collision conduction (Sun & Chen 1988 with Zhou et al.'s c'): every contact onset of two
    /// particles (spheres or bodies) or of a particle and a wall (analytic or mesh) at a
    /// temperature exchanges the impact heat once. Needs SceneSpec::record_contact_onsets.
    bool collision_conduction = false;
    /// Resolved spheres' fields turn with their spin: each keeps an orientation (body -> world),
    /// advanced every mechanical step by its angular velocity, that places contacts, gaps and the
    /// flow direction on its grid. Off: a sphere's grid keeps the world axes (its spin is ignored
    /// thermally, as before 2026-11-24).
    bool sphere_rotation = true;
    /// Temperature of the black enclosure every heated surface with an emissivity radiates to:
    /// q = eps sigma (T_s^4 - T^4) per surface cell (resolved) or particle (lumped), any shape
    /// (K); NaN = no radiation to the ambient.
    double radiation_temperature = std::numeric_limits<double>::quiet_NaN();
    /// Largest H/R (H half the surface gap) at which neighbouring spheres exchange radiation (-).
    double radiation_cutoff = 0.5;
    /// Gas-gap conduction between heated particles and walls (plane, cylinder, mesh) at a
    /// temperature: Cheng et al.'s tubes between the particle and its mirror image in the wall,
    /// while gap / R <= gas.cutoff. Needs gas.conductivity > 0.
    bool wall_gas = false;
    /// Radiation between heated particles with an emissivity and walls at a temperature whose
    /// material has an emissivity: view factor 1/2 (a sphere to the plane it faces) while
    /// gap / R <= radiation_cutoff.
    bool wall_radiation = false;
    std::vector<MaterialHeat> materials; ///< one per material of the scene, same order
    /// Temperature of each wall of the scene (K); NaN = adiabatic (no contact conduction).
    std::vector<double> wall_temperature;
    /// Temperature of each mesh wall of the scene (K), same order as the scene's mesh walls;
    /// NaN = adiabatic.
    std::vector<double> mesh_wall_temperature;
    /// Initial temperature of each explicitly placed particle (K); NaN = its material's value.
    std::vector<double> particle_temperature;
    bool field_output = false;         ///< write intra-particle fields with the VTK frames
    std::vector<long> field_particles; ///< ids whose fields are written; empty = all resolved
};

/// Not-a-number, the "not given" value of temperatures above.
inline constexpr double unset = std::numeric_limits<double>::quiet_NaN();

} // namespace kiln::thermal
