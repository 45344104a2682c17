#include "contact/neighbour_list.hpp"

#include <gtest/gtest.h>
#include <map>
#include <random>
#include <set>

namespace kiln::contact {
namespace {

ParticleStore random_cloud(std::size_t n, double box, std::uint64_t seed) {
    ParticleStore p;
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, box);
    std::uniform_real_distribution<double> r(0.5e-3, 1.5e-3);
    for (std::size_t i = 0; i < n; ++i) {
        p.add_sphere(static_cast<std::int64_t>(i), 0, r(rng), 1000.0, Vec3(u(rng), u(rng), u(rng)),
                     Vec3::Zero(), Vec3::Zero());
    }
    return p;
}

using IdPair = std::pair<std::int64_t, std::int64_t>;

std::set<IdPair> brute_force(const ParticleStore& p, double skin) {
    std::set<IdPair> s;
    for (std::size_t i = 0; i < p.size(); ++i) {
        for (std::size_t j = i + 1; j < p.size(); ++j) {
            const double cut = p.radius[i] + p.radius[j] + skin;
            if ((p.x[i] - p.x[j]).squaredNorm() < cut * cut) {
                s.insert(std::minmax(p.id[i], p.id[j]));
            }
        }
    }
    return s;
}

std::set<IdPair> listed(const NeighbourList& nl, const ParticleStore& p) {
    std::set<IdPair> s;
    for (std::size_t i = 0; i < p.size(); ++i) {
        for (auto k = nl.offsets()[i]; k < nl.offsets()[i + 1]; ++k) {
            const IdPair pr = std::minmax(p.id[i], p.id[nl.partners()[k]]);
            EXPECT_TRUE(s.insert(pr).second) << "pair listed twice";
        }
    }
    return s;
}

TEST(NeighbourList, FindsExactlyTheBruteForcePairs) {
    for (const bool sort : {false, true}) {
        ParticleStore p = random_cloud(2000, 0.03, 7);
        NeighbourList nl(0.3e-3);
        nl.build(p, sort);
        EXPECT_EQ(listed(nl, p), brute_force(p, 0.3e-3)) << "sort = " << sort;
        EXPECT_FALSE(nl.needs_rebuild(p));
    }
}

TEST(NeighbourList, SortingKeepsEveryParticleOnce) {
    ParticleStore p = random_cloud(500, 0.02, 3);
    const ParticleStore before = p;
    NeighbourList nl(0.2e-3);
    const auto order = nl.build(p, true);
    ASSERT_EQ(order.size(), p.size());
    for (std::size_t k = 0; k < p.size(); ++k) {
        EXPECT_EQ(p.id[k], before.id[order[k]]);
        EXPECT_EQ(p.x[k], before.x[order[k]]);
    }
}

TEST(NeighbourList, RebuildIsTriggeredByHalfSkinMotion) {
    ParticleStore p = random_cloud(100, 0.02, 5);
    NeighbourList nl(1e-3);
    nl.build(p, false);
    p.x[10].x() += 0.49e-3;
    EXPECT_FALSE(nl.needs_rebuild(p));
    p.x[10].x() += 0.02e-3;
    EXPECT_TRUE(nl.needs_rebuild(p));
}

TEST(NeighbourList, HistoryFollowsPairsThroughSortingAndRoleSwaps) {
    ParticleStore p = random_cloud(1500, 0.025, 11);
    NeighbourList nl(0.3e-3);
    nl.build(p, false);
    // Tag each entry with a value that encodes the ordered pair (i's id, j's id).
    std::map<IdPair, Vec3> tag;
    for (std::size_t i = 0; i < p.size(); ++i) {
        for (auto k = nl.offsets()[i]; k < nl.offsets()[i + 1]; ++k) {
            const Vec3 v(static_cast<double>(p.id[i]), static_cast<double>(p.id[nl.partners()[k]]),
                         1.0);
            nl.shear()[k] = v;
            tag[{p.id[i], p.id[nl.partners()[k]]}] = v;
        }
    }
    nl.build(p, true); // reorders, so many pairs change which particle owns the entry
    std::size_t checked = 0;
    std::size_t swapped = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        for (auto k = nl.offsets()[i]; k < nl.offsets()[i + 1]; ++k) {
            const std::int64_t a = p.id[i];
            const std::int64_t b = p.id[nl.partners()[k]];
            if (const auto it = tag.find({a, b}); it != tag.end()) {
                EXPECT_EQ(nl.shear()[k], it->second);
            } else {
                ASSERT_TRUE(tag.count({b, a}));
                EXPECT_EQ(nl.shear()[k], -tag.at({b, a})); // history of i relative to j flips sign
                ++swapped;
            }
            ++checked;
        }
    }
    EXPECT_EQ(checked, tag.size());
    EXPECT_GT(swapped, 0U);
}

// A sorted store is searched as runs of cells (index ranges, eight partners at a time with
// AVX-512): each row must hold exactly its higher partners, in increasing index order (the order of
// the cell-by-cell search), and owners() must name the row of every entry. The dense cloud gives
// rows longer than sixteen entries (owners are written sixteen at a time).
TEST(NeighbourList, SortedRowsHoldTheirHigherPartnersInIncreasingOrder) {
    for (const double skin : {0.3e-3, 3e-3}) {
        ParticleStore p = random_cloud(2000, 0.02, 13);
        NeighbourList nl(skin);
        for (int build = 0; build < 2; ++build) {
            nl.build(p, true);
            EXPECT_EQ(listed(nl, p), brute_force(p, skin)) << "skin " << skin;
            std::size_t longest = 0;
            for (std::size_t i = 0; i < p.size(); ++i) {
                const auto k0 = nl.offsets()[i];
                const auto k1 = nl.offsets()[i + 1];
                longest = std::max<std::size_t>(longest, k1 - k0);
                for (auto k = k0; k < k1; ++k) {
                    EXPECT_GT(nl.partners()[k], k == k0 ? i : nl.partners()[k - 1]);
                    EXPECT_EQ(nl.owners()[k], i);
                }
            }
            EXPECT_EQ(nl.owners().size(), nl.partners().size());
            if (skin > 1e-3) {
                EXPECT_GT(longest, 16U);
            }
            for (Vec3& x : p.x) {
                x *= 1.01; // move every particle (another cell order at the second build)
            }
        }
    }
}

// Only entries that hold a history are looked up at a rebuild; the others start at zero. Some
// entries tagged, the particles moved (pairs leave and join the list), the store re-sorted.
TEST(NeighbourList, SparseHistoriesAreCarriedAndOtherEntriesStartAtZero) {
    ParticleStore p = random_cloud(1500, 0.025, 17);
    NeighbourList nl(0.3e-3);
    nl.build(p, false);
    std::map<IdPair, Vec3> tag;
    for (std::size_t i = 0; i < p.size(); ++i) {
        for (auto k = nl.offsets()[i]; k < nl.offsets()[i + 1]; ++k) {
            nl.shear()[k] = Vec3::Zero();
            if (k % 3 == 0) {
                const Vec3 v(static_cast<double>(p.id[i]) + 0.5, -1.0, static_cast<double>(k));
                nl.shear()[k] = v;
                tag[{p.id[i], p.id[nl.partners()[k]]}] = v;
            }
        }
    }
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-0.2e-3, 0.2e-3);
    for (Vec3& x : p.x) {
        x += Vec3(u(rng), u(rng), u(rng));
    }
    nl.build(p, true);
    std::size_t carried = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        for (auto k = nl.offsets()[i]; k < nl.offsets()[i + 1]; ++k) {
            const std::int64_t a = p.id[i];
            const std::int64_t b = p.id[nl.partners()[k]];
            if (const auto it = tag.find({a, b}); it != tag.end()) {
                EXPECT_EQ(nl.shear()[k], it->second);
                ++carried;
            } else if (const auto jt = tag.find({b, a}); jt != tag.end()) {
                EXPECT_EQ(nl.shear()[k], -jt->second);
                ++carried;
            } else {
                EXPECT_EQ(nl.shear()[k], Vec3::Zero());
            }
        }
    }
    EXPECT_GT(carried, tag.size() / 2); // most tagged pairs are still within the cut-off
    EXPECT_LT(carried, tag.size());     // and some left the list
}

} // namespace
} // namespace kiln::contact
