#include "apcLatticeJitter.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>

namespace
{

TEST(LatticeJitter, InUnitIntervalDeterministicAndSpread)
{
  // What makes the jitter usable: every offset in [0, 1) (a sample stays within its lattice
  // step), a pure function of the pixel (every rank computes the same), neighbours far apart
  // (noise, not a gradient), and about uniform (no depth bias in the sample positions).
  constexpr int kSize = 256;
  std::array<int, 8> histogram{};
  double neighbourGap = 0;
  for (int j = 0; j < kSize; ++j)
  {
    for (int i = 0; i < kSize; ++i)
    {
      const double o = apc::LatticeOffset(i, j);
      ASSERT_GE(o, 0.0);
      ASSERT_LT(o, 1.0);
      ASSERT_EQ(o, apc::LatticeOffset(i, j));
      ++histogram[static_cast<int>(o * 8)];
      const double right = apc::LatticeOffset(i + 1, j);
      neighbourGap += std::min(std::abs(o - right), 1 - std::abs(o - right));
    }
  }
  for (int count : histogram)
  {
    EXPECT_NEAR(count, kSize * kSize / 8.0, 0.1 * kSize * kSize / 8.0);
  }
  // A uniform random pair is 0.25 apart on the circle on average; a smooth field far less.
  EXPECT_GT(neighbourGap / (kSize * kSize), 0.15);
}

} // namespace
