#include "io/summary.hpp"

#include "io/files.hpp"

#include <cmath>
#include <fmt/format.h>

namespace kiln::io {

std::string json_string(const std::string& text) {
    std::string out;
    out.reserve(text.size() + 2);
    out += '"';
    for (const char ch : text) {
        switch (ch) {
        case '"':
            out += "\\\"";
            break;
        case '\\':
            out += "\\\\";
            break;
        case '\b':
            out += "\\b";
            break;
        case '\f':
            out += "\\f";
            break;
        case '\n':
            out += "\\n";
            break;
        case '\r':
            out += "\\r";
            break;
        case '\t':
            out += "\\t";
            break;
        default:
            if (static_cast<unsigned char>(ch) < 0x20) {
                const auto code = static_cast<unsigned>(static_cast<unsigned char>(ch));
                out += fmt::format("\\u{:04x}", code);
            } else {
                out += ch;
            }
        }
    }
    out += '"';
    return out;
}

std::string json_number(double x) {
    return std::isfinite(x) ? fmt::format("{}", x) : std::string("null");
}

void write_summary_json(const std::filesystem::path& file, const RunSummary& s) {
    std::string j = "{\n";
    const auto field = [&j](const char* key, const std::string& value) {
        j += fmt::format("  \"{}\": {},\n", key, value);
    };
    field("case_name", json_string(s.case_name));
    field("case_file", json_string(s.case_file));
    field("kiln_version", json_string(s.kiln_version));
    field("git_hash", json_string(s.git_hash));
    field("status", json_string(s.status));
    field("steps", fmt::format("{}", s.steps));
    field("particles", fmt::format("{}", s.particles));
    field("simulated_time", json_number(s.simulated_time));
    field("wall_seconds", json_number(s.wall_seconds));
    field("particle_steps_per_second", json_number(s.particle_steps_per_second));
    field("heat_wall_seconds", json_number(s.heat_wall_seconds));
    field("neighbour_builds", fmt::format("{}", s.neighbour_builds));
    field("bodies", fmt::format("{}", s.bodies));
    field("narrow_phase_calls", fmt::format("{}", s.narrow_phase_calls));
    field("narrow_phase_fallbacks", fmt::format("{}", s.narrow_phase_fallbacks));
    field("narrow_phase_failures", fmt::format("{}", s.narrow_phase_failures));
    field("time_step", json_number(s.time_step));
    field("rayleigh_time_step", json_number(s.rayleigh_time_step));
    field("contact_time", json_number(s.contact_time));

    j += "  \"warnings\": [";
    for (std::size_t k = 0; k < s.warnings.size(); ++k) {
        j += fmt::format("{}\n    {}", k == 0 ? "" : ",", json_string(s.warnings[k]));
    }
    j += s.warnings.empty() ? "],\n" : "\n  ],\n";

    for (const auto& [key, value] : s.sections) {
        field(key.c_str(), value);
    }
    j += "  \"final_monitors\": {";
    for (std::size_t k = 0; k < s.final_monitors.size(); ++k) {
        const auto& [name, value] = s.final_monitors[k];
        const char* sep = k == 0 ? "" : ",";
        j += fmt::format("{}\n    {}: {}", sep, json_string(name), json_number(value));
    }
    j += s.final_monitors.empty() ? "}\n" : "\n  }\n";
    j += "}\n";
    write_text_file(file, j);
}

} // namespace kiln::io
