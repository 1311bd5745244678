// The small pieces the marcher and the segment exchange share: the compressed-row builder,
// the strip-owner rule, the wire format and the grouping of received segments by pixel.
#include "apcCompressedRows.h"
#include "apcRaySegments.h"

#include <gtest/gtest.h>

#include <utility>
#include <vector>

TEST(CompressedRows, CountingSortIsStableAndComplete)
{
  const std::vector<std::pair<int64_t, int>> entries = { { 2, 10 }, { 0, 11 }, { 2, 12 }, { 3, 13 },
    { 0, 14 } };
  std::vector<int64_t> offsets;
  std::vector<int> values;
  apc::BuildCompressedRows<int>(
    5,
    [&](auto&& emit)
    {
      for (const auto& e : entries)
      {
        emit(e.first, e.second);
      }
    },
    offsets, values);
  EXPECT_EQ(offsets, (std::vector<int64_t>{ 0, 2, 2, 4, 5, 5 }));
  EXPECT_EQ(values, (std::vector<int>{ 11, 14, 10, 12, 13 }));
}

TEST(SegmentStrips, CoverTheRowsOnceInOrder)
{
  for (int processes : { 1, 2, 3, 7 })
  {
    for (int rows : { 0, 1, 5, 100 })
    {
      const apc::SegmentStrips strips{ 10, rows, processes };
      EXPECT_EQ(strips.Begin(0), 10);
      EXPECT_EQ(strips.Begin(processes), 10 + rows);
      int total = 0;
      for (int o = 0; o < processes; ++o)
      {
        EXPECT_GE(strips.RowsOf(o), 0);
        EXPECT_LE(strips.RowsOf(o), rows / processes + 1) << "strips are balanced";
        total += strips.RowsOf(o);
      }
      EXPECT_EQ(total, rows);
    }
  }
}

TEST(WireSegment, RoundTripKeepsWhatBlendingNeeds)
{
  const apc::RaySegment s{ 1000000007, 1000000010, { 0.25f, 0.5f, 0.125f }, 0.75f };
  const apc::WireSegment w = apc::WireSegment::From(s, 42, 1000000000);
  EXPECT_EQ(w.Pixel, 42);
  EXPECT_EQ(w.KFirst, 7);
  const apc::RaySegment back = w.ToSegment();
  EXPECT_EQ(back.KFirst, 7);
  EXPECT_EQ(back.Colour, s.Colour);
  EXPECT_EQ(back.Transmittance, s.Transmittance);
}

TEST(GroupByPixel, KeepsArrivalOrderWithinAPixel)
{
  // Two senders; pixel 1 gets one segment from each, in sender order.
  const std::vector<std::vector<apc::WireSegment>> from = {
    { { 1, 5, { 0.1f, 0, 0 }, 0.5f }, { 3, 2, { 0.2f, 0, 0 }, 0.5f } },
    { { 1, 1, { 0.3f, 0, 0 }, 0.5f } },
  };
  apc::SegmentImage strip;
  apc::GroupByPixel(from, 2, 2, strip);
  ASSERT_EQ(strip.Width, 2);
  ASSERT_EQ(strip.Height, 2);
  EXPECT_EQ(strip.Count(0), 0);
  ASSERT_EQ(strip.Count(1), 2);
  EXPECT_EQ(strip.Count(2), 0);
  EXPECT_EQ(strip.Count(3), 1);
  EXPECT_EQ(strip.Segments[strip.Offsets[1]].KFirst, 5);
  EXPECT_EQ(strip.Segments[strip.Offsets[1] + 1].KFirst, 1);
  // Blending sorts by depth: the segment from the second sender (k = 1) comes first.
  const std::array<double, 4> rgba =
    apc::CompositeSegments(strip.Segments.data() + strip.Offsets[1], 2);
  EXPECT_NEAR(rgba[0], 0.3f + 0.5 * 0.1f, 1e-7);
  EXPECT_NEAR(rgba[3], 0.75, 1e-12);
}
