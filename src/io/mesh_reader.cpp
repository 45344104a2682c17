// Reader of .obj and .stl surface meshes; see mesh_reader.hpp.

#include "io/mesh_reader.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <fmt/format.h>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

namespace kiln::io {

namespace {

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

MeshInput read_obj(const std::filesystem::path& file) {
    std::ifstream in(file);
    if (!in) {
        throw InputError(file.string(), 0, "", "cannot open the mesh file");
    }
    MeshInput m;
    std::string line;
    long ln = 0;
    std::vector<std::vector<std::string>> face_tokens;
    std::vector<long> face_lines;
    while (std::getline(in, line)) {
        ++ln;
        std::istringstream ss(line);
        std::string tag;
        if (!(ss >> tag) || tag[0] == '#') {
            continue;
        }
        if (tag == "v") {
            double x = 0.0;
            double y = 0.0;
            double z = 0.0;
            if (!(ss >> x >> y >> z)) {
                throw InputError(file.string(), ln, "v", "expected three coordinates");
            }
            m.points.emplace_back(x, y, z);
        } else if (tag == "f") {
            std::vector<int> poly;
            std::string tok;
            while (ss >> tok) {
                const std::string idx = tok.substr(0, tok.find('/'));
                long i = 0;
                try {
                    i = std::stol(idx);
                } catch (const std::exception&) {
                    throw InputError(file.string(), ln, "f",
                                     fmt::format("'{}' is not a vertex index", tok));
                }
                // 1-based; negative indices count back from the last vertex read so far.
                const long n = static_cast<long>(m.points.size());
                const long k = i > 0 ? i - 1 : n + i;
                if (i == 0 || k < 0 || k >= n) {
                    throw InputError(file.string(), ln, "f",
                                     fmt::format("vertex index {} out of range 1 to {}", i, n));
                }
                poly.push_back(static_cast<int>(k));
            }
            if (poly.size() < 3) {
                throw InputError(file.string(), ln, "f", "a face needs at least 3 vertices");
            }
            for (std::size_t k = 1; k + 1 < poly.size(); ++k) {
                m.triangles.push_back({poly[0], poly[k], poly[k + 1]});
            }
        }
        // Other records (vn, vt, o, g, s, usemtl, mtllib) carry nothing a rigid body needs.
    }
    return m;
}

/// Vertex index of p, merging identical coordinates.
int merged(MeshInput& m, std::map<std::array<double, 3>, int>& ids, const Vec3& p) {
    const std::array<double, 3> key{p.x(), p.y(), p.z()};
    const auto [it, inserted] = ids.try_emplace(key, static_cast<int>(m.points.size()));
    if (inserted) {
        m.points.push_back(p);
    }
    return it->second;
}

MeshInput read_stl(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    if (!in) {
        throw InputError(file.string(), 0, "", "cannot open the mesh file");
    }
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    MeshInput m;
    std::map<std::array<double, 3>, int> ids;
    // Binary: 80-byte header, uint32 count, 50 bytes per triangle. A size that matches is binary
    // even if the header starts with "solid" (some exporters write that).
    std::uint32_t count = 0;
    if (bytes.size() >= 84) {
        std::memcpy(&count, bytes.data() + 80, 4);
    }
    if (bytes.size() >= 84 && bytes.size() == 84 + 50 * static_cast<std::size_t>(count)) {
        for (std::uint32_t t = 0; t < count; ++t) {
            const char* rec = bytes.data() + 84 + 50 * static_cast<std::size_t>(t);
            std::array<int, 3> tri{};
            for (int k = 0; k < 3; ++k) {
                float c[3];
                std::memcpy(c, rec + 12 * (k + 1), 12);
                tri[static_cast<std::size_t>(k)] = merged(m, ids, Vec3(c[0], c[1], c[2]));
            }
            m.triangles.push_back(tri);
        }
        return m;
    }
    std::istringstream ss(bytes);
    std::string line;
    long ln = 0;
    std::vector<int> corner;
    while (std::getline(ss, line)) {
        ++ln;
        std::istringstream ls(line);
        std::string tag;
        if (!(ls >> tag)) {
            continue;
        }
        if (ln == 1 && tag != "solid") {
            throw InputError(file.string(), 0, "",
                             "neither binary STL (size does not match the triangle count) nor "
                             "ASCII STL (does not start with 'solid')");
        }
        if (tag == "vertex") {
            double x = 0.0;
            double y = 0.0;
            double z = 0.0;
            if (!(ls >> x >> y >> z)) {
                throw InputError(file.string(), ln, "vertex", "expected three coordinates");
            }
            corner.push_back(merged(m, ids, Vec3(x, y, z)));
        } else if (tag == "endloop") {
            if (corner.size() != 3) {
                throw InputError(file.string(), ln, "loop",
                                 fmt::format("a facet needs 3 vertices, got {}", corner.size()));
            }
            m.triangles.push_back({corner[0], corner[1], corner[2]});
            corner.clear();
        }
    }
    return m;
}

/// Every undirected edge of the triangles must belong to exactly two of them.
void check_closed(const MeshInput& m, const std::filesystem::path& file) {
    std::map<std::array<int, 2>, int> uses;
    for (const auto& t : m.triangles) {
        for (int k = 0; k < 3; ++k) {
            const int i = t[static_cast<std::size_t>(k)];
            const int j = t[static_cast<std::size_t>((k + 1) % 3)];
            ++uses[{std::min(i, j), std::max(i, j)}];
        }
    }
    for (const auto& [e, n] : uses) {
        if (n != 2) {
            const Vec3& a = m.points[static_cast<std::size_t>(e[0])];
            const Vec3& b = m.points[static_cast<std::size_t>(e[1])];
            throw InputError(file.string(), 0, "",
                             fmt::format("the surface is not closed: the edge ({:g}, {:g}, {:g}) - "
                                         "({:g}, {:g}, {:g}) belongs to {} face(s), not 2",
                                         a.x(), a.y(), a.z(), b.x(), b.y(), b.z(), n));
        }
    }
}

} // namespace

MeshInput read_mesh_file(const std::filesystem::path& file, double scale) {
    return read_mesh_file(file, scale, true);
}

MeshInput read_mesh_file(const std::filesystem::path& file, double scale, bool require_closed) {
    const std::string ext = lower(file.extension().string());
    MeshInput m;
    if (ext == ".obj") {
        m = read_obj(file);
    } else if (ext == ".stl") {
        m = read_stl(file);
    } else {
        throw InputError(file.string(), 0, "",
                         fmt::format("unknown mesh format '{}'; allowed: .obj, .stl", ext));
    }
    if (require_closed && !m.triangles.empty()) {
        check_closed(m, file);
    }
    for (Vec3& p : m.points) {
        p *= scale;
    }
    return m;
}

} // namespace kiln::io
