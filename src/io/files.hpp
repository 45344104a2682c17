#pragma once
// Small file helpers; io is the only module that touches the file system.

#include <filesystem>
#include <string>

namespace kiln::io {

/// Creates `dir` (and parents) if missing; throws InputError when it cannot.
void make_directory(const std::filesystem::path& dir);

/// Writes `text` to `file`, replacing it; throws InputError on failure.
void write_text_file(const std::filesystem::path& file, const std::string& text);

} // namespace kiln::io
