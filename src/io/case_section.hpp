#pragma once
// The bookkeeping reader of one TOML table of a case file (io/case_reader.cpp): allowed ranges,
// typed getters that record every key read and copy it with its default to the resolved case, and
// errors with file, line and full key. Internal to kiln_io.

#include "core/error.hpp"
#include "core/types.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <toml++/toml.h>
#include <vector>

namespace kiln::io::detail {

constexpr double inf = std::numeric_limits<double>::infinity();

/// Allowed interval of a number; prints itself as "lo < value <= hi" and the like.
struct Range {
    double lo = -inf;
    double hi = inf;
    bool lo_closed = false;
    bool hi_closed = false;

    [[nodiscard]] bool contains(double v) const {
        const bool above = lo_closed ? v >= lo : v > lo;
        const bool below = hi_closed ? v <= hi : v < hi;
        return std::isfinite(v) && above && below;
    }
    [[nodiscard]] std::string describe() const {
        const std::string l = lo_closed ? " <= " : " < ";
        const std::string h = hi_closed ? " <= " : " < ";
        if (std::isinf(lo) && std::isinf(hi)) {
            return "any finite number";
        }
        if (std::isinf(hi)) {
            return fmt::format("value{}{:g}", lo_closed ? " >= " : " > ", lo);
        }
        if (std::isinf(lo)) {
            return fmt::format("value{}{:g}", hi_closed ? " <= " : " < ", hi);
        }
        return fmt::format("{:g}{}value{}{:g}", lo, l, h, hi);
    }
};

/// "2500 kg/m^3", or just "0.5" for dimensionless values.
inline std::string with_unit(double v, std::string_view unit) {
    return unit == "-" ? fmt::format("{:g}", v) : fmt::format("{:g} {}", v, unit);
}

inline Range positive() {
    return {0.0, inf, false, false};
}
inline Range non_negative() {
    return {0.0, inf, true, false};
}

/// One TOML table of the case, read with bookkeeping: every key read is recorded (unknown keys are
/// errors in finish()) and copied, with defaults filled in, to the resolved table.
class Section {
  public:
    Section(std::string file, const toml::table& t, std::string path, toml::table& out)
        : file_(std::move(file)), t_(t), path_(std::move(path)), out_(out) {}

    [[noreturn]] void fail(std::string_view key, long line, const std::string& what) const {
        throw InputError(file_, line, full(key), what);
    }
    [[noreturn]] void fail_at(std::string_view key, const std::string& what) const {
        fail(key, line_of(key), what);
    }

    [[nodiscard]] bool has(std::string_view key) const { return t_.contains(key); }

    /// A real number; `def` empty means required.
    double real(std::string_view key, std::optional<double> def, Range r, std::string_view unit) {
        const toml::node* n = take(key);
        double v = 0.0;
        if (n == nullptr) {
            if (!def) {
                fail(key, table_line(),
                     fmt::format("missing required value ({}, {})", unit, r.describe()));
            }
            v = *def;
        } else {
            v = as_real(key, *n, unit);
        }
        if (!r.contains(v)) {
            fail_at(key, fmt::format("{} is out of range; allowed: {}", with_unit(v, unit),
                                     r.describe()));
        }
        out_.insert_or_assign(key, v);
        return v;
    }

    /// An integer; `def` empty means required.
    long integer(std::string_view key, std::optional<long> def, long lo, long hi) {
        const toml::node* n = take(key);
        long v = 0;
        if (n == nullptr) {
            if (!def) {
                fail(key, table_line(), fmt::format("missing required integer ({} to {})", lo, hi));
            }
            v = *def;
        } else {
            if (!n->is_integer()) {
                fail_at(key, fmt::format("expected an integer, got {}", type_name(*n)));
            }
            v = static_cast<long>(n->as_integer()->get());
        }
        if (v < lo || v > hi) {
            fail_at(key, fmt::format("{} is out of range; allowed: {} to {}", v, lo, hi));
        }
        out_.insert_or_assign(key, static_cast<std::int64_t>(v));
        return v;
    }

    bool boolean(std::string_view key, bool def) {
        const toml::node* n = take(key);
        bool v = def;
        if (n != nullptr) {
            if (!n->is_boolean()) {
                fail_at(key, fmt::format("expected true or false, got {}", type_name(*n)));
            }
            v = n->as_boolean()->get();
        }
        out_.insert_or_assign(key, v);
        return v;
    }

    /// A string; `allowed` empty means any non-empty string.
    std::string text(std::string_view key, std::optional<std::string> def,
                     const std::vector<std::string>& allowed = {}) {
        const toml::node* n = take(key);
        std::string v;
        if (n == nullptr) {
            if (!def) {
                fail(key, table_line(), "missing required string" + choices(allowed));
            }
            v = *def;
        } else {
            if (!n->is_string()) {
                fail_at(key,
                        fmt::format("expected a string, got {}", type_name(*n)) + choices(allowed));
            }
            v = n->as_string()->get();
        }
        if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), v) == allowed.end()) {
            fail_at(key, fmt::format("\"{}\" is not allowed", v) + choices(allowed));
        }
        if (allowed.empty() && v.empty()) {
            fail_at(key, "must not be empty");
        }
        out_.insert_or_assign(key, v);
        return v;
    }

    /// A vector of three real numbers.
    Vec3 vec3(std::string_view key, std::optional<Vec3> def, std::string_view unit,
              bool nonzero = false) {
        const toml::node* n = take(key);
        Vec3 v = Vec3::Zero();
        if (n == nullptr) {
            if (!def) {
                fail(key, table_line(),
                     fmt::format("missing required array of 3 numbers ({})", unit));
            }
            v = *def;
        } else {
            const toml::array* a = n->as_array();
            if (a == nullptr || a->size() != 3) {
                fail_at(key, fmt::format("expected an array of 3 numbers ({})", unit));
            }
            for (std::size_t k = 0; k < 3; ++k) {
                v[static_cast<Eigen::Index>(k)] = as_real(key, *a->get(k), unit);
            }
        }
        if (nonzero && v.norm() == 0.0) {
            fail_at(key, "must not be the zero vector");
        }
        out_.insert_or_assign(key, toml::array{v[0], v[1], v[2]});
        return v;
    }

    /// A list of strings.
    std::vector<std::string> strings(std::string_view key,
                                     std::optional<std::vector<std::string>> def,
                                     const std::vector<std::string>& allowed = {}) {
        const toml::node* n = take(key);
        std::vector<std::string> v;
        if (n == nullptr) {
            if (!def) {
                fail(key, table_line(), "missing required array of strings");
            }
            v = *def;
        } else {
            const toml::array* a = n->as_array();
            if (a == nullptr) {
                fail_at(key, "expected an array of strings" + choices(allowed));
            }
            for (const toml::node& e : *a) {
                if (!e.is_string()) {
                    fail_at(key, "expected an array of strings" + choices(allowed));
                }
                v.push_back(e.as_string()->get());
            }
        }
        toml::array arr;
        for (const auto& s : v) {
            if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), s) == allowed.end()) {
                fail_at(key, fmt::format("\"{}\" is not allowed", s) + choices(allowed));
            }
            arr.push_back(s);
        }
        out_.insert_or_assign(key, arr);
        return v;
    }

    /// A list of non-negative real numbers.
    std::vector<double> reals(std::string_view key, std::string_view unit, Range r) {
        const toml::node* n = take(key);
        if (n == nullptr || !n->is_array() || n->as_array()->empty()) {
            fail(key, n ? line_of(key) : table_line(),
                 fmt::format("expected a non-empty array of numbers ({})", unit));
        }
        std::vector<double> v;
        toml::array arr;
        for (const toml::node& e : *n->as_array()) {
            const double x = as_real(key, e, unit);
            if (!r.contains(x)) {
                fail_at(key, fmt::format("{} is out of range; allowed: {}", with_unit(x, unit),
                                         r.describe()));
            }
            v.push_back(x);
            arr.push_back(x);
        }
        out_.insert_or_assign(key, arr);
        return v;
    }

    /// A sub-table (inline or not); nullptr when absent.
    const toml::table* table(std::string_view key) {
        const toml::node* n = take(key);
        if (n == nullptr) {
            return nullptr;
        }
        if (!n->is_table()) {
            fail_at(key, fmt::format("expected a table, got {}", type_name(*n)));
        }
        return n->as_table();
    }

    /// Marks a key as read without reading it (handled by the caller).
    const toml::node* take(std::string_view key) {
        used_.insert(std::string(key));
        return t_.get(key);
    }

    /// Unknown keys are errors.
    void finish(const std::vector<std::string>& hint = {}) const {
        for (auto&& [k, v] : t_) {
            if (used_.count(std::string(k.str())) == 0) {
                std::string known;
                for (const auto& u : used_) {
                    known += (known.empty() ? "" : ", ") + u;
                }
                for (const auto& u : hint) {
                    known += (known.empty() ? "" : ", ") + u;
                }
                fail(k.str(), static_cast<long>(k.source().begin.line),
                     "unknown key; allowed here: " + known);
            }
        }
    }

    [[nodiscard]] long table_line() const { return static_cast<long>(t_.source().begin.line); }
    [[nodiscard]] long line_of(std::string_view key) const {
        const toml::node* n = t_.get(key);
        return n ? static_cast<long>(n->source().begin.line) : table_line();
    }
    [[nodiscard]] std::string full(std::string_view key) const {
        return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
    }
    [[nodiscard]] const std::string& file() const { return file_; }
    [[nodiscard]] toml::table& out() { return out_; }

  private:
    double as_real(std::string_view key, const toml::node& n, std::string_view unit) const {
        if (n.is_integer()) {
            return static_cast<double>(n.as_integer()->get());
        }
        if (n.is_floating_point()) {
            return n.as_floating_point()->get();
        }
        fail(key, static_cast<long>(n.source().begin.line),
             fmt::format("expected a number ({}), got {}", unit, type_name(n)));
    }
    static std::string type_name(const toml::node& n) {
        std::ostringstream os;
        os << n.type();
        return os.str();
    }
    static std::string choices(const std::vector<std::string>& allowed) {
        if (allowed.empty()) {
            return "";
        }
        std::string s = "; allowed: ";
        for (std::size_t k = 0; k < allowed.size(); ++k) {
            s += (k ? ", \"" : "\"") + allowed[k] + "\"";
        }
        return s;
    }

    std::string file_;
    const toml::table& t_;
    std::string path_;
    toml::table& out_;
    std::set<std::string> used_;
};

/// Iterates an array of tables ([[name]]); each element gets its own Section.
template <class F> void for_each_table(Section& root, std::string_view key, F&& f) {
    const toml::node* n = root.take(key);
    if (n == nullptr) {
        return;
    }
    const toml::array* a = n->as_array();
    if (a == nullptr || !a->is_array_of_tables()) {
        root.fail_at(key, fmt::format("expected one or more [[{}]] tables", key));
    }
    toml::array out_arr;
    for (std::size_t k = 0; k < a->size(); ++k) {
        toml::table out_t;
        Section s(root.file(), *a->get(k)->as_table(), fmt::format("{}[{}]", key, k), out_t);
        f(s, k);
        out_arr.push_back(std::move(out_t));
    }
    root.out().insert_or_assign(key, std::move(out_arr));
}

} // namespace kiln::io::detail
