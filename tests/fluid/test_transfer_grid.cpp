// TransferGrid construction (fluid/transfer_grid.hpp): sizes and bad input.

#include "core/error.hpp"
#include "fluid/transfer_grid.hpp"

#include <gtest/gtest.h>
#include <string>

using kiln::Vec3;
namespace f = kiln::fluid;

namespace {
/// The message of the InputError thrown by make(), or "" when none is thrown.
template <class Make> std::string input_error(const Make& make) {
    try {
        make();
    } catch (const kiln::InputError& e) {
        return e.what();
    }
    return "";
}
} // namespace

TEST(TransferGrid, SizesFollowTheRefinement) {
    const f::TransferGrid g(Vec3(1, 2, 3), {4, 5, 6}, 0.5, 4);
    EXPECT_EQ(g.cell_count(), 120U);
    EXPECT_DOUBLE_EQ(g.sub_cell_size(), 0.125);
    EXPECT_DOUBLE_EQ(g.cell_volume(), 0.125);
    EXPECT_DOUBLE_EQ(g.sub_cell_volume(), 0.125 * 0.125 * 0.125);
    EXPECT_EQ(g.cell_index(3, 4, 5), 119);
    EXPECT_TRUE(g.cell_centre(0, 0, 0).isApprox(Vec3(1.25, 2.25, 3.25)));
}

TEST(TransferGrid, ZeroCellsIsAnInputError) {
    const std::string m = input_error([] { f::TransferGrid(Vec3::Zero(), {4, 0, 4}, 1.0, 2); });
    EXPECT_NE(m.find("cell counts must be >= 1"), std::string::npos) << m;
    EXPECT_NE(m.find("(4, 0, 4)"), std::string::npos) << m;
}

TEST(TransferGrid, RefinementBelowOneIsAnInputError) {
    const std::string m = input_error([] { f::TransferGrid(Vec3::Zero(), {4, 4, 4}, 1.0, 0); });
    EXPECT_NE(m.find("refinement s"), std::string::npos) << m;
    EXPECT_NE(m.find("got 0"), std::string::npos) << m;
}

TEST(TransferGrid, NonPositiveCellSizeIsAnInputError) {
    const std::string m = input_error([] { f::TransferGrid(Vec3::Zero(), {4, 4, 4}, -1e-3, 2); });
    EXPECT_NE(m.find("cell size must be positive"), std::string::npos) << m;
    EXPECT_NE(input_error([] { f::TransferGrid(Vec3::Zero(), {4, 4, 4}, 0.0, 2); }), "");
}

TEST(TransferGrid, TooManyCellsIsAnInputError) {
    const std::string m = input_error([] {
        f::TransferGrid(Vec3::Zero(), {2000, 2000, 2000}, 1.0, 2);
    });
    EXPECT_NE(m.find("32-bit"), std::string::npos) << m;
}
