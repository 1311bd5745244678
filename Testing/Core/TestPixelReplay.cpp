// Pass 2's vectorised replay of one pixel (apcPixelReplay.h) against the per-sample path it
// replaces: TransferTable::Lookup, then alpha T(z) from std::expm1 and the pixel's query, summed
// by ColourSums::Add in the order the samples were taken. Runs of every length up to 13 (every
// tail of a 4-sample step), hidden depths that cut runs, faint and dense samples, depths beyond
// [-1,1], scalars beyond the table and non-finite ones.
#include "apcPixelReplay.h"
#include "apcPowerMoments.h"
#include "apcResolve.h"

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

apc::TransferTable Table()
{
  // A ramp of colours and opacities with a transparent start, as ParaView's default.
  std::vector<std::array<float, 3>> colours;
  std::vector<double> opacities;
  for (int i = 0; i < 256; ++i)
  {
    const float x = i / 255.0f;
    colours.push_back({ x, 1.0f - x, 0.5f * x * x });
    opacities.push_back(i < 20 ? 0.0 : 0.99 * x);
  }
  return apc::TransferTable(-2.0, 3.0, colours, opacities, 0.2, 0.05);
}

struct Expected
{
  apc::ColourSums Sums;
  int64_t Hidden = 0;
};

Expected PerSample(const apc::MomentTransmittance<4>& t, double hiddenFrom,
  const apc::TransferTable& table, const std::vector<apc::CachedSample>& samples)
{
  Expected e;
  for (const apc::CachedSample& s : samples)
  {
    if (s.Z >= hiddenFrom)
    {
      ++e.Hidden;
      continue;
    }
    const apc::TransferSample looked = table.Lookup(s.Scalar);
    const double weight = -std::expm1(-static_cast<double>(looked.Absorbance)) * t(s.Z);
    e.Sums.Add(weight, { looked.Colour[0], looked.Colour[1], looked.Colour[2] });
  }
  return e;
}

} // namespace

// Measured worst difference, relative and per unit of b0: 7e-16 (the sums' order and FMA
// rounding in the reconstruction); bound 1e-13, as for MomentTransmittance's batched weights.
// Each vector kernel the CPU runs.
class PixelReplayKernel : public ::testing::TestWithParam<apc::ReplayKernel>
{
};

TEST_P(PixelReplayKernel, MatchesLookupAndQueryPerSample)
{
  const apc::ReplayKernel kernel = GetParam();
  if (!apc::HasReplayKernel(kernel))
  {
    GTEST_SKIP() << "this CPU does not run the kernel";
  }
  const apc::TransferTable table = Table();
  std::mt19937_64 rng(2026);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double worst = 0;
  int replayed = 0;
  int64_t hiddenTotal = 0;
  for (int pixel = 0; pixel < 3000; ++pixel)
  {
    // The pixel's global moments: its own samples and some of other processes'.
    const int n = pixel % 14;
    std::vector<apc::CachedSample> samples(n);
    double moments[5] = { 0, 0, 0, 0, 0 };
    const double density = std::exp(std::log(1e-4) + unit(rng) * std::log(1e5));
    for (int i = 0; i < n + 6; ++i)
    {
      const double z = -1.2 + 2.4 * unit(rng);
      const double scalar = -2.5 + 6.0 * unit(rng);
      const apc::TransferSample looked = table.Lookup(scalar);
      apc::AccumulatePowerMoments<4>(
        moments, std::min(1.0, std::max(-1.0, z)), looked.Absorbance * density);
      if (i < n)
      {
        samples[i] = { static_cast<float>(z), static_cast<float>(scalar) };
      }
    }
    if (pixel % 97 == 0 && n > 2)
    {
      samples[1].Scalar = std::numeric_limits<float>::quiet_NaN();
      samples[2].Scalar = std::numeric_limits<float>::infinity();
    }
    const apc::MomentTransmittance<4> t(moments);
    // No hidden depth, one inside the run's depths, one before all of them.
    const double hiddenFrom = pixel % 3 == 0 ? std::numeric_limits<double>::infinity()
                                             : (pixel % 3 == 1 ? -1.2 + 2.4 * unit(rng) : -2.0);
    const Expected expected = PerSample(t, hiddenFrom, table, samples);
    apc::ColourSums sums;
    int64_t hidden = 0;
    if (!apc::ReplayFourMomentPixel(t, hiddenFrom, table.GetLayout(), samples.data(), n,
          sums.Data(), hidden, nullptr, kernel))
    {
      continue; // no AVX2 here, or an empty pixel: pass 2 takes the per-sample path
    }
    ++replayed;
    hiddenTotal += hidden;
    ASSERT_EQ(hidden, expected.Hidden) << "pixel " << pixel;
    for (int c = 0; c < 4; ++c)
    {
      const double want = expected.Sums.Sums[c];
      // As MomentTransmittance's batched weights: T = exp(-b0 A), so the rounding of A (FMA or
      // not) moves T by b0 times it, relatively.
      const double error = std::abs(sums.Sums[c] - want) / std::max(std::abs(want), 1e-300) /
        std::max(1.0, moments[0]);
      worst = std::max(worst, error);
      ASSERT_LE(error, 1e-13) << "pixel " << pixel << " channel " << c << " got " << sums.Sums[c]
                              << " want " << want << " b0 " << moments[0];
    }
  }
  std::cout << replayed << " pixels replayed, " << hiddenTotal
            << " samples hidden, worst relative difference " << worst << "\n";
  EXPECT_GT(replayed, 2000);
  EXPECT_GT(hiddenTotal, 100);
}

INSTANTIATE_TEST_SUITE_P(Kernels, PixelReplayKernel,
  ::testing::Values(apc::ReplayKernel::Avx2, apc::ReplayKernel::Avx512));

namespace
{

// Two replay kernels on the same random pixels: the same sums to the bit and the same hidden
// count, with and without end weights, for runs of every length up to 40, hidden depths cutting
// the runs, densities 10^logDensityFrom .. 10^(logDensityFrom + logDensitySpan), a NaN and an
// infinite scalar now and then; with clustered, every other pixel's samples gather about one
// depth. Returns the pixels compared (both kernels served them) and their hidden samples.
std::pair<int, int64_t> CompareKernels(apc::ReplayKernel a, apc::ReplayKernel b, uint64_t seed,
  int pixels, double logDensityFrom, double logDensitySpan, bool clustered)
{
  const apc::TransferTable table = Table();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int compared = 0;
  int64_t hiddenTotal = 0;
  for (int pixel = 0; pixel < pixels; ++pixel)
  {
    const int n = pixel % 41;
    std::vector<apc::CachedSample> samples(n);
    std::vector<float> weights(n);
    double moments[5] = { 0, 0, 0, 0, 0 };
    const double density = std::exp(logDensityFrom + unit(rng) * logDensitySpan);
    const double centre = clustered ? -1.0 + 2.0 * unit(rng) : 0.0;
    const double spread = clustered ? 0.02 + unit(rng) : 0.0;
    for (int i = 0; i < n + 6; ++i)
    {
      const double z =
        !clustered || pixel % 2 ? -1.2 + 2.4 * unit(rng) : centre + spread * (unit(rng) - 0.5);
      const double scalar = -2.5 + 6.0 * unit(rng);
      apc::AccumulatePowerMoments<4>(
        moments, std::min(1.0, std::max(-1.0, z)), table.Lookup(scalar).Absorbance * density);
      if (i < n)
      {
        samples[i] = { static_cast<float>(z), static_cast<float>(scalar) };
        weights[i] = static_cast<float>(unit(rng));
      }
    }
    if (pixel % 89 == 0 && n > 2)
    {
      samples[1].Scalar = std::numeric_limits<float>::quiet_NaN();
      samples[2].Scalar = std::numeric_limits<float>::infinity();
    }
    const apc::MomentTransmittance<4> t(moments);
    const double hiddenFrom = pixel % 3 == 0 ? std::numeric_limits<double>::infinity()
                                             : (pixel % 3 == 1 ? -1.2 + 2.4 * unit(rng) : -2.0);
    for (const float* w :
      { static_cast<const float*>(nullptr), static_cast<const float*>(weights.data()) })
    {
      double sumsA[4] = { 0.25, 0, 0, 1 };
      double sumsB[4] = { 0.25, 0, 0, 1 };
      int64_t hiddenA = 0;
      int64_t hiddenB = 0;
      const bool doneA = apc::ReplayFourMomentPixel(
        t, hiddenFrom, table.GetLayout(), samples.data(), n, sumsA, hiddenA, w, a);
      const bool doneB = apc::ReplayFourMomentPixel(
        t, hiddenFrom, table.GetLayout(), samples.data(), n, sumsB, hiddenB, w, b);
      EXPECT_EQ(doneA, doneB) << "pixel " << pixel;
      if (!doneA || !doneB)
      {
        continue;
      }
      ++compared;
      hiddenTotal += hiddenA;
      EXPECT_EQ(hiddenA, hiddenB) << "pixel " << pixel;
      for (int c = 0; c < 4; ++c)
      {
        EXPECT_EQ(std::memcmp(&sumsA[c], &sumsB[c], sizeof(double)), 0)
          << "pixel " << pixel << " n " << n << " channel " << c << ": " << sumsA[c] << " against "
          << sumsB[c];
      }
    }
  }
  return { compared, hiddenTotal };
}

} // namespace

// The AVX-512 replay (8 lanes a group, 16 samples a step) against the AVX2 one (4 lanes, 8 a
// step): every tail of both kernels' steps, faint and dense pixels, and pixels whose samples
// need the query's full path.
TEST(PixelReplay, WideKernelGivesTheSameBits)
{
  if (!apc::HasReplayKernel(apc::ReplayKernel::Avx512) ||
    !apc::HasReplayKernel(apc::ReplayKernel::Avx2))
  {
    GTEST_SKIP() << "this CPU does not run both kernels";
  }
  const auto result = CompareKernels(apc::ReplayKernel::Avx512, apc::ReplayKernel::Avx2, 49, 8000,
    std::log(1e-4), std::log(1e6), false);
  EXPECT_GT(result.first, 14000);
  EXPECT_GT(result.second, 1000);
}

// The AVX2 replay's shortcut (a group whose visible lanes all lie outside their support
// points, c2 > 0, skips the nearer root) against the same kernel without it, on pixels whose
// samples gather about one depth (most groups all one side) or spread over the range (mixed
// groups); lanes past the hidden depth, whatever their c2, are left out of the test.
TEST(PixelReplay, ShortcutGivesTheFullKernelsBits)
{
  if (!apc::HasReplayKernel(apc::ReplayKernel::Avx2))
  {
    GTEST_SKIP() << "this CPU does not run the AVX2 kernel";
  }
  const auto result = CompareKernels(apc::ReplayKernel::Avx2, apc::ReplayKernel::Avx2Full, 2027,
    12000, std::log(1e-5), std::log(1e7), true);
  EXPECT_GT(result.first, 20000);
  EXPECT_GT(result.second, 1000);
}

// A pixel the vector arithmetic does not serve (empty: every sample at full weight) is left
// to the per-sample path, untouched.
TEST(PixelReplay, LeavesEmptyPixelsToThePerSamplePath)
{
  const apc::TransferTable table = Table();
  const double empty[5] = { 0, 0, 0, 0, 0 };
  const apc::MomentTransmittance<4> t(empty);
  const std::vector<apc::CachedSample> samples = { { 0.1f, 1.0f }, { 0.2f, 2.0f } };
  apc::ColourSums sums;
  int64_t hidden = 0;
  EXPECT_FALSE(apc::ReplayFourMomentPixel(t, std::numeric_limits<double>::infinity(),
    table.GetLayout(), samples.data(), 2, sums.Data(), hidden));
  EXPECT_EQ(sums.W(), 0.0);
  EXPECT_EQ(hidden, 0);
}

// The AVX2 replay's look-up (entry and difference read together, apcTransferTable.h's
// EntryDifferences) against TransferTable::Lookup, to the bit: every entry's scalar and those
// about it, the last entry, scalars beyond both ends, -0, non-finite ones (the replay's entry
// 0 with absorbance +0), every lane count, with and without end weights (a float product; 0
// past the lanes). Tables: the ramp, a random one with negative zeros, infinities' neighbours
// and denormals, two entries, and a zero-width range.
TEST(PixelReplay, LookupIsTheTablesToTheBit)
{
  std::mt19937_64 rng(314);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<apc::TransferTable> tables = { Table() };
  {
    std::vector<std::array<float, 3>> colours;
    std::vector<double> opacities;
    const float odd[] = { -0.0f, 0.0f, 1e-40f, -1e-40f, 3.4e38f, -3.4e38f, 1.0f, 0.1f };
    for (int i = 0; i < 37; ++i)
    {
      colours.push_back({ odd[i % 8], static_cast<float>(unit(rng)), odd[(i * 3) % 8] });
      opacities.push_back(i % 5 == 0 ? 0.0 : (i % 7 == 0 ? 1.0 : unit(rng)));
    }
    tables.emplace_back(0.0, 7.0, colours, opacities, 0.3, 0.01);
  }
  tables.emplace_back(-1.0, 1.0,
    std::vector<std::array<float, 3>>{ { 1.f, 0.f, 0.5f }, { 0.f, 1.f, 0.25f } },
    std::vector<double>{ 0.1, 0.9 }, 1.0, 1.0);
  tables.emplace_back(2.0, 2.0,
    std::vector<std::array<float, 3>>{ { 1.f, 0.f, 0.5f }, { 0.f, 1.f, 0.25f } },
    std::vector<double>{ 0.1, 0.9 }, 1.0, 1.0);
  const double inf = std::numeric_limits<double>::infinity();
  int compared = 0;
  for (const apc::TransferTable& table : tables)
  {
    const apc::TransferTable::Layout layout = table.GetLayout();
    ASSERT_EQ(reinterpret_cast<uintptr_t>(layout.EntryDifferences) % 32, 0u);
    std::vector<double> scalars = { -0.0, 0.0, inf, -inf, std::numeric_limits<double>::quiet_NaN(),
      1e300, -1e300, layout.Min - 1, layout.Min + layout.Last / layout.Scale + 1 };
    for (int i = 0; i < layout.Count; ++i)
    {
      const double at = layout.Scale > 0 ? layout.Min + i / layout.Scale : layout.Min;
      scalars.push_back(at);
      scalars.push_back(std::nextafter(at, -inf));
      scalars.push_back(std::nextafter(at, inf));
      scalars.push_back(at + unit(rng) / std::max(layout.Scale, 1.0));
    }
    std::shuffle(scalars.begin(), scalars.end(), rng);
    for (size_t at = 0; at < scalars.size(); at += 3)
    {
      double four[4];
      float weights[4];
      for (int k = 0; k < 4; ++k)
      {
        four[k] = scalars[(at + k) % scalars.size()];
        weights[k] = k == 1 ? 0.0f : static_cast<float>(unit(rng) * 2);
      }
      for (int lanes = 1; lanes <= 4; ++lanes)
      {
        for (const float* w :
          { static_cast<const float*>(nullptr), static_cast<const float*>(weights) })
        {
          double out[16];
          if (!apc::ReplayLookupFour(layout, four, w, lanes, out))
          {
            GTEST_SKIP() << "this CPU does not run the AVX2 replay";
          }
          for (int k = 0; k < 4; ++k)
          {
            apc::TransferSample want = std::isfinite(four[k])
              ? apc::TransferTable::Lookup(layout, four[k])
              : apc::TransferTable::Lookup(layout, layout.Min);
            if (!std::isfinite(four[k]))
            {
              want.Absorbance = 0.0f;
            }
            else if (w)
            {
              want.Absorbance *= k < lanes ? w[k] : 0.0f;
            }
            const double expected[4] = { want.Colour[0], want.Colour[1], want.Colour[2],
              want.Absorbance };
            for (int c = 0; c < 4; ++c)
            {
              ASSERT_EQ(std::memcmp(&out[4 * c + k], &expected[c], sizeof(double)), 0)
                << "scalar " << four[k] << " lane " << k << " channel " << c << " got "
                << out[4 * c + k] << " want " << expected[c] << " lanes " << lanes;
            }
            ++compared;
          }
        }
      }
    }
  }
  EXPECT_GT(compared, 10000);
}
