#pragma once
// The set-up shared by the collision-conduction tests (tests/thermal/test_collision_run.cpp for
// spheres, test_collision_bodies.cpp for bodies): one material, no gravity, contact onsets
// recorded, and the heat spec with collision conduction on. Each test picks its own grid.

#include "dynamics/scene_spec.hpp"
#include "heat/collision_conduction.hpp"
#include "thermal/thermal_system.hpp"

namespace kiln::thermal::collision_test {

inline constexpr double radius = 5e-3;       // m
inline constexpr double youngs = 1e8;        // Pa
inline constexpr double poisson = 0.3;       // -
inline constexpr double density = 2500;      // kg/m^3
inline constexpr double specific_heat = 900; // J/(kg K)
inline constexpr double conductivity = 1.0;  // W/(m K)
inline const heat::ImpactSide side{density, specific_heat, conductivity};
/// E* of two bodies of the test material (Pa).
inline const double e_star = 1.0 / (2.0 * (1.0 - poisson * poisson) / youngs);
/// The same formula evaluated in another order: rounding only.
inline constexpr double formula_tolerance = 1e-12;

/// One material, no gravity, dt = 1e-5 s, contact onsets recorded.
inline dynamics::SceneSpec empty_scene() {
    dynamics::SceneSpec s;
    s.materials.push_back({"a", youngs, poisson, density, 0.9, 0.3, 0.0});
    s.gravity = Vec3::Zero();
    s.time_step = 1e-5;
    s.expected_speed = 1.0;
    s.record_contact_onsets = true;
    return s;
}

/// Heat of every material of `s` with `model` at 300 K, collision conduction on, a thermal step
/// every 1000 steps; the caller sets the grid of resolved particles.
inline HeatSpec collision_heat(const dynamics::SceneSpec& s, heat::HeatModel model) {
    HeatSpec h;
    h.enabled = true;
    h.step_multiple = 1000;
    h.solver.tolerance = 1e-12;
    h.collision_conduction = true;
    MaterialHeat m;
    m.enabled = true;
    m.conductivity = conductivity;
    m.specific_heat = specific_heat;
    m.initial_temperature = 300;
    m.model = model;
    h.materials.assign(s.materials.size(), m);
    return h;
}

} // namespace kiln::thermal::collision_test
