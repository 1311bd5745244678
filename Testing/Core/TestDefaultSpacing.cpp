#include "apcDefaultSpacing.h"

#include <gtest/gtest.h>

#include <cmath>

namespace
{

TEST(DefaultSpacing, MeanCellSizeOfTheBox)
{
  // 350 x 280 x 140 m filled by 331,699 cells (the wind data): cells of about 3.458 m, fewer
  // than the floor's samples along the 476 m diagonal, so the floor decides.
  const double wind[6] = { -20, 330, -50, 230, 0, 140 };
  const double diagonal = std::sqrt(350.0 * 350 + 280 * 280 + 140 * 140);
  EXPECT_NEAR(apc::MeanCellSize(wind, 331699), 3.4584, 1e-4);
  EXPECT_DOUBLE_EQ(apc::DefaultSampleDistance(wind, 331699), diagonal / apc::kMinDefaultSamples);
  // 64 times the cells: a quarter of the size, finer than the floor; the cells decide, and
  // the distance follows them (8 times the cells again: half the distance).
  const double fine = apc::DefaultSampleDistance(wind, 64 * 331699.0);
  EXPECT_NEAR(fine, apc::kDefaultSpacingPerCell * 3.4584 / 4, 1e-4);
  EXPECT_LT(fine, diagonal / apc::kMinDefaultSamples);
  EXPECT_NEAR(apc::DefaultSampleDistance(wind, 512 * 331699.0), 0.5 * fine, 1e-12);
}

TEST(DefaultSpacing, FewCellsStillSampled)
{
  // A 2 x 2 x 2 block of unit cells: one sample per cell would be 3.5 samples along the
  // diagonal; the field inside the cells needs more: the floor.
  const double box[6] = { 0, 2, 0, 2, 0, 2 };
  EXPECT_DOUBLE_EQ(apc::MeanCellSize(box, 8), 1.0);
  EXPECT_DOUBLE_EQ(
    apc::DefaultSampleDistance(box, 8), 2 * std::sqrt(3.0) / apc::kMinDefaultSamples);
}

TEST(DefaultSpacing, DegenerateInputs)
{
  // A flat box (all cells in a plane) or no cells: no mean cell size, the diagonal rule.
  const double flat[6] = { 0, 4, 0, 3, 1, 1 };
  EXPECT_EQ(apc::MeanCellSize(flat, 100), 0.0);
  EXPECT_DOUBLE_EQ(apc::DefaultSampleDistance(flat, 100), 5.0 / apc::kMinDefaultSamples);
  const double box[6] = { 0, 4, 0, 3, 0, 1 };
  EXPECT_EQ(apc::MeanCellSize(box, 0), 0.0);
  EXPECT_DOUBLE_EQ(apc::DefaultSampleDistance(box, 0), std::sqrt(26.0) / apc::kMinDefaultSamples);
  // Never zero, never NaN, for any box with an extent.
  const double thin[6] = { 0, 1, 0, 1, 0, 1e-12 };
  const double d = apc::DefaultSampleDistance(thin, 1e6);
  EXPECT_GT(d, 0.0);
  EXPECT_TRUE(std::isfinite(d));
}

} // namespace
