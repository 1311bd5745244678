// Samples of one lattice point blend in one fixed order: where cells overlap, two or three of
// them sample the same lattice point with different values, and the exact blend and the
// segments' runs must not depend on the order in which the cells delivered them (threads,
// and the cells each rank holds). Hybrid's pass 2 blends a rank's own samples exactly too,
// and is held to the same.
#include "apcColourVisitors.h"
#include "apcRayVisitors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <limits>
#include <vector>

namespace
{
using apc::visitors::SampleRecord;

// One traced pixel of the wind data (Exact (segments), 384^2): the lattice point k = 235 was
// sampled by three cells, with absorbances and colours 2 % apart.
std::vector<SampleRecord> TracedRay()
{
  std::vector<SampleRecord> samples;
  for (int64_t k = 230; k < 241; ++k)
  {
    const float t = static_cast<float>(k - 230) / 10.0f;
    samples.push_back({ k, 0.05f + 0.1f * t, { 0.3f + 0.1f * t, 0.45f - 0.1f * t, 0.8f } });
  }
  samples.push_back({ 235, 0x1.d8fcfap-4f, { 0x1.523118p-2f, 0x1.c285b6p-2f, 0x1.bd7478p-1f } });
  samples.push_back({ 235, 0x1.cd7642p-4f, { 0x1.53db28p-2f, 0x1.c4bd9ap-2f, 0x1.be43d4p-1f } });
  return samples;
}

std::array<double, 4> Blend(const std::vector<SampleRecord>& sorted)
{
  apc::visitors::FrontToBack blend;
  for (const SampleRecord& s : sorted)
  {
    blend.Add(s);
  }
  return { blend.Colour[0], blend.Colour[1], blend.Colour[2], 1.0 - blend.Transmittance };
}
}

TEST(SampleOrder, SamplesOfOneLatticePointBlendTheSameInAnyArrivalOrder)
{
  std::vector<SampleRecord> samples = TracedRay();
  // The three samples of k = 235 sit at 5, 11 and 12; every order of their arrival.
  std::vector<int> slots = { 5, 11, 12 };
  std::array<SampleRecord, 3> triple = { samples[5], samples[11], samples[12] };
  std::sort(triple.begin(), triple.end(), apc::visitors::SampleBefore);
  bool first = true;
  std::array<double, 4> reference{};
  apc::RaySegment referenceRun{};
  do
  {
    apc::visitors::PixelSampleLists lists;
    lists.Pixels.assign(1, samples);
    for (int i = 0; i < 3; ++i)
    {
      lists.Pixels[0][slots[i]] = triple[i];
    }
    const std::vector<SampleRecord>& sorted = lists.Sorted(0);
    ASSERT_TRUE(std::is_sorted(sorted.begin(), sorted.end(),
      [](const SampleRecord& a, const SampleRecord& b) { return a.K < b.K; }));
    const std::array<double, 4> rgba = Blend(sorted);
    std::vector<apc::RaySegment> runs;
    ASSERT_EQ(apc::visitors::Runs::CutRuns(sorted, runs), 1);
    if (first)
    {
      reference = rgba;
      referenceRun = runs[0];
      first = false;
      continue;
    }
    // Bit-identical, not merely close: the exact image and the segments are the references
    // N ranks are held to.
    EXPECT_EQ(rgba, reference);
    EXPECT_EQ(runs[0].Colour, referenceRun.Colour);
    EXPECT_EQ(runs[0].Transmittance, referenceRun.Transmittance);
  } while (std::next_permutation(triple.begin(), triple.end(), apc::visitors::SampleBefore));
}

TEST(SampleOrder, StrictWeakOrderEvenForNaN)
{
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const SampleRecord a{ 7, nan, { 0.5f, 0.5f, 0.5f } };
  const SampleRecord b{ 7, 0.25f, { 0.5f, 0.5f, 0.5f } };
  const SampleRecord c{ 6, nan, { nan, 0, 0 } };
  EXPECT_FALSE(apc::visitors::SampleBefore(a, a));
  EXPECT_NE(apc::visitors::SampleBefore(a, b), apc::visitors::SampleBefore(b, a));
  EXPECT_TRUE(apc::visitors::SampleBefore(c, a)) << "depth first";
  EXPECT_TRUE(apc::visitors::SampleBefore(c, b));
}

TEST(SampleOrder, HybridOwnSamplesOfOneLatticePointWeighTheSameInAnyArrivalOrder)
{
  // Hybrid's own samples are blended exactly (T_own, the ordered product in front of each):
  // the three samples of k = 235 must get the same weights whatever order they arrive in.
  const std::vector<SampleRecord> samples = TracedRay();
  std::array<SampleRecord, 3> triple = { samples[5], samples[11], samples[12] };
  std::sort(triple.begin(), triple.end(), apc::visitors::SampleBefore);
  const apc::LogDepthWarp warp(100.0, 1000.0);
  // The other ranks add nothing here (global = own): the weights are the own ones alone.
  const std::array<double, 5> moments = { 0, 0, 0, 0, 0 };
  const apc::TileRect tile{ 0, 0, 1, 1, 0 };
  bool first = true;
  std::array<double, 4> reference{};
  int orders = 0;
  do
  {
    std::array<double, 4> sums = { 0, 0, 0, 0 };
    apc::visitors::HybridColour<4> visitor(
      sums.data(), 1, &warp, moments.data(), moments.data(), apc::MomentSettings<4>());
    visitor.BeginTile(tile);
    auto add = [&visitor](const SampleRecord& r)
    {
      const double t = 2.0 * static_cast<double>(r.K);
      visitor.Sample(0, r.K, t, 0.0, apc::TransferSample{ r.Colour, r.Absorbance });
    };
    for (size_t i = 0; i < samples.size(); ++i)
    {
      if (i != 5 && i != 11 && i != 12)
      {
        add(samples[i]);
      }
      if (i == 5 || i == 11 || i == 12)
      {
        add(triple[i == 5 ? 0 : (i == 11 ? 1 : 2)]);
      }
    }
    visitor.EndTile(tile);
    ++orders;
    if (first)
    {
      reference = sums;
      first = false;
      EXPECT_GT(reference[3], 0.5);
      continue;
    }
    EXPECT_EQ(sums, reference) << "arrival order " << orders;
  } while (std::next_permutation(triple.begin(), triple.end(), apc::visitors::SampleBefore));
  EXPECT_EQ(orders, 6);
}
