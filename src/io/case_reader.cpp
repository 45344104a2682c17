#include "io/case_reader.hpp"
#include "io/case_section.hpp"
#include "io/mesh_reader.hpp"
#include "io/shape_reader.hpp"
#include "io/toml_text.hpp"

#include "core/error.hpp"
#include "heat/resolved_model.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <toml++/toml.h>

namespace kiln::io {

namespace {

using detail::for_each_table;
using detail::inf;
using detail::non_negative;
using detail::positive;
using detail::Range;
using detail::Section;
using detail::with_unit;

int material_index(Section& s, std::string_view key, const std::map<std::string, int>& mats) {
    std::vector<std::string> names;
    for (const auto& [name, idx] : mats) {
        names.push_back(name);
    }
    const std::string m = s.text(key, std::nullopt, names);
    return mats.at(m);
}

dynamics::SizeDistribution read_radius(Section& s) {
    dynamics::SizeDistribution d;
    const toml::node* n = s.take("radius");
    if (n == nullptr) {
        s.fail("radius", s.table_line(),
               "missing required value (m): a number or a distribution table");
    }
    if (!n->is_table()) {
        d.kind = dynamics::SizeDistribution::Kind::constant;
        d.radius = s.real("radius", std::nullopt, positive(), "m");
        return d;
    }
    toml::table out_t;
    Section r(s.file(), *n->as_table(), s.full("radius"), out_t);
    const std::string kind =
        r.text("distribution", std::nullopt, {"uniform", "normal", "discrete"});
    if (kind == "uniform" || kind == "normal") {
        d.kind = kind == "uniform" ? dynamics::SizeDistribution::Kind::uniform
                                   : dynamics::SizeDistribution::Kind::normal;
        d.min = r.real("min", std::nullopt, positive(), "m");
        d.max = r.real("max", std::nullopt, Range{d.min, inf, true, false}, "m");
        if (kind == "normal") {
            d.mean = r.real("mean", std::nullopt, Range{d.min, d.max, true, true}, "m");
            d.stddev = r.real("stddev", std::nullopt, positive(), "m");
        }
    } else {
        d.kind = dynamics::SizeDistribution::Kind::discrete;
        d.values = r.reals("values", "m", positive());
        if (r.has("weights")) {
            d.weights = r.reals("weights", "-", positive());
        } else {
            d.weights.assign(d.values.size(), 1.0);
            r.take("weights");
            toml::array w;
            for (double x : d.weights) {
                w.push_back(x);
            }
            out_t.insert_or_assign("weights", w);
        }
        if (d.weights.size() != d.values.size()) {
            r.fail_at("weights", fmt::format("has {} entries but values has {}; they must match",
                                             d.weights.size(), d.values.size()));
        }
    }
    r.finish();
    s.out().insert_or_assign("radius", std::move(out_t));
    return d;
}

Aabb read_region(Section& s) {
    const toml::table* t = s.table("region");
    if (t == nullptr) {
        s.fail("region", s.table_line(),
               "missing required table { min = [x, y, z], max = [x, y, z] } (m)");
    }
    toml::table out_t;
    Section r(s.file(), *t, s.full("region"), out_t);
    Aabb box;
    box.lo = r.vec3("min", std::nullopt, "m");
    box.hi = r.vec3("max", std::nullopt, "m");
    if (!((box.hi - box.lo).array() > 0.0).all()) {
        r.fail_at("max", "must exceed min in every coordinate");
    }
    r.finish();
    s.out().insert_or_assign("region", std::move(out_t));
    return box;
}

/// The optional `heat` table of a material (conductivity, specific heat, model, grid, ...).
thermal::MaterialHeat read_material_heat(Section& s, const Material& m) {
    thermal::MaterialHeat h;
    const toml::table* t = s.table("heat");
    if (t == nullptr) {
        return h;
    }
    toml::table out_t;
    Section r(s.file(), *t, s.full("heat"), out_t);
    h.enabled = true;
    h.conductivity = r.real("conductivity", std::nullopt, positive(), "W/(m K)");
    h.specific_heat = r.real("specific_heat", std::nullopt, positive(), "J/(kg K)");
    h.initial_temperature = r.real("initial_temperature", 293.15, positive(), "K");
    const std::string model = r.text("model", "lumped", {"none", "lumped", "resolved", "auto"});
    h.model = model == "none"       ? heat::HeatModel::none
              : model == "lumped"   ? heat::HeatModel::lumped
              : model == "resolved" ? heat::HeatModel::resolved
                                    : heat::HeatModel::automatic;
    h.grid = r.text("grid", "spherical", {"spherical", "cartesian"}) == "spherical"
                 ? thermal::GridKind::spherical
                 : thermal::GridKind::cartesian;
    h.spherical.n_r = static_cast<int>(r.integer("radial_cells", 10, 1, 1000));
    h.spherical.n_theta = static_cast<int>(r.integer("polar_cells", 8, 2, 1000));
    h.spherical.n_phi = static_cast<int>(r.integer("azimuthal_cells", 16, 3, 1000));
    h.cells_across = static_cast<int>(r.integer("cells_across", 10, 2, 1000));
    h.real_youngs_modulus = r.real("real_youngs_modulus", m.youngs_modulus, positive(), "Pa");
    h.emissivity = r.real("emissivity", 0.0, Range{0.0, 1.0, true, true}, "-");
    r.finish();
    s.out().insert_or_assign("heat", std::move(out_t));
    return h;
}

/// The optional `temperature` of a wall table (K), for the walls [first, end) it produced.
void read_wall_temperature(Section& s, CaseSpec& c, std::size_t first) {
    c.heat.wall_temperature.resize(c.scene.walls.size(), thermal::unset);
    if (!s.has("temperature")) {
        return;
    }
    const double t = s.real("temperature", std::nullopt, positive(), "K");
    const auto m = static_cast<std::size_t>(c.scene.walls.at(first).material);
    if (!c.heat.materials.at(m).enabled) {
        s.fail_at("temperature",
                  fmt::format("the wall's material \"{}\" has no heat table; a wall at a "
                              "temperature conducts through its material's conductivity",
                              c.scene.materials[m].name));
    }
    for (std::size_t w = first; w < c.scene.walls.size(); ++w) {
        c.heat.wall_temperature[w] = t;
    }
}

/// The optional `temperature` of a mesh wall table (K), for the mesh wall just read.
void read_mesh_wall_temperature(Section& s, CaseSpec& c) {
    c.heat.mesh_wall_temperature.resize(c.scene.mesh_walls.size(), thermal::unset);
    if (!s.has("temperature")) {
        return;
    }
    const double t = s.real("temperature", std::nullopt, positive(), "K");
    const auto m = static_cast<std::size_t>(c.scene.mesh_walls.back().material);
    if (!c.heat.materials.at(m).enabled) {
        s.fail_at("temperature",
                  fmt::format("the wall's material \"{}\" has no heat table; a wall at a "
                              "temperature conducts through its material's conductivity",
                              c.scene.materials[m].name));
    }
    c.heat.mesh_wall_temperature.back() = t;
}

/// Where a mesh wall was declared, for the side check once the particles are known.
struct MeshWallSite {
    long line = 0;    ///< line of its `file` key
    std::string path; ///< full key path of `flip`
};

/// A mesh wall: `file` (relative to the case file), `scale`, `translate`, `flip`.
void read_mesh_wall(Section& s, CaseSpec& c, const std::string& name, int mat,
                    std::vector<MeshWallSite>& sites) {
    const std::string file = s.text("file", std::nullopt);
    const double scale = s.real("scale", 1.0, positive(), "-");
    const Vec3 shift = s.vec3("translate", Vec3::Zero(), "m");
    const bool flip = s.boolean("flip", false);
    const std::filesystem::path dir = std::filesystem::path(s.file()).parent_path();
    const std::filesystem::path path = dir.empty() ? std::filesystem::path(file) : dir / file;
    MeshInput m;
    try {
        m = read_mesh_file(path, scale, false);
    } catch (const InputError& e) {
        s.fail_at("file", e.what());
    }
    if (m.triangles.empty()) {
        s.fail_at("file", fmt::format("\"{}\" has no triangles; a mesh wall needs faces "
                                      "(STL facets or OBJ f records)",
                                      path.string()));
    }
    for (Vec3& x : m.points) {
        x += shift;
    }
    if (flip) {
        for (auto& t : m.triangles) {
            std::swap(t[1], t[2]);
        }
    }
    try {
        auto mesh = std::make_shared<const geometry::MeshWall>(
            std::move(m.points), std::move(m.triangles), path.string());
        c.scene.mesh_walls.push_back({name, std::move(mesh), mat});
    } catch (const InputError& e) {
        s.fail_at("file", e.what());
    }
    // The resolved case names the file absolutely, so that it reads again from the output folder.
    s.out().insert_or_assign("file", std::filesystem::absolute(path).lexically_normal().string());
    sites.push_back({s.line_of("file"), s.full("flip")});
}

/// Particles and insertion-region centres must lie on the front side of every mesh wall (the side
/// its triangle normals point to); a point behind it means the normals face the wrong way.
void check_mesh_sides(const CaseSpec& c, const std::string& file,
                      const std::vector<MeshWallSite>& sites) {
    std::vector<std::pair<Vec3, std::string>> points;
    for (std::size_t k = 0; k < c.scene.particles.size(); ++k) {
        points.emplace_back(c.scene.particles[k].x, fmt::format("particle {}", k + 1));
    }
    for (std::size_t k = 0; k < c.scene.inserts.size(); ++k) {
        const Aabb& r = c.scene.inserts[k].region;
        points.emplace_back(0.5 * (r.lo + r.hi), fmt::format("the centre of insert {}", k + 1));
    }
    for (std::size_t w = 0; w < c.scene.mesh_walls.size(); ++w) {
        const auto& mesh = *c.scene.mesh_walls[w].mesh;
        for (const auto& [x, what] : points) {
            const double d = mesh.signed_distance(x);
            if (d < 0.0) {
                throw InputError(
                    file, sites[w].line, sites[w].path,
                    fmt::format("{} at ({:g}, {:g}, {:g}) m is {:.3g} m behind the mesh (its "
                                "triangle normals point away from it); set flip = true to "
                                "reverse them, or move the particles to the normals' side",
                                what, x.x(), x.y(), x.z(), -d));
            }
        }
    }
}

void read_walls(Section& root, CaseSpec& c, const std::map<std::string, int>& mats,
                std::vector<MeshWallSite>& sites) {
    for_each_table(root, "wall", [&](Section& s, std::size_t k) {
        const std::string type = s.text("type", std::nullopt, {"plane", "box", "cylinder", "mesh"});
        const int mat = material_index(s, "material", mats);
        const std::string name = s.text("name", fmt::format("{}{}", type, k));
        const std::size_t first_wall = c.scene.walls.size();
        if (type == "mesh") {
            read_mesh_wall(s, c, name, mat, sites);
        } else if (type == "plane") {
            dynamics::PlaneWall w;
            w.point = s.vec3("point", std::nullopt, "m");
            w.normal = s.vec3("normal", std::nullopt, "-", true).normalized();
            c.scene.walls.push_back({name, w, mat});
        } else if (type == "box") {
            const Vec3 lo = s.vec3("min", std::nullopt, "m");
            const Vec3 hi = s.vec3("max", std::nullopt, "m");
            if (!((hi - lo).array() > 0.0).all()) {
                s.fail_at("max", "must exceed min in every coordinate");
            }
            const char* axes = "xyz";
            for (int a = 0; a < 3; ++a) {
                const Vec3 e = Vec3::Unit(a);
                c.scene.walls.push_back(
                    {fmt::format("{}.{}min", name, axes[a]), dynamics::PlaneWall{lo, e}, mat});
                c.scene.walls.push_back(
                    {fmt::format("{}.{}max", name, axes[a]), dynamics::PlaneWall{hi, -e}, mat});
            }
        } else {
            dynamics::CylinderWall w;
            w.axis_point = s.vec3("point", std::nullopt, "m");
            w.axis = s.vec3("axis", std::nullopt, "-", true).normalized();
            w.radius = s.real("radius", std::nullopt, positive(), "m");
            c.scene.walls.push_back({name, w, mat});
        }
        if (type == "mesh") {
            read_mesh_wall_temperature(s, c);
        } else {
            read_wall_temperature(s, c, first_wall);
        }
        s.finish({"point", "normal", "min", "max", "axis", "radius", "file", "scale", "translate",
                  "flip", "temperature"});
    });
}

/// Shape templates of a case, loaded once per name.
struct ShapeTable {
    std::vector<std::filesystem::path> dirs; ///< folders searched for NAME.toml, in order
    std::map<std::string, int> index;        ///< name -> index in SceneSpec::shapes
};

/// Folders searched for shape templates: the case file's folder and its shapes/ subfolder, then
/// $KILN_SHAPES, ./shapes and the source tree's shapes/ (io::default_shape_dirs).
ShapeTable shape_table_for(const std::string& case_file) {
    ShapeTable t;
    const std::filesystem::path dir = std::filesystem::path(case_file).parent_path();
    t.dirs.push_back(dir.empty() ? std::filesystem::path(".") : dir);
    t.dirs.push_back(t.dirs.front() / "shapes");
    for (auto& d : default_shape_dirs()) {
        t.dirs.push_back(d);
    }
    return t;
}

/// Largest half-axis ratio of a superquadric kiln run accepts (aspect ratio 1:10).
constexpr double kMaxAspect = 10.0;

/// Reads `shape = "name"` (absent: -1, a sphere). Loads and checks the template.
int read_shape(Section& s, CaseSpec& c, ShapeTable& shapes) {
    if (!s.has("shape")) {
        s.take("shape");
        return -1;
    }
    const std::string name = s.text("shape", std::nullopt);
    if (const auto it = shapes.index.find(name); it != shapes.index.end()) {
        return it->second;
    }
    std::filesystem::path file;
    try {
        file = find_shape_file(name, shapes.dirs);
    } catch (const InputError& e) {
        s.fail_at("shape", e.what());
    }
    geometry::ShapeTemplate t = read_shape_file(file);
    if (const auto* sq = std::get_if<geometry::Superquadric>(&t.shape)) {
        const double aspect = sq->half_axes.maxCoeff() / sq->half_axes.minCoeff();
        if (aspect > kMaxAspect * (1.0 + 1e-12)) {
            s.fail_at("shape", fmt::format("\"{}\" has a half-axis ratio of {:.3g}; kiln run "
                                           "supports superquadrics with aspect ratios up to {:g}",
                                           name, aspect, kMaxAspect));
        }
    }
    const int k = static_cast<int>(c.scene.shapes.size());
    c.scene.shapes.push_back(std::move(t));
    shapes.index[name] = k;
    return k;
}

/// Reads `orientation`: "random" or [w, x, y, z] (normalised here); `def_random` when absent.
dynamics::OrientationSpec read_orientation(Section& s, bool def_random) {
    dynamics::OrientationSpec o;
    o.random = def_random;
    const toml::node* n = s.take("orientation");
    if (n != nullptr) {
        if (const auto* str = n->as_string()) {
            if (str->get() != "random") {
                s.fail_at("orientation", fmt::format("\"{}\" is not allowed; allowed: \"random\" "
                                                     "or a quaternion [w, x, y, z]",
                                                     str->get()));
            }
            o.random = true;
        } else {
            const toml::array* a = n->as_array();
            if (a == nullptr || a->size() != 4) {
                s.fail_at("orientation", "expected \"random\" or a quaternion [w, x, y, z] "
                                         "(body -> world, any non-zero length)");
            }
            double v[4];
            for (std::size_t k = 0; k < 4; ++k) {
                const auto x = a->get(k)->value<double>();
                if (!x || !std::isfinite(*x)) {
                    s.fail_at("orientation", "expected 4 finite numbers [w, x, y, z]");
                }
                v[k] = *x;
            }
            const Quat q(v[0], v[1], v[2], v[3]);
            if (q.norm() == 0.0) {
                s.fail_at("orientation", "the quaternion must not be zero");
            }
            o.random = false;
            o.fixed = q.normalized();
        }
    }
    if (o.random) {
        s.out().insert_or_assign("orientation", "random");
    } else {
        s.out().insert_or_assign("orientation",
                                 toml::array{o.fixed.w(), o.fixed.x(), o.fixed.y(), o.fixed.z()});
    }
    return o;
}

void read_inserts(Section& root, CaseSpec& c, const std::map<std::string, int>& mats,
                  ShapeTable& shapes) {
    for_each_table(root, "insert", [&](Section& s, std::size_t) {
        dynamics::InsertSpec ins;
        const std::string type = s.text("type", std::nullopt, {"random", "lattice"});
        ins.kind = type == "random" ? dynamics::InsertSpec::Kind::random
                                    : dynamics::InsertSpec::Kind::lattice;
        ins.material = material_index(s, "material", mats);
        ins.region = read_region(s);
        ins.shape = read_shape(s, c, shapes);
        if (ins.shape >= 0) {
            if (s.has("radius")) {
                s.fail_at("radius", "a [[insert]] with a shape takes its size from the template; "
                                    "remove radius");
            }
            ins.size.radius = c.scene.shapes[static_cast<std::size_t>(ins.shape)].bounding_radius();
            ins.orientation = read_orientation(s, true);
        } else {
            if (s.has("orientation")) {
                s.fail_at("orientation", "only used with a shape");
            }
            ins.size = read_radius(s);
        }
        if (ins.kind == dynamics::InsertSpec::Kind::random) {
            ins.count = s.integer("count", std::nullopt, 1, 100'000'000);
        } else {
            ins.count = s.integer("count", 0, 0, 100'000'000);
            ins.spacing = s.real("spacing", 0.0, non_negative(), "m");
            if (ins.spacing > 0.0 && ins.spacing < 2.0 * ins.size.largest()) {
                s.fail_at("spacing",
                          fmt::format("{:g} m would overlap particles of radius {:g} m; "
                                      "allowed: 0 (automatic) or >= {:g}",
                                      ins.spacing, ins.size.largest(), 2.0 * ins.size.largest()));
            }
        }
        ins.velocity = s.vec3("velocity", Vec3::Zero(), "m/s");
        ins.omega = s.vec3("angular_velocity", Vec3::Zero(), "rad/s");
        s.finish({"spacing", "count", "radius", "shape", "orientation"});
        c.scene.inserts.push_back(ins);
    });
}

/// The optional [heat] section; checks that heat data elsewhere has one.
void read_heat(Section& root, CaseSpec& c, const toml::table& doc) {
    const toml::table* t = root.table("heat");
    thermal::HeatSpec& h = c.heat;
    h.wall_temperature.resize(c.scene.walls.size(), thermal::unset);
    h.mesh_wall_temperature.resize(c.scene.mesh_walls.size(), thermal::unset);
    if (t == nullptr) {
        // Heat data without a [heat] section is a mistake, not something to ignore silently.
        const auto refuse = [&](const char* array, const char* key, const char* what) {
            const toml::array* a = doc[array].as_array();
            for (std::size_t k = 0; a != nullptr && k < a->size(); ++k) {
                const toml::table* e = a->get(k)->as_table();
                if (e != nullptr && e->contains(key)) {
                    root.fail(fmt::format("{}[{}].{}", array, k, key),
                              static_cast<long>(e->get(key)->source().begin.line),
                              fmt::format("{} needs a [heat] section (step_multiple, solver, "
                                          "ambient, ...); add [heat] or remove it",
                                          what));
                }
            }
        };
        refuse("material", "heat", "a material heat table");
        refuse("wall", "temperature", "a wall temperature");
        refuse("particle", "temperature", "a particle temperature");
        return;
    }
    toml::table out_t;
    Section s(root.file(), *t, "heat", out_t);
    h.enabled = true;
    h.step_multiple = static_cast<int>(s.integer("step_multiple", 100, 1, 1'000'000'000));
    const std::string solver = s.text("solver", "cg", {"cg", "bicgstab", "cholmod"});
    h.solver.kind = solver == "cg"         ? heat::SolverKind::cg
                    : solver == "bicgstab" ? heat::SolverKind::bicgstab
                                           : heat::SolverKind::cholmod;
    if (h.solver.kind == heat::SolverKind::cholmod && !heat::cholmod_available()) {
        s.fail_at("solver", "\"cholmod\" is not available in this build (no SuiteSparse); "
                            "allowed: \"cg\", \"bicgstab\"");
    }
    h.solver.tolerance = s.real("tolerance", 1e-10, Range{0.0, 1.0, false, false}, "-");
    h.extrapolated_guess =
        s.text("initial_guess", "extrapolated", {"extrapolated", "last"}) == "extrapolated";
    h.solver.max_iterations = static_cast<int>(s.integer("max_iterations", 1000, 1, 1'000'000));
    h.ambient_temperature = s.real("ambient_temperature", 293.15, positive(), "K");
    h.heat_transfer_coefficient =
        s.real("heat_transfer_coefficient", 0.0, non_negative(), "W/(m^2 K)");
    if (s.has("flow_direction")) {
        h.stagnation = true;
        h.flow_direction = s.vec3("flow_direction", std::nullopt, "-", true).normalized();
        if (h.heat_transfer_coefficient == 0.0) {
            s.fail_at("flow_direction", "distributes the heat transfer coefficient around the "
                                        "stagnation point: set heat_transfer_coefficient > 0");
        }
    }
    h.flux = s.real("flux", 0.0, Range{}, "W/m^2");
    h.biot_threshold = s.real("biot_threshold", 0.1, positive(), "-");
    h.contact_radius = s.text("contact_radius", "hertz", {"hertz", "lens"}) == "hertz"
                           ? thermal::ContactRadius::hertz
                           : thermal::ContactRadius::lens;
    h.max_substeps = static_cast<int>(s.integer("max_substeps", 1024, 1, 1'000'000));
    h.gas.conductivity = s.real("gas_conductivity", 0.0, non_negative(), "W/(m K)");
    h.gas.porosity = s.real("gas_porosity", 0.4, Range{0.0, 1.0, false, false}, "-");
    h.gas.cutoff = s.real("gas_cutoff", 0.5, positive(), "-");
    h.radiation_cutoff = s.real("radiation_cutoff", 0.5, positive(), "-");
    if (s.has("radiation_temperature")) {
        h.radiation_temperature = s.real("radiation_temperature", std::nullopt, positive(), "K");
    }
    h.wall_gas = s.boolean("wall_gas_gap", false);
    if (h.wall_gas && !(h.gas.conductivity > 0.0)) {
        s.fail_at("wall_gas_gap", "conducts through the gas between particles and hot walls: "
                                  "set gas_conductivity > 0 (allowed with 0: false)");
    }
    h.wall_radiation = s.boolean("wall_radiation", false);
    h.collision_conduction = s.boolean("collision_conduction", false);
    c.scene.record_contact_onsets = h.collision_conduction; // the force loop records impacts
    h.sphere_rotation = s.boolean("sphere_rotation", true);
    h.field_output = s.boolean("field_output", false);
    if (const toml::node* n = s.take("field_particles")) {
        const toml::array* a = n->as_array();
        toml::array arr;
        for (std::size_t k = 0; a != nullptr && k < a->size(); ++k) {
            const toml::node* e = a->get(k);
            if (!e->is_integer() || e->as_integer()->get() < 0) {
                a = nullptr;
                break;
            }
            h.field_particles.push_back(static_cast<long>(e->as_integer()->get()));
            arr.push_back(e->as_integer()->get());
        }
        if (a == nullptr) {
            s.fail_at("field_particles", "expected an array of particle ids (integers >= 0)");
        }
        out_t.insert_or_assign("field_particles", arr);
    }
    s.finish({"flow_direction", "field_particles", "radiation_temperature"});
    root.out().insert_or_assign("heat", std::move(out_t));
}

} // namespace

CaseSpec read_case_text(const std::string& text, const std::string& name) {
    const toml::table doc = parse_toml_text(text, name);
    CaseSpec c;
    c.source_file = name;
    toml::table resolved;
    Section root(name, doc, "", resolved);

    // [simulation]
    {
        const toml::table* t = root.table("simulation");
        if (t == nullptr) {
            root.fail("simulation", 0, "missing required table [simulation] (time_step, end_time)");
        }
        toml::table out_t;
        Section s(name, *t, "simulation", out_t);
        std::string stem = name.substr(name.find_last_of('/') + 1);
        if (stem == "case.toml" && name.find('/') != std::string::npos) {
            const std::string dir = name.substr(0, name.find_last_of('/'));
            stem = dir.substr(dir.find_last_of('/') + 1);
        } else {
            stem = stem.substr(0, stem.find('.'));
        }
        c.run.name = s.text("name", stem);
        c.scene.time_step = s.real("time_step", std::nullopt, positive(), "s");
        c.run.end_time = s.real("end_time", std::nullopt, positive(), "s");
        c.scene.gravity = s.vec3("gravity", Vec3(0, 0, -9.81), "m/s^2");
        c.scene.seed =
            static_cast<std::uint64_t>(s.integer("seed", 1, 0, std::numeric_limits<long>::max()));
        c.scene.time_step_fraction =
            s.real("time_step_fraction", 0.1, Range{0, 1, false, true}, "-");
        c.scene.allow_unsafe_time_step = s.boolean("allow_unsafe_time_step", false);
        c.scene.expected_speed = s.real("expected_impact_speed", 0.0, non_negative(), "m/s");
        if (c.run.end_time < c.scene.time_step) {
            s.fail_at("end_time", fmt::format("{:g} s is shorter than one time step ({:g} s)",
                                              c.run.end_time, c.scene.time_step));
        }
        s.finish();
        resolved.insert_or_assign("simulation", std::move(out_t));
    }

    // [[material]]
    std::map<std::string, int> mats;
    for_each_table(root, "material", [&](Section& s, std::size_t) {
        Material m;
        m.name = s.text("name", std::nullopt);
        if (mats.count(m.name) != 0) {
            s.fail_at("name", fmt::format("material \"{}\" is defined twice; names must be unique",
                                          m.name));
        }
        m.youngs_modulus = s.real("youngs_modulus", std::nullopt, positive(), "Pa");
        m.poisson_ratio =
            s.real("poisson_ratio", std::nullopt, Range{-1.0, 0.5, false, false}, "-");
        m.density = s.real("density", std::nullopt, positive(), "kg/m^3");
        m.restitution = s.real("restitution", std::nullopt, Range{0.0, 1.0, false, true}, "-");
        m.friction = s.real("friction", 0.0, non_negative(), "-");
        m.rolling_friction = s.real("rolling_friction", 0.0, non_negative(), "-");
        c.heat.materials.push_back(read_material_heat(s, m));
        s.finish();
        mats[m.name] = static_cast<int>(c.scene.materials.size());
        c.scene.materials.push_back(m);
    });
    if (mats.empty()) {
        root.fail("material", 0, "at least one [[material]] table is required");
    }

    // [contact]
    {
        const toml::table* t = root.table("contact");
        const toml::table empty;
        toml::table out_t;
        Section s(name, t ? *t : empty, "contact", out_t);
        const std::string model = s.text("model", "hertz_mindlin", {"hertz_mindlin", "linear"});
        if (model == "linear") {
            contact::LinearSpringDashpot lin;
            lin.stiffness = s.real("stiffness", std::nullopt, positive(), "N/m");
            lin.tangential_ratio =
                s.real("tangential_stiffness_ratio", 2.0 / 7.0, Range{0, 10, false, true}, "-");
            c.scene.contact.law = lin;
        } else if (s.has("stiffness") || s.has("tangential_stiffness_ratio")) {
            s.fail_at(s.has("stiffness") ? "stiffness" : "tangential_stiffness_ratio",
                      "only used by model = \"linear\"; Hertz-Mindlin takes its stiffness from the "
                      "materials");
        }
        const std::string rolling = s.text("rolling", "none", {"none", "constant_torque"});
        c.scene.contact.rolling = rolling == "none" ? contact::RollingModel::none
                                                    : contact::RollingModel::constant_torque;
        c.scene.contact.clamp_normal_force = s.boolean("clamp_normal_force", true);
        c.scene.contact.rebound_restitution =
            s.text("restitution_meaning", "rebound", {"rebound", "dashpot"}) == "rebound";
        c.scene.skin = s.real("skin", 0.0, non_negative(), "m");
        c.scene.sort_particles = s.boolean("sort_particles", true);
        c.scene.narrow_phase = s.text("narrow_phase", "newton", {"newton", "gjk_epa"}) == "newton"
                                   ? dynamics::NarrowPhase::newton
                                   : dynamics::NarrowPhase::gjk_epa;
        c.scene.body_radius =
            s.text("body_radius", "first_touch", {"first_touch", "per_step"}) == "first_touch"
                ? dynamics::BodyRadius::first_touch
                : dynamics::BodyRadius::per_step;
        s.finish({"stiffness", "tangential_stiffness_ratio"});
        resolved.insert_or_assign("contact", std::move(out_t));
    }

    // [[pair]]
    for_each_table(root, "pair", [&](Section& s, std::size_t) {
        const toml::node* n = s.take("materials");
        const toml::array* a = n ? n->as_array() : nullptr;
        if (a == nullptr || a->size() != 2 || !a->get(0)->is_string() || !a->get(1)->is_string()) {
            s.fail("materials", n ? s.line_of("materials") : s.table_line(),
                   "expected an array of two material names");
        }
        PairOverride o;
        const std::string na = a->get(0)->as_string()->get();
        const std::string nb = a->get(1)->as_string()->get();
        for (const auto& nm : {na, nb}) {
            if (mats.count(nm) == 0) {
                s.fail_at("materials", fmt::format("unknown material \"{}\"", nm));
            }
        }
        o.a = mats.at(na);
        o.b = mats.at(nb);
        s.out().insert_or_assign("materials", toml::array{na, nb});
        if (s.has("restitution")) {
            o.restitution = s.real("restitution", std::nullopt, Range{0.0, 1.0, false, true}, "-");
        }
        if (s.has("friction")) {
            o.friction = s.real("friction", std::nullopt, non_negative(), "-");
        }
        if (s.has("rolling_friction")) {
            o.rolling_friction = s.real("rolling_friction", std::nullopt, non_negative(), "-");
        }
        s.finish({"restitution", "friction", "rolling_friction"});
        c.scene.pairs.push_back(o);
    });

    std::vector<MeshWallSite> mesh_sites;
    read_walls(root, c, mats, mesh_sites);

    // [[particle]]
    ShapeTable shapes = shape_table_for(name);
    for_each_table(root, "particle", [&](Section& s, std::size_t) {
        dynamics::ParticleSpec p;
        p.material = material_index(s, "material", mats);
        p.shape = read_shape(s, c, shapes);
        if (p.shape >= 0) {
            if (s.has("radius")) {
                s.fail_at("radius", "a [[particle]] with a shape takes its size from the "
                                    "template; remove radius");
            }
            p.radius = c.scene.shapes[static_cast<std::size_t>(p.shape)].bounding_radius();
            p.orientation = read_orientation(s, false);
        } else {
            if (s.has("orientation")) {
                s.fail_at("orientation", "only used with a shape");
            }
            p.radius = s.real("radius", std::nullopt, positive(), "m");
        }
        p.x = s.vec3("position", std::nullopt, "m");
        p.v = s.vec3("velocity", Vec3::Zero(), "m/s");
        p.omega = s.vec3("angular_velocity", Vec3::Zero(), "rad/s");
        c.heat.particle_temperature.push_back(
            s.has("temperature") ? s.real("temperature", std::nullopt, positive(), "K")
                                 : thermal::unset);
        s.finish({"radius", "shape", "orientation", "temperature"});
        c.scene.particles.push_back(p);
    });

    read_inserts(root, c, mats, shapes);
    if (c.scene.particles.empty() && c.scene.inserts.empty()) {
        root.fail("insert", 0, "the case has no particles; add [[particle]] or [[insert]] tables");
    }
    check_mesh_sides(c, name, mesh_sites);

    // [output]
    {
        const toml::table* t = root.table("output");
        const toml::table empty;
        toml::table out_t;
        Section s(name, t ? *t : empty, "output", out_t);
        const double T = c.run.end_time;
        c.output.vtk_interval = s.real("vtk_interval", T / 50.0, non_negative(), "s");
        c.output.monitor_interval = s.real("monitor_interval", T / 200.0, positive(), "s");
        // Group monitors: the mean temperature of the spheres and of each shape template.
        std::vector<std::string> allowed = monitor_names();
        allowed.push_back(std::string(group_temperature_prefix) + "sphere");
        for (const auto& shape : c.scene.shapes) {
            allowed.push_back(group_temperature_prefix + shape.name);
        }
        c.output.monitors =
            s.strings("monitors",
                      std::vector<std::string>{"time", "kinetic_energy", "rotational_energy",
                                               "contacts", "coordination", "max_overlap_ratio"},
                      allowed);
        c.output.checkpoint_interval = s.real("checkpoint_interval", 0.0, non_negative(), "s");
        c.output.progress = s.boolean("progress", true);
        s.finish();
        resolved.insert_or_assign("output", std::move(out_t));
    }

    read_heat(root, c, doc);

    // [run]
    {
        const toml::table* t = root.table("run");
        const toml::table empty;
        toml::table out_t;
        Section s(name, t ? *t : empty, "run", out_t);
        c.scene.threads = static_cast<int>(s.integer("threads", 0, 0, 1024));
        s.finish();
        resolved.insert_or_assign("run", std::move(out_t));
    }

    root.finish();
    std::ostringstream os;
    os << resolved << "\n";
    c.resolved_toml = os.str();
    return c;
}

CaseSpec read_case_file(const std::string& path) {
    std::ifstream in(path);
    if (!in) {
        throw InputError(path, 0, "", "cannot open the case file");
    }
    std::stringstream ss;
    ss << in.rdbuf();
    return read_case_text(ss.str(), path);
}

} // namespace kiln::io
