// How far a tile's rays have come towards opaque (walk::RayProgress, apcRayWalk.h): the bin
// of a lattice index found without a division is OpaqueBins::Of's, for any bins the frame
// can make and any index, before, inside and past them.
#include "apcRayWalk.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <random>

namespace
{

// Every index from well before the bins to well past them, and random ones far away.
void ExpectBinOfIsOf(const apc::OpaqueBins& bins, std::mt19937_64& random)
{
  auto progress = std::make_unique<apc::walk::RayProgress>();
  progress->Begin(1, &bins);
  for (int b = 0; b < apc::OpaqueBins::kBins; ++b)
  {
    ASSERT_EQ(progress->Ends[b], bins.End(b)) << "bin " << b; // StopIndex and the walker's
  }
  const int64_t span = apc::OpaqueBins::kBins * bins.Width;
  for (int64_t k = bins.Base - 2 * bins.Width - 3; k <= bins.Base + span + 2 * bins.Width + 3; ++k)
  {
    ASSERT_EQ(progress->BinOf(k), bins.Of(k))
      << "k " << k << " base " << bins.Base << " width " << bins.Width;
  }
  std::uniform_int_distribution<int64_t> far(-(int64_t(1) << 40), int64_t(1) << 40);
  for (int i = 0; i < 1000; ++i)
  {
    const int64_t k = bins.Base + far(random);
    ASSERT_EQ(progress->BinOf(k), bins.Of(k)) << "k " << k;
  }
}

}

TEST(RayProgress, BinOfIsOpaqueBinsOf)
{
  std::mt19937_64 random(26);
  // The frame's bins: near and far distances (spans from a few steps to the largest the
  // bins allow, near planes at and away from 0, negative ones included) and spacings.
  std::uniform_real_distribution<double> nearT(-50.0, 500.0);
  std::uniform_real_distribution<double> steps(0.0, apc::OpaqueBins::kMaxSpan);
  std::uniform_real_distribution<double> spacing(1e-3, 5.0);
  int made = 0;
  for (int i = 0; i < 200; ++i)
  {
    const double h = spacing(random);
    const double n = nearT(random);
    const double s = i < 20 ? static_cast<double>(i) : steps(random);
    const apc::OpaqueBins bins = apc::OpaqueBins::Make(std::log(1e4), n, n + s * h, h);
    if (!bins.Active())
    {
      continue;
    }
    ++made;
    ExpectBinOfIsOf(bins, random);
  }
  EXPECT_GT(made, 150);
}
