#include "apcPowerMoments.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <vector>

namespace
{

TEST(Absorbance, FromAlpha)
{
  EXPECT_EQ(apc::AbsorbanceFromAlpha(0.0), 0.0);
  EXPECT_EQ(apc::AbsorbanceFromAlpha(-0.5), 0.0);
  EXPECT_EQ(apc::AbsorbanceFromAlpha(std::numeric_limits<double>::quiet_NaN()), 0.0);
  EXPECT_EQ(apc::AbsorbanceFromAlpha(1.0), apc::kAbsorbanceMax);
  EXPECT_EQ(apc::AbsorbanceFromAlpha(2.0), apc::kAbsorbanceMax);
  EXPECT_EQ(apc::AbsorbanceFromAlpha(1.0 - 1e-9), apc::kAbsorbanceMax); // -ln 1e-9 ~ 20.7
  // 1e-15 relative: log1p is correctly rounded to within an ulp or two.
  EXPECT_NEAR(apc::AbsorbanceFromAlpha(0.5), std::log(2.0), 1e-15);
  EXPECT_NEAR(apc::AbsorbanceFromAlpha(1e-12), 1e-12 + 0.5e-24, 1e-27); // 2nd-order term kept
}

TEST(PowerMoments, SumsOfPowers)
{
  apc::PowerMoments<8> m;
  m.Add(0.5, 2.0);
  m.Add(-1.0, 1.0);
  for (int k = 0; k <= 8; ++k)
  {
    // Exact: powers of 0.5 and -1 are representable.
    EXPECT_EQ(m.Sums[k], 2.0 * std::pow(0.5, k) + std::pow(-1.0, k)) << "k = " << k;
  }
}

TEST(PowerMoments, SkipsInvalidSamplesAndClampsDepth)
{
  const double nan = std::numeric_limits<double>::quiet_NaN();
  apc::PowerMoments<4> m;
  m.Add(0.3, 0.0);
  m.Add(0.3, -1.0);
  m.Add(0.3, nan);
  m.Add(nan, 1.0);
  m.AddAlpha(0.3, nan);
  m.AddAlpha(0.3, 0.0);
  for (double b : m.Sums)
  {
    EXPECT_EQ(b, 0.0);
  }
  m.Add(3.0, std::numeric_limits<double>::infinity()); // opaque, beyond the far end
  EXPECT_EQ(m.B0(), apc::kAbsorbanceMax);
  for (int k = 1; k <= 4; ++k)
  {
    EXPECT_EQ(m.Sums[k], apc::kAbsorbanceMax) << "z clamped to 1";
  }
}

TEST(PowerMoments, RawBufferAndOperatorsAgree)
{
  apc::PowerMoments<6> a, b;
  double raw[7] = {};
  double rawA[7] = {};
  const double zs[] = { -0.9, -0.2, 0.1, 0.7 };
  for (int i = 0; i < 4; ++i)
  {
    const double absorbance = 0.1 * (i + 1);
    (i % 2 ? a : b).Add(zs[i], absorbance);
    apc::AccumulatePowerMoments<6>(raw, zs[i], absorbance);
  }
  apc::AddPowerMoments<6>(rawA, a.Data());
  apc::AddPowerMoments<6>(rawA, b.Data());
  const apc::PowerMoments<6> sum = a + b;
  apc::PowerMoments<6> viaCopy = apc::PowerMoments<6>::FromData(a.Data());
  viaCopy += b;
  for (int k = 0; k <= 6; ++k)
  {
    // Sums of 4 terms in different groupings: a few ulps of b0 = 1.
    EXPECT_NEAR(sum.Sums[k], raw[k], 1e-15);
    EXPECT_EQ(sum.Sums[k], rawA[k]);
    EXPECT_EQ(sum.Sums[k], viaCopy.Sums[k]);
  }
  EXPECT_EQ(static_cast<const void*>(sum.Data()), static_cast<const void*>(&sum));
}

template <int N>
void CheckPermutationInvariance()
{
  // Small but deliberately uneven samples, so that rounding could differ by order.
  std::vector<std::pair<double, double>> samples = { { -0.83, 0.31 }, { -0.41, 0.07 },
    { 0.02, 0.66 }, { 0.29, 0.013 }, { 0.57, 0.9 }, { 0.91, 0.45 } };
  std::sort(samples.begin(), samples.end());
  apc::PowerMoments<N> first;
  for (const auto& s : samples)
  {
    first.AddAlpha(s.first, s.second);
  }
  int permutations = 0;
  double worst = 0.0;
  do
  {
    apc::PowerMoments<N> m;
    for (const auto& s : samples)
    {
      m.AddAlpha(s.first, s.second);
    }
    for (int k = 0; k <= N; ++k)
    {
      worst = std::max(worst, std::abs(m.Sums[k] - first.Sums[k]) / first.B0());
    }
    ++permutations;
  } while (std::next_permutation(samples.begin(), samples.end()));
  EXPECT_EQ(permutations, 720);
  // Each sum has 6 terms bounded by b0 in magnitude: reordering changes it by at most
  // ~6 ulps of b0 (~1.3e-15 relative); 1e-14 leaves room without hiding a real bug.
  EXPECT_LE(worst, 1e-14);
  std::cout << "N=" << N << " worst relative moment change over 720 orders: " << worst << "\n";
}

TEST(PowerMoments, OrderIndependent4)
{
  CheckPermutationInvariance<4>();
}
TEST(PowerMoments, OrderIndependent6)
{
  CheckPermutationInvariance<6>();
}
TEST(PowerMoments, OrderIndependent8)
{
  CheckPermutationInvariance<8>();
}

} // namespace
