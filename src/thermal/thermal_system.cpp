#include "thermal/thermal_system.hpp"

#include "thermal/body_shapes.hpp"

#include "core/error.hpp"
#include "geometry/shape_metrics.hpp"
#include "heat/cartesian_grid.hpp"
#include "heat/collision_conduction.hpp"
#include "heat/contact_conduction.hpp"
#include "heat/convection.hpp"
#include "heat/gas_conduction.hpp"
#include "heat/radiation.hpp"
#include "heat/shape.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <fmt/format.h>
#include <numbers>
#include <unordered_map>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace kiln::thermal {

namespace {

/// Sub-steps are chosen so that dt_sub * (largest contact conductance / heat capacity) stays below
/// this bound. The lagged exchange is an explicit Euler step of the contact network; at 1 a pair
/// of lumped particles would equalise in one step, at 0.5 the difference halves per step and can
/// never change sign (no oscillation, no undershoot below the partner temperatures).
constexpr double lag_safety = 0.5;

double sphere_volume(double r) {
    return 4.0 / 3.0 * std::numbers::pi * r * r * r;
}

double sphere_area(double r) {
    return 4.0 * std::numbers::pi * r * r;
}

/// Template of particle index i, nullptr for a sphere.
const geometry::ShapeTemplate* shape_of(const dynamics::System& sys, std::size_t i) {
    const int s = sys.particles().shape[i];
    return s >= 0 ? &sys.spec().shapes[static_cast<std::size_t>(s)] : nullptr;
}

/// Effective modulus of two bodies, 1 / ((1 - nu1^2) / E1 + (1 - nu2^2) / E2) (Pa).
double effective_modulus(double e1, double nu1, double e2, double nu2) {
    return 1.0 / ((1.0 - nu1 * nu1) / e1 + (1.0 - nu2 * nu2) / e2);
}

} // namespace

struct ThermalSystem::Template {
    int material = 0;
    double radius = 0;
    std::shared_ptr<const heat::ThermalGrid> grid;
    bool spherical = true;
    heat::SphericalResolution res;
    std::vector<double> h_face; // template h per boundary face (W/(m^2 K))
    heat::ThermalProperties props;
    heat::SolverSettings solver;
    double base_dt = 0;
    // Operators by (sub-step count, thread): each holds its own solver workspace.
    std::map<std::pair<int, int>, std::unique_ptr<heat::ResolvedOperator>> ops;
    std::vector<double> capacity; // per cell (J/K)
    double total_capacity = 0;
    double full_cell_capacity = 0;   // capacity of a full Cartesian cell, rho c_p h^3 (J/K)
    bool turning_stagnation = false; // a body under f(theta): uniform h in the matrix, the rest
                                     // lagged per body and thermal step
};

/// One conducting contact of the current thermal step, with its patches in each body.
struct ThermalSystem::ContactData {
    Record a;                    // particle i
    Record b;                    // partner j (material -1 for a wall)
    double conductance = 0;      // H (W/K)
    double wall_temperature = 0; // K, walls only
    bool wall = false;
    bool radiative = false;     // conductance holds K (W/K^4): rate K (T_j^4 - T_i^4)
    std::vector<int> patches_a; // boundary patches of i under the contact (resolved)
    std::vector<int> patches_b; // of j
};

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
            throw InputError(fmt::format(
                "{} (resolved material \"{}\", shape template \"{}\", {})", e.what(), mats[m].name,
                sys.spec().shapes[static_cast<std::size_t>(shape)].name, where));
        }
    }
    // Gas-gap conduction is a sphere-pair model (Cheng et al. 1999): refuse heated bodies. The
    // radiation view factor is a sphere estimate: refuse bodies of a material with an emissivity.
    // With radiation to the ambient they radiate to it only (a warning says so).
    bool warned_bodies = false;
    for (const auto& [material, shape, where] : kinds) {
        const MaterialHeat& mh = spec_.materials[static_cast<std::size_t>(material)];
        if (shape >= 0 && mh.enabled && mh.emissivity > 0.0) {
            if (std::isnan(spec_.radiation_temperature)) {
                throw InputError(fmt::format(
                    "heat: material \"{}\" has an emissivity and non-spherical particles (shape "
                    "\"{}\", {}): radiation between non-spherical neighbours: not yet (the view "
                    "factor is a sphere estimate; set emissivity = 0, use spheres, or set "
                    "radiation_temperature for radiation to the ambient only)",
                    mats[static_cast<std::size_t>(material)].name,
                    sys.spec().shapes[static_cast<std::size_t>(shape)].name, where));
            }
            if (!warned_bodies) {
                warned_bodies = true;
                warnings_.push_back(fmt::format(
                    "heat: non-spherical particles of material \"{}\" (shape \"{}\") radiate to "
                    "the ambient only: radiation between neighbours is for spheres",
                    mats[static_cast<std::size_t>(material)].name,
                    sys.spec().shapes[static_cast<std::size_t>(shape)].name));
            }
        }
    }
    if (spec_.gas.conductivity > 0.0) {
        for (const auto& [material, shape, where] : kinds) {
            if (shape >= 0 && spec_.materials[static_cast<std::size_t>(material)].enabled) {
                throw InputError(fmt::format(
                    "heat: gas_conductivity > 0 with heated non-spherical particles (material "
                    "\"{}\", shape \"{}\", {}): gas-gap conduction for non-spherical shapes: "
                    "not yet (the Cheng et al. lens model is for spheres; set gas_conductivity "
                    "= 0 or use spheres)",
                    mats[static_cast<std::size_t>(material)].name,
                    sys.spec().shapes[static_cast<std::size_t>(shape)].name, where));
            }
        }
    }
    if (spec_.collision_conduction) {
        // Impacts come from the sphere kernel's onset records: bodies (element contacts in
        // system_bodies.cpp) and mesh walls record none yet.
        if (!sys.spec().record_contact_onsets) {
            throw InputError("heat: collision_conduction needs the System to record contact "
                             "onsets (SceneSpec::record_contact_onsets = true)");
        }
        for (const auto& [material, shape, where] : kinds) {
            if (shape >= 0) {
                throw InputError(fmt::format(
                    "heat: collision_conduction with non-spherical particles (shape \"{}\", {}): "
                    "not yet for bodies (impacts are recorded for spheres only; set "
                    "collision_conduction = false or use spheres)",
                    sys.spec().shapes[static_cast<std::size_t>(shape)].name, where));
            }
        }
        for (std::size_t w = 0; w < spec_.mesh_wall_temperature.size(); ++w) {
            if (!std::isnan(spec_.mesh_wall_temperature[w])) {
                throw InputError(fmt::format(
                    "heat: collision_conduction with mesh wall \"{}\" at a temperature: not yet "
                    "for mesh walls (their impacts are not recorded; set collision_conduction = "
                    "false or leave the mesh wall adiabatic)",
                    sys.spec().mesh_walls[w].name));
            }
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
    // Spheres have no orientation: body frame = world axes, so the stagnation direction is the
    // same in every sphere and the local h goes into the template matrix exactly. Bodies turn:
    // their matrix keeps the uniform mean h, and h f(theta) of the body's current orientation
    // enters as the lagged correction of convection.hpp (thermal_step).
    if (spec_.heat_transfer_coefficient > 0.0 && spec_.stagnation && body != nullptr) {
        t->h_face = {spec_.heat_transfer_coefficient};
        t->turning_stagnation = true;
    } else if (spec_.heat_transfer_coefficient > 0.0 && spec_.stagnation) {
        t->h_face = heat::stagnation_distribution(*t->grid, -spec_.flow_direction,
                                                  spec_.heat_transfer_coefficient);
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
            pool_template_.push_back(r.templ);
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

double ThermalSystem::patch_weight(const Template& t, int patch) const {
    const heat::BoundaryFace& face = t.grid->boundary[static_cast<std::size_t>(patch)];
    // Spherical grids: by area (uniform flux over the contact patches, validation 24). Cartesian
    // cut cells: by cell heat capacity, so every patch cell warms at the same rate; by area a
    // sliver cut cell (volume fraction ~1e-4, but a full share of the surface) would receive heat
    // it cannot hold within one lagged step (found by validation 26).
    return t.spherical ? face.area : t.capacity[static_cast<std::size_t>(face.cell)];
}

void ThermalSystem::split_weights(const Template& t, std::span<const double> field,
                                  const std::vector<int>& patches, double q, double t_other,
                                  std::vector<double>& w) const {
    w.resize(patches.size());
    double total = 0.0;
    if (!t.spherical) {
        // Each cell by its capacity times how far it is from the partner's temperature on the
        // side the heat flows: a receiving cell by C_k max(0, T_other - T_k), a giving one by
        // C_k max(0, T_k - T_other). With the contact temperature the capacity mean of the same
        // cells, the drop of cell k's distance to T_other per sub-step is then at most
        // dt H / sum C_m (<= the lag limit's 0.5) times that distance: no cell crosses T_other,
        // so a donor cell at the scene's lowest temperature gives nothing (validation 29's dip).
        const double sign = q > 0.0 ? 1.0 : -1.0;
        for (std::size_t k = 0; k < patches.size(); ++k) {
            const auto cell = static_cast<std::size_t>(
                t.grid->boundary[static_cast<std::size_t>(patches[k])].cell);
            w[k] = t.capacity[cell] * std::max(0.0, sign * (t_other - field[cell]));
            total += w[k];
        }
    }
    if (!(total > 0.0)) {
        // Spherical grids (uniform flux by area: their contact temperature is the undisturbed
        // one, not a mean of these cells), or no cell on the flowing side (q = 0): as before.
        for (std::size_t k = 0; k < patches.size(); ++k) {
            w[k] = patch_weight(t, patches[k]);
        }
    }
}

double ThermalSystem::patch_capacity(const Record& r, const std::vector<int>& patches) const {
    if (r.templ < 0) {
        return lumped_capacity_[static_cast<std::size_t>(r.slot)];
    }
    const Template& t = *templates_[static_cast<std::size_t>(r.templ)];
    double c = 0.0;
    for (const int b : patches) {
        c += t.capacity[static_cast<std::size_t>(
            t.grid->boundary[static_cast<std::size_t>(b)].cell)];
    }
    return c;
}

double ThermalSystem::contact_temperature(const Record& r, const ContactData& c,
                                          bool side_b) const {
    if (r.templ < 0) {
        return lumped_[static_cast<std::size_t>(r.slot)];
    }
    const Template& t = *templates_[static_cast<std::size_t>(r.templ)];
    const std::span<const double> f = pool_.field(r.slot);
    const std::vector<int>& patches = side_b ? c.patches_b : c.patches_a;
    if (t.spherical && !c.radiative) {
        // The seed's undisturbed temperature (Inv. V L1965) along the rows under the contact.
        return heat::undisturbed_temperature(*t.grid, t.res, f, patches);
    }
    // Cartesian grids have no radial rows: the node temperature of the patch cells under the
    // contact, weighted as the heat is spread (by capacity), i.e. their mean heat content.
    double sum = 0.0;
    double weight = 0.0;
    for (const int b : patches) {
        const double w = patch_weight(t, b);
        sum += w * f[static_cast<std::size_t>(t.grid->boundary[static_cast<std::size_t>(b)].cell)];
        weight += w;
    }
    return sum / weight;
}

bool ThermalSystem::after_step(const dynamics::System& sys) {
    if (spec_.collision_conduction) {
        const std::vector<dynamics::ContactOnset>& e = sys.contact_onsets();
        onsets_.insert(onsets_.end(), e.begin(), e.end());
    }
    if (sys.step_count() % spec_.step_multiple != 0) {
        return false;
    }
    thermal_step(sys);
    return true;
}

void ThermalSystem::thermal_step(const dynamics::System& sys) {
    sync(sys);
    const ParticleStore& p = sys.particles();
    const auto& mats = sys.spec().materials;
    sys.collect_contacts(contacts_);

    // Conductances and patches of the conducting contacts (geometry fixed for the step).
    data_.clear();
    std::vector<double> g_sum(p.size(), 0.0); // W/K per particle index
    double worst = 0.0;                       // largest conductance / capacity (1/s)
    for (const dynamics::ContactRecord& rec : contacts_) {
        ContactData d;
        d.wall = rec.wall;
        d.a = by_id_[static_cast<std::size_t>(p.id[rec.i])];
        if (d.a.slot < 0) {
            continue;
        }
        const double ri = p.radius[rec.i];
        const Material& mi = mats[static_cast<std::size_t>(d.a.material)];
        const MaterialHeat& hi = spec_.materials[static_cast<std::size_t>(d.a.material)];
        int mat_j = 0;
        double rj = 0.0;
        if (rec.wall) {
            // Analytic walls first, then the mesh walls (the contact keys' order).
            const std::size_t n_walls = spec_.wall_temperature.size();
            const bool mesh = rec.j >= n_walls;
            d.wall_temperature =
                mesh ? spec_.mesh_wall_temperature[rec.j - n_walls] : spec_.wall_temperature[rec.j];
            if (std::isnan(d.wall_temperature)) {
                continue;
            }
            mat_j = mesh ? sys.spec().mesh_walls[rec.j - n_walls].material
                         : sys.spec().walls[rec.j].material;
        } else {
            d.b = by_id_[static_cast<std::size_t>(p.id[rec.j])];
            if (d.b.slot < 0) {
                continue;
            }
            mat_j = d.b.material;
            rj = p.radius[rec.j];
        }
        const Material& mj = mats[static_cast<std::size_t>(mat_j)];
        const MaterialHeat& hj = spec_.materials[static_cast<std::size_t>(mat_j)];
        // Bodies (element contacts) always use the Hertz radius: the lens rule needs sphere radii.
        const bool body_i = p.shape[rec.i] >= 0;
        const bool body_j = !rec.wall && p.shape[rec.j] >= 0;
        double rc = 0.0;
        if (spec_.contact_radius == ContactRadius::hertz || body_i || body_j) {
            rc = std::sqrt(rec.r_eff * rec.overlap);
        } else if (rec.wall) {
            // Intersection circle of a sphere with a plane at depth delta.
            rc = std::sqrt(std::max(0.0, rec.overlap * (2.0 * ri - rec.overlap)));
        } else {
            rc = heat::lens_contact_radius(rec.overlap, ri, rj);
        }
        // Zhou et al.'s c = (E*_sim / E*_real)^(1/5) (seed Inv. V eq. 12) with the pair's
        // effective moduli; 1 when both materials use their real modulus.
        const double ei = hi.real_youngs_modulus > 0.0 ? hi.real_youngs_modulus : mi.youngs_modulus;
        const double ej = hj.real_youngs_modulus > 0.0 ? hj.real_youngs_modulus : mj.youngs_modulus;
        const double correction = heat::softened_modulus_correction(
            effective_modulus(mi.youngs_modulus, mi.poisson_ratio, mj.youngs_modulus,
                              mj.poisson_ratio),
            effective_modulus(ei, mi.poisson_ratio, ej, mj.poisson_ratio));
        d.conductance =
            heat::static_contact_conductance(hi.conductivity, hj.conductivity, rc, correction);
        // Patches under the contact disc, in each body frame: world offsets and normals turned
        // by q^-1 for bodies (world -> body); spheres have no orientation (world axes).
        const auto patches = [&](const Record& r, std::uint32_t k, bool body, const Vec3& n) {
            const Template& t = *templates_[static_cast<std::size_t>(r.templ)];
            const Quat inv = body ? p.q[k].conjugate() : Quat::Identity();
            const Vec3 x = inv * (rec.point - p.x[k]);
            const Vec3 nb = inv * n;
            std::vector<int> out = heat::contact_patches(*t.grid, x, nb, rc);
            if (!t.spherical) {
                widen_to_one_cell(*t.grid, t.capacity, t.full_cell_capacity, x, nb, out);
            }
            return out;
        };
        if (d.a.templ >= 0) {
            d.patches_a = patches(d.a, rec.i, body_i, rec.normal);
        }
        if (!rec.wall && d.b.templ >= 0) {
            d.patches_b = patches(d.b, rec.j, body_j, -rec.normal);
        }
        // The capacity that answers a lagged contact rate within one step: the whole lumped
        // particle, or the cells under the contact of a resolved one (a conservative choice: the
        // implicit conduction inside spreads the heat further during the step).
        g_sum[rec.i] += d.conductance;
        double pair_rate = d.conductance / patch_capacity(d.a, d.patches_a);
        if (!rec.wall) {
            g_sum[rec.j] += d.conductance;
            pair_rate += d.conductance / patch_capacity(d.b, d.patches_b);
        }
        worst = std::max(worst, pair_rate);
        data_.push_back(std::move(d));
    }
    add_gas_gaps(sys, g_sum, worst);
    add_radiation(sys, g_sum, worst);
    add_collisions(sys, g_sum, worst);
    for (std::size_t i = 0; i < p.size(); ++i) {
        if (g_sum[i] > 0.0) {
            const Record& r = by_id_[static_cast<std::size_t>(p.id[i])];
            worst = std::max(worst, g_sum[i] / capacity_of(r));
        }
    }
    // Bodies under f(theta): h per face for the current orientation (flow direction turned into
    // the body frame with q^-1); the lagged part (G_b(h f) - G_b(h)) / C_cell joins the lag limit.
    // Resolved particles radiating to the ambient: the lagged face rate's linearised conductance
    // A / (1 / (4 eps sigma T^3) + d / k) at the hotter of node and ambient joins the lag limit.
    const double t_rad = spec_.radiation_temperature;
    std::vector<char> radiating(static_cast<std::size_t>(pool_.size()), 0);
    if (!std::isnan(t_rad)) {
        for (int slot = 0; slot < pool_.size(); ++slot) {
            const Template& t = *templates_[static_cast<std::size_t>(
                pool_template_[static_cast<std::size_t>(slot)])];
            const double eps = spec_.materials[static_cast<std::size_t>(t.material)].emissivity;
            if (!(eps > 0.0)) {
                continue;
            }
            radiating[static_cast<std::size_t>(slot)] = 1;
            const std::span<const double> f = pool_.field(slot);
            for (const heat::BoundaryFace& face : t.grid->boundary) {
                const auto cell = static_cast<std::size_t>(face.cell);
                const double tm = std::max(f[cell], t_rad);
                const double hr = 4.0 * eps * heat::stefan_boltzmann * tm * tm * tm;
                const double g = face.area / (1.0 / hr + face.distance / t.props.conductivity);
                worst = std::max(worst, g / t.capacity[cell]);
            }
        }
    }
    std::vector<char> stagnant(static_cast<std::size_t>(pool_.size()), 0);
    for (std::size_t i = 0; i < p.size(); ++i) {
        const Record& r = by_id_[static_cast<std::size_t>(p.id[i])];
        if (r.templ < 0 || !templates_[static_cast<std::size_t>(r.templ)]->turning_stagnation) {
            continue;
        }
        const Template& t = *templates_[static_cast<std::size_t>(r.templ)];
        const std::vector<double> hf = heat::stagnation_distribution(
            *t.grid, p.q[i].conjugate() * (-spec_.flow_direction), spec_.heat_transfer_coefficient);
        const std::size_t off = face_offset_[static_cast<std::size_t>(r.slot)];
        for (std::size_t b = 0; b < hf.size(); ++b) {
            stag_h_[off + b] = hf[b];
            const heat::BoundaryFace& f = t.grid->boundary[b];
            const double dg =
                heat::surface_conductance(f, hf[b], t.props.conductivity) -
                heat::surface_conductance(f, spec_.heat_transfer_coefficient, t.props.conductivity);
            worst = std::max(worst, std::abs(dg) / t.capacity[static_cast<std::size_t>(f.cell)]);
        }
        stagnant[static_cast<std::size_t>(r.slot)] = 1;
    }
    // Lag limit: sub-steps (a power of two, so few operators are built) keep
    // dt_sub * worst <= lag_safety.
    const double ratio = dt_ * worst;
    int substeps = 1;
    while (ratio / substeps > lag_safety) {
        substeps *= 2;
        if (substeps > spec_.max_substeps) {
            throw RunError(sys.step_count(),
                           fmt::format("heat: the thermal step {:.3g} s is {:.3g} times the lagged "
                                       "contact-coupling limit {:.3g} s (heat capacity / contact "
                                       "conductance); more than max_substeps = {} sub-steps "
                                       "would be needed: lower [heat] step_multiple",
                                       dt_, ratio / lag_safety, lag_safety / worst,
                                       spec_.max_substeps));
        }
    }
    counters_.max_lag_ratio = std::max(counters_.max_lag_ratio, ratio);
    if (substeps > 1 && !warned_lag_) {
        warned_lag_ = true;
        warnings_.push_back(fmt::format(
            "heat: thermal step {:.3g} s exceeds the lagged contact-coupling limit {:.3g} s "
            "(heat capacity / contact conductance x {}); sub-stepping ({} sub-steps at t = {:.6g} "
            "s; later steps may use other counts)",
            dt_, lag_safety / worst, lag_safety, substeps, sys.time()));
    }
    const double dt_sub = dt_ / substeps;

    std::vector<double> weights; // patch shares of one contact side
    for (int s = 0; s < substeps; ++s) {
        std::fill(face_rate_.begin(), face_rate_.end(), 0.0);
        std::fill(lumped_rate_.begin(), lumped_rate_.end(), 0.0);
        // Lagged contact heat rates from the temperatures at the start of the sub-step; what
        // leaves one body enters the other (the same number with the opposite sign).
        // `t_other` is the partner's contact temperature (K). Cartesian patches split by
        // temperature: see split_weights.
        const auto add = [&](const Record& r, const std::vector<int>& patches, double q,
                             double t_other) {
            if (r.templ < 0) {
                lumped_rate_[static_cast<std::size_t>(r.slot)] += q;
                return;
            }
            const Template& t = *templates_[static_cast<std::size_t>(r.templ)];
            split_weights(t, pool_.field(r.slot), patches, q, t_other, weights);
            double total = 0.0;
            std::size_t largest = 0;
            for (std::size_t k = 0; k < patches.size(); ++k) {
                total += weights[k];
                largest = weights[k] > weights[largest] ? k : largest;
            }
            double* rate = face_rate_.data() + face_offset_[static_cast<std::size_t>(r.slot)];
            double given = 0.0;
            for (std::size_t k = 0; k < patches.size(); ++k) {
                if (k != largest) {
                    const double part = q * (weights[k] / total);
                    rate[patches[k]] += part;
                    given += part;
                }
            }
            rate[patches[largest]] += q - given; // the remainder: the parts sum to q exactly
        };
        for (const ContactData& d : data_) {
            const double ta = contact_temperature(d.a, d, false);
            const double tb = d.wall ? d.wall_temperature : contact_temperature(d.b, d, true);
            const double q = d.radiative ? d.conductance * (tb * tb * tb * tb - ta * ta * ta * ta)
                                         : d.conductance * (tb - ta); // into i
            add(d.a, d.patches_a, q, tb);
            if (d.wall) {
                external_heat_ += q * dt_sub;
            } else {
                add(d.b, d.patches_b, -q, ta);
            }
        }
        // Lumped particles: backward Euler with implicit convection (h mean: f(theta) averages
        // to 1 over a sphere).
        // Radiation to the ambient linearised about T^n, eps sigma A (T_a^4 - T^n^4 - 4 T^n^3
        // (T^(n+1) - T^n)): implicit in the linear part, so never below T_a when cooling
        // ((T_a^4 + 3 T^4) / (4 T^3) >= T_a), first order in dt like the rest.
        const double h = spec_.heat_transfer_coefficient;
        const double ta4 = std::isnan(t_rad) ? 0.0 : t_rad * t_rad * t_rad * t_rad;
        for (std::size_t k = 0; k < lumped_.size(); ++k) {
            const double c = lumped_capacity_[k];
            const double a = lumped_area_[k];
            const double t_old = lumped_[k];
            const double gr =
                std::isnan(t_rad) ? 0.0 : lumped_emissivity_[k] * heat::stefan_boltzmann * a;
            const double t3 = t_old * t_old * t_old;
            const double t_new =
                (c * t_old + dt_sub * (h * a * spec_.ambient_temperature + spec_.flux * a +
                                       lumped_rate_[k] + gr * (ta4 + 3.0 * t3 * t_old))) /
                (c + dt_sub * (h * a + 4.0 * gr * t3));
            external_heat_ +=
                dt_sub * (h * a * (spec_.ambient_temperature - t_new) + spec_.flux * a +
                          gr * (ta4 + 3.0 * t3 * t_old - 4.0 * t3 * t_new));
            lumped_[k] = t_new;
        }
        // Bodies under f(theta): the lagged convection correction from the field at the start of
        // the sub-step, added to the contact rates (and booked as external heat below).
        const double t_inf = spec_.ambient_temperature;
        const double h_mean = spec_.heat_transfer_coefficient;
        for (int slot = 0; slot < pool_.size(); ++slot) {
            if (stagnant[static_cast<std::size_t>(slot)] == 0) {
                continue;
            }
            const Template& t = *templates_[static_cast<std::size_t>(
                pool_template_[static_cast<std::size_t>(slot)])];
            const std::size_t off = face_offset_[static_cast<std::size_t>(slot)];
            const std::size_t nb = t.grid->boundary.size();
            const std::span<double> conv(conv_rate_.data() + off, nb);
            heat::lagged_convection(*t.grid, t.props.conductivity,
                                    std::span<const double>(stag_h_.data() + off, nb),
                                    std::span<const double>(&h_mean, 1),
                                    std::span<const double>(&t_inf, 1), pool_.field(slot), conv);
            for (std::size_t b = 0; b < nb; ++b) {
                face_rate_[off + b] += conv[b];
            }
        }
        // Radiation to the ambient of resolved particles: per face eps sigma A (T_a^4 - T_s^4),
        // T_s from the surface balance with the node at the start of the sub-step (lagged; booked
        // as external heat below).
        for (int slot = 0; slot < pool_.size(); ++slot) {
            if (radiating[static_cast<std::size_t>(slot)] == 0) {
                continue;
            }
            const Template& t = *templates_[static_cast<std::size_t>(
                pool_template_[static_cast<std::size_t>(slot)])];
            const double eps = spec_.materials[static_cast<std::size_t>(t.material)].emissivity;
            const std::size_t off = face_offset_[static_cast<std::size_t>(slot)];
            const std::span<const double> f = pool_.field(slot);
            for (std::size_t b = 0; b < t.grid->boundary.size(); ++b) {
                const heat::BoundaryFace& face = t.grid->boundary[b];
                const double ts = heat::radiating_surface_temperature(
                    f[static_cast<std::size_t>(face.cell)], face.distance, t.props.conductivity,
                    eps, t_rad);
                const double q =
                    eps * heat::stefan_boltzmann * face.area * (ta4 - ts * ts * ts * ts);
                rad_rate_[off + b] = q;
                face_rate_[off + b] += q;
            }
        }
        // Resolved particles: one backward-Euler solve each with the lagged heat rates. The solves
        // are independent: threads take slots, each with its own operator (built here, outside
        // the parallel loop); the sums below run in slot order, so results do not depend on the
        // number of threads.
        const int n_slots = pool_.size();
        const int threads = std::max(1, std::min(threads_, n_slots));
        for (const auto& t : templates_) {
            for (int th = 0; th < threads; ++th) {
                operator_for(*t, substeps, th);
            }
        }
        reports_.resize(static_cast<std::size_t>(n_slots));
#pragma omp parallel for num_threads(threads) schedule(dynamic, 8)
        for (int slot = 0; slot < n_slots; ++slot) {
            int th = 0;
#ifdef _OPENMP
            th = omp_get_thread_num();
#endif
            Template& t = *templates_[static_cast<std::size_t>(
                pool_template_[static_cast<std::size_t>(slot)])];
            heat::ResolvedOperator& op = *t.ops.at({substeps, th});
            heat::BoundaryLoad load;
            load.ambient = spec_.ambient_temperature;
            load.flux = spec_.flux;
            load.heat_rate = std::span<const double>(
                face_rate_.data() + face_offset_[static_cast<std::size_t>(slot)],
                t.grid->boundary.size());
            reports_[static_cast<std::size_t>(slot)] = op.step(pool_.field(slot), load);
        }
        for (int slot = 0; slot < n_slots; ++slot) {
            const heat::StepReport& rep = reports_[static_cast<std::size_t>(slot)];
            const Template& t = *templates_[static_cast<std::size_t>(
                pool_template_[static_cast<std::size_t>(slot)])];
            const double* rates = face_rate_.data() + face_offset_[static_cast<std::size_t>(slot)];
            double contact_in = 0.0; // lagged contact rates: internal, not external heat
            const bool conv = stagnant[static_cast<std::size_t>(slot)] != 0;
            const bool rad = radiating[static_cast<std::size_t>(slot)] != 0;
            const double* rad_rates =
                rad_rate_.data() + face_offset_[static_cast<std::size_t>(slot)];
            const double* conv_rates =
                conv_rate_.data() + face_offset_[static_cast<std::size_t>(slot)];
            for (std::size_t b = 0; b < t.grid->boundary.size(); ++b) {
                contact_in += rates[b] - (conv ? conv_rates[b] : 0.0) - (rad ? rad_rates[b] : 0.0);
            }
            external_heat_ += rep.heat_in - dt_sub * contact_in;
            ++counters_.solves;
            counters_.iterations += rep.solve.iterations;
            counters_.max_iterations = std::max(counters_.max_iterations, rep.solve.iterations);
            if (!rep.solve.converged) {
                ++counters_.unconverged;
                if (!warned_solver_) {
                    warned_solver_ = true;
                    warnings_.push_back(fmt::format(
                        "heat: a {} solve stopped at the iteration cap ({}) with relative "
                        "residual {:.3g} (tolerance {:.3g}) at t = {:.6g} s",
                        heat::to_string(spec_.solver.kind), spec_.solver.max_iterations,
                        rep.solve.residual, spec_.solver.tolerance, sys.time()));
                }
            }
        }
    }
    ++counters_.thermal_steps;
    counters_.substeps += substeps;
    counters_.max_substeps = std::max(counters_.max_substeps, substeps);
    counters_.contacts += static_cast<long>(data_.size());
}

void ThermalSystem::add_gas_gaps(const dynamics::System& sys, std::vector<double>& g_sum,
                                 double& worst) {
    if (!(spec_.gas.conductivity > 0.0)) {
        return;
    }
    // Heated spheres only (radius 0 hides the others from the pair search). The search is a cell
    // list of its own at each thermal step, so the cut-off does not depend on the neighbour list's
    // skin (by default 0.2 R, well below the seed's gap cut-off of R).
    const ParticleStore& p = sys.particles();
    std::vector<double> r(p.size(), 0.0);
    for (std::size_t i = 0; i < p.size(); ++i) {
        if (p.shape[i] < 0 && by_id_[static_cast<std::size_t>(p.id[i])].slot >= 0) {
            r[i] = p.radius[i];
        }
    }
    long pairs = 0;
    for (const heat::NearPair& np : heat::near_sphere_pairs(p.x, r, spec_.gas.cutoff)) {
        ContactData d;
        d.a = by_id_[static_cast<std::size_t>(p.id[np.i])];
        d.b = by_id_[static_cast<std::size_t>(p.id[np.j])];
        const Vec3 between = p.x[np.j] - p.x[np.i];
        const double s = between.norm();
        const double k_a = spec_.materials[static_cast<std::size_t>(d.a.material)].conductivity;
        const double k_b = spec_.materials[static_cast<std::size_t>(d.b.material)].conductivity;
        d.conductance = heat::gas_gap_conductance(r[np.i], r[np.j], s, k_a, k_b, spec_.gas);
        if (!(d.conductance > 0.0)) {
            continue;
        }
        // Resolved spheres take the heat on the patches under the lens r <= r_sf around the
        // line of centres (world axes = body frame for spheres).
        const Vec3 n = between / s;
        const double lens = heat::gas_gap_radius(r[np.i], r[np.j], s, spec_.gas);
        if (d.a.templ >= 0) {
            d.patches_a = heat::contact_patches(
                *templates_[static_cast<std::size_t>(d.a.templ)]->grid, r[np.i] * n, n, lens);
        }
        if (d.b.templ >= 0) {
            d.patches_b = heat::contact_patches(
                *templates_[static_cast<std::size_t>(d.b.templ)]->grid, -r[np.j] * n, -n, lens);
        }
        g_sum[np.i] += d.conductance;
        g_sum[np.j] += d.conductance;
        worst = std::max(worst, d.conductance / patch_capacity(d.a, d.patches_a) +
                                    d.conductance / patch_capacity(d.b, d.patches_b));
        data_.push_back(std::move(d));
        ++pairs;
    }
    gas_pairs_ += pairs;
}

void ThermalSystem::add_radiation(const dynamics::System& sys, std::vector<double>& g_sum,
                                  double& worst) {
    const ParticleStore& p = sys.particles();
    const auto emissivity = [&](const Record& rec) {
        return spec_.materials[static_cast<std::size_t>(rec.material)].emissivity;
    };
    // Heated spheres with an emissivity (others radius 0: left out of the search).
    std::vector<double> r(p.size(), 0.0);
    bool any = false;
    for (std::size_t i = 0; i < p.size(); ++i) {
        const Record& rec = by_id_[static_cast<std::size_t>(p.id[i])];
        if (p.shape[i] < 0 && rec.slot >= 0 && emissivity(rec) > 0.0) {
            r[i] = p.radius[i];
            any = true;
        }
    }
    if (!any) {
        return;
    }
    long pairs = 0;
    for (const heat::NearPair& np : heat::near_sphere_pairs(p.x, r, spec_.radiation_cutoff)) {
        ContactData d;
        d.radiative = true;
        d.a = by_id_[static_cast<std::size_t>(p.id[np.i])];
        d.b = by_id_[static_cast<std::size_t>(p.id[np.j])];
        const Vec3 between = p.x[np.j] - p.x[np.i];
        const double s = between.norm();
        // Overlapping (touching) spheres radiate as if just touching.
        d.conductance = heat::radiative_coefficient(
            r[np.i], r[np.j], std::max(s, r[np.i] + r[np.j]), emissivity(d.a), emissivity(d.b));
        // Resolved spheres exchange over the hemisphere facing the partner (world axes = body
        // frame for spheres): its area-weighted cell temperature, and the heat spread over it.
        const Vec3 n = between / s;
        if (d.a.templ >= 0) {
            d.patches_a = heat::contact_patches(
                *templates_[static_cast<std::size_t>(d.a.templ)]->grid, r[np.i] * n, n, r[np.i]);
        }
        if (d.b.templ >= 0) {
            d.patches_b = heat::contact_patches(
                *templates_[static_cast<std::size_t>(d.b.templ)]->grid, -r[np.j] * n, -n, r[np.j]);
        }
        // Lag limit with the linearised conductance at the hotter side's current temperature.
        const double g = heat::radiative_conductance_bound(
            d.conductance, contact_temperature(d.a, d, false), contact_temperature(d.b, d, true));
        g_sum[np.i] += g;
        g_sum[np.j] += g;
        worst = std::max(worst, g / patch_capacity(d.a, d.patches_a) +
                                    g / patch_capacity(d.b, d.patches_b));
        data_.push_back(std::move(d));
        ++pairs;
    }
    radiation_pairs_ += pairs;
}

void ThermalSystem::add_collisions(const dynamics::System& sys, std::vector<double>& g_sum,
                                   double& worst) {
    if (onsets_.empty()) {
        return;
    }
    const ParticleStore& p = sys.particles();
    const auto& mats = sys.spec().materials;
    std::vector<std::int64_t> index(by_id_.size(), -1); // particle index by id (lag limit)
    for (std::size_t i = 0; i < p.size(); ++i) {
        index[static_cast<std::size_t>(p.id[i])] = static_cast<std::int64_t>(i);
    }
    const auto record_of = [&](std::int64_t id) {
        const auto k = static_cast<std::size_t>(id);
        return k < by_id_.size() && index[k] >= 0 ? by_id_[k] : Record{};
    };
    long taken = 0;
    for (const dynamics::ContactOnset& e : onsets_) {
        ContactData d;
        d.a = record_of(e.id_i);
        if (d.a.slot < 0 || !(e.speed > 0.0)) {
            continue; // no heat model (or the particle left), or no approach
        }
        int mat_j = 0;
        if (e.wall >= 0) {
            d.wall = true;
            d.wall_temperature = spec_.wall_temperature[static_cast<std::size_t>(e.wall)];
            if (std::isnan(d.wall_temperature)) {
                continue; // adiabatic wall
            }
            mat_j = sys.spec().walls[static_cast<std::size_t>(e.wall)].material;
        } else {
            d.b = record_of(e.id_j);
            if (d.b.slot < 0) {
                continue;
            }
            mat_j = d.b.material;
        }
        const auto side = [&](int m) {
            const MaterialHeat& h = spec_.materials[static_cast<std::size_t>(m)];
            return heat::ImpactSide{density_[static_cast<std::size_t>(m)], h.specific_heat,
                                    h.conductivity};
        };
        // The impact itself with the real moduli (real_youngs_modulus where given): duration and
        // contact radius are physical, as the static law's c maps its radius to the real one.
        const Material& mi = mats[static_cast<std::size_t>(d.a.material)];
        const Material& mj = mats[static_cast<std::size_t>(mat_j)];
        const double ei_real =
            spec_.materials[static_cast<std::size_t>(d.a.material)].real_youngs_modulus;
        const double ej_real = spec_.materials[static_cast<std::size_t>(mat_j)].real_youngs_modulus;
        const double e_eff =
            effective_modulus(ei_real > 0.0 ? ei_real : mi.youngs_modulus, mi.poisson_ratio,
                              ej_real > 0.0 ? ej_real : mj.youngs_modulus, mj.poisson_ratio);
        double energy = 0.0; // J into i per kelvin of T_j - T_i
        double rc = 0.0;
        try {
            const double tc = heat::hertz_impact_duration(e.m_eff, e_eff, e.r_eff, e.speed);
            rc = heat::hertz_impact_radius(e.m_eff, e_eff, e.r_eff, e.speed);
            energy = heat::impact_heat(side(d.a.material), side(mat_j), tc, rc, 0.0, 1.0);
        } catch (const InputError& err) {
            throw RunError(sys.step_count(),
                           fmt::format("{} (impact of particle {} at step {}, {:.3g} m/s)",
                                       err.what(), e.id_i, e.step, e.speed));
        }
        // Exchanged over this thermal step as a lagged conductance: with one sub-step the heat
        // moved is E (T_j - T_i) with the temperatures at the start of the step.
        d.conductance = energy / dt_;
        // Resolved spheres: the patches under the impact's contact disc, at the normal of the
        // onset (spheres carry no orientation: world axes = body frame).
        const Vec3 n(e.normal[0], e.normal[1], e.normal[2]);
        const auto patches = [&](const Record& r, const Vec3& nb) {
            const Template& t = *templates_[static_cast<std::size_t>(r.templ)];
            const Vec3 x = t.radius * nb;
            std::vector<int> out = heat::contact_patches(*t.grid, x, nb, rc);
            if (!t.spherical) {
                widen_to_one_cell(*t.grid, t.capacity, t.full_cell_capacity, x, nb, out);
            }
            return out;
        };
        if (d.a.templ >= 0) {
            d.patches_a = patches(d.a, n);
        }
        if (!d.wall && d.b.templ >= 0) {
            d.patches_b = patches(d.b, -n);
        }
        const auto ia = static_cast<std::size_t>(index[static_cast<std::size_t>(e.id_i)]);
        g_sum[ia] += d.conductance;
        double pair_rate = d.conductance / patch_capacity(d.a, d.patches_a);
        if (!d.wall) {
            g_sum[static_cast<std::size_t>(index[static_cast<std::size_t>(e.id_j)])] +=
                d.conductance;
            pair_rate += d.conductance / patch_capacity(d.b, d.patches_b);
        }
        worst = std::max(worst, pair_rate);
        data_.push_back(std::move(d));
        ++taken;
    }
    collisions_ += taken;
    onsets_.clear();
}

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
        if (p.shape[i] >= 0) {
            v.q = p.q[i];
        }
        out.push_back(v);
    }
    std::sort(out.begin(), out.end(),
              [](const FieldView& a, const FieldView& b) { return a.id < b.id; });
    return out;
}

ThermalState ThermalSystem::save_state() const {
    ThermalState s;
    s.fields = pool_.values();
    s.lumped = lumped_;
    s.ids = slot_ids_;
    s.external_heat = external_heat_;
    s.counters = counters_;
    s.onsets = onsets_;
    return s;
}

void ThermalSystem::restore_state(const ThermalState& s, const dynamics::System& sys) {
    sync(sys);
    if (s.ids != slot_ids_ || s.fields.size() != pool_.values().size() ||
        s.lumped.size() != lumped_.size()) {
        throw InputError("heat: the checkpoint's temperatures do not fit this case (different "
                         "particles or heat models); restart with the case that wrote it");
    }
    std::size_t at = 0;
    for (int slot = 0; slot < pool_.size(); ++slot) {
        const std::span<double> f = pool_.field(slot);
        std::copy_n(s.fields.begin() + static_cast<std::ptrdiff_t>(at), f.size(), f.begin());
        at += f.size();
    }
    lumped_ = s.lumped;
    external_heat_ = s.external_heat;
    counters_ = s.counters;
    onsets_ = s.onsets;
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
    j += fmt::format("    \"collisions\": {},\n", collisions_);
    j += fmt::format("    \"thermal_energy\": {},\n", num(thermal_energy()));
    j += fmt::format("    \"external_heat\": {}\n", num(external_heat_));
    j += "  }";
    return j;
}

} // namespace kiln::thermal
