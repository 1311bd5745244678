#include "apcAutoMode.h"

#include <gtest/gtest.h>

namespace
{

constexpr double kMomentBytes = 37; // 4 moments on the compact wire

TEST(AutoMode, FirstFrameMeasuresSegments)
{
  apc::AutoMode mode;
  EXPECT_FALSE(mode.HasEstimate());
  EXPECT_EQ(mode.Choose(4, kMomentBytes), apc::AutoMode::Segments);
}

TEST(AutoMode, FewSegmentsKeepTheExactPicture)
{
  // The wind data at 2 ranks: ~2.2 segments per covered pixel, each rank covering most.
  apc::AutoMode mode;
  mode.Choose(2, kMomentBytes);
  mode.Record(1000, 1600, 2200);
  EXPECT_EQ(mode.Choose(2, kMomentBytes), apc::AutoMode::Segments);
  // Bytes: segments (1/2)(24 * 2200 + 16 * 1000) = 34400 against moments 2 * 37 * 1000.
  EXPECT_DOUBLE_EQ(mode.EstimatedSegmentBytes(2), 34400);
  EXPECT_DOUBLE_EQ(mode.EstimatedMomentBytes(2, kMomentBytes), 74000);
}

TEST(AutoMode, ManySegmentsSwitchToMoments)
{
  // The gear teeth at 8 ranks: every rank covers every pixel with 4 slabs.
  apc::AutoMode mode;
  mode.Choose(8, kMomentBytes);
  mode.Record(1000, 8000, 32000);
  EXPECT_EQ(mode.Choose(8, kMomentBytes), apc::AutoMode::Moments);
  // Moment frames keep the runs per covering process and update the coverage: when the
  // camera moves so that fewer ranks overlap, the estimate follows and segments return.
  mode.Record(1000, 1200, -1);
  EXPECT_EQ(mode.Choose(8, kMomentBytes), apc::AutoMode::Segments);
}

TEST(AutoMode, HysteresisHoldsCloseCalls)
{
  apc::AutoMode mode;
  mode.Choose(4, kMomentBytes);
  // Segments cost (3/4)(24 r s + 16 u); moments 4 * 37 u. Choose r s so that moments are 10%
  // cheaper: not enough to leave segments.
  const double u = 1000;
  const double momentBytes = 4 * kMomentBytes * u;
  const double segmentsNeeded = (momentBytes / 0.9 / 0.75 - 16 * u) / 24;
  mode.Record(u, u, segmentsNeeded);
  EXPECT_EQ(mode.Choose(4, kMomentBytes), apc::AutoMode::Segments);
  // Twice the segments: moments win clearly.
  mode.Record(u, u, 2 * segmentsNeeded);
  EXPECT_EQ(mode.Choose(4, kMomentBytes), apc::AutoMode::Moments);
  // Back to the close call: moments stay.
  mode.Record(u, u, segmentsNeeded);
  EXPECT_EQ(mode.Choose(4, kMomentBytes), apc::AutoMode::Moments);
}

TEST(AutoMode, OneProcessIsExact)
{
  // Nothing travels on one process: the exact picture costs no more.
  apc::AutoMode mode;
  mode.Choose(1, kMomentBytes);
  mode.Record(1000, 1000, 50000);
  EXPECT_EQ(mode.Choose(1, kMomentBytes), apc::AutoMode::Segments);
}

TEST(AutoMode, OneProcessFollowsTheMeasuredTime)
{
  // The wind data at 1 process, lower bytes irrelevant (none travel): the segments march every
  // sample and sort them (9 s), APC stops where rays are opaque (3 s).
  apc::AutoMode mode;
  EXPECT_EQ(mode.Choose(1, kMomentBytes), apc::AutoMode::Segments);
  mode.Record(1000, 1000, 50000, 9.0, true);
  EXPECT_EQ(mode.Choose(1, kMomentBytes), apc::AutoMode::Moments) << "times APC once";
  mode.Record(1000, 1000, -1, 3.0, false);
  EXPECT_EQ(mode.Choose(1, kMomentBytes), apc::AutoMode::Moments);
  EXPECT_DOUBLE_EQ(mode.GetSecondsPerPixel(apc::AutoMode::Moments), 3e-3);
  // An untimed (interactive) frame keeps the measurements.
  mode.Record(500, 500, -1);
  EXPECT_EQ(mode.Choose(1, kMomentBytes), apc::AutoMode::Moments);
}

TEST(AutoMode, MeasuredTimeOverridesBytes)
{
  // Many segments (bytes favour APC), but the segment frames measured faster: they stay.
  apc::AutoMode mode;
  mode.Choose(8, kMomentBytes);
  mode.Record(1000, 8000, 32000, 2.0, true);
  EXPECT_EQ(mode.Choose(8, kMomentBytes), apc::AutoMode::Moments) << "times APC once";
  mode.Record(1000, 8000, -1, 3.0, false);
  EXPECT_EQ(mode.Choose(8, kMomentBytes), apc::AutoMode::Segments);
  // Within the hysteresis (APC 10 % cheaper per pixel): segments stay; clearly cheaper: APC.
  mode.Record(1000, 8000, 32000, 3.3, true);
  EXPECT_EQ(mode.Choose(8, kMomentBytes), apc::AutoMode::Segments);
  mode.Record(1000, 8000, 32000, 4.0, true);
  EXPECT_EQ(mode.Choose(8, kMomentBytes), apc::AutoMode::Moments);
}

} // namespace
