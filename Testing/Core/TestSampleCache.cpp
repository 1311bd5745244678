// The sample cache alone: a tile's recorded samples grouped by pixel in the order they were
// taken, sized exactly, the lattice bits kept only when asked (in the arena, after the
// samples), the budget, and the default budget's rule.
#include "apcSampleCache.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
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

// The compact form: every sample's depth replaced by the index of the depth table's entry that
// is its depth bit for bit (that index also gives back its lattice bits), end weights of 1
// left out, everything else kept whole as escapes. Expanded, a compact tile is the full form
// bit for bit: the same grouping, depths, scalars, lattice bits and weights, in fewer bytes.
TEST(SampleCache, CompactTilesExpandToTheFullForm)
{
  // A full table (the lattice warp's largest): its last index is never an entry. Its base
  // does not start at a multiple of 2^16, so the lattice bits wrap inside it.
  const int64_t entries = 65536;
  const int64_t base = 3 * 65536 - 1000;
  std::vector<double> table(static_cast<size_t>(entries));
  for (int64_t i = 0; i < entries; ++i)
  {
    table[static_cast<size_t>(i)] = -1.0 + 2.0 * std::sqrt(static_cast<double>(i) / entries);
  }
  auto depthOf = [&](int64_t k)
  { return static_cast<float>(table[static_cast<size_t>(k - base)]); };
  std::vector<apc::RecordedSample> recorded;
  std::vector<float> weights;
  std::vector<uint32_t> counts(kPixels, 0);
  std::vector<int> escaped;
  uint32_t random = 12345;
  auto next = [&random]() { return random = random * 1664525u + 1013904223u; };
  for (int i = 0; i < 3005; ++i) // not a whole number of the expansion's 8-sample steps
  {
    const uint16_t pixel = static_cast<uint16_t>(next() % kPixels);
    int64_t k = base + static_cast<int64_t>(next() % 4000) + (i % 2 ? 0 : 990);
    float z = depthOf(k);
    float weight = 1.0f;
    const uint32_t kind = next() % 40;
    if (kind == 0)
    {
      z = std::nextafter(z, 2.0f); // a depth off the lattice (a pair's middle sample)
    }
    else if (kind == 1)
    {
      weight = 0.25f + static_cast<float>(next() % 100) / 64; // an end weight
    }
    else if (kind == 2)
    {
      k = base - 1 - static_cast<int64_t>(next() % 50); // in front of the table
      z = -1.0f;
    }
    else if (kind == 3)
    {
      k = base + entries - 1; // the last entry: kEscapedDepth, never an index
      z = static_cast<float>(table.back());
    }
    else if (kind == 4)
    {
      z = -0.0f; // equal to entry 16384 (+0) but not its bits
      k = base + entries / 4;
    }
    recorded.push_back({ z, 0.001f * static_cast<float>(i), pixel, static_cast<uint16_t>(k) });
    weights.push_back(weight);
    ++counts[pixel];
  }
  for (bool withOrder : { false, true })
  {
    for (bool withWeights : { false, true })
    {
      const float* w = withWeights ? weights.data() : nullptr;
      apc::SampleCache full;
      full.CompactRecords = false;
      full.SetDepthTable(table.data(), entries, base);
      full.Empty(1, 0, 1);
      full.Keep(0, recorded.data(), recorded.size(), counts.data(), kPixels, withOrder, w);
      apc::SampleCache compact;
      compact.SetDepthTable(table.data(), entries, base);
      ASSERT_EQ(compact.DepthTable.size(), size_t(entries - 1));
      compact.Empty(1, 0, 1);
      compact.Keep(0, recorded.data(), recorded.size(), counts.data(), kPixels, withOrder, w);
      ASSERT_TRUE(full.Kept[0] && compact.Kept[0]);
      const apc::CachedTile& f = full.Tiles[0];
      const apc::CachedTile& c = compact.Tiles[0];
      ASSERT_FALSE(f.IsCompact());
      ASSERT_TRUE(c.IsCompact());
      EXPECT_TRUE(c.Samples.empty());
      EXPECT_EQ(c.Count(), recorded.size());
      // Most samples are on the table: 6 bytes each, against 8, 10 or 14.
      EXPECT_LT(c.Compact.EscapeCount, recorded.size() / 5);
      EXPECT_GT(c.Compact.EscapeCount, recorded.size() / 20);
      EXPECT_LT(compact.Bytes.load(), full.Bytes.load());
      EXPECT_EQ(compact.Bytes.load(), c.Bytes());
      apc::ExpandedTile scratch;
      const apc::CachedTile& e = apc::Expand(c, compact.DepthTable, compact.DepthBase, scratch);
      ASSERT_TRUE(std::equal(f.Starts.begin(), f.Starts.end(), e.Starts.begin(), e.Starts.end()));
      ASSERT_EQ(e.Samples.size(), f.Samples.size());
      ASSERT_EQ(e.K16.size(), f.K16.size());
      ASSERT_EQ(e.Weights.size(), f.Weights.size());
      for (size_t i = 0; i < f.Samples.size(); ++i)
      {
        EXPECT_EQ(std::memcmp(&e.Samples[i], &f.Samples[i], sizeof(apc::CachedSample)), 0)
          << i << (withOrder ? ", lattice bits" : "") << (withWeights ? ", weights" : "");
        if (withOrder)
        {
          EXPECT_EQ(e.K16[i], f.K16[i]) << i;
        }
        if (withWeights)
        {
          EXPECT_EQ(std::memcmp(&e.Weights[i], &f.Weights[i], sizeof(float)), 0) << i;
        }
      }
      // Without the lattice bits (pass 2's colour: eight samples a step where the CPU has
      // AVX2), the same samples and weights, none of the bits.
      apc::ExpandedTile bare;
      const apc::CachedTile& b =
        apc::Expand(c, compact.DepthTable, compact.DepthBase, bare, /*withOrder=*/false);
      ASSERT_TRUE(std::equal(f.Starts.begin(), f.Starts.end(), b.Starts.begin(), b.Starts.end()));
      ASSERT_EQ(b.Samples.size(), f.Samples.size());
      EXPECT_EQ(b.K16.size(), size_t(0));
      ASSERT_EQ(b.Weights.size(), f.Weights.size());
      for (size_t i = 0; i < f.Samples.size(); ++i)
      {
        EXPECT_EQ(std::memcmp(&b.Samples[i], &f.Samples[i], sizeof(apc::CachedSample)), 0)
          << i << " without lattice bits" << (withWeights ? ", weights" : "");
        if (withWeights)
        {
          EXPECT_EQ(std::memcmp(&b.Weights[i], &f.Weights[i], sizeof(float)), 0) << i;
        }
      }
      // A full-form tile expands to itself.
      EXPECT_EQ(&apc::Expand(f, full.DepthTable, full.DepthBase, scratch), &f);
    }
  }
}

// Without a depth table (a lattice too fine for one), or where the escapes would make the
// compact form larger (depths off the table: jittered rays), the cache keeps the full form.
TEST(SampleCache, TheFullFormWhereCompactIsNotSmaller)
{
  std::vector<uint32_t> counts;
  const std::vector<apc::RecordedSample> recorded = Recorded(counts);
  apc::SampleCache cache;
  cache.SetDepthTable(nullptr, 0, 0);
  cache.Empty(1, 0, 1);
  cache.Keep(0, recorded, counts.data(), kPixels, true);
  EXPECT_FALSE(cache.Tiles[0].IsCompact());
  EXPECT_EQ(cache.Tiles[0].Samples.size(), recorded.size());

  // Recorded's lattice bits 100 to 105, its depths 0.5 to 5.5: 0.5 is entry 100's, the others
  // are off the table.
  const std::vector<double> table(200, 0.5);
  cache.SetDepthTable(table.data(), 200, 0);
  for (bool withOrder : { false, true })
  {
    cache.Empty(1, 0, 1);
    cache.Keep(0, recorded, counts.data(), kPixels, withOrder);
    EXPECT_FALSE(cache.Tiles[0].IsCompact()) << withOrder;
    EXPECT_EQ(cache.Tiles[0].Samples.size(), recorded.size());
  }
  // On the table: compact.
  std::vector<apc::RecordedSample> onTable = recorded;
  for (apc::RecordedSample& r : onTable)
  {
    r.Z = 0.5f;
  }
  cache.Empty(1, 0, 1);
  cache.Keep(0, onTable, counts.data(), kPixels, true);
  EXPECT_TRUE(cache.Tiles[0].IsCompact());
  EXPECT_EQ(cache.Tiles[0].Compact.EscapeCount, 0u);
}

// The compact keep against a plain reference written from its definition, byte for byte: the
// records stably sorted by pixel, each one's depth slot its lattice bits' index in the table
// if the entry there is its depth bit for bit and its weight 1, else an escape in sample
// order. Random tiles: runs of one pixel as pass 1 records them, empty pixels, short and full
// tables, escapes of every kind, with and without lattice bits and weights.
TEST(SampleCache, CompactKeepMatchesAPlainReference)
{
  uint32_t random = 987654321;
  auto next = [&random]() { return (random = random * 1664525u + 1013904223u) >> 8; };
  int compactTiles = 0;
  for (int round = 0; round < 24; ++round)
  {
    const int64_t entries = round % 3 == 0 ? 65536 : 50 + static_cast<int64_t>(next() % 3000);
    const int64_t base = static_cast<int64_t>(next() % 200000) - 100000;
    std::vector<double> table(static_cast<size_t>(entries));
    for (int64_t i = 0; i < entries; ++i)
    {
      table[static_cast<size_t>(i)] = -1.0 + 2.0 * static_cast<double>(i) / entries;
    }
    apc::SampleCache cache;
    cache.SetDepthTable(table.data(), entries, base);
    const std::vector<float>& depths = cache.DepthTable;
    const int64_t kept = static_cast<int64_t>(depths.size());
    // Pixels used: a few (most empty) or all of them.
    const int used = round % 4 == 1 ? 3 : kPixels;
    std::vector<apc::RecordedSample> recorded;
    std::vector<float> weights;
    std::vector<uint32_t> counts(kPixels, 0);
    const size_t n = round % 5 == 4 ? 1 + next() % 7 : 200 + next() % 5000;
    while (recorded.size() < n)
    {
      const uint16_t pixel = static_cast<uint16_t>((next() % used) * (kPixels / used));
      const size_t run = 1 + next() % 9;
      int64_t k = base + static_cast<int64_t>(next() % static_cast<uint32_t>(kept));
      for (size_t j = 0; j < run && recorded.size() < n; ++j, ++k)
      {
        float z = k >= base && k - base < kept ? depths[static_cast<size_t>(k - base)] : 0.5f;
        float weight = 1.0f;
        const uint32_t kind = next() % 32;
        if (kind == 0)
        {
          z = std::nextafter(z, 2.0f); // off the lattice
        }
        else if (kind == 1)
        {
          weight = static_cast<float>(next() % 100) / 64; // an end weight (may be 1)
        }
        else if (kind == 2)
        {
          k = base - 1 - static_cast<int64_t>(next() % 50); // in front of the table
        }
        else if (kind == 3)
        {
          z = -z; // -0 against +0, or another depth
        }
        recorded.push_back({ z, static_cast<float>(next()) * 1e-3f, pixel,
          static_cast<uint16_t>(static_cast<uint64_t>(k)) });
        weights.push_back(weight);
        ++counts[pixel];
      }
    }
    for (bool withOrder : { false, true })
    {
      for (bool withWeights : { false, true })
      {
        const float* w = withWeights ? weights.data() : nullptr;
        // The reference.
        std::vector<uint32_t> order(n);
        for (size_t i = 0; i < n; ++i)
        {
          order[i] = static_cast<uint32_t>(i);
        }
        std::stable_sort(order.begin(), order.end(),
          [&](uint32_t a, uint32_t b) { return recorded[a].Pixel < recorded[b].Pixel; });
        std::vector<uint32_t> starts(kPixels + 1, 0);
        for (int p = 0; p < kPixels; ++p)
        {
          starts[p + 1] = starts[p] + counts[p];
        }
        std::vector<float> scalars;
        std::vector<uint16_t> slots;
        std::vector<apc::EscapedSample> escapes;
        for (uint32_t i : order)
        {
          const apc::RecordedSample& r = recorded[i];
          const int64_t at = static_cast<uint16_t>(r.K16 - static_cast<uint16_t>(base));
          const float weight = w ? w[i] : 1.0f;
          const bool onTable = at < kept &&
            std::memcmp(&depths[static_cast<size_t>(at)], &r.Z, sizeof(float)) == 0 &&
            weight == 1.0f;
          scalars.push_back(r.Scalar);
          slots.push_back(onTable ? static_cast<uint16_t>(at) : apc::kEscapedDepth);
          if (!onTable)
          {
            escapes.push_back({ r.Z, weight, r.K16, 0 });
          }
        }
        cache.Empty(1, 0, 1);
        cache.Keep(0, recorded.data(), n, counts.data(), kPixels, withOrder, w);
        ASSERT_TRUE(cache.Kept[0]);
        const apc::CachedTile& c = cache.Tiles[0];
        const std::string what = "round " + std::to_string(round) +
          (withOrder ? ", lattice bits" : "") + (withWeights ? ", weights" : "");
        if (!c.IsCompact())
        {
          // The full form only where compact would not be smaller.
          EXPECT_GE(apc::CachedTile::CompactBytes(n, escapes.size()),
            n * (sizeof(apc::CachedSample) + (withOrder ? 2 : 0) + (withWeights ? 4 : 0)))
            << what;
          continue;
        }
        ++compactTiles;
        const apc::CompactSpan& compact = c.Compact;
        ASSERT_EQ(compact.Size, n) << what;
        ASSERT_EQ(compact.EscapeCount, escapes.size()) << what;
        EXPECT_EQ(compact.Ordered, withOrder) << what;
        EXPECT_EQ(compact.Weighted, withWeights) << what;
        EXPECT_TRUE(std::equal(starts.begin(), starts.end(), c.Starts.begin(), c.Starts.end()))
          << what;
        EXPECT_EQ(std::memcmp(compact.Scalars, scalars.data(), n * sizeof(float)), 0) << what;
        EXPECT_EQ(std::memcmp(compact.Depths, slots.data(), n * sizeof(uint16_t)), 0) << what;
        for (size_t e = 0; e < escapes.size(); ++e)
        {
          const apc::EscapedSample& have = compact.Escapes[e];
          EXPECT_EQ(std::memcmp(&have.Z, &escapes[e].Z, sizeof(float)), 0) << what << " " << e;
          EXPECT_EQ(std::memcmp(&have.Weight, &escapes[e].Weight, sizeof(float)), 0) << what;
          EXPECT_EQ(have.K16, escapes[e].K16) << what << " " << e;
        }
      }
    }
  }
  EXPECT_GT(compactTiles, 64); // of 96
}
