#pragma once
// A whole case: the mechanical scene plus run control and output settings.

#include "dynamics/scene_spec.hpp"
#include "thermal/heat_spec.hpp"

#include <string>
#include <vector>

namespace kiln::io {

/// Which quantities the CSV monitor file records, one column each, in this order.
/// Allowed names: time, step, kinetic_energy, rotational_energy, potential_energy, elastic_energy,
/// total_energy, contacts, wall_contacts, coordination, max_overlap_ratio, max_velocity,
/// mean_height, max_height, neighbour_builds, and with heat: mean_temperature, min_temperature,
/// max_temperature, thermal_energy, external_heat.
struct OutputSpec {
    double vtk_interval = 0;           ///< simulated time between VTK particle files (s), 0 = none
    double monitor_interval = 0;       ///< simulated time between monitor rows (s)
    std::vector<std::string> monitors; ///< monitor columns
    double checkpoint_interval = 0;    ///< simulated time between checkpoints (s), 0 = none
    bool progress = true;              ///< progress line on stderr (only when it is a terminal)
};

/// Run control.
struct RunSpec {
    double end_time = 0; ///< simulated end time (s)
    std::string name;    ///< case name, for output and messages
};

/// The complete, validated case.
struct CaseSpec {
    dynamics::SceneSpec scene;
    OutputSpec output;
    RunSpec run;
    thermal::HeatSpec heat;    ///< heat coupling; heat.enabled is false without a [heat] section
    std::string source_file;   ///< path of the case file
    std::string resolved_toml; ///< the case with every default filled in, as TOML text
};

/// Names accepted in OutputSpec::monitors (besides the group monitors below).
const std::vector<std::string>& monitor_names();

/// Prefix of the group monitors: "mean_temperature:NAME" is the heat-capacity-weighted mean
/// temperature (K) of the particles of shape template NAME, or of the spheres for NAME "sphere".
inline constexpr const char* group_temperature_prefix = "mean_temperature:";

} // namespace kiln::io
