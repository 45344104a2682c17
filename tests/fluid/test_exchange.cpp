// Exchange through footprints (fluid/exchange.hpp): conservative sources, interpolation of a
// linear field, the same bits on one and two threads.

#include "fluid_helpers.hpp"

#include <cstring>
#include <gtest/gtest.h>

using kiln::Quat;
using kiln::Vec3;
namespace f = kiln::fluid;
namespace t = kiln::test;

namespace {

/// A random bed of the four shape kinds (and tiny spheres too small for the sub-grid) in a
/// 10 x 10 x 10 grid of 2 mm cells, some particles reaching out of the domain.
struct Bed {
    f::TransferGrid grid{Vec3::Zero(), {10, 10, 10}, 2e-3, 4};
    std::vector<f::DepositTemplate> templates;
    std::vector<int> shape;
    std::vector<Vec3> pos;
    std::vector<Quat> rot;

    explicit Bed(std::size_t n) {
        for (const auto& s :
             {t::sphere_template(1.2e-3), t::shape_file("cube"), t::superquadric_template(),
              t::clump_template(), t::sphere_template(5e-5)}) {
            templates.push_back(f::make_deposit_template(s));
        }
        std::mt19937_64 rng(5);
        std::uniform_real_distribution<double> u(-1e-3, 21e-3);
        for (std::size_t p = 0; p < n; ++p) {
            shape.push_back(static_cast<int>(p % templates.size()));
            pos.emplace_back(u(rng), u(rng), u(rng));
            rot.push_back(t::random_rotation(rng));
        }
    }
    [[nodiscard]] f::Footprints footprints(int threads) const {
        f::Footprints fp;
        f::compute_footprints(grid, templates, {shape, pos, rot}, fp, threads);
        return fp;
    }
};

template <class T> bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

} // namespace

TEST(Exchange, SourcesSumToTheParticleValues) {
    const Bed bed(600);
    const f::Footprints fp = bed.footprints(1);
    ASSERT_GT(fp.clipped, 0U);
    ASSERT_GT(fp.too_small, 0U);
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<double> u(0.1, 1.0);
    std::normal_distribution<double> n;
    std::vector<double> heat(bed.pos.size());
    std::vector<Vec3> force(bed.pos.size());
    double heat_in = 0.0;
    Vec3 force_in = Vec3::Zero();
    double force_scale = 0.0;
    for (std::size_t p = 0; p < heat.size(); ++p) {
        if (fp.placement[p] == f::Placement::outside) {
            continue; // deposited nowhere by design: left at zero
        }
        heat[p] = u(rng);
        force[p] = Vec3(n(rng), n(rng), n(rng));
        heat_in += heat[p];
        force_in += force[p];
        force_scale += force[p].norm();
    }
    std::vector<double> heat_cells(fp.cells);
    std::vector<Vec3> force_cells(fp.cells);
    f::spread(fp, heat, heat_cells);
    f::spread(fp, force, force_cells);
    double heat_out = 0.0;
    Vec3 force_out = Vec3::Zero();
    for (std::size_t c = 0; c < fp.cells; ++c) {
        heat_out += heat_cells[c];
        force_out += force_cells[c];
    }
    constexpr double kConservative = 1e-12; // shares sum to 1 to round-off; 600 particles summed
    EXPECT_NEAR(heat_out / heat_in, 1.0, kConservative);
    EXPECT_LT((force_out - force_in).norm() / force_scale, kConservative);
}

TEST(Exchange, LinearFieldGivesItsValueAtTheSubCellCentroid) {
    const Bed bed(300);
    const f::Footprints fp = bed.footprints(1);
    const Vec3 slope(3.0, -2.0, 5.0); // K/m
    const auto field = [&](const Vec3& x) { return 300.0 + slope.dot(x); };
    std::vector<double> cells(fp.cells);
    const auto& n = bed.grid.cells();
    for (int k = 0; k < n[2]; ++k) {
        for (int j = 0; j < n[1]; ++j) {
            for (int i = 0; i < n[0]; ++i) {
                cells[bed.grid.cell_index(i, j, k)] = field(bed.grid.cell_centre(i, j, k));
            }
        }
    }
    std::vector<double> at(bed.pos.size());
    f::interpolate(fp, cells, at);
    // Interpolation is exact for a linear field between the outermost cell centres, so only
    // particles whose world box stays at least a cell from the domain faces are checked.
    const kiln::Aabb inner{Vec3::Constant(3e-3), Vec3::Constant(17e-3)};
    constexpr double kRoundOff = 1e-13; // relative, a few dozen weights times values of 300
    std::size_t checked = 0;
    for (std::size_t p = 0; p < at.size(); ++p) {
        if (fp.placement[p] == f::Placement::inside && inner.contains(bed.pos[p])) {
            EXPECT_NEAR(at[p] / field(fp.centroid[p]), 1.0, kRoundOff) << "particle " << p;
            ++checked;
        }
    }
    EXPECT_GT(checked, 20U);
}

TEST(Exchange, SubCellCentroidApproachesTheParticleCentroid) {
    // The bodies' centres of mass are their body origins; the mean of the sub-cell centres
    // tends to them as the sub-grid is refined.
    std::mt19937_64 rng(13);
    const auto cube = t::shape_file("cube");
    double last = 1.0;
    for (const int s : {4, 16, 64}) {
        const f::TransferGrid grid(Vec3::Zero(), {4, 4, 4}, 2e-3, s);
        double worst = 0.0;
        for (int k = 0; k < 8; ++k) {
            const Vec3 x = Vec3(3.1e-3, 4.2e-3, 3.7e-3) + 1e-4 * Vec3::Random();
            const f::Footprints fp = t::deposit_one(grid, cube, x, t::random_rotation(rng));
            worst = std::max(worst, (fp.centroid[0] - x).norm() / 2.26e-3);
        }
        std::printf("s = %d: largest centroid offset %.2e of the edge\n", s, worst);
        EXPECT_LT(worst, last);
        last = worst;
    }
    constexpr double kFine = 1e-3; // of the edge at s = 64 (73 sub-cells per edge)
    EXPECT_LT(last, kFine);
}

TEST(Exchange, OneAndTwoThreadsGiveTheSameBits) {
    const Bed bed(3000);
    const f::Footprints a = bed.footprints(1);
    const f::Footprints b = bed.footprints(2);
    EXPECT_TRUE(same_bits(a.cell, b.cell));
    EXPECT_TRUE(same_bits(a.volume, b.volume));
    EXPECT_TRUE(same_bits(a.weight, b.weight));
    EXPECT_TRUE(same_bits(a.stencil_weight, b.stencil_weight));
    EXPECT_TRUE(same_bits(a.centroid, b.centroid));
    std::vector<double> va(a.cells);
    std::vector<double> vb(b.cells);
    f::solid_volume(a, va, 1);
    f::solid_volume(b, vb, 2);
    EXPECT_TRUE(same_bits(va, vb));
    std::vector<Vec3> force(bed.pos.size());
    for (std::size_t p = 0; p < force.size(); ++p) {
        const auto x = static_cast<double>(p);
        force[p] = Vec3(std::sin(x), std::cos(x), 1.0 / (1.0 + x));
    }
    std::vector<Vec3> fa(a.cells);
    std::vector<Vec3> fb(b.cells);
    f::spread(a, force, fa, 1);
    f::spread(b, force, fb, 2);
    EXPECT_TRUE(same_bits(fa, fb));
    std::vector<Vec3> ga(bed.pos.size());
    std::vector<Vec3> gb(bed.pos.size());
    f::interpolate(a, fa, ga, 1);
    f::interpolate(b, fb, gb, 2);
    EXPECT_TRUE(same_bits(ga, gb));
}
