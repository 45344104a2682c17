#pragma once
// Monitors: scalar quantities of a running System, evaluated by name and written as CSV rows.
// The allowed names are listed in OutputSpec (case_spec.hpp) and returned by monitor_names().

#include "dynamics/system.hpp"
#include "io/case_spec.hpp" // monitor_names()
#include "thermal/thermal_system.hpp"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace kiln::io {

/// Where a restarted run picks up its output: the checkpoint's simulated time (s) and step, and
/// the steps between monitor rows of the run being continued.
struct ResumePoint {
    double time = 0;    ///< simulated time of the checkpoint (s)
    long step = 0;      ///< step count of the checkpoint (-)
    long row_every = 0; ///< steps between monitor rows (-); 0 when monitors are off
};

/// Value of monitor `name` for `sys`, SI units: energies (J), heights (m, along -gravity, or z
/// when gravity is zero), max_velocity (m/s), counts and ratios (-), time (s). Heights are NaN for
/// an empty system. Throws InputError for a name not in monitor_names().
double monitor_value(const dynamics::System& sys, const std::string& name);

/// The same with the temperatures of `heat` (may be null): mean_temperature (K, heat-capacity
/// weighted), min_temperature and max_temperature (K, over all cells), thermal_energy (J, sum C T),
/// external_heat (J, from convection, flux and walls so far); NaN without heat.
double monitor_value(const dynamics::System& sys, const thermal::ThermalSystem* heat,
                     const std::string& name);

/// Writes one CSV column per monitor: a header line with the names, then one row per write() at
/// full precision (%.10g), flushed at once so a crash loses nothing already written.
class MonitorWriter {
  public:
    /// Creates (truncates) `csv` and writes the header; no file is created when `names` is empty.
    /// Throws InputError for an unknown name or when the file cannot be written.
    MonitorWriter(std::filesystem::path csv, std::vector<std::string> names);

    /// Continues an existing `csv` after a restart at `at`: keeps the header and the rows up to the
    /// checkpoint (by the `time` column, else the `step` column, else by counting rows of
    /// `at.row_every` steps from step 0), drops the rows the interrupted run wrote after it and
    /// appends from there. Starts a new file when `csv` does not exist. Throws InputError when
    /// the existing columns differ from `names` or the file cannot be read or written.
    MonitorWriter(std::filesystem::path csv, std::vector<std::string> names, const ResumePoint& at);

    /// Appends one row of the monitors of `sys`; throws InputError when the file cannot be written.
    void write(const dynamics::System& sys);

    /// Temperatures for the heat monitors (null: they are NaN); must outlive the writer's use.
    void set_heat(const thermal::ThermalSystem* heat) { heat_ = heat; }

    /// Values of the last row written, in column order (SI units, see monitor_value).
    [[nodiscard]] const std::vector<double>& last_row() const { return last_row_; }

    /// Data rows in the file (kept from an earlier run plus written by this one).
    [[nodiscard]] long rows() const { return rows_; }

    /// Column names, in order.
    [[nodiscard]] const std::vector<std::string>& names() const { return names_; }

  private:
    /// Shared constructor: `at` is null for a new file.
    MonitorWriter(std::filesystem::path csv, std::vector<std::string> names, const ResumePoint* at);

    /// Rows of the existing file to keep when continuing at `at` (see the resuming constructor).
    [[nodiscard]] std::vector<std::string> kept_rows(const ResumePoint& at) const;

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
    long rows_ = 0;
    const thermal::ThermalSystem* heat_ = nullptr;
};

} // namespace kiln::io
