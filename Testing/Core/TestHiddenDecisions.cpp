// The hidden depth's decisions T(z) <= limit on vector arithmetic (apcHiddenDecisions.h) against
// the scalar query's, and HiddenDepth built on them against the bisection with the query alone.

#include "apcHiddenDecisions.h"
#include "apcMomentTestRays.h"
#include "apcMomentTransmittance.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iostream>
#include <limits>
#include <random>
#include <utility>
#include <vector>

namespace
{

using apctest::RayMoments;

// What HiddenDepth asks of the query at z.
bool QueryHidden(const apc::MomentTransmittance<4>& t, double z, double limit)
{
  const apc::TransmittanceQuery q = t.Query(z);
  return !q.Fallback && q.Transmittance <= limit;
}

// The pixels: rays as pass 2 sees them (b0 up to ~30x a ray's), and the discrete cases of the
// query: moments symmetric about 0 (kernel polynomial's degree drops at z = 0), all absorbance
// at one or two depths on the bisection's grid (the bias alone keeps the Hankel matrix positive,
// discriminants near 0, a kernel root at a grid point), and b0 about the crossing
// exp(-b0) b0 = w below which no pixel has a hidden depth.
std::vector<std::vector<double>> Pixels(std::mt19937_64& rng)
{
  std::vector<std::vector<double>> pixels;
  std::vector<double> depths;
  for (int set = 0; set < 1500; ++set)
  {
    std::vector<double> sums = RayMoments(rng, 4, depths);
    for (double& s : sums)
    {
      s *= 1.0 + (set % 8) * 4.0;
    }
    pixels.push_back(sums);
  }
  std::uniform_int_distribution<int> grid(-512, 512);
  std::uniform_real_distribution<double> absorbance(0.5, 60.0);
  for (int set = 0; set < 300; ++set)
  {
    const double a = absorbance(rng);
    const double z1 = grid(rng) / 512.0;
    const double z2 = grid(rng) / 512.0;
    const double share = set % 3 == 0 ? 1.0 : (set % 3 == 1 ? 0.5 : 0.999);
    std::vector<double> sums(5, 0.0);
    for (int k = 0; k <= 4; ++k)
    {
      sums[k] = a * (share * std::pow(z1, k) + (1.0 - share) * std::pow(z2, k));
    }
    pixels.push_back(sums);
    // Symmetric: b1 = b3 = 0.
    pixels.push_back({ a, 0.0, a * z1 * z1, 0.0, a * z1 * z1 * z1 * z1 });
  }
  // b0 about the crossing for w = 1e-4 (~11.6), a ray's shape.
  for (int set = 0; set < 200; ++set)
  {
    std::vector<double> sums = RayMoments(rng, 4, depths);
    const double target = 11.0 + set * (1.5 / 200);
    const double scale = target / sums[0];
    for (double& s : sums)
    {
      s *= scale;
    }
    pixels.push_back(sums);
  }
  return pixels;
}

// Every decided lane answers as the query does, the vector kernel answers lane by lane as the
// scalar one, and almost every lane is decided. The limits: random ones, and the query's own T
// at each depth moved by 0 to 1e-8 relative either way (the lanes nearest the exponential's
// rounding, which only the margin keeps from deciding wrongly).
TEST(HiddenDecisions, AgreeWithTheQuery)
{
  std::mt19937_64 rng(2026);
  const std::vector<std::vector<double>> pixels = Pixels(rng);
  std::vector<double> zs;
  for (int k = -512; k <= 512; k += 8)
  {
    zs.push_back(k / 512.0);
  }
  for (const double z : { -1.0 + 1.0 / 512, 1.0 / 1024, -1.0 / 1024, 1.0 - 1.0 / 512 })
  {
    zs.push_back(z);
  }
  const int n = static_cast<int>(zs.size());
  std::vector<int8_t> scalar(n);
  std::vector<int8_t> vector(n);
  std::uniform_real_distribution<double> logLimit(std::log(1e-12), std::log(0.9));
  const bool avx2 = apc::HasHiddenKernel(apc::HiddenKernel::Avx2);
  int64_t lanes = 0;
  int64_t undecided = 0;
  int64_t nearLanes = 0;
  int64_t nearUndecided = 0;
  for (size_t p = 0; p < pixels.size(); ++p)
  {
    const apc::MomentTransmittance<4> t(pixels[p].data());
    apc::FourMomentPixel px;
    if (!t.GetFourMomentPixel(px))
    {
      continue;
    }
    std::vector<double> limits;
    for (int i = 0; i < 3; ++i)
    {
      limits.push_back(std::exp(logLimit(rng)));
    }
    const double near = t.Query(zs[p % zs.size()]).Transmittance;
    for (const double rel :
      { 0.0, 1e-16, -1e-16, 4e-16, -4e-16, 1e-13, -1e-13, 1e-9, -1e-9, 1e-8, -1e-8 })
    {
      limits.push_back(near * (1.0 + rel));
    }
    limits.push_back(std::nextafter(near, 0.0));
    limits.push_back(std::nextafter(near, 2.0));
    for (size_t l = 0; l < limits.size(); ++l)
    {
      const double limit = limits[l];
      if (!(limit >= apc::kLowestHiddenLimit && limit < 1.0))
      {
        continue;
      }
      const double lnLimit = std::log(limit);
      apc::DecideHidden(px, lnLimit, zs.data(), scalar.data(), n, apc::HiddenKernel::Scalar);
      if (avx2)
      {
        // Every tail length of the four-wide steps.
        const int count = n - static_cast<int>(l % 4);
        apc::DecideHidden(px, lnLimit, zs.data(), vector.data(), count, apc::HiddenKernel::Avx2);
        for (int i = 0; i < count; ++i)
        {
          ASSERT_EQ(vector[i], scalar[i]) << "pixel " << p << " z " << zs[i];
        }
      }
      for (int i = 0; i < n; ++i)
      {
        ++lanes;
        const bool isNear = l >= 3 && i == static_cast<int>(p % zs.size());
        nearLanes += isNear;
        if (scalar[i] == apc::kHiddenUndecided)
        {
          ++undecided;
          nearUndecided += isNear;
          continue;
        }
        ASSERT_EQ(scalar[i] == apc::kHiddenYes, QueryHidden(t, zs[i], limit))
          << "pixel " << p << " z " << zs[i] << " limit " << limit;
      }
    }
  }
  std::cout << lanes << " lanes, " << undecided << " undecided; at the limit " << nearLanes << ", "
            << nearUndecided << " undecided\n";
  EXPECT_LT(undecided, lanes / 100);
  // The lanes placed within the margin of the limit are left to the query.
  EXPECT_GT(nearUndecided, nearLanes / 2);
}

// HiddenDepth on the decisions is the bisection with the query alone, two steps a round with
// the samples' cut, to the bit; the weights put the limit on T at grid depths (within an ulp),
// where a wrong decision would move the depth.
TEST(HiddenDecisions, HiddenDepthIsTheQuerysBisection)
{
  std::mt19937_64 rng(4052);
  const std::vector<std::vector<double>> pixels = Pixels(rng);
  std::uniform_real_distribution<double> depth(-1.0, 1.0);
  int bisected = 0;
  for (size_t p = 0; p < pixels.size(); ++p)
  {
    const std::vector<double>& sums = pixels[p];
    const apc::MomentTransmittance<4> t(sums.data());
    const double gridZ = static_cast<int>(p % 1025 - 512) / 512.0;
    std::vector<double> weights = { 1e-2, 1e-4, 1e-6 };
    const double atGrid = t.Query(gridZ).Transmittance * sums[0];
    for (const double rel : { 0.0, 1e-16, -1e-16, 2e-16, -2e-16 })
    {
      weights.push_back(atGrid * (1.0 + rel));
    }
    double a = depth(rng);
    double b = depth(rng);
    const std::pair<double, double> samples(std::min(a, b), std::max(a, b));
    for (const double weight : weights)
    {
      const double limit = weight / sums[0];
      auto hidden = [&](double z) { return QueryHidden(t, z, limit); };
      double expected = std::numeric_limits<double>::infinity();
      if (!t.IsEmpty() && !t.IsDegenerate() && weight > 0.0 &&
        std::exp(-sums[0]) * sums[0] <= weight && hidden(1.0))
      {
        double lo = -1.0;
        double hi = 1.0;
        if (hidden(-1.0))
        {
          hi = -1.0;
        }
        else
        {
          ++bisected;
          for (int step = 0; step < 10; ++step)
          {
            if (step % 2 == 0 && (samples.second <= lo || samples.first >= hi))
            {
              break;
            }
            const double mid = 0.5 * (lo + hi);
            (hidden(mid) ? hi : lo) = mid;
          }
        }
        expected = hi;
      }
      ASSERT_EQ(t.HiddenDepth(weight, [&] { return samples; }), expected)
        << "pixel " << p << " weight " << weight;
    }
  }
  EXPECT_GT(bisected, 1000);
}

// The valid 4-moment pixels of Pixels(rng), as the kernels take them.
std::vector<apc::FourMomentPixel> ValidPixels(std::mt19937_64& rng)
{
  std::vector<apc::FourMomentPixel> valid;
  for (const std::vector<double>& sums : Pixels(rng))
  {
    apc::FourMomentPixel px;
    if (apc::MomentTransmittance<4>(sums.data()).GetFourMomentPixel(px))
    {
      valid.push_back(px);
    }
  }
  return valid;
}

// The jobs' decisions are each DecideHidden's for the job's pixel, limit and four depths, in
// both kernels, with the jobs' pixels and limits mixed from job to job.
TEST(HiddenDecisions, JobsDecideAsEachPixelsCall)
{
  std::mt19937_64 rng(77);
  const std::vector<apc::FourMomentPixel> valid = ValidPixels(rng);
  ASSERT_GT(valid.size(), 1000u);
  std::uniform_real_distribution<double> logLimit(std::log(1e-12), std::log(0.9));
  std::uniform_int_distribution<int> grid(-512, 512);
  std::uniform_int_distribution<size_t> pick(0, valid.size() - 1);
  int64_t checked = 0;
  for (int round = 0; round < 400; ++round)
  {
    const int jobs = 1 + round % 17;
    std::vector<const apc::FourMomentPixel*> px(jobs);
    std::vector<double> lnLimits(jobs);
    std::vector<double> z(4 * jobs);
    for (int j = 0; j < jobs; ++j)
    {
      px[j] = &valid[pick(rng)];
      lnLimits[j] = logLimit(rng);
      for (int k = 0; k < 4; ++k)
      {
        z[4 * j + k] = grid(rng) / 512.0;
      }
    }
    for (const apc::HiddenKernel kernel : { apc::HiddenKernel::Scalar, apc::HiddenKernel::Avx2 })
    {
      if (!apc::HasHiddenKernel(kernel))
      {
        continue;
      }
      std::vector<int8_t> together(4 * jobs, 7);
      apc::DecideHiddenJobs(px.data(), lnLimits.data(), z.data(), together.data(), jobs, kernel);
      for (int j = 0; j < jobs; ++j)
      {
        int8_t alone[4];
        apc::DecideHidden(*px[j], lnLimits[j], z.data() + 4 * j, alone, 4, kernel);
        for (int k = 0; k < 4; ++k)
        {
          ASSERT_EQ(together[4 * j + k], alone[k]) << "round " << round << " job " << j;
          ++checked;
        }
      }
    }
  }
  EXPECT_GT(checked, 10000);
}

// DecideHiddenLanes (a pixel and limit per lane, the constants set lane by lane) decides each
// lane as DecideHidden decides it for its pixel alone: 400 batches of 1-17 lanes (whole vectors
// and tails) of mixed pixels and limits, both kernels.
TEST(HiddenDecisions, LanesDecideAsEachPixelsCall)
{
  std::mt19937_64 rng(78);
  const std::vector<apc::FourMomentPixel> valid = ValidPixels(rng);
  ASSERT_GT(valid.size(), 1000u);
  std::uniform_real_distribution<double> logLimit(std::log(1e-12), std::log(0.9));
  std::uniform_int_distribution<int> grid(-512, 512);
  std::uniform_int_distribution<size_t> pick(0, valid.size() - 1);
  int64_t checked = 0;
  int64_t decidedBoth[2] = { 0, 0 };
  for (int round = 0; round < 400; ++round)
  {
    const int n = 1 + round % 17;
    std::vector<const apc::FourMomentPixel*> px(n);
    std::vector<double> lnLimits(n);
    std::vector<double> z(n);
    for (int i = 0; i < n; ++i)
    {
      px[i] = &valid[pick(rng)];
      lnLimits[i] = logLimit(rng);
      z[i] = grid(rng) / 512.0;
    }
    for (const apc::HiddenKernel kernel : { apc::HiddenKernel::Scalar, apc::HiddenKernel::Avx2 })
    {
      if (!apc::HasHiddenKernel(kernel))
      {
        continue;
      }
      std::vector<int8_t> lanes(n, 7);
      apc::DecideHiddenLanes(px.data(), lnLimits.data(), z.data(), lanes.data(), n, kernel);
      for (int i = 0; i < n; ++i)
      {
        int8_t alone;
        apc::DecideHidden(*px[i], lnLimits[i], &z[i], &alone, 1, kernel);
        ASSERT_EQ(lanes[i], alone) << "round " << round << " lane " << i;
        ++decidedBoth[lanes[i] == apc::kHiddenYes ? 1 : 0];
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 3000);
  EXPECT_GT(decidedBoth[0], 100);
  EXPECT_GT(decidedBoth[1], 100);
}

// HiddenDepths (the pixels' bisections round by round together) gives each pixel's HiddenDepth
// to the bit: groups of 0-40 pixels mixing every kind (empty, degenerate, no hidden depth, a
// limit of 1 or above, hidden everywhere, bisecting, cut short by the samples' range or not),
// weights that put the limit on T at a grid depth to the ulp.
TEST(HiddenDecisions, HiddenDepthsAreEachPixelsHiddenDepth)
{
  std::mt19937_64 rng(9090);
  std::vector<std::vector<double>> pixels = Pixels(rng);
  pixels.push_back({ 0.0, 0.0, 0.0, 0.0, 0.0 });
  pixels.push_back({ 1e-5, 0.0, 1e-6, 0.0, 1e-7 });
  pixels.push_back({ std::numeric_limits<double>::infinity(), 0.0, 0.0, 0.0, 0.0 });
  pixels.push_back({ 5.0, std::nan(""), 1.0, 0.0, 1.0 });
  pixels.push_back({ 1e-3 * 2, 1e-3, 1e-3, 1e-3, 1e-3 }); // limit above 1 for w = 1e-2
  std::shuffle(pixels.begin(), pixels.end(), rng);
  std::uniform_real_distribution<double> depth(-1.0, 1.0);
  std::uniform_int_distribution<int> size(0, 40);
  using Range = std::pair<double, double>;
  struct Fixed
  {
    Range R;
    Range operator()() const { return this->R; }
  };
  int bisected = 0;
  int differentKinds = 0;
  for (const double weight : { 1e-4, 1e-2, 1e-6 })
  {
    for (size_t at = 0; at < pixels.size();)
    {
      const size_t count = std::min(pixels.size() - at, static_cast<size_t>(size(rng)));
      std::vector<apc::MomentTransmittance<4>> group;
      std::vector<Fixed> ranges;
      for (size_t i = 0; i < count; ++i)
      {
        group.emplace_back(pixels[at + i].data());
        const double a = depth(rng);
        const double b = depth(rng);
        const double inf = std::numeric_limits<double>::infinity();
        ranges.push_back(
          { (at + i) % 5 == 0 ? Range(-inf, inf) : Range(std::min(a, b), std::max(a, b)) });
      }
      std::vector<double> together(count, 42.0);
      apc::MomentTransmittance<4>::HiddenDepths(
        group.data(), weight, ranges.data(), together.data(), static_cast<int>(count));
      bool none = false;
      bool some = false;
      for (size_t i = 0; i < count; ++i)
      {
        const double alone = group[i].HiddenDepth(weight, ranges[i]);
        ASSERT_EQ(std::memcmp(&together[i], &alone, sizeof(double)), 0)
          << "pixel " << at + i << " weight " << weight << ": " << together[i] << " against "
          << alone;
        bisected += alone > -1.0 && alone < 1.0;
        none = none || std::isinf(alone);
        some = some || !std::isinf(alone);
      }
      differentKinds += none && some;
      at += count;
    }
  }
  // At the grid's limits: each pixel's own T at a grid depth times b0 as its weight.
  for (size_t p = 0; p < pixels.size(); p += 7)
  {
    const size_t count = std::min<size_t>(7, pixels.size() - p);
    for (const double rel : { 0.0, 1e-16, -1e-16, 2e-16, -2e-16 })
    {
      for (size_t i = 0; i < count; ++i)
      {
        const apc::MomentTransmittance<4> t(pixels[p + i].data());
        const double gridZ = static_cast<int>((p + i) % 1025) / 512.0 - 1.0;
        const double weight = t.Query(gridZ).Transmittance * pixels[p + i][0] * (1.0 + rel);
        // The same weight for the group: its other pixels take it as any weight.
        std::vector<apc::MomentTransmittance<4>> group;
        std::vector<Fixed> ranges;
        for (size_t k = 0; k < count; ++k)
        {
          group.emplace_back(pixels[p + k].data());
          ranges.push_back({ Range(-0.9, 0.9) });
        }
        std::vector<double> together(count);
        apc::MomentTransmittance<4>::HiddenDepths(
          group.data(), weight, ranges.data(), together.data(), static_cast<int>(count));
        for (size_t k = 0; k < count; ++k)
        {
          const double alone = group[k].HiddenDepth(weight, ranges[k]);
          ASSERT_EQ(std::memcmp(&together[k], &alone, sizeof(double)), 0)
            << "pixel " << p + k << " weight " << weight;
        }
      }
    }
  }
  EXPECT_GT(bisected, 1000);
  EXPECT_GT(differentKinds, 10);
}

} // namespace
