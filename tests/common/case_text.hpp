#pragma once
// Helpers of the case-reader tests: edit a case text in place and read the error it raises.

#include "core/error.hpp"
#include "io/case_reader.hpp"

#include <gtest/gtest.h>
#include <string>

namespace kiln::test {

/// `text` with its first occurrence of `from` replaced by `to` (a test failure if there is none).
inline std::string edited(std::string text, const std::string& from, const std::string& to) {
    const auto pos = text.find(from);
    EXPECT_NE(pos, std::string::npos) << from;
    return pos == std::string::npos ? text : text.replace(pos, from.size(), to);
}

/// The error message of reading `text` as the case file `path`, or "" when it reads fine.
inline std::string case_error(const std::string& text, const std::string& path = "case.toml") {
    try {
        io::read_case_text(text, path);
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

} // namespace kiln::test
