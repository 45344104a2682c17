#pragma once
// Checkpoints: the full evolving state of a System in a binary file, read back bit for bit.

#include "dynamics/system.hpp"
#include "thermal/thermal_system.hpp"

#include <filesystem>
#include <optional>

namespace kiln::io {

/// Writes `s` to `file` atomically (temporary file, then rename).
void write_checkpoint(const std::filesystem::path& file, const dynamics::SystemState& s);

/// Reads a checkpoint written by write_checkpoint; throws InputError on a damaged or foreign file.
dynamics::SystemState read_checkpoint(const std::filesystem::path& file);

/// Writes `s` and, when `heat` is not null, the temperatures after it (a tagged section that
/// readers of the mechanical state skip), atomically.
void write_checkpoint(const std::filesystem::path& file, const dynamics::SystemState& s,
                      const thermal::ThermalState* heat);

/// The temperatures of a checkpoint, or nothing when it has none (a run without heat). Throws
/// InputError on a damaged or foreign file.
std::optional<thermal::ThermalState> read_checkpoint_heat(const std::filesystem::path& file);

} // namespace kiln::io
