// The sample cache alone: a tile's recorded samples grouped by pixel in the order they were
// taken, sized exactly, the lattice bits kept only when asked, the budget, and the default
// budget's rule.
#include "apcSampleCache.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace
{
constexpr int kPixels = 256;

// Samples of pixels 5, 0, 5, 255, 0, 5 in that order, with distinct depths and lattice bits.
std::vector<apc::RecordedSample> Recorded(std::vector<uint32_t>& counts)
{
  const uint16_t pixels[] = { 5, 0, 5, 255, 0, 5 };
  std::vector<apc::RecordedSample> recorded;
  counts.assign(kPixels, 0);
  for (int i = 0; i < 6; ++i)
  {
    recorded.push_back({ 0.5f + i, 10.0f + i, pixels[i], static_cast<uint16_t>(100 + i) });
    ++counts[pixels[i]];
  }
  return recorded;
}
}

TEST(SampleCache, GroupsByPixelInTakenOrder)
{
  std::vector<uint32_t> counts;
  const std::vector<apc::RecordedSample> recorded = Recorded(counts);
  for (bool withOrder : { false, true })
  {
    apc::SampleCache cache;
    cache.Empty(3, 0, 3);
    cache.Keep(1, recorded, counts.data(), kPixels, withOrder);
    ASSERT_TRUE(cache.Kept[1]);
    EXPECT_FALSE(cache.Kept[0]);
    const apc::CachedTile& tile = cache.Tiles[1];
    ASSERT_EQ(tile.Starts.size(), size_t(kPixels + 1));
    EXPECT_EQ(tile.Starts[0], 0u);
    EXPECT_EQ(tile.Starts[1], 2u); // pixel 0: samples 1 and 4
    EXPECT_EQ(tile.Starts[5], 2u);
    EXPECT_EQ(tile.Starts[6], 5u); // pixel 5: samples 0, 2 and 5
    EXPECT_EQ(tile.Starts[255], 5u);
    EXPECT_EQ(tile.Starts[256], 6u); // pixel 255: sample 3
    const int taken[] = { 1, 4, 0, 2, 5, 3 };
    ASSERT_EQ(tile.Samples.size(), 6u);
    for (int i = 0; i < 6; ++i)
    {
      EXPECT_EQ(tile.Samples[i].Z, recorded[taken[i]].Z) << i;
      EXPECT_EQ(tile.Samples[i].Scalar, recorded[taken[i]].Scalar) << i;
    }
    ASSERT_EQ(tile.K16.size(), withOrder ? 6u : 0u);
    for (size_t i = 0; i < tile.K16.size(); ++i)
    {
      EXPECT_EQ(tile.K16[i], recorded[taken[i]].K16) << i;
    }
    // Sized with a quarter's slack at most, and counted as such against the budget.
    EXPECT_GE(tile.Samples.capacity(), 6u);
    EXPECT_LE(tile.Samples.capacity(), 7u);
    EXPECT_EQ(cache.Bytes.load(), tile.Bytes());
    EXPECT_LE(cache.Bytes.load(),
      (kPixels + 1) * sizeof(uint32_t) + 7 * sizeof(apc::CachedSample) +
        (withOrder ? 7 * sizeof(uint16_t) : 0));
  }
}

TEST(SampleCache, KeepsMemoryAcrossFramesAndStopsAtTheBudget)
{
  std::vector<uint32_t> counts;
  const std::vector<apc::RecordedSample> recorded = Recorded(counts);
  apc::SampleCache cache;
  cache.Empty(2, 0, 2);
  cache.Keep(0, recorded, counts.data(), kPixels, false);
  const apc::CachedSample* memory = cache.Tiles[0].Samples.data();
  // The next frame of the same view writes into the same memory.
  cache.Empty(2, 0, 2);
  cache.Keep(0, recorded, counts.data(), kPixels, false);
  EXPECT_EQ(cache.Tiles[0].Samples.data(), memory);
  EXPECT_TRUE(cache.Kept[0]);

  // A budget one tile's worth: the second tile does not fit, is freed and stops the recording.
  cache.MaxBytes = cache.Bytes.load();
  cache.Empty(2, 0, 2);
  cache.Keep(0, recorded, counts.data(), kPixels, false);
  EXPECT_TRUE(cache.Kept[0]);
  EXPECT_TRUE(cache.Record.load());
  cache.Keep(1, recorded, counts.data(), kPixels, false);
  EXPECT_FALSE(cache.Kept[1]);
  EXPECT_FALSE(cache.Record.load());
  EXPECT_EQ(cache.Tiles[1].Bytes(), 0u);
  EXPECT_EQ(cache.Bytes.load(), cache.MaxBytes);
}

TEST(SampleCache, EmptyTilesTakeNoMemory)
{
  apc::SampleCache cache;
  cache.Empty(2, 0, 2);
  const std::vector<uint32_t> counts(kPixels, 0);
  cache.Keep(0, {}, counts.data(), kPixels, true);
  EXPECT_TRUE(cache.Kept[0]) << "kept: pass 2 has nothing to march again";
  EXPECT_EQ(cache.Tiles[0].Bytes(), 0u);
  EXPECT_EQ(cache.Bytes.load(), 0u);
}

TEST(SampleCache, DefaultBudgetIsTheNodesShare)
{
  const uint64_t gib = uint64_t(1) << 30;
  EXPECT_EQ(apc::NodeShareOfMemory(24 * gib, 1), 6 * gib);
  EXPECT_EQ(apc::NodeShareOfMemory(24 * gib, 4), 3 * gib / 2);
  EXPECT_EQ(apc::NodeShareOfMemory(24 * gib, 0), 6 * gib); // at least one process
  EXPECT_EQ(apc::NodeShareOfMemory(0, 2), gib);            // unknown memory: 1 GiB
}
