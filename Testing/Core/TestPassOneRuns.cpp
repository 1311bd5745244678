// Pass 1's runs (the walker's lanes hand a ray's steps over at once): RayProgress::AddRun
// against RayProgress::Add per visible sample, and Moments' RunBegin/RunAdd/RunEnd against
// Moments::Sample per visible sample; the same profiles, totals, farthest indices, moment sums,
// records and counts, bit for bit, on random runs.
#include "apcDepthWarp.h"
#include "apcOpaqueBins.h"
#include "apcRayVisitors.h"
#include "apcRayWalk.h"
#include "apcSampleCache.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <random>
#include <vector>

namespace
{

// A run's absorbances: transparent (0), tiny, moderate and large.
float RandomAbsorbance(std::mt19937& rng)
{
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double r = u(rng);
  if (r < 0.25)
  {
    return 0.0f;
  }
  return static_cast<float>(std::pow(10.0, -6.0 + 6.5 * u(rng)));
}

}

TEST(PassOneRuns, AddRunIsAddPerVisibleSample)
{
  std::mt19937 rng(38);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto runs = std::make_unique<apc::walk::RayProgress>();
  auto single = std::make_unique<apc::walk::RayProgress>();
  constexpr int kPixels = 4;
  int added = 0;
  int crossingBins = 0;
  int turningOpaque = 0;
  int afterOpaque = 0;
  for (int frame = 0; frame < 300; ++frame)
  {
    const double spacing = 0.1;
    const double nearT = spacing * std::floor(20.0 + 40.0 * u(rng));
    const double span = 16.0 + 300.0 * u(rng);
    // Thresholds a run reaches in one sample, in a few, or only over many runs.
    const double threshold = std::pow(10.0, -2.0 + 3.0 * u(rng));
    const apc::OpaqueBins bins =
      apc::OpaqueBins::Make(threshold, nearT, nearT + span * spacing, spacing);
    ASSERT_TRUE(bins.Active());
    runs->Begin(kPixels, &bins);
    single->Begin(kPixels, &bins);
    for (int r = 0; r < 60; ++r)
    {
      const int p = static_cast<int>(u(rng) * kPixels);
      const int n = 1 + static_cast<int>(u(rng) * apc::walk::RayProgress::kMaxRun);
      const int64_t k = bins.Base - 5 + static_cast<int64_t>(u(rng) * (span + 10.0));
      float absorbance[apc::walk::RayProgress::kMaxRun];
      uint32_t q[apc::walk::RayProgress::kMaxRun];
      uint32_t sum = 0;
      int last = -1;
      for (int s = 0; s < n; ++s)
      {
        absorbance[s] = RandomAbsorbance(rng);
        q[s] = bins.Quanta(absorbance[s]);
        sum += q[s];
        last = absorbance[s] > 0 ? s : last;
      }
      const bool wasOpaque = single->Opaque[p];
      bool opaque = false;
      for (int s = 0; s < n; ++s)
      {
        if (absorbance[s] > 0)
        {
          opaque = single->Add(p, k + s, single->BinOf(k + s), absorbance[s]) || opaque;
        }
      }
      // A run goes at once exactly where no sample of it turns the pixel opaque.
      ASSERT_EQ(runs->RunStaysOpen(p, sum), !opaque) << "frame " << frame << " run " << r;
      if (opaque)
      {
        ++turningOpaque;
        for (int s = 0; s < n; ++s)
        {
          if (absorbance[s] > 0)
          {
            runs->Add(p, k + s, runs->BinOf(k + s), absorbance[s]);
          }
        }
      }
      else
      {
        runs->AddRun(p, k, runs->BinOf(k), q, sum, last);
        ++added;
        crossingBins += last > 0 && runs->BinOf(k) != runs->BinOf(k + last) ? 1 : 0;
        afterOpaque += wasOpaque && last >= 0 ? 1 : 0;
      }
      for (int b = 0; b < apc::OpaqueBins::kBins; ++b)
      {
        ASSERT_EQ(runs->Profile[p][b], single->Profile[p][b])
          << "frame " << frame << " run " << r << " bin " << b;
      }
      ASSERT_EQ(runs->Total[p], single->Total[p]) << "frame " << frame << " run " << r;
      ASSERT_EQ(runs->FarK[p], single->FarK[p]) << "frame " << frame << " run " << r;
      ASSERT_EQ(runs->Opaque[p], single->Opaque[p]) << "frame " << frame << " run " << r;
    }
  }
  // Runs within one bin and across bins, runs of pixels already opaque, and runs that turn
  // a pixel opaque (taken sample by sample).
  EXPECT_GT(added, 3000);
  EXPECT_GT(crossingBins, 300);
  EXPECT_GT(afterOpaque, 300);
  EXPECT_GT(turningOpaque, 300);
}

TEST(PassOneRuns, MomentRunsAreSamplesOneAtATime)
{
  std::mt19937 rng(39);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double spacing = 0.05;
  const apc::LatticeDepthWarp warp(apc::LogDepthWarp(2.0, 9.0), spacing);
  const apc::TileRect tile{ 0, 0, 16, 16, 0 };
  constexpr int kWidth = 16;
  std::vector<double> imageRuns(5 * 256, 0.0);
  std::vector<double> imageSingle(5 * 256, 0.0);
  apc::SampleCache cacheRuns;
  apc::SampleCache cacheSingle;
  cacheRuns.Record = true;
  cacheSingle.Record = true;
  apc::visitors::Moments<4> runs(imageRuns.data(), kWidth, &warp, &cacheRuns);
  apc::visitors::Moments<4> single(imageSingle.data(), kWidth, &warp, &cacheSingle);
  int visible = 0;
  int dropped = 0;
  for (int t = 0; t < 20; ++t)
  {
    runs.BeginTile(tile);
    single.BeginTile(tile);
    for (int r = 0; r < 2000; ++r)
    {
      const int p = static_cast<int>(u(rng) * tile.Pixels());
      const int n = 1 + static_cast<int>(u(rng) * 8);
      // Depths on the lattice (the warp's table) and, now and then, off it (jittered rays).
      const int64_t k = 30 + static_cast<int64_t>(u(rng) * 160);
      const double offset = r % 5 == 0 ? u(rng) : 0.0;
      double depth[8];
      double scalar[8];
      float absorbance[8];
      for (int s = 0; s < n; ++s)
      {
        depth[s] = (static_cast<double>(k + s) + offset) * spacing;
        scalar[s] = 10.0 * u(rng);
        absorbance[s] = RandomAbsorbance(rng);
      }
      // A run begun and dropped (the walker's run in which the pixel turns opaque) leaves
      // nothing behind.
      if (r % 7 == 0)
      {
        apc::visitors::Moments<4>::Run run;
        runs.RunBegin(run, p, n);
        for (int s = 0; s < n; ++s)
        {
          runs.RunAdd(run, p, k + s, 2.0 * depth[s], scalar[s], 1.0f);
        }
        ++dropped;
      }
      apc::visitors::Moments<4>::Run run;
      runs.RunBegin(run, p, n);
      for (int s = 0; s < n; ++s)
      {
        runs.RunAdd(run, p, k + s, depth[s], scalar[s], absorbance[s]);
        if (absorbance[s] > 0)
        {
          single.Sample(
            p, k + s, depth[s], scalar[s], apc::TransferSample{ { 0.f, 0.f, 0.f }, absorbance[s] });
          ++visible;
        }
      }
      runs.RunEnd(run, p);
    }
    ASSERT_EQ(runs.Sums.size(), single.Sums.size());
    ASSERT_EQ(
      std::memcmp(runs.Sums.data(), single.Sums.data(), runs.Sums.size() * sizeof(double)), 0)
      << "tile " << t;
    ASSERT_EQ(runs.Buffer->Used, single.Buffer->Used) << "tile " << t;
    for (size_t i = 0; i < single.Buffer->Used; ++i)
    {
      const apc::RecordedSample& a = runs.Buffer->Recorded[i];
      const apc::RecordedSample& b = single.Buffer->Recorded[i];
      ASSERT_TRUE(std::memcmp(&a.Z, &b.Z, sizeof a.Z) == 0 &&
        std::memcmp(&a.Scalar, &b.Scalar, sizeof a.Scalar) == 0 && a.Pixel == b.Pixel &&
        a.K16 == b.K16)
        << "tile " << t << " record " << i;
    }
    ASSERT_EQ(runs.Buffer->Counts, single.Buffer->Counts) << "tile " << t;
  }
  EXPECT_GT(visible, 100000);
  EXPECT_GT(dropped, 1000);
}

TEST(PassOneRuns, WeightedRunsLeavePlainRecordsWeightOne)
{
  // Sample End Weights = Boundary: weighted runs (a cell with a boundary face in the lanes)
  // and plain samples (the other cells, which weigh nothing) share a tile's records. A run's
  // invisible step and a dropped run (the pixel turns opaque) leave no weight behind where a
  // plain sample is recorded next.
  const double spacing = 0.05;
  const apc::LatticeDepthWarp warp(apc::LogDepthWarp(2.0, 9.0), spacing);
  const apc::TileRect tile{ 0, 0, 16, 16, 0 };
  std::vector<double> image(5 * 256, 0.0);
  apc::SampleCache cache;
  cache.Record = true;
  apc::visitors::Moments<4> moments(image.data(), 16, &warp, &cache);
  moments.Weighted = true;
  moments.BeginTile(tile);
  const apc::TransferSample plain{ { 0.f, 0.f, 0.f }, 0.25f };
  apc::visitors::Moments<4>::Run run;
  // Kept, its last step invisible: weight 0.3 is not kept.
  moments.RunBegin(run, 1, 3, true);
  moments.RunAddWeighted(run, 1, 40, 40 * spacing, 0.5, 0.35f, 0.7f);
  moments.RunAddWeighted(run, 1, 41, 41 * spacing, 0.5, 0.5f, 1.f);
  moments.RunAddWeighted(run, 1, 42, 42 * spacing, 0.5, 0.f, 0.3f);
  moments.RunEnd(run, 1);
  moments.Sample(2, 40, 40 * spacing, 0.5, plain);
  // Dropped: weights 0.4 and 0.6 were written.
  moments.RunBegin(run, 3, 2, true);
  moments.RunAddWeighted(run, 3, 50, 50 * spacing, 0.5, 0.2f, 0.4f);
  moments.RunAddWeighted(run, 3, 51, 51 * spacing, 0.5, 0.3f, 0.6f);
  moments.RunDrop(run);
  moments.Sample(4, 50, 50 * spacing, 0.5, plain);
  moments.Sample(4, 51, 51 * spacing, 0.5, plain);
  const apc::RecordBuffer& buffer = *moments.Buffer;
  ASSERT_EQ(buffer.Used, 5u);
  ASSERT_GE(buffer.Weights.size(), 5u);
  const float expected[5] = { 0.7f, 1.f, 1.f, 1.f, 1.f };
  for (int i = 0; i < 5; ++i)
  {
    EXPECT_EQ(buffer.Weights[i], expected[i]) << "record " << i;
  }
}
