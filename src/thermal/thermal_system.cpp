// ThermalSystem set-up: model choice per material, refusals of unsupported scenes, heat
// templates and the particle records (see thermal_system_detail.hpp for the other files).

#include "thermal/thermal_system_detail.hpp"

#include "thermal/body_shapes.hpp"

#include "core/error.hpp"
#include "geometry/shape_metrics.hpp"
#include "heat/cartesian_grid.hpp"
#include "heat/convection.hpp"
#include "heat/shape.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <fmt/format.h>

namespace kiln::thermal {

using namespace detail;

namespace {

/// `material "M", shape "S", where` for the set-up's refusals and warnings (where may be empty).
std::string describe_kind(const dynamics::System& sys, int material, int shape,
                          const std::string& where) {
    std::string s = fmt::format("material \"{}\"",
                                sys.spec().materials[static_cast<std::size_t>(material)].name);
    if (shape >= 0) {
        s += fmt::format(", shape \"{}\"", sys.spec().shapes[static_cast<std::size_t>(shape)].name);
    }
    if (!where.empty()) {
        s += ", " + where;
    }
    return s;
}

} // namespace

ThermalSystem::ThermalSystem(const HeatSpec& spec, const dynamics::System& sys) : spec_(spec) {
    const auto& mats = sys.spec().materials;
    if (spec_.materials.size() != mats.size()) {
        throw InputError(fmt::format("heat: {} material heat entries for {} materials",
                                     spec_.materials.size(), mats.size()));
    }
    if (spec_.step_multiple < 1) {
        throw InputError("heat: step_multiple must be >= 1");
    }
    dt_ = static_cast<double>(spec_.step_multiple) * sys.dt();
    threads_ = sys.threads();
    for (const Material& m : mats) {
        material_names_.push_back(m.name);
        density_.push_back(m.density);
    }
    spec_.flow_direction = spec_.flow_direction.normalized();
    spec_.wall_temperature.resize(sys.spec().walls.size(), unset);
    spec_.mesh_wall_temperature.resize(sys.spec().mesh_walls.size(), unset);
    // Walls (analytic, then mesh) at a temperature conduct through their material.
    const auto check_wall = [&](double t, int material, const std::string& name) {
        const auto m = static_cast<std::size_t>(material);
        if (!std::isnan(t) && !spec_.materials[m].enabled) {
            throw InputError(fmt::format(
                "heat: wall \"{}\" has a temperature but its material \"{}\" has no heat "
                "properties (give the material a heat table with a conductivity)",
                name, mats[m].name));
        }
    };
    for (std::size_t w = 0; w < spec_.wall_temperature.size(); ++w) {
        check_wall(spec_.wall_temperature[w], sys.spec().walls[w].material,
                   sys.spec().walls[w].name);
    }
    for (std::size_t w = 0; w < spec_.mesh_wall_temperature.size(); ++w) {
        check_wall(spec_.mesh_wall_temperature[w], sys.spec().mesh_walls[w].material,
                   sys.spec().mesh_walls[w].name);
    }
    // Surface area of every shape template (lumped bodies, Biot numbers).
    for (const geometry::ShapeTemplate& t : sys.spec().shapes) {
        shape_area_.push_back(geometry::surface_area(t.shape).value);
    }
    // The particle with the largest V / A per material decides "auto" (the thickest particle of
    // the type; for spheres V / A = r / 3, so the largest radius).
    const ParticleStore& p = sys.particles();
    std::vector<std::pair<double, double>> thickest(mats.size(), {0.0, 0.0}); // (V, A)
    for (std::size_t i = 0; i < p.size(); ++i) {
        const std::pair<double, double> va = volume_area(sys, i);
        auto& best = thickest[static_cast<std::size_t>(p.material[i])];
        if (best.second == 0.0 || va.first / va.second > best.first / best.second) {
            best = va;
        }
    }
    choice_.resize(mats.size());
    for (std::size_t m = 0; m < mats.size(); ++m) {
        const MaterialHeat& mh = spec_.materials[m];
        MaterialChoice& c = choice_[m];
        if (!mh.enabled) {
            continue;
        }
        c.requested = mh.model;
        if (thickest[m].second > 0.0) {
            c.biot = heat::biot_number(spec_.heat_transfer_coefficient, thickest[m].first,
                                       thickest[m].second, mh.conductivity);
        }
        c.used = heat::choose_model(mh.model, c.biot, spec_.biot_threshold);
    }
    // Resolved bodies need a heat grid of their shape: checked here for the particles placed by
    // hand and those inserted later.
    std::vector<std::tuple<int, int, std::string>> kinds; // (material, shape, where)
    for (std::size_t k = 0; k < sys.spec().particles.size(); ++k) {
        const auto& ps = sys.spec().particles[k];
        kinds.emplace_back(ps.material, ps.shape, fmt::format("particle {}", k));
    }
    for (std::size_t k = 0; k < sys.spec().inserts.size(); ++k) {
        const auto& ins = sys.spec().inserts[k];
        kinds.emplace_back(ins.material, ins.shape, fmt::format("insert block {}", k));
    }
    std::vector<char> checked(sys.spec().shapes.size(), 0); // each template once
    for (const auto& [material, shape, where] : kinds) {
        const auto m = static_cast<std::size_t>(material);
        if (shape < 0 || choice_[m].used != heat::HeatModel::resolved ||
            checked[static_cast<std::size_t>(shape)] != 0) {
            continue;
        }
        checked[static_cast<std::size_t>(shape)] = 1;
        try {
            heat::validate(heat_shape(sys.spec().shapes[static_cast<std::size_t>(shape)]));
        } catch (const InputError& e) {
            throw InputError(fmt::format("{} (resolved {})", e.what(),
                                         describe_kind(sys, material, shape, where)));
        }
    }
    // Gas-gap conduction and neighbour radiation take every shape: bodies use the sphere
    // formulas with an equivalent radius (thermal_body_pairs.cpp, docs/theory/heat.md).
    if (spec_.collision_conduction) {
        // Impacts come from the System's onset records (sphere kernel, body element contacts and
        // every contact with a mesh wall).
        if (!sys.spec().record_contact_onsets) {
            throw InputError("heat: collision_conduction needs the System to record contact "
                             "onsets (SceneSpec::record_contact_onsets = true)");
        }
    }
    sync(sys);
    for (std::size_t m = 0; m < mats.size(); ++m) {
        MaterialChoice& c = choice_[m];
        bool spherical = false;
        bool cartesian = false;
        for (const auto& t : templates_) {
            if (t->material == static_cast<int>(m)) {
                c.cells = t->grid->size();
                (t->spherical ? spherical : cartesian) = true;
            }
        }
        if (c.used == heat::HeatModel::resolved) {
            if (!spherical && !cartesian) { // no particle yet: what spheres would get
                spherical = spec_.materials[m].grid == GridKind::spherical;
                cartesian = !spherical;
            }
            c.grid = spherical && cartesian ? "spherical+cartesian"
                     : spherical            ? "spherical"
                                            : "cartesian";
        }
    }
}

std::pair<double, double> ThermalSystem::volume_area(const dynamics::System& sys,
                                                     std::size_t i) const {
    const geometry::ShapeTemplate* t = shape_of(sys, i);
    if (t == nullptr) {
        const double r = sys.particles().radius[i];
        return {sphere_volume(r), sphere_area(r)};
    }
    return {t->volume, shape_area_[static_cast<std::size_t>(sys.particles().shape[i])]};
}

ThermalSystem::~ThermalSystem() = default;

int ThermalSystem::template_for(const dynamics::System& sys, std::size_t i) {
    const int material = sys.particles().material[i];
    const double radius = sys.particles().radius[i];
    const geometry::ShapeTemplate* body = shape_of(sys, i);
    const auto key = body != nullptr
                         ? std::make_tuple(material, sys.particles().shape[i], std::uint64_t{0})
                         : std::make_tuple(material, -1, std::bit_cast<std::uint64_t>(radius));
    const auto it = template_index_.find(key);
    if (it != template_index_.end()) {
        return it->second;
    }
    const MaterialHeat& mh = spec_.materials[static_cast<std::size_t>(material)];
    auto t = std::make_unique<Template>();
    t->material = material;
    t->radius = radius;
    // Bodies always get the Cartesian grid of their shape (the spherical grid is for spheres).
    t->spherical = body == nullptr && mh.grid == GridKind::spherical;
    t->res = mh.spherical;
    if (t->spherical) {
        t->grid =
            std::make_shared<const heat::ThermalGrid>(heat::make_spherical_grid(radius, t->res));
    } else {
        heat::CartesianResolution cr;
        cr.cells_across = mh.cells_across;
        const heat::Shape shape =
            body != nullptr ? heat_shape(*body) : heat::Shape{heat::Sphere{radius}};
        t->grid = std::make_shared<const heat::ThermalGrid>(heat::make_cartesian_grid(shape, cr));
    }
    // Spheres: the stagnation distribution for the world axes goes into the template matrix
    // exactly; a sphere whose grid has turned (sphere_rotation) gets the difference to the
    // distribution of its own orientation lagged (prepare_surface), which vanishes while it has
    // not turned. Bodies turn: their matrix keeps the uniform mean h, and h f(theta) of the
    // body's current orientation enters as the lagged correction of convection.hpp.
    if (spec_.heat_transfer_coefficient > 0.0 && spec_.stagnation && body != nullptr) {
        t->h_face = {spec_.heat_transfer_coefficient};
        t->turning_stagnation = true;
    } else if (spec_.heat_transfer_coefficient > 0.0 && spec_.stagnation) {
        t->h_face = heat::stagnation_distribution(*t->grid, -spec_.flow_direction,
                                                  spec_.heat_transfer_coefficient);
        t->sphere_stagnation = true;
    } else if (spec_.heat_transfer_coefficient > 0.0) {
        t->h_face = {spec_.heat_transfer_coefficient};
    }
    t->props.conductivity = mh.conductivity;
    t->props.heat_capacity = mh.specific_heat;
    // Bodies: the density their mass uses (with a template's density correction), so C = m c_p.
    t->props.density = density_.at(static_cast<std::size_t>(material)) *
                       (body != nullptr ? body->density_factor() : 1.0);
    t->solver = spec_.solver;
    t->base_dt = dt_;
    const heat::ResolvedOperator& first = operator_for(*t, 1, 0);
    t->capacity = first.cell_capacity();
    t->total_capacity = first.total_capacity();
    // rho c_p h^3: capacity / volume fraction of any cell (the fraction is volume / h^3).
    const auto c0 = static_cast<std::size_t>(t->grid->centre_cell);
    t->full_cell_capacity = t->spherical ? 0.0 : t->capacity[c0] / t->grid->volume_fraction[c0];
    templates_.push_back(std::move(t));
    const int index = static_cast<int>(templates_.size()) - 1;
    template_index_[key] = index;
    return index;
}

heat::ResolvedOperator& ThermalSystem::operator_for(Template& t, int substeps, int thread) {
    auto& op = t.ops[{substeps, thread}];
    if (!op) {
        op = std::make_unique<heat::ResolvedOperator>(
            t.grid, t.props, t.base_dt / static_cast<double>(substeps), t.h_face, t.solver);
    }
    return *op;
}

void ThermalSystem::sync(const dynamics::System& sys) {
    const ParticleStore& p = sys.particles();
    std::vector<std::pair<std::int64_t, std::size_t>> fresh;
    for (std::size_t i = 0; i < p.size(); ++i) {
        const auto id = static_cast<std::size_t>(p.id[i]);
        if (id >= by_id_.size() || by_id_[id].material < 0) {
            fresh.emplace_back(p.id[i], i);
        }
    }
    if (fresh.empty()) {
        return;
    }
    std::sort(fresh.begin(), fresh.end());
    by_id_.resize(
        std::max<std::size_t>(by_id_.size(), static_cast<std::size_t>(fresh.back().first) + 1));
    radius_.resize(by_id_.size(), 0.0);
    for (const auto& [id, i] : fresh) {
        const int m = p.material[i];
        const MaterialHeat& mh = spec_.materials[static_cast<std::size_t>(m)];
        Record r;
        r.material = m;
        radius_[static_cast<std::size_t>(id)] = p.radius[i];
        double t0 = mh.initial_temperature;
        if (static_cast<std::size_t>(id) < spec_.particle_temperature.size() &&
            !std::isnan(spec_.particle_temperature[static_cast<std::size_t>(id)])) {
            t0 = spec_.particle_temperature[static_cast<std::size_t>(id)];
        }
        const heat::HeatModel used = choice_[static_cast<std::size_t>(m)].used;
        if (used == heat::HeatModel::lumped) {
            r.slot = static_cast<int>(lumped_.size());
            lumped_.push_back(t0);
            // rho c_p V and A of the sphere, or of the body's template (its mass density, with a
            // template's density correction, so C = m c_p).
            const auto [volume, area] = volume_area(sys, i);
            const geometry::ShapeTemplate* body = shape_of(sys, i);
            lumped_capacity_.push_back(density_[static_cast<std::size_t>(m)] *
                                       (body != nullptr ? body->density_factor() : 1.0) *
                                       mh.specific_heat * volume);
            lumped_area_.push_back(area);
            lumped_emissivity_.push_back(mh.emissivity);
            lumped_rate_.push_back(0.0);
        } else if (used == heat::HeatModel::resolved) {
            r.templ = template_for(sys, i);
            const heat::ThermalGrid& g = *templates_[static_cast<std::size_t>(r.templ)]->grid;
            r.slot = pool_.add(g.size(), t0);
            if (keeps_previous()) {
                previous_.add(g.size(), t0); // the same slot: both pools grow together
            }
            pool_template_.push_back(r.templ);
            pool_q_.push_back(Quat::Identity());
            turning_spheres_ = turning_spheres_ || (spec_.sphere_rotation && p.shape[i] < 0);
            face_offset_.push_back(face_rate_.size());
            face_rate_.resize(face_rate_.size() + g.boundary.size(), 0.0);
            stag_h_.resize(face_rate_.size(), 0.0);
            conv_rate_.resize(face_rate_.size(), 0.0);
            rad_rate_.resize(face_rate_.size(), 0.0);
        }
        by_id_[static_cast<std::size_t>(id)] = r;
        slot_ids_.push_back(id);
    }
}

double ThermalSystem::capacity_of(const Record& r) const {
    if (r.slot < 0) {
        return 0.0;
    }
    if (r.templ < 0) {
        return lumped_capacity_[static_cast<std::size_t>(r.slot)];
    }
    return templates_[static_cast<std::size_t>(r.templ)]->total_capacity;
}
} // namespace kiln::thermal
