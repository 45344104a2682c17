#pragma once
// Internal to kiln_thermal (not installed, not included outside src/thermal): the template and
// contact records of ThermalSystem and the small helpers its source files share. The class is
// split by concern: thermal_system.cpp (set-up, refusals, templates, particle records),
// thermal_contacts.cpp (contact conduction, patches and their lagged rates), thermal_pairs.cpp
// (gas gaps, neighbour radiation, impacts), thermal_body_pairs.cpp (the same for pairs with a
// body), thermal_walls.cpp (gas gaps and radiation to walls), thermal_surface.cpp (convection,
// radiation to the ambient, lumped update), thermal_step.cpp (the thermal step and its lag limit),
// thermal_state.cpp (output, summary and checkpoint).

#include "thermal/thermal_system.hpp"

#include "heat/resolved_model.hpp"

#include <map>
#include <memory>
#include <numbers>
#include <utility>
#include <vector>

namespace kiln::thermal {

namespace detail {

/// Sub-steps are chosen so that dt_sub * (largest contact conductance / heat capacity) stays below
/// this bound. The lagged exchange is an explicit Euler step of the contact network; at 1 a pair
/// of lumped particles would equalise in one step, at 0.5 the difference halves per step and can
/// never change sign (no oscillation, no undershoot below the partner temperatures).
inline constexpr double lag_safety = 0.5;

/// Volume of a sphere of radius `r` (m^3).
inline double sphere_volume(double r) {
    return 4.0 / 3.0 * std::numbers::pi * r * r * r;
}

/// Surface area of a sphere of radius `r` (m^2).
inline double sphere_area(double r) {
    return 4.0 * std::numbers::pi * r * r;
}

/// Template of particle index i, nullptr for a sphere.
inline const geometry::ShapeTemplate* shape_of(const dynamics::System& sys, std::size_t i) {
    const int s = sys.particles().shape[i];
    return s >= 0 ? &sys.spec().shapes[static_cast<std::size_t>(s)] : nullptr;
}

/// Effective modulus of two bodies, 1 / ((1 - nu1^2) / E1 + (1 - nu2^2) / E2) (Pa).
inline double effective_modulus(double e1, double nu1, double e2, double nu2) {
    return 1.0 / ((1.0 - nu1 * nu1) / e1 + (1.0 - nu2 * nu2) / e2);
}

} // namespace detail

struct ThermalSystem::Template {
    int material = 0;
    double radius = 0;
    std::shared_ptr<const heat::ThermalGrid> grid;
    bool spherical = true;
    heat::SphericalResolution res;
    std::vector<double> h_face; // template h per boundary face (W/(m^2 K))
    heat::ThermalProperties props;
    heat::SolverSettings solver;
    double base_dt = 0;
    // Operators by (sub-step count, thread): each holds its own solver workspace.
    std::map<std::pair<int, int>, std::unique_ptr<heat::ResolvedOperator>> ops;
    std::vector<double> capacity; // per cell (J/K)
    double total_capacity = 0;
    double full_cell_capacity = 0;   // capacity of a full Cartesian cell, rho c_p h^3 (J/K)
    bool turning_stagnation = false; // a body under f(theta): uniform h in the matrix, the rest
                                     // lagged per body and thermal step
    // A sphere under f(theta): h_face holds the distribution for the world axes (exact, implicit);
    // a sphere whose grid has turned (sphere_rotation) gets the difference to its own lagged.
    bool sphere_stagnation = false;
};

/// One conducting contact of the current thermal step, with its patches in each body.
struct ThermalSystem::ContactData {
    Record a;                    // particle i
    Record b;                    // partner j (material -1 for a wall)
    double conductance = 0;      // H (W/K)
    double wall_temperature = 0; // K, walls only
    bool wall = false;
    bool radiative = false;     // conductance holds K (W/K^4): rate K (T_j^4 - T_i^4)
    std::vector<int> patches_a; // boundary patches of i under the contact (resolved)
    std::vector<int> patches_b; // of j
};
} // namespace kiln::thermal
