#include "io/checkpoint.hpp"

#include "core/error.hpp"

#include <cstring>
#include <fmt/format.h>
#include <fstream>
#include <type_traits>

namespace kiln::io {

namespace {

// Version 2: body state (shape, orientation, angular momentum, inertia) and body contacts.
constexpr char magic[8] = {'K', 'I', 'L', 'N', 'C', 'K', 'P', '2'};

class Out {
  public:
    explicit Out(std::ofstream& f) : f_(f) {}
    template <class T> void pod(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        f_.write(reinterpret_cast<const char*>(&v), sizeof(T));
    }
    template <class T> void vec(const std::vector<T>& v) {
        pod(static_cast<std::uint64_t>(v.size()));
        if constexpr (std::is_same_v<T, Vec3>) {
            for (const Vec3& x : v) {
                f_.write(reinterpret_cast<const char*>(x.data()), 3 * sizeof(double));
            }
        } else if constexpr (std::is_same_v<T, Quat>) {
            for (const Quat& x : v) {
                f_.write(reinterpret_cast<const char*>(x.coeffs().data()), 4 * sizeof(double));
            }
        } else {
            static_assert(std::is_trivially_copyable_v<T>);
            f_.write(reinterpret_cast<const char*>(v.data()),
                     static_cast<std::streamsize>(v.size() * sizeof(T)));
        }
    }
    void str(const std::string& s) {
        pod(static_cast<std::uint64_t>(s.size()));
        f_.write(s.data(), static_cast<std::streamsize>(s.size()));
    }

  private:
    std::ofstream& f_;
};

class In {
  public:
    In(std::ifstream& f, std::string name) : f_(f), name_(std::move(name)) {}
    template <class T> void pod(T& v) {
        f_.read(reinterpret_cast<char*>(&v), sizeof(T));
        check();
    }
    template <class T> void vec(std::vector<T>& v) {
        std::uint64_t n = 0;
        pod(n);
        if (n > (std::uint64_t{1} << 40)) {
            throw InputError(name_, 0, "", "damaged checkpoint (absurd array length)");
        }
        v.resize(n);
        if constexpr (std::is_same_v<T, Vec3>) {
            for (Vec3& x : v) {
                f_.read(reinterpret_cast<char*>(x.data()), 3 * sizeof(double));
            }
        } else if constexpr (std::is_same_v<T, Quat>) {
            for (Quat& x : v) {
                f_.read(reinterpret_cast<char*>(x.coeffs().data()), 4 * sizeof(double));
            }
        } else {
            f_.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(n * sizeof(T)));
        }
        check();
    }
    void str(std::string& s) {
        std::uint64_t n = 0;
        pod(n);
        if (n > (std::uint64_t{1} << 30)) {
            throw InputError(name_, 0, "", "damaged checkpoint (absurd string length)");
        }
        s.resize(n);
        f_.read(s.data(), static_cast<std::streamsize>(n));
        check();
    }

  private:
    void check() const {
        if (!f_) {
            throw InputError(name_, 0, "", "truncated or unreadable checkpoint");
        }
    }
    std::ifstream& f_;
    std::string name_;
};

template <class IO, class State, class Store> void fields(IO& io, State& s, Store& p) {
    io.vec(p.id);
    io.vec(p.material);
    io.vec(p.radius);
    io.vec(p.mass);
    io.vec(p.inv_mass);
    io.vec(p.inv_inertia);
    io.vec(p.x);
    io.vec(p.v);
    io.vec(p.omega);
    io.vec(p.force);
    io.vec(p.torque);
    io.vec(p.shape);
    io.vec(p.q);
    io.vec(p.ang_mom);
    io.vec(p.inertia);
    io.vec(s.nl_offsets);
    io.vec(s.nl_partners);
    io.vec(s.nl_shear);
    io.vec(s.nl_x_build);
    io.vec(s.nl_ids);
    io.pod(s.nl_builds);
    io.vec(s.wall_shear);
    io.pod(s.time);
    io.pod(s.step);
    io.pod(s.next_id);
    io.pod(s.counters);
    io.str(s.rng);
    io.pod(s.narrow_phase);
}

/// Body contacts as parallel arrays (keys are plain data; Eigen vectors are written by value).
struct BodyContactArrays {
    std::vector<dynamics::BodyContactKey> keys;
    std::vector<Vec3> shear, normal, point, force;
    std::vector<double> overlap, r_eff;

    template <class IO> void io(IO& x) {
        x.vec(keys);
        x.vec(shear);
        x.vec(normal);
        x.vec(point);
        x.vec(force);
        x.vec(overlap);
        x.vec(r_eff);
    }
};

/// The checkpoint file opened for reading, positioned after its magic bytes; refuses a file that
/// cannot be opened or is not a kiln checkpoint.
std::ifstream open_checkpoint(const std::filesystem::path& file) {
    std::ifstream f(file, std::ios::binary);
    if (!f) {
        throw InputError(file.string(), 0, "", "cannot open the checkpoint file");
    }
    char m[sizeof magic] = {};
    f.read(m, sizeof m);
    if (!f || std::memcmp(m, magic, sizeof magic) != 0) {
        throw InputError(file.string(), 0, "", "not a kiln checkpoint (wrong magic bytes)");
    }
    return f;
}

} // namespace

/// Tag of the optional heat section after the mechanical state.
constexpr char heat_magic[8] = {'K', 'I', 'L', 'N', 'H', 'E', 'A', 'T'};

/// Tag of the optional list of pending impacts (thermal::PendingImpact) after the heat section.
constexpr char onset_magic[8] = {'K', 'I', 'L', 'N', 'I', 'M', 'P', '1'};
/// Tag of the optional grid orientations of resolved spheres (ThermalState::orientations), last.
constexpr char orientation_magic[8] = {'K', 'I', 'L', 'N', 'O', 'R', 'I', '1'};
/// Tag of the optional resolved fields one thermal step earlier (ThermalState::previous_fields),
/// after the orientations.
constexpr char previous_magic[8] = {'K', 'I', 'L', 'N', 'P', 'R', 'V', '1'};
/// Tag of the same list before impacts carried body-frame contacts (not readable any more).
constexpr char old_onset_magic[8] = {'K', 'I', 'L', 'N', 'O', 'N', 'S', 'T'};

template <class IO, class Heat> void heat_fields(IO& io, Heat& h) {
    io.vec(h.fields);
    io.vec(h.lumped);
    io.vec(h.ids);
    io.pod(h.external_heat);
    io.pod(h.counters);
}

void write_checkpoint(const std::filesystem::path& file, const dynamics::SystemState& s) {
    write_checkpoint(file, s, nullptr);
}

std::optional<thermal::ThermalState> read_checkpoint_heat(const std::filesystem::path& file) {
    std::ifstream f = open_checkpoint(file);
    dynamics::SystemState s;
    In in(f, file.string());
    fields(in, s, s.particles);
    BodyContactArrays b;
    b.io(in); // body contacts come before the heat section
    char h[sizeof heat_magic] = {};
    f.read(h, sizeof h);
    if (!f || std::memcmp(h, heat_magic, sizeof heat_magic) != 0) {
        return std::nullopt;
    }
    thermal::ThermalState t;
    heat_fields(in, t);
    // Optional, in this order: contact onsets not yet exchanged (collision conduction), the
    // grid orientations of resolved spheres, the fields one thermal step earlier.
    char o[sizeof onset_magic] = {};
    f.read(o, sizeof o);
    if (f && std::memcmp(o, onset_magic, sizeof onset_magic) == 0) {
        in.vec(t.onsets);
        f.read(o, sizeof o);
    } else if (f && std::memcmp(o, old_onset_magic, sizeof old_onset_magic) == 0) {
        throw InputError(file.string(), 0, "",
                         "pending contact onsets in an older checkpoint format (before impacts "
                         "of bodies): restart the run from its case file");
    }
    if (f && std::memcmp(o, orientation_magic, sizeof orientation_magic) == 0) {
        in.vec(t.orientations);
        f.read(o, sizeof o);
    }
    if (f && std::memcmp(o, previous_magic, sizeof previous_magic) == 0) {
        in.vec(t.previous_fields);
    }
    return t;
}

void write_checkpoint(const std::filesystem::path& file, const dynamics::SystemState& s,
                      const thermal::ThermalState* heat) {
    const std::filesystem::path tmp = file.string() + ".tmp";
    {
        std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
        if (!f) {
            throw InputError(tmp.string(), 0, "", "cannot write the checkpoint file");
        }
        f.write(magic, sizeof magic);
        Out out(f);
        fields(out, s, s.particles);
        BodyContactArrays b;
        for (const auto& [k, c] : s.body_contacts) {
            b.keys.push_back(k);
            b.shear.push_back(c.shear);
            b.normal.push_back(c.normal);
            b.point.push_back(c.point);
            b.force.push_back(c.force);
            b.overlap.push_back(c.overlap);
            b.r_eff.push_back(c.r_eff);
        }
        b.io(out);
        if (heat != nullptr) {
            f.write(heat_magic, sizeof heat_magic);
            thermal::ThermalState copy = *heat;
            heat_fields(out, copy);
            if (!copy.onsets.empty()) {
                static_assert(std::is_trivially_copyable_v<thermal::PendingImpact>);
                f.write(onset_magic, sizeof onset_magic);
                out.vec(copy.onsets);
            }
            if (!copy.orientations.empty()) {
                f.write(orientation_magic, sizeof orientation_magic);
                out.vec(copy.orientations);
            }
            if (!copy.previous_fields.empty()) {
                f.write(previous_magic, sizeof previous_magic);
                out.vec(copy.previous_fields);
            }
        }
        if (!f) {
            throw InputError(tmp.string(), 0, "", "writing the checkpoint failed (disk full?)");
        }
    }
    std::filesystem::rename(tmp, file);
}

dynamics::SystemState read_checkpoint(const std::filesystem::path& file) {
    std::ifstream f = open_checkpoint(file);
    dynamics::SystemState s;
    In in(f, file.string());
    fields(in, s, s.particles);
    BodyContactArrays b;
    b.io(in);
    const std::size_t n = b.keys.size();
    if (b.shear.size() != n || b.normal.size() != n || b.point.size() != n || b.force.size() != n ||
        b.overlap.size() != n || b.r_eff.size() != n) {
        throw InputError(file.string(), 0, "", "damaged checkpoint (body contact arrays differ)");
    }
    for (std::size_t k = 0; k < n; ++k) {
        s.body_contacts.emplace_back(b.keys[k],
                                     dynamics::BodyContact{b.shear[k], b.normal[k], b.point[k],
                                                           b.overlap[k], b.r_eff[k], b.force[k]});
    }
    return s;
}

} // namespace kiln::io
