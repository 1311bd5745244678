// What pass 2 asks of the reconstruction: the depth behind which a pixel's samples are hidden
// (HiddenDepth) and the batched weights of a cached run, against the per-sample query.

#include "apcMomentTestRays.h"
#include "apcMomentTransmittance.h"
#include "apcOrderedReference.h"
#include "apcPolynomialRoots.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>
#include <sstream>
#include <type_traits>
#include <utility>
#include <vector>

namespace
{

using apctest::RayMoments;

template <typename T>
class MomentQueryTest : public ::testing::Test
{
};
TYPED_TEST_SUITE(MomentQueryTest, apctest::MomentOrders);

// HiddenDepth(w): from it on T(z) b0 <= w (what pass 2 may skip), and it is no more than one
// bisection step (2/1024) behind the first depth where that holds, on rays as pass 2 sees
// them with b0 up to ~100, so that many of them have a hidden depth.
TYPED_TEST(MomentQueryTest, HiddenDepthBoundsTheSkippedWeight)
{
  constexpr int N = TypeParam::value;
  constexpr double kWeight = 1e-4;
  std::mt19937_64 rng(77 + N);
  std::vector<double> depths;
  int found = 0;
  double worst = 0.0; // largest T b0 / w at or behind the hidden depth
  for (int set = 0; set < 2000; ++set)
  {
    std::vector<double> sums = RayMoments(rng, N, depths);
    const double scale = 1.0 + (set % 8) * 4.0; // b0 up to ~32x a ray's
    for (double& s : sums)
    {
      s *= scale;
    }
    const apc::MomentTransmittance<N> t(sums.data());
    const double hidden = t.HiddenDepth(kWeight);
    if (!std::isfinite(hidden))
    {
      // None found: then the far end is not hidden.
      ASSERT_GT(t(1.0) * sums[0], kWeight) << "set " << set;
      continue;
    }
    ++found;
    ASSERT_GE(hidden, -1.0);
    ASSERT_LE(hidden, 1.0);
    if (hidden > -1.0)
    {
      EXPECT_GT(t(hidden - 2.0 / 1024) * sums[0], kWeight) << "set " << set;
    }
    std::vector<double> zs = depths;
    for (int i = 0; i <= 200; ++i)
    {
      zs.push_back(hidden + (1.0 - hidden) * i / 200);
    }
    for (const double z : zs)
    {
      if (z >= hidden)
      {
        worst = std::max(worst, t(z) * sums[0] / kWeight);
        ASSERT_LE(t(z) * sums[0], kWeight * (1 + 1e-9)) << "set " << set << " z " << z;
      }
    }
  }
  std::cout << "N=" << N << ": " << found << " of 2000 rays with a hidden depth, largest T b0 / w "
            << worst << " behind it\n";
  EXPECT_GT(found, 500);
  // Empty and degenerate pixels, and a zero weight, skip nothing.
  const double empty[N + 1] = {};
  EXPECT_EQ(apc::MomentTransmittance<N>(empty).HiddenDepth(kWeight),
    std::numeric_limits<double>::infinity());
  std::vector<double> sums = RayMoments(rng, N, depths);
  EXPECT_EQ(apc::MomentTransmittance<N>(sums.data()).HiddenDepth(0.0),
    std::numeric_limits<double>::infinity());
}

namespace
{
// The hidden-depth tests' rays: RayMoments' scaled 1 to 29 times as set cycles (faint to far
// past opaque), and the weight bound they hide below (two of them).
std::vector<double> DenserRayMoments(
  std::mt19937_64& rng, int n, int set, std::vector<double>& depths)
{
  std::vector<double> sums = RayMoments(rng, n, depths);
  for (double& s : sums)
  {
    s *= 1.0 + (set % 8) * 4.0;
  }
  return sums;
}

double HiddenWeightOf(int set)
{
  return set % 3 == 0 ? 1e-2 : 1e-4;
}
}

// HiddenDepth takes two bisection steps a round (three independent queries): its depth is the
// one-step-at-a-time bisection's, to the bit, written here with the public query.
TYPED_TEST(MomentQueryTest, HiddenDepthIsTheOneStepBisection)
{
  constexpr int N = TypeParam::value;
  std::mt19937_64 rng(99 + N);
  std::vector<double> depths;
  int found = 0;
  for (int set = 0; set < 2000; ++set)
  {
    const std::vector<double> sums = DenserRayMoments(rng, N, set, depths);
    const apc::MomentTransmittance<N> t(sums.data());
    const double weight = HiddenWeightOf(set);
    const double limit = weight / sums[0];
    auto hidden = [&](double z)
    {
      const apc::TransmittanceQuery q = t.Query(z);
      return !q.Fallback && q.Transmittance <= limit;
    };
    double expected = std::numeric_limits<double>::infinity();
    if (std::exp(-sums[0]) * sums[0] <= weight && hidden(1.0))
    {
      double lo = -1.0;
      double hi = 1.0;
      if (hidden(-1.0))
      {
        hi = -1.0;
      }
      else
      {
        for (int step = 0; step < 10; ++step)
        {
          const double mid = 0.5 * (lo + hi);
          (hidden(mid) ? hi : lo) = mid;
        }
      }
      expected = hi;
      ++found;
    }
    ASSERT_EQ(t.HiddenDepth(weight), expected) << "set " << set;
  }
  EXPECT_GT(found, 500);
}

// HiddenDepth's test without an exponential answers only where exp(-b0) b0 > w (no hidden
// depth): b0 on a dense grid over every weight's crossings, the crossings themselves to the
// last bits, and it answers most pixels below the far crossing (b0 ~ ln(1/w)).
TEST(HiddenDepthBound, AnswersOnlyWhereTheExponentialWould)
{
  int answered = 0;
  int below = 0;
  for (const double w : { 1e-2, 1e-4, 1e-6, 0.3 })
  {
    std::vector<double> b0s;
    for (double b = 1e-8; b < 600.0; b *= 1.0001)
    {
      b0s.push_back(b);
    }
    // Near the crossings exp(-b) b = w, found by bisection, both sides by a few ulps.
    for (double lo0 : { 1e-9, 1.0 })
    {
      double lo = lo0;
      double hi = lo0 == 1.0 ? 700.0 : 1.0;
      for (int i = 0; i < 200; ++i)
      {
        const double mid = 0.5 * (lo + hi);
        const bool above = std::exp(-mid) * mid > w;
        ((above == (lo0 == 1.0)) ? lo : hi) = mid;
      }
      double b = lo;
      for (int i = 0; i < 64; ++i)
      {
        b = std::nextafter(b, 0.0);
      }
      for (int i = 0; i < 128; ++i, b = std::nextafter(b, 1e300))
      {
        b0s.push_back(b);
      }
    }
    const double far = -std::log(w) + std::log(-std::log(w));
    for (const double b0 : b0s)
    {
      const bool expAnswer = !(std::exp(-b0) * b0 <= w);
      if (apc::SurelyNoHiddenDepth(b0, w))
      {
        ++answered;
        ASSERT_TRUE(expAnswer) << "b0 " << b0 << " w " << w;
      }
      else if (expAnswer && b0 > 10.0 * w && b0 < 0.8 * far)
      {
        ++below; // left to the exponential although far from both crossings
      }
    }
  }
  EXPECT_GT(answered, 100000);
  EXPECT_EQ(below, 0);
}

// The far side's test without an exponential answers only where exp(-b0) b0 <= w, and it
// answers every b0 from 1.5 past the far crossing up to its end at 512: b0 on a
// dense grid and 128 ulps about each crossing.
TEST(HiddenDepthBound, AnswersTheFarSideOnlyWhereTheExponentialWould)
{
  int answered = 0;
  int missed = 0;
  for (const double w : { 1e-2, 1e-4, 1e-6, 0.3 })
  {
    std::vector<double> b0s;
    for (double b = 1e-8; b < 600.0; b *= 1.0001)
    {
      b0s.push_back(b);
    }
    double farCrossing = 0.0;
    for (double lo0 : { 1e-9, 1.0 })
    {
      double lo = lo0;
      double hi = lo0 == 1.0 ? 700.0 : 1.0;
      for (int i = 0; i < 200; ++i)
      {
        const double mid = 0.5 * (lo + hi);
        const bool above = std::exp(-mid) * mid > w;
        ((above == (lo0 == 1.0)) ? lo : hi) = mid;
      }
      farCrossing = lo;
      double b = lo;
      for (int i = 0; i < 64; ++i)
      {
        b = std::nextafter(b, 0.0);
      }
      for (int i = 0; i < 128; ++i, b = std::nextafter(b, 1e300))
      {
        b0s.push_back(b);
      }
    }
    for (const double b0 : b0s)
    {
      const bool belowW = std::exp(-b0) * b0 <= w;
      if (apc::SurelyMayHaveHiddenDepth(b0, w))
      {
        ++answered;
        ASSERT_TRUE(belowW) << "b0 " << b0 << " w " << w;
      }
      else if (b0 > farCrossing + 1.5 && b0 < 512.0)
      {
        ++missed; // left to the exponential although far past the crossing
      }
    }
  }
  EXPECT_GT(answered, 100000);
  EXPECT_EQ(missed, 0);
}

// Given the range of a pixel's samples, HiddenDepth stops its bisection once no sample lies
// between its bounds: the depth may differ from HiddenDepth(w), but every sample, and every
// depth in the range, falls on the same side of both. Rays as above, their samples as the
// range (some pixels' samples only the front part of the ray, as a stopped ray's cache holds
// them).
TYPED_TEST(MomentQueryTest, HiddenDepthWithinTheSamplesSkipsTheSameSamples)
{
  constexpr int N = TypeParam::value;
  std::mt19937_64 rng(313 + N);
  std::vector<double> depths;
  int found = 0;
  int stoppedEarly = 0;
  for (int set = 0; set < 4000; ++set)
  {
    const std::vector<double> sums = DenserRayMoments(rng, N, set, depths);
    const apc::MomentTransmittance<N> t(sums.data());
    const double weight = HiddenWeightOf(set);
    // The samples as pass 2 holds them (floats), all of the ray's or its front half.
    std::vector<float> samples(depths.begin(), depths.end());
    std::sort(samples.begin(), samples.end());
    if (set % 2 == 1)
    {
      samples.resize((samples.size() + 1) / 2);
    }
    const float nearest = samples.front();
    const float farthest = samples.back();
    int calls = 0;
    const double plain = t.HiddenDepth(weight);
    const double within = t.HiddenDepth(weight,
      [&]
      {
        ++calls;
        return std::make_pair(static_cast<double>(nearest), static_cast<double>(farthest));
      });
    ASSERT_LE(calls, 1);
    if (!std::isfinite(plain))
    {
      ASSERT_EQ(within, plain) << "set " << set;
      continue;
    }
    ++found;
    stoppedEarly += within != plain;
    for (const float z : samples)
    {
      ASSERT_EQ(z >= plain, z >= within) << "set " << set << " z " << z;
    }
    // Every depth of the range too (the samples' own at the ends), on a fine grid.
    for (int i = 0; i <= 400; ++i)
    {
      const double z = nearest + (static_cast<double>(farthest) - nearest) * i / 400;
      ASSERT_EQ(z >= plain, z >= within) << "set " << set << " z " << z;
    }
  }
  std::cout << "N=" << N << ": " << found << " pixels with a hidden depth, " << stoppedEarly
            << " of them found in fewer steps\n";
  EXPECT_GT(found, 500);
  EXPECT_GT(stoppedEarly, found / 10); // the steps are saved, not only the samples the same
}

// The batched weights (vector arithmetic and a polynomial exponential for 4 moments) against
// the per-sample query and std::expm1, over pass-2-like rays, absorbances from 1e-7 to the cap
// and depths beyond [-1,1], relative to the weight and per unit of b0. Measured worst:
// 1.8e-15 (N=4; 0 for 6 and 8, which query per sample); bound 1e-13.
TYPED_TEST(MomentQueryTest, BatchedWeightsMatchTheQuery)
{
  constexpr int N = TypeParam::value;
  std::mt19937_64 rng(4242 + N);
  std::uniform_real_distribution<double> logAbsorbance(std::log(1e-7), std::log(10.0));
  std::vector<double> depths;
  double worst = 0.0;
  for (int set = 0; set < 1000; ++set)
  {
    std::vector<double> sums = RayMoments(rng, N, depths);
    for (double& s : sums)
    {
      s *= 1.0 + (set % 5) * 10.0;
    }
    const apc::MomentTransmittance<N> t(sums.data());
    for (int i = 0; i <= 20; ++i)
    {
      depths.push_back(-1.1 + 2.2 * i / 20);
    }
    std::vector<double> absorbances(depths.size());
    for (double& a : absorbances)
    {
      a = std::exp(logAbsorbance(rng));
    }
    std::vector<double> weights(depths.size(), -1.0);
    t.Weights(depths.data(), absorbances.data(), weights.data(), static_cast<int>(depths.size()));
    for (size_t i = 0; i < depths.size(); ++i)
    {
      const double expected = -std::expm1(-absorbances[i]) * t(depths[i]);
      // T = exp(-b0 A): the rounding of A (FMA or not) moves T by b0 times it, relatively.
      const double error =
        std::abs(weights[i] - expected) / std::max(expected, 1e-300) / std::max(1.0, sums[0]);
      worst = std::max(worst, expected > 1e-300 ? error : 0.0);
      ASSERT_LE(error, 1e-13) << "set " << set << " z " << depths[i] << " a " << absorbances[i];
    }
  }
  std::cout << "N=" << N << " worst |batched - queried weight| / weight / b0: " << worst << "\n";
  // Empty pixels weigh alpha alone.
  const double empty[N + 1] = {};
  const double z = 0.25;
  const double a = 0.5;
  double w = 0;
  apc::MomentTransmittance<N>(empty).Weights(&z, &a, &w, 1);
  EXPECT_DOUBLE_EQ(w, -std::expm1(-a));
}

} // namespace
