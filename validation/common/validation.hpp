#pragma once
// Shared helpers of the validation checks: load a case folder, record measured values.

#include "io/case_reader.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace kiln::validation {

/// Reads the case file `name` (default case.toml) of this validation folder.
inline io::CaseSpec load_case(const std::string& name = "case.toml") {
    return io::read_case_file(std::string(KILN_CASE_DIR) + "/" + name);
}

/// Appends "quantity,measured,reference,tolerance,unit" to results.csv of this case and prints it.
/// `tolerance` is the allowed relative (or absolute, as the check states) deviation.
inline void record(const std::string& quantity, double measured, double reference, double tolerance,
                   const std::string& unit) {
    const std::filesystem::path file = std::filesystem::path(KILN_RESULT_DIR) / "results.csv";
    const bool fresh = !std::filesystem::exists(file);
    std::ofstream f(file, std::ios::app);
    if (fresh) {
        f << "quantity,measured,reference,tolerance,unit\n";
    }
    f.precision(10);
    f << quantity << ',' << measured << ',' << reference << ',' << tolerance << ',' << unit << '\n';
    std::printf("  %-40s measured %.6g, reference %.6g %s (tolerance %.3g)\n", quantity.c_str(),
                measured, reference, unit.c_str(), tolerance);
}

/// Removes results.csv of this case (call once at the start of a check).
inline void reset_results() {
    std::filesystem::create_directories(KILN_RESULT_DIR);
    std::filesystem::remove(std::filesystem::path(KILN_RESULT_DIR) / "results.csv");
}

} // namespace kiln::validation
