#include "apcDefaultSpacing.h"
#include "apcExactSum.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace
{

TEST(DefaultSpacing, MeanCellSizeOfTheBox)
{
  const double wind[6] = { -20, 330, -50, 230, 0, 140 };
  EXPECT_NEAR(apc::MeanCellSize(wind, 331699), 3.4584, 1e-4);
}

TEST(DefaultSpacing, TheCellsOwnVolumeDecides)
{
  // The wind data: 350 x 280 x 140 m, 331,699 cells filling 98 % of the box (13.46e6 m^3):
  // its mean cell (3.436 m, rounded down to 3.375) decides, finer than either floor
  // (diagonal / 96 = 4.89 m, diagonal / 128 = 3.67 m). With weighted boundary ends (the
  // default) 1.25 of it, 4.21875 m; on the plain lattice one, 3.375 m. The first rule (box
  // volume per cell, at least 192 samples along the diagonal) gave 2.45 m.
  const double wind[6] = { -20, 330, -50, 230, 0, 140 };
  const double diagonal = std::sqrt(350.0 * 350 + 280 * 280 + 140 * 140);
  const double volume = 0.981 * 350 * 280 * 140;
  EXPECT_DOUBLE_EQ(apc::MeanCellVolumeSize(volume, 331699), 3.375);
  EXPECT_DOUBLE_EQ(apc::DefaultSampleDistance(wind, 331699, volume, true), 4.21875);
  EXPECT_DOUBLE_EQ(apc::DefaultSampleDistance(wind, 331699, volume, false), 3.375);
  EXPECT_GT(apc::DefaultSampleDistance(wind, 331699, volume, false), diagonal / 192 * 1.3);
  // 64 times the cells in the same volume: a quarter of the size, and 8 times again half.
  for (bool weighted : { true, false })
  {
    const double fine = apc::DefaultSampleDistance(wind, 64 * 331699.0, volume, weighted);
    EXPECT_NEAR(fine, (weighted ? 1.25 : 1.0) * 3.375 / 4, 1e-12);
    EXPECT_NEAR(
      apc::DefaultSampleDistance(wind, 512 * 331699.0, volume, weighted), 0.5 * fine, 1e-12);
  }
}

TEST(DefaultSpacing, WeightedEndsTakeACoarserLattice)
{
  // Sample End Weights (Boundary, the default) remove the staircase that set the plain
  // lattice's error: 1.25 mean cell sizes, at least 96 samples along the diagonal, against
  // one mean cell size and 128 samples for the plain lattice (docs/evaluation.md, 4.2).
  EXPECT_DOUBLE_EQ(apc::kDefaultSpacingPerCell, 1.25);
  EXPECT_DOUBLE_EQ(apc::kMinDefaultSamples, 96.0);
  EXPECT_DOUBLE_EQ(apc::kPlainSpacingPerCell, 1.0);
  EXPECT_DOUBLE_EQ(apc::kPlainMinDefaultSamples, 128.0);
  // Like the flange: 5,712 cells filling a quarter of their box, the floor decides in both.
  const double flange[6] = { -0.0488, 0.0488, -0.0488, 0.0488, -0.0318, 0.0794 };
  const double diagonal = apc::BoundsDiagonal(flange);
  const double volume = 0.25 * 0.0976 * 0.0976 * 0.1112;
  EXPECT_DOUBLE_EQ(apc::DefaultSampleDistance(flange, 5712, volume, true), diagonal / 96);
  EXPECT_DOUBLE_EQ(apc::DefaultSampleDistance(flange, 5712, volume, false), diagonal / 128);
}

TEST(DefaultSpacing, SparseMeshesGetTheFloor)
{
  // Cells filling a quarter of their box (the flange): by the box they would be sampled
  // at cbrt(4) their own size; by their volume at their size, and the floor keeps at least
  // kMinDefaultSamples along the diagonal when the cells are few and large.
  const double box[6] = { 0, 2, 0, 2, 0, 2 };
  const double diagonal = 2 * std::sqrt(3.0);
  EXPECT_DOUBLE_EQ(
    apc::DefaultSampleDistance(box, 8, 2.0, true), diagonal / apc::kMinDefaultSamples);
  EXPECT_DOUBLE_EQ(
    apc::DefaultSampleDistance(box, 8, 2.0, false), diagonal / apc::kPlainMinDefaultSamples);
  // 1e6 cells in a quarter of the box: cbrt(2e-6) = 0.0126 (0.0122 after rounding), against
  // cbrt(8e-6) = 0.02 from the box.
  const double d = apc::DefaultSampleDistance(box, 1e6, 2.0, false);
  EXPECT_LT(d, std::cbrt(2e-6));
  EXPECT_GT(d, 0.96 * std::cbrt(2e-6));
  EXPECT_DOUBLE_EQ(apc::DefaultSampleDistance(box, 1e6, 2.0, true), 1.25 * d);
}

TEST(DefaultSpacing, RoundedDownToFewBits)
{
  // Five significant bits: a small change of the volume does not move the lattice, and the
  // distance is never coarser than the exact mean cell size (at most 1/32 finer).
  for (double v : { 1.0, 1.0001, 1.01, 3.7, 1e-9, 12345.0 })
  {
    const double exact = std::cbrt(v);
    const double rounded = apc::MeanCellVolumeSize(v, 1);
    EXPECT_LE(rounded, exact);
    EXPECT_GT(rounded, exact * (1 - 1.0 / 16));
    int e = 0;
    const double m = std::frexp(rounded, &e);
    EXPECT_DOUBLE_EQ(
      std::ldexp(m, apc::kSpacingBits), std::floor(std::ldexp(m, apc::kSpacingBits)));
  }
  EXPECT_EQ(apc::MeanCellVolumeSize(1.0, 1), apc::MeanCellVolumeSize(1.0001, 1));
}

TEST(DefaultSpacing, DegenerateInputs)
{
  // A flat box (all cells in a plane) or no cells: no mean cell size, the diagonal rule.
  const double flat[6] = { 0, 4, 0, 3, 1, 1 };
  EXPECT_EQ(apc::MeanCellSize(flat, 100), 0.0);
  EXPECT_DOUBLE_EQ(apc::DefaultSampleDistance(flat, 100, 0, true), 5.0 / apc::kMinDefaultSamples);
  const double box[6] = { 0, 4, 0, 3, 0, 1 };
  EXPECT_EQ(apc::MeanCellSize(box, 0), 0.0);
  EXPECT_EQ(apc::MeanCellVolumeSize(5.0, 0), 0.0);
  EXPECT_EQ(apc::MeanCellVolumeSize(NAN, 10), 0.0);
  EXPECT_EQ(apc::MeanCellVolumeSize(INFINITY, 10), 0.0);
  EXPECT_DOUBLE_EQ(
    apc::DefaultSampleDistance(box, 0, 0, true), std::sqrt(26.0) / apc::kMinDefaultSamples);
  // No volume (every cell flat): the box's mean cell size stands in.
  EXPECT_DOUBLE_EQ(apc::DefaultSampleDistance(box, 1e6, 0, false), std::cbrt(12e-6));
  // Never zero, never NaN, for any box with an extent.
  const double thin[6] = { 0, 1, 0, 1, 0, 1e-12 };
  const double d = apc::DefaultSampleDistance(thin, 1e6, 1e-300, true);
  EXPECT_GT(d, 0.0);
  EXPECT_TRUE(std::isfinite(d));
}

TEST(ExactSum, OrderAndSplitDoNotMatter)
{
  // Volumes of many magnitudes: a floating sum depends on the order, the exact one does not,
  // nor on how the terms are split into partial sums (processes) and joined.
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> exponent(-40, 40);
  std::vector<double> terms(20000);
  for (double& t : terms)
  {
    t = std::exp2(exponent(random)) * (1 + 1e-3 * exponent(random));
  }
  apc::ExactSum forward;
  for (double t : terms)
  {
    forward.Add(t);
  }
  std::vector<double> shuffled = terms;
  std::shuffle(shuffled.begin(), shuffled.end(), random);
  apc::ExactSum parts[3];
  double floating = 0;
  for (size_t i = 0; i < shuffled.size(); ++i)
  {
    parts[i % 3].Add(shuffled[i]);
    floating += shuffled[i];
  }
  // Joined as the agreement does: the parts' digits added as integers, then normalised.
  std::array<uint64_t, apc::ExactSum::kLanes> lanes{};
  for (apc::ExactSum& part : parts)
  {
    const auto l = part.Lanes();
    for (int i = 0; i < apc::ExactSum::kLanes; ++i)
    {
      lanes[i] += l[i];
    }
  }
  const apc::ExactSum joined = apc::ExactSum::FromLanes(lanes);
  EXPECT_TRUE(joined == forward);
  EXPECT_EQ(joined.Value(), forward.Value());
  EXPECT_NEAR(forward.Value(), floating, 1e-12 * floating);
}

TEST(ExactSum, ExactWhereDoublesAreNot)
{
  // 1 + 2^-60 + ... : doubles lose the small terms, the exact sum keeps them until rounding.
  apc::ExactSum a;
  a.Add(1.0);
  for (int i = 0; i < 1024; ++i)
  {
    a.Add(std::ldexp(1.0, -60));
  }
  EXPECT_EQ(a.Value(), 1.0 + std::ldexp(1.0, -50));
  // The extremes of the range, and terms that are not added.
  apc::ExactSum b;
  b.Add(std::numeric_limits<double>::denorm_min());
  b.Add(std::numeric_limits<double>::max());
  b.Add(-1.0);
  b.Add(NAN);
  b.Add(INFINITY);
  EXPECT_EQ(b.Value(), std::numeric_limits<double>::max());
  apc::ExactSum c;
  c.Add(std::numeric_limits<double>::denorm_min());
  c.Add(std::numeric_limits<double>::denorm_min());
  EXPECT_EQ(c.Value(), 2 * std::numeric_limits<double>::denorm_min());
  EXPECT_EQ(apc::ExactSum().Value(), 0.0);
}

} // namespace
