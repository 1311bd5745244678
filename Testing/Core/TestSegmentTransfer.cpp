// The direct-send and binary-swap segment counts (apc::CountSegmentTransfer) on hand-made
// segment lists whose transfers can be counted on paper.
#include "apcSegmentTransfer.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <utility>
#include <vector>

namespace
{
using Runs = std::vector<std::pair<int64_t, int64_t>>;

// A width x height image whose every pixel in `filled` has the given runs (others empty).
apc::SegmentImage Image(int width, int height, const Runs& runs, const std::vector<int>& filled)
{
  apc::SegmentImage image;
  image.Reset(width, height);
  std::vector<bool> has(static_cast<size_t>(width) * height, false);
  for (int p : filled)
  {
    has[p] = true;
  }
  for (size_t p = 0; p < has.size(); ++p)
  {
    if (has[p])
    {
      for (const auto& run : runs)
      {
        image.Segments.push_back({ run.first, run.second, { 0.f, 0.f, 0.f }, 0.5f });
      }
    }
    image.Offsets[p + 1] = static_cast<int64_t>(image.Segments.size());
  }
  return image;
}

std::vector<const apc::SegmentImage*> Pointers(const std::vector<apc::SegmentImage>& images)
{
  std::vector<const apc::SegmentImage*> pointers;
  for (const auto& image : images)
  {
    pointers.push_back(&image);
  }
  return pointers;
}

// Gear teeth on one pixel: `slabs` periods, in each the ranks' slabs of 10 samples in the
// order `order` (order[s] = rank of the s-th slab of a period), all touching.
std::vector<apc::SegmentImage> Slabs(const std::vector<int>& order, int slabs)
{
  const int n = static_cast<int>(order.size());
  std::vector<Runs> runs(n);
  for (int period = 0; period < slabs; ++period)
  {
    for (int s = 0; s < n; ++s)
    {
      const int64_t first = 10 * (period * n + s);
      runs[order[s]].emplace_back(first, first + 9);
    }
  }
  std::vector<apc::SegmentImage> images;
  for (int r = 0; r < n; ++r)
  {
    images.push_back(Image(1, 1, runs[r], { 0 }));
  }
  return images;
}
}

TEST(SegmentTransfer, TwoRanksOnePixel)
{
  // One row: rank 1 owns it (strips [0, 0) and [0, 1)), so rank 0's segment travels; binary
  // swap's one round splits a 1-pixel region into [0, 0) and [0, 1): rank 1 keeps it too.
  const std::vector<apc::SegmentImage> images = { Image(1, 1, { { 0, 4 } }, { 0 }),
    Image(1, 1, { { 5, 9 } }, { 0 }) };
  const apc::SegmentTransferCounts c = apc::CountSegmentTransfer(Pointers(images));
  EXPECT_EQ(c.NonEmptyPixels, 1);
  EXPECT_EQ(c.Segments, 2);
  EXPECT_EQ(c.MaxSegmentsPerPixel, 2);
  EXPECT_EQ(c.DirectSend, 1);
  EXPECT_EQ(c.BinarySwap, 1);
  EXPECT_EQ(c.BinarySwapUnmerged, 1);
}

TEST(SegmentTransfer, InterleavedSlabsMergeInBinarySwap)
{
  // 4 ranks, 2 periods of slabs in rank order 0 1 2 3: round 0 sends one rank's 2 slabs from
  // each of 2 pairs (4); round 1 sends one block {0,1} or {2,3}, whose 4 slabs merge into 2
  // runs (2; 4 unmerged). Direct send: 8 segments, the owner's 2 stay.
  const auto images = Slabs({ 0, 1, 2, 3 }, 2);
  const apc::SegmentTransferCounts c = apc::CountSegmentTransfer(Pointers(images));
  EXPECT_EQ(c.Segments, 8);
  EXPECT_EQ(c.DirectSend, 6);
  EXPECT_EQ(c.BinarySwap, 6);
  EXPECT_EQ(c.BinarySwapUnmerged, 8);
}

TEST(SegmentTransfer, NonAdjacentBlocksDoNotMerge)
{
  // Slab order 0 2 1 3: blocks {0,1} and {2,3} are never next to each other in depth.
  const auto images = Slabs({ 0, 2, 1, 3 }, 2);
  const apc::SegmentTransferCounts c = apc::CountSegmentTransfer(Pointers(images));
  EXPECT_EQ(c.BinarySwap, 8);
  EXPECT_EQ(c.BinarySwapUnmerged, 8);
}

TEST(SegmentTransfer, EightRanksAnalytic)
{
  // K slabs per rank in rank order: binary swap sends, per round r, n / 2^(r+1) blocks of K
  // merged runs, K (n - 1) in all (as direct send); unmerged, K n log2(n) / 2.
  const int k = 3;
  const auto images = Slabs({ 0, 1, 2, 3, 4, 5, 6, 7 }, k);
  const apc::SegmentTransferCounts c = apc::CountSegmentTransfer(Pointers(images));
  EXPECT_EQ(c.Segments, 8 * k);
  EXPECT_EQ(c.DirectSend, 7 * k);
  EXPECT_EQ(c.BinarySwap, 7 * k);
  EXPECT_EQ(c.BinarySwapUnmerged, k * 8 * 3 / 2);
}

TEST(SegmentTransfer, StripsAndHalvesFollowThePixels)
{
  // 2 ranks, 4 x 2 image, every pixel has one segment on each rank: rank 0 owns row 0, rank 1
  // row 1, so each pixel sends one segment (8). Binary swap: the lower rank keeps the first
  // half (row 0), the same 8. Only rank 0 has segments in row 1 (pixels 4..7): there they all
  // travel to rank 1 in both patterns; in row 0 nothing is sent.
  const std::vector<int> all = { 0, 1, 2, 3, 4, 5, 6, 7 };
  std::vector<apc::SegmentImage> images = { Image(4, 2, { { 0, 1 } }, all),
    Image(4, 2, { { 2, 3 } }, all) };
  apc::SegmentTransferCounts c = apc::CountSegmentTransfer(Pointers(images));
  EXPECT_EQ(c.RowBegin, 0);
  EXPECT_EQ(c.RowEnd, 2);
  EXPECT_EQ(c.DirectSend, 8);
  EXPECT_EQ(c.BinarySwap, 8);

  images = { Image(4, 2, { { 0, 1 } }, { 4, 5, 6, 7 }), Image(4, 2, { { 2, 3 } }, { 0, 1, 2, 3 }) };
  c = apc::CountSegmentTransfer(Pointers(images));
  EXPECT_EQ(c.NonEmptyPixels, 8);
  EXPECT_EQ(c.MaxSegmentsPerPixel, 1);
  EXPECT_EQ(c.DirectSend, 4 + 4) << "rank 1's row-0 segments go to rank 0, rank 0's row 1 to 1";
  EXPECT_EQ(c.BinarySwap, 8);

  // The heatmap adds the ranks up.
  const std::vector<int32_t> heat = apc::SegmentCountImage(Pointers(images));
  EXPECT_EQ(heat, std::vector<int32_t>(8, 1));
}

TEST(SegmentTransfer, EmptyRowsAreNotStriped)
{
  // Segments only in row 2 of 4: both strips are cut from that row alone.
  std::vector<apc::SegmentImage> images = { Image(2, 4, { { 0, 0 } }, { 4, 5 }),
    Image(2, 4, { { 1, 1 } }, { 4, 5 }) };
  const apc::SegmentTransferCounts c = apc::CountSegmentTransfer(Pointers(images));
  EXPECT_EQ(c.RowBegin, 2);
  EXPECT_EQ(c.RowEnd, 3);
  EXPECT_EQ(c.DirectSend, 2);
  const apc::SegmentTransferCounts all = apc::CountSegmentTransfer(Pointers(images), 0, 4);
  EXPECT_EQ(all.RowBegin, 0);
  EXPECT_EQ(all.DirectSend, 2) << "rank 1 owns rows 2-3: rank 0's two segments travel";
}

TEST(SegmentTransfer, ThreeRanksHaveNoBinarySwap)
{
  const auto images = Slabs({ 0, 1, 2 }, 1);
  const apc::SegmentTransferCounts c = apc::CountSegmentTransfer(Pointers(images));
  EXPECT_EQ(c.BinarySwap, -1);
  EXPECT_EQ(c.DirectSend, 2);
}

TEST(SegmentTransfer, BadInputThrows)
{
  EXPECT_THROW(apc::CountSegmentTransfer({}), std::invalid_argument);
  EXPECT_THROW(apc::CountSegmentTransfer({ nullptr }), std::invalid_argument);
  const apc::SegmentImage a = Image(2, 2, {}, {});
  const apc::SegmentImage b = Image(3, 2, {}, {});
  EXPECT_THROW(apc::CountSegmentTransfer({ &a, &b }), std::invalid_argument);
  EXPECT_THROW(apc::CountSegmentTransfer({ &a }, 1, 3), std::invalid_argument);
  EXPECT_THROW(apc::SegmentCountImage({ &a, &b }), std::invalid_argument);
}
