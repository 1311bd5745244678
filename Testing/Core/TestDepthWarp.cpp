#include "apcDepthWarp.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace
{

TEST(DepthWarp, EndpointsAndGeometricMidpoint)
{
  const apc::LogDepthWarp warp{ 2.0, 50.0 };
  EXPECT_FALSE(warp.IsDegenerate());
  // Tolerance 1e-15: a handful of ulps from two logs and a multiply.
  EXPECT_NEAR(warp(2.0), -1.0, 1e-15);
  EXPECT_NEAR(warp(50.0), 1.0, 1e-15);
  // The warp is linear in ln d, so the geometric mean lands in the middle.
  EXPECT_NEAR(warp(std::sqrt(2.0 * 50.0)), 0.0, 1e-14);
}

TEST(DepthWarp, MonotoneAndClamped)
{
  const apc::LogDepthWarp warp{ 0.5, 20.0 };
  double previous = -2.0;
  for (int i = 0; i <= 10000; ++i)
  {
    const double d = 0.01 + i * 0.003; // 0.01 .. 30.01, beyond both ends
    const double z = warp(d);
    ASSERT_GE(z, previous) << "d = " << d;
    ASSERT_GE(z, -1.0);
    ASSERT_LE(z, 1.0);
    previous = z;
  }
  EXPECT_EQ(warp(0.1), -1.0);
  EXPECT_EQ(warp(-3.0), -1.0);
  EXPECT_EQ(warp(21.0), 1.0);
  EXPECT_EQ(warp(std::numeric_limits<double>::infinity()), 1.0);
  EXPECT_EQ(warp(std::numeric_limits<double>::quiet_NaN()), 1.0);
}

TEST(DepthWarp, NonPositiveNearPlaneIsReplaced)
{
  for (const double zmin : { 0.0, -1.0 })
  {
    const apc::LogDepthWarp warp{ zmin, 10.0 };
    EXPECT_FALSE(warp.IsDegenerate());
    EXPECT_DOUBLE_EQ(warp.Near(), apc::LogDepthWarp::kMinNearFraction * 10.0);
    EXPECT_EQ(warp(0.0), -1.0);
    EXPECT_NEAR(warp(10.0), 1.0, 1e-15);
    EXPECT_TRUE(std::isfinite(warp(1e-9)));
  }
}

TEST(DepthWarp, DegenerateRangesAreFinite)
{
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const apc::LogDepthWarp cases[] = { { 5.0, 5.0 }, { 5.0, 1.0 }, { 1.0, -1.0 }, { nan, 3.0 },
    { 1.0, nan }, { 1.0, inf }, { 0.0, 0.0 } };
  for (const apc::LogDepthWarp& warp : cases)
  {
    EXPECT_TRUE(warp.IsDegenerate());
    for (const double d : { -1.0, 0.0, 1.0, 5.0, 1e300, inf, nan })
    {
      EXPECT_EQ(warp(d), 0.0) << "documented: a degenerate range maps everything to 0";
    }
  }
}

} // namespace
