// Particle insertion at start-up: lattice filling and random sequential placement without overlap.

#include "core/error.hpp"
#include "dynamics/system.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <functional>
#include <numeric>
#include <unordered_map>

namespace kiln::dynamics {

double SizeDistribution::largest() const {
    switch (kind) {
    case Kind::constant:
        return radius;
    case Kind::uniform:
    case Kind::normal:
        return max;
    case Kind::discrete:
        return values.empty() ? 0.0 : *std::max_element(values.begin(), values.end());
    }
    return 0.0;
}

double SizeDistribution::sample(std::mt19937_64& rng) const {
    switch (kind) {
    case Kind::constant:
        return radius;
    case Kind::uniform:
        return std::uniform_real_distribution<double>(min, max)(rng);
    case Kind::normal: {
        std::normal_distribution<double> d(mean, stddev);
        for (int tries = 0; tries < 1000; ++tries) {
            const double r = d(rng);
            if (r >= min && r <= max) {
                return r;
            }
        }
        return std::clamp(mean, min, max);
    }
    case Kind::discrete: {
        std::discrete_distribution<std::size_t> d(weights.begin(), weights.end());
        return values[d(rng)];
    }
    }
    return radius;
}

namespace {

/// Hash grid of placed spheres for overlap checks during insertion.
class PlacementGrid {
  public:
    explicit PlacementGrid(double cell) : cell_(cell) {}
    void add(const Vec3& x, double r) {
        const std::size_t k = centres_.size();
        centres_.push_back(x);
        radii_.push_back(r);
        cells_[key(x)].push_back(k);
    }
    [[nodiscard]] bool free(const Vec3& x, double r) const {
        const long cx = coord(x[0]);
        const long cy = coord(x[1]);
        const long cz = coord(x[2]);
        for (long z = cz - 1; z <= cz + 1; ++z) {
            for (long y = cy - 1; y <= cy + 1; ++y) {
                for (long xx = cx - 1; xx <= cx + 1; ++xx) {
                    const auto it = cells_.find(pack(xx, y, z));
                    if (it == cells_.end()) {
                        continue;
                    }
                    for (const std::size_t k : it->second) {
                        const double s = r + radii_[k];
                        if ((centres_[k] - x).squaredNorm() < s * s) {
                            return false;
                        }
                    }
                }
            }
        }
        return true;
    }

  private:
    [[nodiscard]] long coord(double v) const { return static_cast<long>(std::floor(v / cell_)); }
    static std::int64_t pack(long x, long y, long z) {
        return ((x & 0x1FFFFF) << 42) | ((y & 0x1FFFFF) << 21) | (z & 0x1FFFFF);
    }
    [[nodiscard]] std::int64_t key(const Vec3& x) const {
        return pack(coord(x[0]), coord(x[1]), coord(x[2]));
    }
    double cell_;
    std::vector<Vec3> centres_;
    std::vector<double> radii_;
    std::unordered_map<std::int64_t, std::vector<std::size_t>> cells_;
};

} // namespace

void System::place(const InsertSpec& ins, double radius, const Vec3& x) {
    if (ins.shape >= 0) {
        // A body's insertion radius is its bounding radius (the reader sets a constant size).
        add_body(ins.material, ins.shape, x, ins.velocity, ins.omega,
                 initial_orientation(ins.orientation));
    } else {
        add_particle(ins.material, radius, x, ins.velocity, ins.omega);
    }
}

void System::insert(const InsertSpec& ins) {
    const double rmax = ins.size.largest();
    const Aabb& reg = ins.region;
    if (ins.kind == InsertSpec::Kind::lattice) {
        const double a = ins.spacing > 0.0 ? ins.spacing : 2.0 * rmax;
        const Vec3 room = reg.extent() - Vec3::Constant(2.0 * rmax);
        const auto count = [&](int k) {
            return room[k] < 0 ? 0L : 1 + static_cast<long>(room[k] / a);
        };
        const long nx = count(0);
        const long ny = count(1);
        const long nz = count(2);
        const long capacity = nx * ny * nz;
        if (capacity == 0 || (ins.count > capacity)) {
            throw InputError(
                "", 0, "insert.count",
                fmt::format("a lattice of spacing {:.4g} m in this region holds {} particles, "
                            "{} requested; enlarge the region or reduce count",
                            a, capacity, ins.count));
        }
        const long want = ins.count > 0 ? ins.count : capacity;
        long placed = 0;
        for (long z = 0; z < nz && placed < want; ++z) {
            for (long y = 0; y < ny && placed < want; ++y) {
                for (long x = 0; x < nx && placed < want; ++x) {
                    const Vec3 c = reg.lo + Vec3::Constant(rmax) +
                                   a * Vec3(static_cast<double>(x), static_cast<double>(y),
                                            static_cast<double>(z));
                    place(ins, ins.size.sample(rng_), c);
                    ++placed;
                }
            }
        }
        return;
    }

    // Random sequential addition: uniform candidate centres, rejected when they overlap anything.
    double rall = rmax;
    for (double r : p_.radius) {
        rall = std::max(rall, r);
    }
    PlacementGrid grid(2.0 * rall);
    for (std::size_t i = 0; i < p_.size(); ++i) {
        grid.add(p_.x[i], p_.radius[i]);
    }
    // The radii are drawn first, once per particle, and placed largest first: drawing a new radius
    // for every rejected position would favour small particles (they fit more often) and skew the
    // size distribution, the more so the fuller the region.
    std::vector<double> radii(static_cast<std::size_t>(std::max(0L, ins.count)));
    for (double& r : radii) {
        r = ins.size.sample(rng_);
    }
    std::stable_sort(radii.begin(), radii.end(), std::greater<>());
    const long max_attempts = 1000 * std::max(1L, ins.count) + 100000;
    long attempts = 0;
    long placed = 0;
    while (placed < ins.count && attempts < max_attempts) {
        ++attempts;
        const double r = radii[static_cast<std::size_t>(placed)];
        Vec3 c;
        for (int k = 0; k < 3; ++k) {
            const double lo = reg.lo[k] + r;
            const double hi = reg.hi[k] - r;
            if (hi < lo) {
                throw InputError(
                    "", 0, "insert.region",
                    fmt::format("region narrower than a particle of radius {:.4g} m", r));
            }
            c[k] = std::uniform_real_distribution<double>(lo, hi)(rng_);
        }
        if (!grid.free(c, r)) {
            continue;
        }
        grid.add(c, r);
        place(ins, r, c);
        ++placed;
    }
    if (placed < ins.count) {
        const double vol = reg.extent().prod();
        throw InputError(
            "", 0, "insert.count",
            fmt::format("placed only {} of {} particles without overlap after {} attempts "
                        "(region volume {:.4g} m^3); enlarge the region or reduce count "
                        "(random placement reaches a solid fraction of about 0.3)",
                        placed, ins.count, attempts, vol));
    }
}

} // namespace kiln::dynamics
