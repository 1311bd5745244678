#include "apcDepthWarp.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
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

// The tabulated warp of lattice depths is the warp itself, bit for bit: at every lattice depth
// (the lattice's own arithmetic, offset 0), at jittered depths between them, beyond near and
// far, and where no table is built (a degenerate warp, a range of too many indices).
TEST(DepthWarp, LatticeTableIsTheWarpBitForBit)
{
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case
  {
    double Near, Far, Spacing;
    bool Tabulated;
  };
  const Case cases[] = { { 2.0, 50.0, 0.37, true }, { 1234.5, 1300.25, 0.0183, true },
    { 0.0, 10.0, 0.01, true }, { 5.0, 5.0, 0.1, false }, { nan, 3.0, 0.1, false },
    { 1.0, 1e4, 1e-3, false } };
  for (const Case& c : cases)
  {
    const apc::LogDepthWarp warp(c.Near, c.Far);
    const apc::LatticeDepthWarp lattice(warp, c.Spacing);
    EXPECT_EQ(lattice.GetNumberOfEntries() > 0, c.Tabulated) << c.Near;
    // A warp without a finite near plane has no table: walk the indices from 0 (the cast of a
    // non-finite quotient would be undefined).
    const double nearIndex = std::floor(warp.Near() / c.Spacing);
    const int64_t first = (std::isfinite(nearIndex) ? static_cast<int64_t>(nearIndex) : 0) - 20;
    const int64_t last = static_cast<int64_t>(std::ceil(c.Far / c.Spacing)) + 20;
    const int64_t step = std::max<int64_t>(1, (last - first) / 5000);
    for (int64_t k = first; k <= last; k += step)
    {
      for (const double offset : { 0.0, -0.0, 0.25, 0.5, 1e-9 })
      {
        // Lattice::At's expression.
        const double t = (static_cast<double>(k) + offset) * c.Spacing;
        const double expected = warp(t);
        const double got = lattice(k, t);
        ASSERT_EQ(std::memcmp(&expected, &got, sizeof got), 0)
          << "near " << c.Near << " k " << k << " offset " << offset;
      }
    }
  }
}

// The table's entries are read only where the depth is its index's lattice depth: a wrong
// index, or a depth that is not t_k, gets the warp of the depth given.
TEST(DepthWarp, LatticeTableChecksTheDepth)
{
  const apc::LogDepthWarp warp(2.0, 50.0);
  const apc::LatticeDepthWarp lattice(warp, 0.5);
  ASSERT_GT(lattice.GetNumberOfEntries(), 0);
  EXPECT_EQ(lattice(20, 10.0), warp(10.0));
  EXPECT_EQ(lattice(21, 10.0), warp(10.0));
  EXPECT_EQ(lattice(20, std::nextafter(10.0, 11.0)), warp(std::nextafter(10.0, 11.0)));
  EXPECT_NE(warp(10.0), warp(10.5));
}

} // namespace
