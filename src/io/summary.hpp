#pragma once
// summary.json: what a run did, how fast, and how it ended; written once at the end of every run.

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace kiln::io {

/// The record of one run, written as summary.json.
struct RunSummary {
    std::string case_name;                ///< case name from the case file
    std::string case_file;                ///< path of the case file
    std::string kiln_version;             ///< kiln's semantic version
    std::string git_hash;                 ///< git hash of the source tree kiln was built from
    long steps = 0;                       ///< mechanical steps taken by this run (-)
    long particles = 0;                   ///< particles at the end (-)
    double simulated_time = 0;            ///< simulated time at the end (s)
    double wall_seconds = 0;              ///< wall-clock time of the stepping loop (s)
    double particle_steps_per_second = 0; ///< steps * particles / wall_seconds (1/s)
    double heat_wall_seconds = 0;         ///< part of wall_seconds spent in thermal steps (s)
    long neighbour_builds = 0;            ///< neighbour-list builds (-)
    std::vector<std::string> warnings;    ///< set-up warnings
    std::vector<std::pair<std::string, double>> final_monitors; ///< monitors at the end (SI)
    std::string status;              ///< "completed" or "failed: <reason>"
    double time_step = 0;            ///< mechanical time step (s)
    double rayleigh_time_step = 0;   ///< smallest Rayleigh critical step (s)
    double contact_time = 0;         ///< shortest expected contact duration (s)
    long bodies = 0;                 ///< non-spherical particles at the end (-)
    long narrow_phase_calls = 0;     ///< superquadric narrow-phase queries (-)
    long narrow_phase_fallbacks = 0; ///< Newton did not converge, GJK/EPA answered (-)
    long narrow_phase_failures = 0;  ///< no method converged, contact skipped for a step (-)
    /// Further top-level objects: key and JSON text (e.g. "heat" from thermal::ThermalSystem).
    std::vector<std::pair<std::string, std::string>> sections;
};

/// Writes `s` to `file` as pretty-printed JSON (UTF-8, strings escaped, non-finite numbers as
/// null); throws InputError when the file cannot be written.
void write_summary_json(const std::filesystem::path& file, const RunSummary& s);

/// `text` as a quoted JSON string literal with ", \ and control characters escaped.
std::string json_string(const std::string& text);

/// `x` as a JSON number at full precision (shortest round-trip form), or null when not finite.
std::string json_number(double x);

} // namespace kiln::io
