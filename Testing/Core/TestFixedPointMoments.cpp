#include "apcFixedPointMoments.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace fp = apc::fixedpoint;

namespace
{

TEST(FixedPointMoments, ExponentBoundsB0)
{
  EXPECT_EQ(fp::ExponentByte(0.0), 0);
  EXPECT_EQ(fp::ExponentByte(-1.0), 0);
  EXPECT_EQ(fp::ExponentByte(std::nan("")), 0);
  for (double b0 : { 1e-30, 1e-3, 0.5, 1.0, 3.0, 1024.0, 7.5e5 })
  {
    const int e = fp::ExponentByte(b0) - 128;
    EXPECT_LT(b0, std::ldexp(1.0, e)) << b0;
    EXPECT_GE(b0, std::ldexp(1.0, e - 1)) << b0; // tight: the bits are not wasted
  }
  EXPECT_EQ(fp::ExponentByte(1e-300), 1);  // clamped at 2^-127
  EXPECT_EQ(fp::ExponentByte(1e300), 255); // clamped at 2^127
}

TEST(FixedPointMoments, Headroom)
{
  EXPECT_EQ(fp::HeadroomBits(1), 0);
  EXPECT_EQ(fp::HeadroomBits(2), 1);
  EXPECT_EQ(fp::HeadroomBits(3), 2);
  EXPECT_EQ(fp::HeadroomBits(8), 3);
  EXPECT_EQ(fp::HeadroomBits(9), 4);
  EXPECT_EQ(fp::HeadroomBits(256), 8);
}

// N processes' moments of one pixel, as the pass would produce them: |b_k| <= b0 per process.
std::vector<std::vector<double>> RandomProcessMoments(std::mt19937& random, int processes)
{
  std::uniform_real_distribution<double> depth(-1.0, 1.0);
  std::exponential_distribution<double> absorbance(3.0);
  std::vector<std::vector<double>> moments(processes, std::vector<double>(5, 0.0));
  for (auto& b : moments)
  {
    for (int s = 0; s < 20; ++s)
    {
      const double a = absorbance(random);
      const double z = depth(random);
      for (int k = 0; k < 5; ++k)
      {
        b[k] += std::pow(z, k) * a;
      }
    }
  }
  return moments;
}

TEST(FixedPointMoments, SumsAreExactAndOrderIndependent)
{
  std::mt19937 random(11);
  for (int processes : { 2, 3, 8, 64, 256 })
  {
    const int headroom = fp::HeadroomBits(processes);
    const auto moments = RandomProcessMoments(random, processes);
    unsigned char agreed = 0;
    for (const auto& b : moments)
    {
      agreed = std::max(agreed, fp::ExponentByte(b[0]));
    }
    const double scale = fp::Scale(agreed, headroom);
    std::vector<int32_t> codes;
    double exact[5] = { 0, 0, 0, 0, 0 };
    std::vector<int64_t> wide(5, 0);
    for (const auto& b : moments)
    {
      for (int k = 0; k < 5; ++k)
      {
        codes.push_back(fp::Encode(b[k], scale, headroom));
        wide[k] += codes.back();
        exact[k] += b[k];
      }
    }
    for (int k = 0; k < 5; ++k)
    {
      // No int32 overflow: the sum fits, whatever the order of the partial sums.
      ASSERT_LE(std::abs(wide[k]), static_cast<int64_t>(std::numeric_limits<int32_t>::max()));
      // Each code is off by at most half a step: the sum by processes / 2 steps.
      EXPECT_LE(std::abs(fp::Decode(static_cast<int32_t>(wide[k]), scale) - exact[k]),
        0.5 * processes / scale * (1 + 1e-12))
        << processes << " processes, moment " << k;
    }
    // Any order of int32 additions gives the same bits (the sum is exact).
    for (int shuffle = 0; shuffle < 5; ++shuffle)
    {
      std::vector<int> order(processes);
      for (int p = 0; p < processes; ++p)
      {
        order[p] = p;
      }
      std::shuffle(order.begin(), order.end(), random);
      for (int k = 0; k < 5; ++k)
      {
        int32_t sum = 0;
        for (int p : order)
        {
          sum += codes[static_cast<size_t>(p) * 5 + k];
        }
        EXPECT_EQ(sum, static_cast<int32_t>(wide[k]));
      }
    }
  }
}

TEST(FixedPointMoments, BeatsFloatRelativeToB0AtFewProcesses)
{
  // The worst-case step relative to the largest b0: 2^-(29) at 2 processes, finer than the
  // float ulp 2^-24 that float sums start from.
  const double scale = fp::Scale(fp::ExponentByte(1.0), fp::HeadroomBits(2));
  EXPECT_LT(1.0 / scale, std::ldexp(1.0, -24));
}

TEST(FixedPointMoments, EncodeSaturatesAndRejectsNaN)
{
  const int headroom = 3;
  const double scale = fp::Scale(fp::ExponentByte(1.0), headroom);
  const int32_t limit = 1 << (30 - headroom);
  EXPECT_EQ(fp::Encode(1e9, scale, headroom), limit);
  EXPECT_EQ(fp::Encode(-1e9, scale, headroom), -limit);
  EXPECT_EQ(fp::Encode(std::nan(""), scale, headroom), 0);
  EXPECT_EQ(fp::Encode(-0.5, scale, headroom), -(limit / 4)); // exact for powers of two
}

} // namespace
