#pragma once
// Checkpoints: the full evolving state of a System in a binary file, read back bit for bit.

#include "dynamics/system.hpp"

#include <filesystem>

namespace kiln::io {

/// Writes `s` to `file` atomically (temporary file, then rename).
void write_checkpoint(const std::filesystem::path& file, const dynamics::SystemState& s);

/// Reads a checkpoint written by write_checkpoint; throws InputError on a damaged or foreign file.
dynamics::SystemState read_checkpoint(const std::filesystem::path& file);

} // namespace kiln::io
