#include "core/error.hpp"

#include <cstdio>
#include <cstdlib>
#include <fmt/format.h>

namespace kiln {

namespace {
std::string located(const std::string& file, long line, const std::string& key,
                    const std::string& what) {
    std::string where = file;
    if (!file.empty() && line > 0) {
        where += fmt::format(":{}", line);
    }
    if (!key.empty()) {
        where += (where.empty() ? "" : ": ") + key;
    }
    return where + (where.empty() ? "" : ": ") + what;
}
} // namespace

InputError::InputError(const std::string& file, long line, const std::string& key,
                       const std::string& what)
    : std::runtime_error(located(file, line, key, what)) {
}

RunError::RunError(long step, const std::string& what)
    : std::runtime_error(fmt::format("step {}: {}", step, what)) {
}

void assert_fail(const char* expr, const char* file, int line) {
    std::fprintf(stderr, "kiln internal error: assertion '%s' failed at %s:%d\n", expr, file, line);
    std::abort();
}

} // namespace kiln
