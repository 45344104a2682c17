#pragma once
// Runs a case from start to end with output, monitors, checkpoints and a summary.

#include "io/case_spec.hpp"

#include <filesystem>

namespace kiln::app {

/// Options of `kiln run`.
struct RunOptions {
    std::filesystem::path out_dir; ///< output folder
    std::filesystem::path restart; ///< checkpoint to continue from (empty = fresh start)
    bool quiet = false;            ///< no progress line, no summary on stdout
};

/// Runs the case; returns the process exit code (0 = completed). Input errors propagate as
/// InputError; a numerical failure is recorded in summary.json and returns 3; SIGINT or SIGTERM
/// stops the run after the current step, writes a checkpoint and returns 130.
int run_case(const io::CaseSpec& spec, const RunOptions& opt);

/// Builds the case's mechanical system and, with [heat], its thermal system without running a
/// step, so `kiln check` refuses what `kiln run` refuses at start-up (e.g. heat set-ups not
/// supported yet). Throws InputError prefixed by the case file.
void check_setup(const io::CaseSpec& spec);

} // namespace kiln::app
