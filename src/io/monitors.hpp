#pragma once
// Monitors: scalar quantities of a running System, evaluated by name and written as CSV rows.
// The allowed names are listed in OutputSpec (case_spec.hpp) and returned by monitor_names().

#include "dynamics/system.hpp"
#include "io/case_spec.hpp" // monitor_names()

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace kiln::io {

/// Value of monitor `name` for `sys`, SI units: energies (J), heights (m, along -gravity, or z
/// when gravity is zero), max_velocity (m/s), counts and ratios (-), time (s). Heights are NaN for
/// an empty system. Throws InputError for a name not in monitor_names().
double monitor_value(const dynamics::System& sys, const std::string& name);

/// Writes one CSV column per monitor: a header line with the names, then one row per write() at
/// full precision (%.10g), flushed at once so a crash loses nothing already written.
class MonitorWriter {
  public:
    /// Creates (truncates) `csv` and writes the header; no file is created when `names` is empty.
    /// Throws InputError for an unknown name or when the file cannot be written.
    MonitorWriter(std::filesystem::path csv, std::vector<std::string> names);

    /// Appends one row of the monitors of `sys`; throws InputError when the file cannot be written.
    void write(const dynamics::System& sys);

    /// Values of the last row written, in column order (SI units, see monitor_value).
    [[nodiscard]] const std::vector<double>& last_row() const { return last_row_; }

    /// Column names, in order.
    [[nodiscard]] const std::vector<std::string>& names() const { return names_; }

  private:
    /// Closes the CSV file.
    struct Closer {
        void operator()(std::FILE* f) const;
    };

    void put(const std::string& line);

    std::filesystem::path file_;
    std::vector<std::string> names_;
    std::vector<int> columns_; // monitor of each column, index into monitor_names()
    std::unique_ptr<std::FILE, Closer> out_;
    std::vector<double> last_row_;
};

} // namespace kiln::io
