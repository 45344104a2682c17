#pragma once
// Parsing of TOML text shared by the case and shape readers: the one place a syntax error becomes
// an InputError with file and line.

#include "core/error.hpp"

#include <string>
#include <toml++/toml.h>

namespace kiln::io {

/// Parses `text` (read from file `name`, used in messages); throws InputError at the line of a
/// syntax error.
inline toml::table parse_toml_text(const std::string& text, const std::string& name) {
    try {
        return toml::parse(text, name);
    } catch (const toml::parse_error& e) {
        throw InputError(name, static_cast<long>(e.source().begin.line), "",
                         std::string("TOML syntax error: ") + std::string(e.description()));
    }
}

} // namespace kiln::io
