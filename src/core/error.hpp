#pragma once
// Two kinds of checks (see STYLE.md): KILN_ASSERT for programmer errors, InputError for bad user
// input.

#include <stdexcept>
#include <string>

namespace kiln {

/// A user-input problem (case file, command line, data file). The message reads
/// "file:line: key: what is wrong, what is allowed" when a location is known.
class InputError : public std::runtime_error {
  public:
    /// Error without a source location.
    explicit InputError(const std::string& what) : std::runtime_error(what) {}
    /// Error located in a file; line 0 means "line unknown".
    InputError(const std::string& file, long line, const std::string& key, const std::string& what);
};

/// A numerical failure during a run (non-finite state, blow-up). Carries the step for diagnosis.
class RunError : public std::runtime_error {
  public:
    /// Error at mechanical step `step` (0-based).
    RunError(long step, const std::string& what);
};

[[noreturn]] void assert_fail(const char* expr, const char* file, int line);

} // namespace kiln

#ifdef NDEBUG
#define KILN_ASSERT(expr) ((void)0)
#else
/// Checks an internal invariant in debug builds; a failure is a bug in kiln, never a user error.
#define KILN_ASSERT(expr) ((expr) ? (void)0 : ::kiln::assert_fail(#expr, __FILE__, __LINE__))
#endif
