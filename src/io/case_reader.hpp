#pragma once
// Reads a TOML case file into a CaseSpec. Strict: unknown keys, wrong types, missing required
// values and out-of-range values are InputErrors reading "file:line: key: what is wrong, what is
// allowed". The key list with units and defaults is docs/case-format.md.

#include "io/case_spec.hpp"

#include <string>

namespace kiln::io {

/// Parses and validates the case file at `path`.
CaseSpec read_case_file(const std::string& path);

/// Parses and validates case text; `name` is used as the file name in messages.
CaseSpec read_case_text(const std::string& text, const std::string& name);

} // namespace kiln::io
