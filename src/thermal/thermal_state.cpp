// ThermalSystem: what leaves it: particle temperatures and fields for output, energy sums, the
// start-up description and summary.json, and the checkpoint state.

#include "thermal/thermal_system_detail.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>

namespace kiln::thermal {

using namespace detail;

void ThermalSystem::particle_temperatures(const dynamics::System& sys,
                                          ParticleTemperatures& out) const {
    const ParticleStore& p = sys.particles();
    const double nan = std::numeric_limits<double>::quiet_NaN();
    out.mean.assign(p.size(), nan);
    out.core.assign(p.size(), nan);
    out.surface.assign(p.size(), nan);
    std::vector<double> ts;
    for (std::size_t i = 0; i < p.size(); ++i) {
        const auto id = static_cast<std::size_t>(p.id[i]);
        if (id >= by_id_.size() || by_id_[id].slot < 0) {
            continue;
        }
        const Record& r = by_id_[id];
        if (r.templ < 0) {
            const double t = lumped_[static_cast<std::size_t>(r.slot)];
            out.mean[i] = out.core[i] = out.surface[i] = t;
            continue;
        }
        const Template& t = *templates_[static_cast<std::size_t>(r.templ)];
        const std::span<const double> f = pool_.field(r.slot);
        out.mean[i] = heat::mean_temperature(*t.grid, f);
        out.core[i] = f[static_cast<std::size_t>(t.grid->centre_cell)];
        heat::BoundaryLoad load;
        load.ambient = spec_.ambient_temperature;
        load.flux = spec_.flux;
        ts.resize(t.grid->boundary.size());
        t.ops.begin()->second->surface_temperature(f, load, ts); // any operator: same G_b
        double sum = 0.0;
        double area = 0.0;
        for (std::size_t b = 0; b < ts.size(); ++b) {
            sum += t.grid->boundary[b].area * ts[b];
            area += t.grid->boundary[b].area;
        }
        out.surface[i] = sum / area;
    }
}

double ThermalSystem::mean_temperature(const dynamics::System& sys, std::size_t i) const {
    const auto id = static_cast<std::size_t>(sys.particles().id[i]);
    if (id >= by_id_.size() || by_id_[id].slot < 0) {
        return std::numeric_limits<double>::quiet_NaN();
    }
    const Record& r = by_id_[id];
    if (r.templ < 0) {
        return lumped_[static_cast<std::size_t>(r.slot)];
    }
    return heat::mean_temperature(*templates_[static_cast<std::size_t>(r.templ)]->grid,
                                  pool_.field(r.slot));
}

double ThermalSystem::heat_capacity(const dynamics::System& sys, std::size_t i) const {
    const auto id = static_cast<std::size_t>(sys.particles().id[i]);
    return id < by_id_.size() ? capacity_of(by_id_[id]) : 0.0;
}

double ThermalSystem::thermal_energy() const {
    double e = 0.0;
    for (std::size_t k = 0; k < lumped_.size(); ++k) {
        e += lumped_capacity_[k] * lumped_[k];
    }
    for (int slot = 0; slot < pool_.size(); ++slot) {
        const Template& t =
            *templates_[static_cast<std::size_t>(pool_template_[static_cast<std::size_t>(slot)])];
        e += heat::stored_heat(t.capacity, pool_.field(slot));
    }
    return e;
}

double ThermalSystem::heat_capacity() const {
    double c = 0.0;
    for (const double x : lumped_capacity_) {
        c += x;
    }
    for (int slot = 0; slot < pool_.size(); ++slot) {
        c += templates_[static_cast<std::size_t>(pool_template_[static_cast<std::size_t>(slot)])]
                 ->total_capacity;
    }
    return c;
}

std::pair<double, double> ThermalSystem::temperature_range() const {
    double lo = std::numeric_limits<double>::infinity();
    double hi = -lo;
    for (const double t : lumped_) {
        lo = std::min(lo, t);
        hi = std::max(hi, t);
    }
    for (const double t : pool_.values()) {
        lo = std::min(lo, t);
        hi = std::max(hi, t);
    }
    return {lo, hi};
}

std::vector<FieldView> ThermalSystem::fields(const dynamics::System& sys,
                                             const std::vector<long>& ids) const {
    const ParticleStore& p = sys.particles();
    std::vector<FieldView> out;
    for (std::size_t i = 0; i < p.size(); ++i) {
        const auto id = static_cast<std::size_t>(p.id[i]);
        if (id >= by_id_.size() || by_id_[id].templ < 0) {
            continue;
        }
        if (!ids.empty() && std::find(ids.begin(), ids.end(), p.id[i]) == ids.end()) {
            continue;
        }
        const Record& r = by_id_[id];
        const Template& t = *templates_[static_cast<std::size_t>(r.templ)];
        FieldView v;
        v.id = p.id[i];
        v.grid = t.grid.get();
        v.spherical = t.spherical ? &t.res : nullptr;
        v.field = pool_.field(r.slot);
        v.position = p.x[i];
        v.q = grid_orientation(p, i, r);
        out.push_back(v);
    }
    std::sort(out.begin(), out.end(),
              [](const FieldView& a, const FieldView& b) { return a.id < b.id; });
    return out;
}

ThermalState ThermalSystem::save_state() const {
    ThermalState s;
    s.fields = pool_.values();
    if (keeps_previous()) {
        s.previous_fields = previous_.values();
    }
    s.lumped = lumped_;
    s.ids = slot_ids_;
    s.external_heat = external_heat_;
    s.counters = counters_;
    s.onsets = onsets_;
    if (turning_spheres_) {
        for (const Quat& q : pool_q_) {
            s.orientations.insert(s.orientations.end(), {q.w(), q.x(), q.y(), q.z()});
        }
    }
    return s;
}

void ThermalSystem::restore_state(const ThermalState& s, const dynamics::System& sys) {
    sync(sys);
    if (s.ids != slot_ids_ || s.fields.size() != pool_.values().size() ||
        s.lumped.size() != lumped_.size()) {
        throw InputError("heat: the checkpoint's temperatures do not fit this case (different "
                         "particles or heat models); restart with the case that wrote it");
    }
    pool_.assign(s.fields);
    if (keeps_previous()) {
        // A checkpoint without them (written with the last-field guess, or before they were
        // kept) restarts the extrapolation: the first guess is the field itself.
        const std::vector<double>& prev = s.previous_fields.empty() ? s.fields : s.previous_fields;
        if (prev.size() != s.fields.size()) {
            throw InputError("heat: the checkpoint's previous temperatures do not fit its "
                             "temperatures; the file is damaged");
        }
        previous_.assign(prev);
    }
    lumped_ = s.lumped;
    external_heat_ = s.external_heat;
    counters_ = s.counters;
    onsets_ = s.onsets;
    if (!s.orientations.empty() && s.orientations.size() != 4 * pool_q_.size()) {
        throw InputError("heat: the checkpoint's grid orientations do not fit this case; restart "
                         "with the case that wrote it");
    }
    for (std::size_t k = 0; k < pool_q_.size(); ++k) {
        pool_q_[k] = s.orientations.empty()
                         ? Quat::Identity()
                         : Quat(s.orientations[4 * k], s.orientations[4 * k + 1],
                                s.orientations[4 * k + 2], s.orientations[4 * k + 3]);
    }
}

void ThermalSystem::set_temperature(std::int64_t id, double t) {
    const Record& r = by_id_.at(static_cast<std::size_t>(id));
    if (r.slot < 0) {
        throw InputError(fmt::format("heat: particle {} has no heat model", id));
    }
    if (r.templ < 0) {
        lumped_[static_cast<std::size_t>(r.slot)] = t;
        return;
    }
    const std::span<double> f = pool_.field(r.slot);
    std::fill(f.begin(), f.end(), t);
    if (keeps_previous()) {
        // No extrapolation across a temperature set from outside.
        const std::span<double> prev = previous_.field(r.slot);
        std::fill(prev.begin(), prev.end(), t);
    }
}

std::vector<std::string> ThermalSystem::describe() const {
    std::vector<std::string> lines;
    for (std::size_t m = 0; m < choice_.size(); ++m) {
        const MaterialChoice& c = choice_[m];
        if (!spec_.materials[m].enabled) {
            continue;
        }
        std::string s =
            fmt::format("material {}: {} (requested {}, Bi = {:.3g}", material_names_[m],
                        heat::to_string(c.used), heat::to_string(c.requested), c.biot);
        if (c.requested == heat::HeatModel::automatic) {
            s += fmt::format(", threshold {:g}", spec_.biot_threshold);
        }
        s += ")";
        if (c.used == heat::HeatModel::resolved) {
            s += fmt::format(", {} grid of {} cells", c.grid, c.cells);
        }
        lines.push_back(s);
    }
    return lines;
}

std::string ThermalSystem::summary_json() const {
    const auto num = [](double x) {
        return std::isfinite(x) ? fmt::format("{}", x) : std::string("null");
    };
    std::string j = "{\n";
    j += fmt::format("    \"thermal_time_step\": {},\n", num(dt_));
    j += fmt::format("    \"step_multiple\": {},\n", spec_.step_multiple);
    j += fmt::format("    \"solver\": \"{}\",\n", heat::to_string(spec_.solver.kind));
    j += fmt::format("    \"tolerance\": {},\n", num(spec_.solver.tolerance));
    j += "    \"materials\": [";
    bool first = true;
    for (std::size_t m = 0; m < choice_.size(); ++m) {
        if (!spec_.materials[m].enabled) {
            continue;
        }
        const MaterialChoice& c = choice_[m];
        j += fmt::format("{}\n      {{\"name\": \"{}\", \"requested\": \"{}\", \"used\": \"{}\", "
                         "\"biot\": {}, \"grid\": \"{}\", \"cells\": {}}}",
                         first ? "" : ",", material_names_[m], heat::to_string(c.requested),
                         heat::to_string(c.used), num(c.biot), c.grid, c.cells);
        first = false;
    }
    j += first ? "],\n" : "\n    ],\n";
    const ThermalCounters& k = counters_;
    j += fmt::format("    \"thermal_steps\": {},\n", k.thermal_steps);
    j += fmt::format("    \"substeps\": {},\n", k.substeps);
    j += fmt::format("    \"max_substeps\": {},\n", k.max_substeps);
    j += fmt::format("    \"max_lag_ratio\": {},\n", num(k.max_lag_ratio));
    j += fmt::format("    \"solves\": {},\n", k.solves);
    j += fmt::format("    \"iterations\": {},\n", k.iterations);
    j += fmt::format("    \"mean_iterations\": {},\n",
                     num(k.solves > 0
                             ? static_cast<double>(k.iterations) / static_cast<double>(k.solves)
                             : 0.0));
    j += fmt::format("    \"max_iterations\": {},\n", k.max_iterations);
    j += fmt::format("    \"unconverged_solves\": {},\n", k.unconverged);
    j += fmt::format("    \"conducting_contacts\": {},\n", k.contacts);
    j += fmt::format("    \"gas_gap_pairs\": {},\n", gas_pairs_);
    j += fmt::format("    \"radiation_pairs\": {},\n", radiation_pairs_);
    j += fmt::format("    \"wall_gas_gaps\": {},\n", wall_gas_gaps_);
    j += fmt::format("    \"wall_radiation\": {},\n", wall_radiation_);
    j += fmt::format("    \"collisions\": {},\n", collisions_);
    j += fmt::format("    \"thermal_energy\": {},\n", num(thermal_energy()));
    j += fmt::format("    \"external_heat\": {}\n", num(external_heat_));
    j += "  }";
    return j;
}
} // namespace kiln::thermal
