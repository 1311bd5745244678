#include "apcAloneBands.h"

#include <gtest/gtest.h>

// One process renders in bands of kAloneBandPixels or of kAloneBandTilesPerThread tiles a
// thread, whichever is larger, and never in larger bands than the setting asks.
TEST(AloneBands, SmallBandsForFewThreads)
{
  const size_t whole = size_t(1) << 21; // the default setting: a 1024² frame in one band
  EXPECT_EQ(apc::AloneBandPixels(whole, 1, 16), apc::kAloneBandPixels);
  EXPECT_EQ(apc::AloneBandPixels(whole, 2, 16), apc::kAloneBandPixels);
  EXPECT_EQ(apc::AloneBandPixels(whole, 0, 16), apc::kAloneBandPixels);  // unknown: one thread
  EXPECT_EQ(apc::AloneBandPixels(whole, -3, 16), apc::kAloneBandPixels); // likewise
}

TEST(AloneBands, TilesPerThread)
{
  const size_t tile = 16 * 16;
  EXPECT_EQ(apc::AloneBandPixels(size_t(1) << 30, 8, 16), 8 * apc::kAloneBandTilesPerThread * tile);
  EXPECT_EQ(
    apc::AloneBandPixels(size_t(1) << 30, 64, 16), 64 * apc::kAloneBandTilesPerThread * tile);
  // Larger tiles, larger bands.
  EXPECT_EQ(apc::AloneBandPixels(size_t(1) << 30, 4, 32), 4 * apc::kAloneBandTilesPerThread * 1024);
}

TEST(AloneBands, NeverAboveTheSetting)
{
  EXPECT_EQ(apc::AloneBandPixels(1, 1, 16), 1u);
  EXPECT_EQ(apc::AloneBandPixels(50000, 64, 16), 50000u);
}
