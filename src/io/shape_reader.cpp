// Strict reader of shape template files; see shape_reader.hpp and shapes/README.md.

#include "io/shape_reader.hpp"
#include "io/toml_text.hpp"

#include "core/error.hpp"
#include "geometry/hull.hpp"
#include "io/mesh_reader.hpp"

#include <cmath>
#include <cstdlib>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <fstream>
#include <numbers>
#include <set>
#include <sstream>
#include <toml++/toml.h>

namespace kiln::io {

namespace {

using geometry::ClumpSphere;

/// A table read with location-aware errors; unknown keys are reported by finish().
class Reader {
  public:
    Reader(std::string file, const toml::table& t, std::string prefix)
        : file_(std::move(file)), t_(t), prefix_(std::move(prefix)) {}

    [[noreturn]] void fail(std::string_view key, const std::string& what) const {
        const toml::node* n = t_.get(key);
        const long line = n != nullptr ? static_cast<long>(n->source().begin.line)
                                       : static_cast<long>(t_.source().begin.line);
        throw InputError(file_, line, prefix_ + std::string(key), what);
    }

    [[nodiscard]] bool has(std::string_view key) const { return t_.contains(key); }

    double real(std::string_view key, double lo, double hi, std::string_view unit) {
        seen_.insert(std::string(key));
        const toml::node* n = t_.get(key);
        if (n == nullptr) {
            fail(key, fmt::format("missing required value ({}, {:g} to {:g})", unit, lo, hi));
        }
        const auto v = n->value<double>();
        if (!v || !n->is_number()) {
            fail(key, fmt::format("expected a number ({})", unit));
        }
        if (!(*v >= lo && *v <= hi)) {
            fail(key,
                 fmt::format("{:g} {} is out of range; allowed: {:g} to {:g}", *v, unit, lo, hi));
        }
        return *v;
    }

    double real_or(std::string_view key, double def, double lo, double hi, std::string_view unit) {
        return has(key) ? real(key, lo, hi, unit) : (seen_.insert(std::string(key)), def);
    }

    long integer(std::string_view key, long def, long lo, long hi) {
        seen_.insert(std::string(key));
        const toml::node* n = t_.get(key);
        if (n == nullptr) {
            return def;
        }
        if (!n->is_integer()) {
            fail(key, "expected an integer");
        }
        const long v = static_cast<long>(n->as_integer()->get());
        if (v < lo || v > hi) {
            fail(key, fmt::format("{} is out of range; allowed: {} to {}", v, lo, hi));
        }
        return v;
    }

    bool boolean(std::string_view key, bool def) {
        seen_.insert(std::string(key));
        const toml::node* n = t_.get(key);
        if (n == nullptr) {
            return def;
        }
        if (!n->is_boolean()) {
            fail(key, "expected true or false");
        }
        return n->as_boolean()->get();
    }

    std::string string(std::string_view key, const std::string& def,
                       const std::set<std::string>& allowed) {
        seen_.insert(std::string(key));
        const toml::node* n = t_.get(key);
        if (n == nullptr) {
            if (def.empty() && !allowed.empty()) {
                fail(key,
                     fmt::format("missing required value; allowed: {}", fmt::join(allowed, ", ")));
            }
            return def;
        }
        if (!n->is_string()) {
            fail(key, "expected a string");
        }
        std::string v = n->as_string()->get();
        if (!allowed.empty() && !allowed.contains(v)) {
            fail(key, fmt::format("'{}' is not allowed; allowed: {}", v, fmt::join(allowed, ", ")));
        }
        return v;
    }

    template <int N>
    Eigen::Matrix<double, N, 1> vec(std::string_view key, double lo, double hi,
                                    std::string_view unit) {
        seen_.insert(std::string(key));
        const toml::node* n = t_.get(key);
        if (n == nullptr) {
            fail(key, fmt::format("missing required array of {} numbers ({})", N, unit));
        }
        const toml::array* a = n->as_array();
        if (a == nullptr || a->size() != static_cast<std::size_t>(N)) {
            fail(key, fmt::format("expected an array of {} numbers ({})", N, unit));
        }
        Eigen::Matrix<double, N, 1> v;
        for (int i = 0; i < N; ++i) {
            const auto x = (*a)[static_cast<std::size_t>(i)].value<double>();
            if (!x) {
                fail(key, fmt::format("expected an array of {} numbers ({})", N, unit));
            }
            if (!(*x >= lo && *x <= hi)) {
                fail(key, fmt::format("component {} = {:g} {} is out of range; allowed: {:g} to "
                                      "{:g}",
                                      i, *x, unit, lo, hi));
            }
            v[i] = *x;
        }
        return v;
    }

    const toml::array* array_of_tables(std::string_view key) {
        seen_.insert(std::string(key));
        const toml::node* n = t_.get(key);
        if (n == nullptr) {
            return nullptr;
        }
        if (!n->is_array_of_tables()) {
            fail(key, "expected an array of tables ([[...]])");
        }
        return n->as_array();
    }

    const toml::table* table(std::string_view key) {
        seen_.insert(std::string(key));
        const toml::node* n = t_.get(key);
        if (n != nullptr && !n->is_table()) {
            fail(key, "expected a table");
        }
        return n != nullptr ? n->as_table() : nullptr;
    }

    /// Every key not read is an error (a typo must not pass silently).
    void finish() const {
        for (const auto& [k, v] : t_) {
            if (!seen_.contains(std::string(k.str()))) {
                fail(k.str(), "unknown key");
            }
        }
    }

  private:
    std::string file_;
    const toml::table& t_;
    std::string prefix_;
    std::set<std::string> seen_;
};

constexpr double kMaxLength = 10.0; // m; anything larger is a unit mistake, not a particle

std::vector<ClumpSphere> read_clump_spheres(Reader& root, const std::string& file) {
    std::vector<ClumpSphere> out;
    if (const toml::array* spheres = root.array_of_tables("sphere")) {
        for (std::size_t i = 0; i < spheres->size(); ++i) {
            Reader s(file, *(*spheres)[i].as_table(), fmt::format("sphere[{}].", i));
            ClumpSphere cs;
            cs.centre = s.vec<3>("centre", -kMaxLength, kMaxLength, "m");
            cs.radius = s.real("radius", 1e-9, kMaxLength, "m");
            s.finish();
            out.push_back(cs);
        }
    }
    if (const toml::array* rings = root.array_of_tables("ring")) {
        for (std::size_t i = 0; i < rings->size(); ++i) {
            Reader s(file, *(*rings)[i].as_table(), fmt::format("ring[{}].", i));
            const long count = s.integer("count", 0, 1, 10000);
            const double ring_radius = s.real("ring_radius", 0.0, kMaxLength, "m");
            const double z = s.real("z", -kMaxLength, kMaxLength, "m");
            const double radius = s.real("radius", 1e-9, kMaxLength, "m");
            const double phase = s.real_or("phase", 0.0, -360.0, 360.0, "deg");
            const bool centre = s.boolean("centre_sphere", false);
            s.finish();
            for (long k = 0; k < count; ++k) {
                const double a =
                    (phase + 360.0 * static_cast<double>(k) / static_cast<double>(count)) *
                    std::numbers::pi / 180.0;
                out.push_back(
                    {Vec3(ring_radius * std::cos(a), ring_radius * std::sin(a), z), radius});
            }
            if (centre) {
                out.push_back({Vec3(0.0, 0.0, z), radius});
            }
        }
    }
    if (out.empty()) {
        root.fail("sphere", "a clump needs [[sphere]] or [[ring]] entries");
    }
    return out;
}

geometry::ReferenceSolid read_reference(Reader& root, const std::string& file) {
    geometry::ReferenceSolid ref;
    ref.kind = "none";
    const toml::table* t = root.table("reference");
    if (t == nullptr) {
        return ref;
    }
    Reader r(file, *t, "reference.");
    ref.kind = r.string("kind", "", {"sphere", "cylinder", "box"});
    if (ref.kind == "sphere") {
        ref.size = Vec3(r.real("radius", 1e-9, kMaxLength, "m"), 0.0, 0.0);
    } else if (ref.kind == "cylinder") {
        ref.size = Vec3(r.real("radius", 1e-9, kMaxLength, "m"),
                        r.real("length", 1e-9, kMaxLength, "m"), 0.0);
    } else {
        ref.size = r.vec<3>("edges", 1e-9, kMaxLength, "m");
    }
    r.finish();
    return ref;
}

/// Polyhedron template: the convex hull of the mesh file's points. Non-convex input is replaced by
/// its hull with a warning stating the volume ratio (decomposition is not offered).
geometry::ShapeTemplate read_polyhedron(Reader& root, const std::string& file,
                                        const std::string& stem) {
    const std::string mesh_name = root.string("mesh", "", {});
    if (mesh_name.empty()) {
        root.fail("mesh", "missing required value: a .obj or .stl file, relative to this file");
    }
    const double scale = root.real_or("scale", 1.0, 1e-9, 1e3, "m per file unit");
    const std::filesystem::path mesh_file = std::filesystem::path(file).parent_path() / mesh_name;
    if (!std::filesystem::exists(mesh_file)) {
        root.fail("mesh", fmt::format("mesh file {} not found", mesh_file.string()));
    }
    const MeshInput in = read_mesh_file(mesh_file, scale);
    const geometry::Hull hull = geometry::convex_hull(in.points, mesh_file.string());
    geometry::ShapeTemplate t = geometry::make_template(
        stem, geometry::make_polyhedron(hull.vertices, hull.faces, mesh_file.string()));
    if (!in.triangles.empty()) {
        // A closed input surface encloses at most its hull's volume; less means it is not convex.
        const double v_in =
            std::abs(geometry::polyhedron_mass_properties(in.points, in.triangles).volume);
        constexpr double kConvexTolerance = 1e-9; // relative round-off of the two volume sums
        if (v_in < (1.0 - kConvexTolerance) * t.volume) {
            t.warnings.push_back(fmt::format(
                "{}: the mesh is not convex; using its convex hull (mesh volume / hull volume = "
                "{:.6f})",
                mesh_file.string(), v_in / t.volume));
        }
    }
    return t;
}

} // namespace

geometry::ShapeTemplate read_shape_text(const std::string& text, const std::string& name) {
    const toml::table doc = parse_toml_text(text, name);
    Reader root(name, doc, "");
    const std::string kind =
        root.string("kind", "", {"sphere", "clump", "superquadric", "polyhedron"});
    (void)root.string("description", "-", {});
    const std::string stem = std::filesystem::path(name).stem().string();
    geometry::ShapeTemplate t;
    if (kind == "sphere") {
        t = geometry::make_template(stem,
                                    geometry::Sphere{root.real("radius", 1e-9, kMaxLength, "m")});
    } else if (kind == "superquadric") {
        geometry::Superquadric q;
        q.half_axes = root.vec<3>("half_axes", 1e-9, kMaxLength, "m");
        const Eigen::Vector2d e = root.vec<2>("exponents", geometry::Superquadric::kMinExponent,
                                              geometry::Superquadric::kMaxExponent, "-");
        q.e1 = e[0];
        q.e2 = e[1];
        q.validate(name);
        t = geometry::make_template(stem, q);
    } else if (kind == "polyhedron") {
        t = read_polyhedron(root, name, stem);
    } else {
        const std::vector<ClumpSphere> spheres = read_clump_spheres(root, name);
        const long n = root.integer("resolution", 1200, 50, 20000);
        t = geometry::make_template(stem, geometry::make_clump(spheres, name, static_cast<int>(n)));
    }
    t.reference = read_reference(root, name);
    t.density_correction = root.boolean("density_correction", false);
    if (t.density_correction && t.reference.kind == "none") {
        root.fail("density_correction", "needs a [reference] solid whose volume the mass matches");
    }
    root.finish();
    t.source = name;
    return t;
}

geometry::ShapeTemplate read_shape_file(const std::filesystem::path& file) {
    std::ifstream in(file);
    if (!in) {
        throw InputError(file.string(), 0, "", "cannot open the shape file");
    }
    std::stringstream ss;
    ss << in.rdbuf();
    return read_shape_text(ss.str(), file.string());
}

std::vector<std::filesystem::path> default_shape_dirs() {
    std::vector<std::filesystem::path> dirs;
    if (const char* env = std::getenv("KILN_SHAPES"); env != nullptr && *env != '\0') {
        dirs.emplace_back(env);
    }
    dirs.emplace_back("shapes");
    dirs.emplace_back(KILN_SOURCE_SHAPES_DIR);
    return dirs;
}

std::filesystem::path find_shape_file(const std::string& name_or_path,
                                      const std::vector<std::filesystem::path>& dirs) {
    const std::filesystem::path p(name_or_path);
    if (p.extension() == ".toml") {
        if (std::filesystem::exists(p)) {
            return p;
        }
        throw InputError(name_or_path, 0, "", "shape file not found");
    }
    std::vector<std::string> tried;
    for (const auto& d : dirs) {
        const std::filesystem::path f = d / (name_or_path + ".toml");
        if (std::filesystem::exists(f)) {
            return f;
        }
        tried.push_back(d.string());
    }
    throw InputError(fmt::format("unknown shape '{}': no {}.toml in {}", name_or_path, name_or_path,
                                 fmt::join(tried, ", ")));
}

geometry::ShapeRegistry load_shape_folder(const std::filesystem::path& dir) {
    geometry::ShapeRegistry reg;
    for (const auto& e : std::filesystem::directory_iterator(dir)) {
        if (e.path().extension() == ".toml") {
            reg.add(read_shape_file(e.path()));
        }
    }
    return reg;
}

} // namespace kiln::io
