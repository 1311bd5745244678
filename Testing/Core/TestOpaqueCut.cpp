// The opaque stop's agreed cut (apcOpaqueBins.h): random rays of random samples split among
// random numbers of processes, each visiting its samples roughly front to back and stopping
// as pass 1 does (RayProgress). The cut from the summed per-process profiles must be the one
// the complete profile gives, and every sample the cut keeps must be one its process took,
// so that N processes keep exactly the samples one process keeps. With a predicted bound
// (apcOpaquePrediction.h) the summed profile gives that cut wherever it reaches the threshold
// by the bound, and flags the pixel unresolved otherwise.
#include "apcOpaqueBins.h"
#include "apcOpaquePrediction.h"
#include "apcOpaqueSummary.h"
#include "apcRayWalk.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace
{
using apc::OpaqueBins;

struct Sample
{
  int64_t K;
  double Absorbance;
  int Process;
  double Order; // when its process visits it: k plus noise (cells binned by depth)
};

// One process's pass 1 over its samples: its profile, and whether it took each sample. No
// sample past the end of bin bound is taken either (kBins - 1: no bound).
std::array<uint16_t, OpaqueBins::kBins> Pass1(const OpaqueBins& bins, std::vector<Sample>& samples,
  int process, std::vector<bool>& taken, int bound = OpaqueBins::kBins - 1)
{
  std::vector<size_t> visit;
  for (size_t s = 0; s < samples.size(); ++s)
  {
    if (samples[s].Process == process)
    {
      visit.push_back(s);
    }
  }
  std::sort(visit.begin(), visit.end(),
    [&](size_t a, size_t b) { return samples[a].Order < samples[b].Order; });
  apc::walk::RayProgress progress;
  progress.Begin(1, &bins);
  int64_t stop = bins.End(bound);
  for (size_t s : visit)
  {
    if (samples[s].K >= stop)
    {
      continue;
    }
    taken[s] = true;
    if (progress.Add(0, samples[s].K, bins.Of(samples[s].K), samples[s].Absorbance))
    {
      stop = std::min(stop, progress.StopIndex(0));
    }
  }
  std::array<uint16_t, OpaqueBins::kBins> profile{};
  for (int b = 0; b < OpaqueBins::kBins; ++b)
  {
    profile[b] = static_cast<uint16_t>(progress.Profile[0][b]);
  }
  return profile;
}

// A random ray of 1-400 samples spread over processes, with noisy visiting orders.
std::vector<Sample> RandomRay(const OpaqueBins& bins, int processes, std::mt19937& rng)
{
  const int count = std::uniform_int_distribution<int>(1, 400)(rng);
  const double mean = std::uniform_real_distribution<double>(0.005, 0.5)(rng);
  const double noise = std::uniform_real_distribution<double>(0.0, 80.0)(rng);
  std::exponential_distribution<double> absorbance(1.0 / mean);
  std::vector<Sample> samples;
  for (int s = 0; s < count; ++s)
  {
    const int64_t k = bins.Base + std::uniform_int_distribution<int64_t>(-5, 420)(rng);
    const int process = std::uniform_int_distribution<int>(0, processes - 1)(rng);
    samples.push_back({ k, absorbance(rng), process,
      static_cast<double>(k) + std::uniform_real_distribution<double>(0.0, noise)(rng) });
  }
  return samples;
}

// The cut of every sample's profile: what one process with all of them finds.
int CompleteCut(const OpaqueBins& bins, const std::vector<Sample>& samples)
{
  std::array<uint16_t, OpaqueBins::kBins> complete{};
  for (const Sample& s : samples)
  {
    complete[bins.Of(s.K)] = OpaqueBins::Add(complete[bins.Of(s.K)], bins.Quanta(s.Absorbance));
  }
  return apc::CutBin(complete.data());
}

// Every process's pass 1 over the ray (each bounded by bound; taken marks what they took),
// their profiles summed as the profiles' allreduce does.
std::array<uint16_t, OpaqueBins::kBins> SummedPass1(const OpaqueBins& bins,
  std::vector<Sample>& samples, int processes, std::vector<bool>& taken,
  int bound = OpaqueBins::kBins - 1)
{
  std::array<uint16_t, OpaqueBins::kBins> summed{};
  for (int p = 0; p < processes; ++p)
  {
    const auto profile = Pass1(bins, samples, p, taken, bound);
    apc::AddProfiles(summed.data(), profile.data(), summed.size());
  }
  return summed;
}

// Every process's pass 1 over the ray (each bounded by bound) into profiles, and their
// summaries combined as the summaries' allreduce does.
uint16_t SummarisedPass1(const OpaqueBins& bins, std::vector<Sample>& samples, int processes,
  std::vector<std::array<uint16_t, OpaqueBins::kBins>>& profiles, int bound = OpaqueBins::kBins - 1)
{
  std::vector<bool> taken(samples.size(), false);
  uint16_t combined = 0;
  for (int p = 0; p < processes; ++p)
  {
    profiles.push_back(Pass1(bins, samples, p, taken, bound));
    const uint16_t own = apc::OpaqueSummary::Of(profiles.back().data());
    combined = p == 0 ? own : apc::OpaqueSummary::Combine(combined, own);
  }
  return combined;
}

// The profiles' first keep bins summed, as the profiles' allreduce sends them.
std::array<uint16_t, OpaqueBins::kBins> SumFirstBins(
  const std::vector<std::array<uint16_t, OpaqueBins::kBins>>& profiles, int keep)
{
  std::array<uint16_t, OpaqueBins::kBins> summed{};
  for (const auto& profile : profiles)
  {
    apc::AddProfiles(summed.data(), profile.data(), static_cast<size_t>(keep));
  }
  return summed;
}
}

TEST(OpaqueCut, BinsFollowTheLattice)
{
  const OpaqueBins bins = OpaqueBins::Make(9.21, 10.0, 50.0, 0.1);
  ASSERT_TRUE(bins.Active());
  EXPECT_EQ(bins.Base, 100);
  EXPECT_EQ(bins.Width, 25); // 400 steps in 16 bins
  EXPECT_EQ(bins.Of(0), 0);
  EXPECT_EQ(bins.Of(124), 0);
  EXPECT_EQ(bins.Of(125), 1);
  EXPECT_EQ(bins.Of(1000000), OpaqueBins::kBins - 1);
  EXPECT_EQ(bins.End(0), 125);
  EXPECT_EQ(bins.End(OpaqueBins::kBins - 1), std::numeric_limits<int64_t>::max());
  for (int64_t k = 0; k < 600; ++k)
  {
    ASSERT_EQ(bins.OfLow16(static_cast<uint16_t>(k)), bins.Of(k)) << k;
  }
  // Rounded down: a sample just under the threshold is not opaque alone.
  EXPECT_EQ(bins.Quanta(9.21), OpaqueBins::kOpaque);
  EXPECT_LT(bins.Quanta(9.2099), OpaqueBins::kOpaque);
  EXPECT_EQ(bins.Quanta(1e300), OpaqueBins::kOpaque);
  EXPECT_EQ(bins.Quanta(0.0), 0u);
  // No threshold, or a span the cache's 16 lattice bits cannot hold: nothing stops.
  EXPECT_FALSE(OpaqueBins::Make(std::numeric_limits<double>::infinity(), 1, 2, 0.1).Active());
  EXPECT_FALSE(OpaqueBins::Make(9.21, 1, 1e6, 1.0).Active());
}

TEST(OpaqueCut, ProfilesSummedOverProcessesGiveTheCompleteCut)
{
  const OpaqueBins bins = OpaqueBins::Make(9.21, 10.0, 50.0, 0.1);
  std::mt19937 rng(26);
  int cutEarly = 0;
  int stoppedPast = 0;
  int leftOut = 0;
  for (int trial = 0; trial < 4000; ++trial)
  {
    const int processes = 1 + trial % 4;
    std::vector<Sample> samples = RandomRay(bins, processes, rng);
    const int expected = CompleteCut(bins, samples);

    std::vector<bool> taken(samples.size(), false);
    const auto summed = SummedPass1(bins, samples, processes, taken);
    const int cut = apc::CutBin(summed.data());
    ASSERT_EQ(cut, expected) << "trial " << trial;
    for (size_t s = 0; s < samples.size(); ++s)
    {
      if (bins.Of(samples[s].K) <= cut)
      {
        ASSERT_TRUE(taken[s]) << "trial " << trial << ": the cut keeps a sample pass 1 left out";
      }
      stoppedPast += taken[s] && bins.Of(samples[s].K) > cut ? 1 : 0;
      leftOut += taken[s] ? 0 : 1;
    }
    cutEarly += cut < OpaqueBins::kBins - 1 ? 1 : 0;
  }
  // The trials must exercise the stop: rays cut short, samples left out, and processes that
  // took samples past the agreed cut (which the cut then drops).
  EXPECT_GT(cutEarly, 1000);
  EXPECT_GT(stoppedPast, 1000);
  EXPECT_GT(leftOut, 10000);
}

// Random rays as above, each process also bounded by a random predicted last bin (the same on
// every process): where the summed profile reaches the threshold by the bound, its cut is the
// complete one and keeps only samples pass 1 took; elsewhere the pixel is unresolved (and the
// complete cut indeed lies past the bound), and marching again without the bound gives it.
TEST(OpaqueCut, APredictedBoundGivesTheCompleteCutOrLeavesItUnresolved)
{
  const OpaqueBins bins = OpaqueBins::Make(9.21, 10.0, 50.0, 0.1);
  std::mt19937 rng(33);
  int resolved = 0;
  int unresolved = 0;
  int wrongWithoutRedo = 0;
  for (int trial = 0; trial < 4000; ++trial)
  {
    const int processes = 2 + trial % 3;
    std::vector<Sample> samples = RandomRay(bins, processes, rng);
    const int expected = CompleteCut(bins, samples);
    const uint8_t bound =
      static_cast<uint8_t>(std::uniform_int_distribution<int>(0, OpaqueBins::kBins - 1)(rng));

    std::vector<bool> taken(samples.size(), false);
    auto summed = SummedPass1(bins, samples, processes, taken, bound);
    uint8_t open = 0;
    apc::MarkUnresolved(&bound, summed.data(), 1, &open);
    if (open)
    {
      ++unresolved;
      ASSERT_GT(expected, bound) << "trial " << trial << ": unresolved, yet opaque by the bound";
      wrongWithoutRedo += apc::CutBin(summed.data()) != expected ? 1 : 0;
      std::fill(taken.begin(), taken.end(), false);
      summed = SummedPass1(bins, samples, processes, taken);
    }
    else
    {
      ++resolved;
    }
    const int cut = apc::CutBin(summed.data());
    ASSERT_EQ(cut, expected) << "trial " << trial << ", bound " << int(bound);
    for (size_t s = 0; s < samples.size(); ++s)
    {
      if (bins.Of(samples[s].K) <= cut)
      {
        ASSERT_TRUE(taken[s]) << "trial " << trial << ": the cut keeps a sample pass 1 left out";
      }
    }
  }
  // Both outcomes occur, and taking an unresolved pixel's summed profile at its word would
  // give a wrong cut.
  EXPECT_GT(resolved, 1000);
  EXPECT_GT(unresolved, 500);
  EXPECT_GT(wrongWithoutRedo, 200);
}

// Without a predicted bound (a first frame), the processes combine a summary of each pixel's
// profile first and sum only the bins it says the cut needs: the earliest own cut's, or none
// where the totals stay below the threshold. The partial sums must give the complete cut,
// and leave out most bins of these rays.
TEST(OpaqueCut, ProfilesSummedAsFarAsTheSummarySaysGiveTheCompleteCut)
{
  const OpaqueBins bins = OpaqueBins::Make(9.21, 10.0, 50.0, 0.1);
  std::mt19937 rng(41);
  size_t binsSent = 0;
  int noneSent = 0;
  int partial = 0;
  constexpr int trials = 4000;
  for (int trial = 0; trial < trials; ++trial)
  {
    const int processes = 1 + trial % 4;
    std::vector<Sample> samples = RandomRay(bins, processes, rng);
    // Fainter rays too, whose totals add up to less than the threshold.
    if (trial % 3 == 0)
    {
      for (Sample& s : samples)
      {
        s.Absorbance *= 0.02;
      }
    }
    const int expected = CompleteCut(bins, samples);
    std::vector<std::array<uint16_t, OpaqueBins::kBins>> profiles;
    const uint16_t combined = SummarisedPass1(bins, samples, processes, profiles);
    for (const auto& profile : profiles)
    {
      ASSERT_EQ(apc::OpaqueSummary::Of(profile.data()) >> apc::OpaqueSummary::kTotalBits,
        apc::CutBin(profile.data()));
    }
    const int keep = apc::OpaqueSummary::Bins(combined);
    ASSERT_LE(keep, OpaqueBins::kBins);
    const auto summed = SumFirstBins(profiles, keep);
    ASSERT_EQ(apc::CutBin(summed.data()), expected) << "trial " << trial << ", keep " << keep;
    binsSent += static_cast<size_t>(keep);
    noneSent += keep == 0 ? 1 : 0;
    partial += keep > 0 && keep < OpaqueBins::kBins ? 1 : 0;
  }
  EXPECT_GT(noneSent, 1000);
  EXPECT_GT(partial, 1000);
  EXPECT_LT(binsSent, size_t(trials) * OpaqueBins::kBins / 2);
}

// A later frame: each process bounded by a predicted last bin, the summary's cut folded with
// the bound (bins 0..min(bound, S) sent). The partial sums must flag the same pixels
// unresolved as the whole bounded sums and, where resolved, give the complete cut.
TEST(OpaqueCut, TheSummaryWithAPredictedBoundResolvesAsTheWholeSums)
{
  const OpaqueBins bins = OpaqueBins::Make(9.21, 10.0, 50.0, 0.1);
  std::mt19937 rng(52);
  size_t binsSent = 0;
  size_t boundBins = 0;
  int unresolved = 0;
  constexpr int trials = 4000;
  for (int trial = 0; trial < trials; ++trial)
  {
    const int processes = 2 + trial % 3;
    std::vector<Sample> samples = RandomRay(bins, processes, rng);
    const int expected = CompleteCut(bins, samples);
    const uint8_t bound =
      static_cast<uint8_t>(std::uniform_int_distribution<int>(0, OpaqueBins::kBins - 1)(rng));
    std::vector<std::array<uint16_t, OpaqueBins::kBins>> profiles;
    const uint16_t combined = SummarisedPass1(bins, samples, processes, profiles, bound);
    auto whole = SumFirstBins(profiles, OpaqueBins::kBins);
    const int keep = apc::OpaqueSummary::Bins(apc::OpaqueSummary::Bounded(combined, bound));
    ASSERT_LE(keep, apc::BoundedProfileBins(bound));
    auto summed = SumFirstBins(profiles, keep);
    uint8_t openWhole = 0;
    uint8_t open = 0;
    apc::MarkUnresolved(&bound, whole.data(), 1, &openWhole);
    apc::MarkUnresolved(&bound, summed.data(), 1, &open);
    ASSERT_EQ(open, openWhole) << "trial " << trial << ", keep " << keep;
    if (!open)
    {
      ASSERT_EQ(apc::CutBin(summed.data()), expected) << "trial " << trial << ", keep " << keep;
    }
    unresolved += open;
    binsSent += static_cast<size_t>(keep);
    boundBins += static_cast<size_t>(apc::BoundedProfileBins(bound));
  }
  EXPECT_GT(unresolved, 500);
  EXPECT_LT(binsSent, boundBins * 3 / 4); // fewer than the bound alone sends
}

// The summary's total rounds up and saturates: a total below its saturation is below the
// threshold, and a total at the threshold saturates it.
TEST(OpaqueCut, TheSummarysTotalNeverUnderstatesTheThreshold)
{
  std::array<uint16_t, OpaqueBins::kBins> profile{};
  profile[3] = OpaqueBins::kOpaque - 1; // just below the threshold: not opaque alone
  const uint16_t below = apc::OpaqueSummary::Of(profile.data());
  EXPECT_EQ(below >> 12, OpaqueBins::kBins - 1);
  EXPECT_EQ(apc::OpaqueSummary::Bins(below), OpaqueBins::kBins); // may reach it with others
  std::array<uint16_t, OpaqueBins::kBins> one{};
  one[9] = 1;
  const uint16_t two = apc::OpaqueSummary::Combine(below, apc::OpaqueSummary::Of(one.data()));
  EXPECT_EQ(apc::OpaqueSummary::Bins(two), OpaqueBins::kBins); // reaches it: every bin
  profile[3] = static_cast<uint16_t>(
    (apc::OpaqueSummary::kTotalMask - 1) * apc::OpaqueSummary::kQuantaPerUnit);
  EXPECT_EQ(apc::OpaqueSummary::Bins(apc::OpaqueSummary::Of(profile.data())), 0);
  profile[3] = OpaqueBins::kOpaque;
  const uint16_t opaque = apc::OpaqueSummary::Of(profile.data());
  EXPECT_EQ(apc::OpaqueSummary::Bins(opaque), 4); // its own cut, bin 3
  EXPECT_EQ(apc::OpaqueSummary::Bins(apc::OpaqueSummary::Combine(opaque, two)), 4);
  // 17 processes of 3855 quanta each reach the threshold (65535) together: rounded down,
  // their totals would add up to 4080 of 4095 units and the pixel would send nothing.
  std::array<uint16_t, OpaqueBins::kBins> part{};
  part[5] = 3855;
  uint16_t all = apc::OpaqueSummary::Of(part.data());
  for (int p = 1; p < 17; ++p)
  {
    all = apc::OpaqueSummary::Combine(all, apc::OpaqueSummary::Of(part.data()));
  }
  EXPECT_EQ(apc::OpaqueSummary::Bins(all), OpaqueBins::kBins);
}

// The bound: the largest previous cut within the radius, plus the margin, at most kBins - 1;
// kBins - 1 outside the previous rectangle; nothing for another image.
TEST(OpaqueCut, TheBoundIsTheNeighbourhoodsLargestCutPlusAMargin)
{
  constexpr int none = OpaqueBins::kBins - 1;
  apc::OpaqueCutMemory previous;
  previous.Begin({ 64, 64 }, 10, 20, 8, 6);
  std::fill(previous.Cut.begin(), previous.Cut.end(), uint8_t(3));
  previous.Cut[2 * 8 + 4] = 9;  // image pixel (14, 22)
  previous.Cut[5 * 8 + 7] = 14; // image pixel (17, 25)
  std::vector<uint8_t> bound(8 * 6, 0);
  EXPECT_FALSE(apc::PredictOpaqueBound(previous, { 64, 32 }, 10, 20, 8, 6, 1, 1, bound.data()));
  ASSERT_TRUE(apc::PredictOpaqueBound(previous, { 64, 64 }, 10, 20, 8, 6, 1, 1, bound.data()));
  auto at = [&](int i, int j) { return int(bound[(j - 20) * 8 + (i - 10)]); };
  EXPECT_EQ(at(14, 22), 10);
  EXPECT_EQ(at(13, 21), 10);   // a diagonal neighbour
  EXPECT_EQ(at(10, 22), none); // by the rectangle's edge: outside it, nothing was opaque
  EXPECT_EQ(at(14, 20), none);
  EXPECT_EQ(at(12, 23), 4);
  EXPECT_EQ(at(16, 24), none); // 14 + 1, capped
  // A rectangle moved by two columns reads the same image pixels.
  std::vector<uint8_t> moved(8 * 6, 0);
  ASSERT_TRUE(apc::PredictOpaqueBound(previous, { 64, 64 }, 12, 20, 8, 6, 1, 1, moved.data()));
  EXPECT_EQ(int(moved[2 * 8 + 2]), 10);   // image pixel (14, 22)
  EXPECT_EQ(int(moved[2 * 8 + 7]), none); // image pixel (19, 22): outside the previous one
}

// A first frame's probe (every step-th pixel from offset) spreads its cuts over the rectangle:
// each pixel takes the largest cut of the probe pixels on either side of it in each direction,
// so a pixel between an opaque probe pixel and an open one is bounded by neither's alone.
TEST(OpaqueCut, TheProbesCutsSpreadToThePixelsAroundThem)
{
  constexpr int none = OpaqueBins::kBins - 1;
  // A 10 x 7 rectangle probed every 4th pixel from 2: probe columns 2, 6 (and 10, past it:
  // ProbeSize counts 2), rows 2, 6.
  EXPECT_EQ(apc::ProbeSize(10, 4, 2), 2);
  EXPECT_EQ(apc::ProbeSize(7, 4, 2), 2);
  EXPECT_EQ(apc::ProbeSize(1, 4, 2), 1);
  const std::vector<uint8_t> probe = { 3, 5, // row 2: columns 2, 6
    7, none };                               // row 6
  apc::OpaqueCutMemory memory;
  memory.Begin({ 64, 64 }, 0, 0, 10, 7);
  apc::SpreadProbeCuts(probe.data(), 2, 2, 4, 2, memory);
  auto at = [&](int i, int j) { return int(memory.Cut[j * 10 + i]); };
  EXPECT_EQ(at(0, 0), 3);    // before the first probe pixel: its cut alone
  EXPECT_EQ(at(2, 2), none); // on a probe pixel: it and the ones after it (PredictOpaqueBound
                             // reaches them from it anyway)
  EXPECT_EQ(at(1, 1), 3);
  EXPECT_EQ(at(0, 3), 7);    // between rows 2 and 6 of column 2
  EXPECT_EQ(at(4, 1), 5);    // between columns 2 and 6 of row 2 (and before it)
  EXPECT_EQ(at(4, 4), none); // among all four
  EXPECT_EQ(at(9, 0), 5);    // past the last probe column: its cut alone
  EXPECT_EQ(at(9, 6), none);
  EXPECT_EQ(at(0, 6), 7);
}
