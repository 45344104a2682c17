#include "io/monitors.hpp"

#include "core/error.hpp"
#include "io/case_spec.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <fstream>
#include <limits>
#include <utility>

namespace kiln::io {

namespace {

/// Monitors in the order of monitor_names().
enum class Monitor {
    time,
    step,
    kinetic_energy,
    rotational_energy,
    potential_energy,
    elastic_energy,
    total_energy,
    contacts,
    wall_contacts,
    coordination,
    max_overlap_ratio,
    max_velocity,
    mean_height,
    max_height,
    neighbour_builds,
    mean_temperature,
    min_temperature,
    max_temperature,
    thermal_energy,
    external_heat,
    count
};

/// Index of `name` in monitor_names(); throws InputError when it is not there.
int monitor_index(const std::string& name) {
    const auto& all = monitor_names();
    const auto it = std::find(all.begin(), all.end(), name);
    if (it == all.end()) {
        throw InputError(
            fmt::format("unknown monitor '{}'; allowed: {}", name, fmt::join(all, ", ")));
    }
    return static_cast<int>(it - all.begin());
}

/// The group of a group monitor ("mean_temperature:NAME" -> "NAME"), or "" for any other name.
std::string group_of(const std::string& name) {
    return name.starts_with(group_temperature_prefix)
               ? name.substr(std::string_view(group_temperature_prefix).size())
               : std::string();
}

/// Heights of the particles along the direction opposing gravity (m).
struct Heights {
    double mean = 0; ///< mean height (m), NaN without particles
    double max = 0;  ///< largest height (m), NaN without particles
};

/// Evaluates monitors of one System state; sums over particles are computed once and shared.
class Sampler {
  public:
    explicit Sampler(const dynamics::System& sys, const thermal::ThermalSystem* heat = nullptr)
        : sys_(sys), heat_(heat) {}

    /// Value of monitor `m` (SI units).
    double value(Monitor m) {
        const auto& c = sys_.counters();
        switch (m) {
        case Monitor::time:
            return sys_.time();
        case Monitor::step:
            return static_cast<double>(sys_.step_count());
        case Monitor::kinetic_energy:
            return energies().kinetic;
        case Monitor::rotational_energy:
            return energies().rotational;
        case Monitor::potential_energy:
            return energies().potential;
        case Monitor::elastic_energy:
            return energies().elastic;
        case Monitor::total_energy:
            return energies().total();
        case Monitor::contacts:
            return static_cast<double>(c.particle_contacts);
        case Monitor::wall_contacts:
            return static_cast<double>(c.wall_contacts);
        case Monitor::coordination:
            return coordination();
        case Monitor::max_overlap_ratio:
            return c.max_overlap_ratio;
        case Monitor::max_velocity:
            return max_velocity();
        case Monitor::mean_height:
            return heights().mean;
        case Monitor::max_height:
            return heights().max;
        case Monitor::neighbour_builds:
            return static_cast<double>(sys_.neighbour_builds());
        case Monitor::mean_temperature:
        case Monitor::min_temperature:
        case Monitor::max_temperature:
        case Monitor::thermal_energy:
        case Monitor::external_heat:
            return heat_value(m);
        case Monitor::count:
            break;
        }
        KILN_ASSERT(false);
        return std::numeric_limits<double>::quiet_NaN();
    }

    /// Heat-capacity-weighted mean temperature (K) of the particles of shape template `group`
    /// ("sphere": the spheres); NaN without heat or without heated particles of that group.
    [[nodiscard]] double group_mean_temperature(const std::string& group) const {
        const double nan = std::numeric_limits<double>::quiet_NaN();
        if (heat_ == nullptr) {
            return nan;
        }
        int shape = -1;
        if (group != "sphere") {
            const auto& shapes = sys_.spec().shapes;
            const auto it = std::find_if(shapes.begin(), shapes.end(),
                                         [&](const auto& t) { return t.name == group; });
            if (it == shapes.end()) {
                return nan;
            }
            shape = static_cast<int>(it - shapes.begin());
        }
        const ParticleStore& p = sys_.particles();
        double c_sum = 0.0;
        double ct_sum = 0.0;
        for (std::size_t i = 0; i < p.size(); ++i) {
            if (std::max(p.shape[i], -1) != shape) {
                continue;
            }
            const double c = heat_->heat_capacity(sys_, i);
            if (c > 0.0) {
                c_sum += c;
                ct_sum += c * heat_->mean_temperature(sys_, i);
            }
        }
        return c_sum > 0.0 ? ct_sum / c_sum : nan;
    }

    /// Value of the monitor called `name` (standard or group).
    double value(const std::string& name) {
        const std::string group = group_of(name);
        return group.empty() ? value(static_cast<Monitor>(monitor_index(name)))
                             : group_mean_temperature(group);
    }

  private:
    /// Heat monitors: capacity-weighted mean, lowest and highest cell temperature (K), stored
    /// heat sum C T (J), heat from outside so far (J); NaN in a run without heat.
    [[nodiscard]] double heat_value(Monitor m) const {
        if (heat_ == nullptr) {
            return std::numeric_limits<double>::quiet_NaN();
        }
        switch (m) {
        case Monitor::mean_temperature:
            return heat_->thermal_energy() / heat_->heat_capacity();
        case Monitor::min_temperature:
            return heat_->temperature_range().first;
        case Monitor::max_temperature:
            return heat_->temperature_range().second;
        case Monitor::thermal_energy:
            return heat_->thermal_energy();
        default:
            return heat_->external_heat();
        }
    }

    const dynamics::Energies& energies() {
        if (!have_energies_) {
            energies_ = sys_.energies();
            have_energies_ = true;
        }
        return energies_;
    }

    /// 2 * particle contacts / particles (-); 0 without particles.
    [[nodiscard]] double coordination() const {
        const std::size_t n = sys_.particles().size();
        return n == 0 ? 0.0
                      : 2.0 * static_cast<double>(sys_.counters().particle_contacts) /
                            static_cast<double>(n);
    }

    /// Largest speed |v| (m/s); 0 without particles.
    [[nodiscard]] double max_velocity() const {
        double v2 = 0;
        for (const Vec3& v : sys_.particles().v) {
            v2 = std::max(v2, v.squaredNorm());
        }
        return std::sqrt(v2);
    }

    const Heights& heights() {
        if (!have_heights_) {
            const Vec3& g = sys_.spec().gravity;
            const double g_norm = g.norm();
            const Vec3 up = g_norm > 0.0 ? Vec3(-g / g_norm) : Vec3::UnitZ();
            const auto& x = sys_.particles().x;
            Heights h;
            if (x.empty()) {
                h.mean = h.max = std::numeric_limits<double>::quiet_NaN();
            } else {
                double sum = 0;
                h.max = -std::numeric_limits<double>::infinity();
                for (const Vec3& p : x) {
                    const double z = p.dot(up);
                    sum += z;
                    h.max = std::max(h.max, z);
                }
                h.mean = sum / static_cast<double>(x.size());
            }
            heights_ = h;
            have_heights_ = true;
        }
        return heights_;
    }

    const dynamics::System& sys_;
    const thermal::ThermalSystem* heat_;
    bool have_energies_ = false;
    dynamics::Energies energies_;
    bool have_heights_ = false;
    Heights heights_;
};

} // namespace

const std::vector<std::string>& monitor_names() {
    static const std::vector<std::string> names = {"time",
                                                   "step",
                                                   "kinetic_energy",
                                                   "rotational_energy",
                                                   "potential_energy",
                                                   "elastic_energy",
                                                   "total_energy",
                                                   "contacts",
                                                   "wall_contacts",
                                                   "coordination",
                                                   "max_overlap_ratio",
                                                   "max_velocity",
                                                   "mean_height",
                                                   "max_height",
                                                   "neighbour_builds",
                                                   "mean_temperature",
                                                   "min_temperature",
                                                   "max_temperature",
                                                   "thermal_energy",
                                                   "external_heat"};
    KILN_ASSERT(names.size() == static_cast<std::size_t>(Monitor::count));
    return names;
}

double monitor_value(const dynamics::System& sys, const std::string& name) {
    Sampler s(sys);
    return s.value(name);
}

double monitor_value(const dynamics::System& sys, const thermal::ThermalSystem* heat,
                     const std::string& name) {
    Sampler s(sys, heat);
    return s.value(name);
}

void MonitorWriter::Closer::operator()(std::FILE* f) const {
    std::fclose(f);
}

MonitorWriter::MonitorWriter(std::filesystem::path csv, std::vector<std::string> names)
    : MonitorWriter(std::move(csv), std::move(names), nullptr) {
}

MonitorWriter::MonitorWriter(std::filesystem::path csv, std::vector<std::string> names,
                             const ResumePoint& at)
    : MonitorWriter(std::move(csv), std::move(names), &at) {
}

MonitorWriter::MonitorWriter(std::filesystem::path csv, std::vector<std::string> names,
                             const ResumePoint* at)
    : file_(std::move(csv)), names_(std::move(names)) {
    columns_.reserve(names_.size());
    for (const auto& n : names_) {
        columns_.push_back(group_of(n).empty() ? monitor_index(n) : -1); // -1: a group monitor
    }
    if (names_.empty()) {
        return;
    }
    const std::vector<std::string> kept =
        at != nullptr ? kept_rows(*at) : std::vector<std::string>{};
    out_.reset(std::fopen(file_.c_str(), "w"));
    if (!out_) {
        throw InputError(file_.string(), 0, "", "cannot create the monitor file");
    }
    std::string text = fmt::format("{}\n", fmt::join(names_, ","));
    for (const auto& row : kept) {
        text += row + "\n";
    }
    put(text);
    rows_ = static_cast<long>(kept.size());
}

std::vector<std::string> MonitorWriter::kept_rows(const ResumePoint& at) const {
    std::vector<std::string> kept;
    if (!std::filesystem::exists(file_)) {
        return kept;
    }
    std::ifstream in(file_);
    std::string line;
    if (!in || !std::getline(in, line)) {
        throw InputError(file_.string(), 1, "", "cannot read the monitor file to continue it");
    }
    const std::string header = fmt::format("{}", fmt::join(names_, ","));
    if (line != header) {
        throw InputError(file_.string(), 1, "",
                         fmt::format("columns '{}' differ from the case's monitors '{}'; "
                                     "restart into a fresh --out folder",
                                     line, header));
    }
    const auto col = [&](const char* name) {
        const auto it = std::find(names_.begin(), names_.end(), name);
        return it == names_.end() ? -1 : static_cast<int>(it - names_.begin());
    };
    const int time_col = col("time");
    const int step_col = col("step");
    // Rows are printed with 10 significant digits: compare times with that resolution.
    const double time_limit = at.time * (1.0 + 1e-9) + 1e-300;
    const long count_limit = at.row_every > 0 ? at.step / at.row_every + 1 : 0;
    while (std::getline(in, line)) {
        bool keep = false;
        if (time_col >= 0 || step_col >= 0) {
            std::size_t start = 0;
            const int c = time_col >= 0 ? time_col : step_col;
            for (int k = 0; k < c && start != std::string::npos; ++k) {
                start = line.find(',', start);
                start = start == std::string::npos ? start : start + 1;
            }
            const double v =
                start == std::string::npos ? HUGE_VAL : std::strtod(line.c_str() + start, nullptr);
            keep = time_col >= 0 ? v <= time_limit : v <= static_cast<double>(at.step);
        } else {
            keep = static_cast<long>(kept.size()) < count_limit;
        }
        if (!keep) {
            break;
        }
        kept.push_back(line);
    }
    return kept;
}

void MonitorWriter::write(const dynamics::System& sys) {
    Sampler s(sys, heat_);
    last_row_.resize(columns_.size());
    for (std::size_t k = 0; k < columns_.size(); ++k) {
        last_row_[k] = columns_[k] >= 0 ? s.value(static_cast<Monitor>(columns_[k]))
                                        : s.group_mean_temperature(group_of(names_[k]));
    }
    if (out_) {
        put(fmt::format("{:.10g}\n", fmt::join(last_row_, ",")));
        ++rows_;
    }
}

void MonitorWriter::put(const std::string& line) {
    if (std::fputs(line.c_str(), out_.get()) < 0 || std::fflush(out_.get()) != 0) {
        throw InputError(file_.string(), 0, "", "cannot write the monitor file");
    }
}

} // namespace kiln::io
