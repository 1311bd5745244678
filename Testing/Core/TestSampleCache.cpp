// The sample cache alone: a tile's recorded samples grouped by pixel in the order they were
// taken, sized exactly, the lattice bits kept only when asked (in the arena, after the
// samples), the budget, and the default budget's rule.
#include "apcSampleCache.h"

#include <gtest/gtest.h>

#include <algorithm>
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
    // The samples sized exactly, the lattice bits right after them in the arena (its huge
    // pages, no memory of the tile's own) in whole 8-byte words, and counted as such against
    // the budget.
    EXPECT_EQ(tile.Samples.size(), 6u);
    if (withOrder)
    {
      EXPECT_EQ(static_cast<const void*>(tile.K16.data()),
        static_cast<const void*>(tile.Samples.data() + 6));
    }
    EXPECT_EQ(cache.Bytes.load(), tile.Bytes());
    EXPECT_EQ(cache.Bytes.load(),
      (kPixels + 1) * sizeof(uint32_t) + 6 * sizeof(apc::CachedSample) + (withOrder ? 16 : 0));
  }
}

// Runs of one pixel (a cell's samples along a ray arrive together), runs that end at the
// last record, a pixel coming back after others, against a stable sort by pixel.
TEST(SampleCache, GroupsRunsOfOnePixelInTakenOrder)
{
  const uint16_t pixels[] = { 7, 7, 7, 3, 7, 7, 0, 0, 255, 3, 3, 7, 255, 255 };
  const int n = static_cast<int>(sizeof(pixels) / sizeof(pixels[0]));
  std::vector<apc::RecordedSample> recorded;
  std::vector<uint32_t> counts(kPixels, 0);
  for (int i = 0; i < n; ++i)
  {
    recorded.push_back({ 0.25f * i, 2.0f + i, pixels[i], static_cast<uint16_t>(1000 + i) });
    ++counts[pixels[i]];
  }
  std::vector<apc::RecordedSample> expected = recorded;
  std::stable_sort(expected.begin(), expected.end(),
    [](const apc::RecordedSample& a, const apc::RecordedSample& b) { return a.Pixel < b.Pixel; });
  for (bool withOrder : { false, true })
  {
    apc::SampleCache cache;
    cache.Empty(1, 0, 1);
    cache.Keep(0, recorded, counts.data(), kPixels, withOrder);
    const apc::CachedTile& tile = cache.Tiles[0];
    ASSERT_EQ(tile.Samples.size(), size_t(n));
    for (int i = 0; i < n; ++i)
    {
      EXPECT_EQ(tile.Samples[i].Z, expected[i].Z) << i;
      EXPECT_EQ(tile.Samples[i].Scalar, expected[i].Scalar) << i;
      if (withOrder)
      {
        EXPECT_EQ(tile.K16[i], expected[i].K16) << i;
      }
    }
    for (int p = 0; p < kPixels; ++p)
    {
      EXPECT_EQ(tile.Starts[p + 1] - tile.Starts[p], counts[p]) << p;
    }
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

// The records of a frame go into the pages the frames before it touched, in whatever order its
// tiles finish: a view that needs no more than before takes no new memory.
TEST(SampleCache, LaterFramesRefillTheSamePages)
{
  std::vector<uint32_t> counts;
  const std::vector<apc::RecordedSample> recorded = Recorded(counts);
  apc::SampleCache cache;
  cache.Empty(3, 0, 3);
  ASSERT_GE(cache.Arena.Capacity(), cache.MaxBytes);
  for (size_t t : { 0, 1, 2 })
  {
    cache.Keep(t, recorded, counts.data(), kPixels, false);
  }
  const apc::CachedSample* low = cache.Tiles[0].Samples.data();
  const apc::CachedSample* high = cache.Tiles[2].Samples.data() + 6;
  for (size_t t : { 2, 0, 1 })
  {
    cache.Empty(3, 0, 3);
    cache.Keep(t, recorded, counts.data(), kPixels, false);
    cache.Keep((t + 1) % 3, recorded, counts.data(), kPixels, false);
    cache.Keep((t + 2) % 3, recorded, counts.data(), kPixels, false);
    for (const apc::CachedTile& tile : cache.Tiles)
    {
      EXPECT_GE(tile.Samples.data(), low);
      EXPECT_LE(tile.Samples.data() + tile.Samples.size(), high);
    }
  }
}

// Where the arena has less room than the budget (a system that grants less address space),
// a tile that does not fit is not kept and stops the recording, as at the budget.
TEST(SampleCache, AFullArenaStopsTheRecording)
{
  std::vector<uint32_t> counts;
  const std::vector<apc::RecordedSample> recorded = Recorded(counts);
  apc::SampleCache cache;
  cache.Empty(2, 0, 2);
  // Leave room for 7 records only.
  ASSERT_NE(cache.Arena.Take(cache.Arena.Capacity() - 7 * sizeof(apc::CachedSample)), nullptr);
  cache.Keep(0, recorded, counts.data(), kPixels, false);
  EXPECT_TRUE(cache.Kept[0]);
  cache.Keep(1, recorded, counts.data(), kPixels, false);
  EXPECT_FALSE(cache.Kept[1]);
  EXPECT_FALSE(cache.Record.load());
  EXPECT_EQ(cache.Tiles[1].Bytes(), 0u);
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
