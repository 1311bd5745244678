// The MBOIT passes stop a ray once its own absorbance reaches the opaque threshold
// (VolumeRayMarcher::SetOpaqueAbsorbance). Checked on a thick, nearly opaque block of
// distorted hexahedra against the exact ordered blend of every sample: samples are skipped,
// the opacity stays within exp(-threshold) of the exact one, no pixel moves farther from the
// exact image than 1/255 beyond where marching every sample leaves it, pass 2 takes exactly
// pass 1's samples whether it replays them or marches again, and the block cut in two meshes
// (two ranks, interleaved cells) keeps the same bounds.
#include "apcCellMesh.h"
#include "apcDepthWarp.h"
#include "apcOpaquePrediction.h"
#include "apcOpaqueSummary.h"
#include "apcRayCamera.h"
#include "apcResolve.h"
#include "apcTransferTable.h"
#include "apcVolumeRayMarcher.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace
{
constexpr int kSize = 48;
constexpr size_t kPixels = static_cast<size_t>(kSize) * kSize;
constexpr int kCells = 8; // per side

// Corner points of an n^3 block over [-1,1]^3, interior points moved by up to a tenth of a
// cell (non-affine hexahedra, as in real meshes), scalars varying along every axis.
void Block(std::vector<std::array<double, 3>>& points, std::vector<float>& scalars)
{
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.1, 0.1);
  const double h = 2.0 / kCells;
  for (int k = 0; k <= kCells; ++k)
  {
    for (int j = 0; j <= kCells; ++j)
    {
      for (int i = 0; i <= kCells; ++i)
      {
        const bool inner = i > 0 && i < kCells && j > 0 && j < kCells && k > 0 && k < kCells;
        std::array<double, 3> x = { -1 + i * h, -1 + j * h, -1 + k * h };
        for (double& c : x)
        {
          c += inner ? jitter(rng) * h : 0.0;
        }
        points.push_back(x);
        scalars.push_back(
          static_cast<float>(0.5 + 0.3 * std::sin(2 * x[0]) * std::cos(3 * x[2]) + 0.15 * x[1]));
      }
    }
  }
}

// The block's cells, all of them (part < 0) or those of one of two interleaved parts, or
// with parts > 0, those that a random split (seed) into that many parts gives part.
apc::CellMesh BlockMesh(int part, int parts = 0, unsigned seed = 0)
{
  std::mt19937 split(seed);
  apc::CellMesh mesh;
  Block(mesh.Points, mesh.PointScalars);
  auto id = [](int i, int j, int k)
  { return static_cast<int64_t>((k * (kCells + 1) + j) * (kCells + 1) + i); };
  for (int k = 0; k < kCells; ++k)
  {
    for (int j = 0; j < kCells; ++j)
    {
      for (int i = 0; i < kCells; ++i)
      {
        const int owner =
          parts > 0 ? std::uniform_int_distribution<int>(0, parts - 1)(split) : (i + j + k) % 2;
        if (part >= 0 && owner != part)
        {
          continue;
        }
        const int64_t ids[8] = { id(i, j, k), id(i + 1, j, k), id(i + 1, j + 1, k), id(i, j + 1, k),
          id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1) };
        mesh.AddCell(apc::CellShape::Hexahedron, ids);
      }
    }
  }
  EXPECT_TRUE(mesh.Finalize());
  return mesh;
}

// Seen obliquely: rays cross 2-3 units of the block, about 30 absorbance units each.
apc::RayCamera Camera()
{
  return apc::RayCamera(
    { 1.2, 0.9, 4.0 }, { 0, 0, 0 }, { 0, 1, 0 }, 40.0, false, 1.0, kSize, kSize, 0.1, 20.0);
}

apc::TransferTable Table()
{
  std::vector<std::array<float, 3>> colours = { { 0.1f, 0.2f, 0.9f }, { 0.9f, 0.9f, 0.9f },
    { 0.9f, 0.1f, 0.1f } };
  std::vector<double> opacities = { 0.3, 0.6, 0.9 };
  return apc::TransferTable(0.0, 1.0, colours, opacities, 0.02, 0.1);
}

struct Frame
{
  std::vector<double> Moments = std::vector<double>(kPixels * 5, 0.0);
  std::vector<double> Sums = std::vector<double>(kPixels * 4, 0.0);
  int64_t Pass1Samples = 0;
  int64_t Pass2Samples = 0;

  std::vector<float> Image() const
  {
    std::vector<float> rgba(kPixels * 4);
    apc::ResolveImage(apc::ResolveMode::Renormalised, kPixels, this->Moments.data(), 5,
      this->Sums.data(), rgba.data());
    return rgba;
  }
};

struct Scene
{
  apc::TransferTable TF = Table();
  apc::RayCamera View = Camera();
  apc::LogDepthWarp Warp = apc::LogDepthWarp(2.0, 7.5);
};

// Pass 1 of every mesh, then pass 2 of every mesh with the summed moments (ranks).
Frame Render(const Scene& scene, std::vector<apc::VolumeRayMarcher*> marchers)
{
  Frame frame;
  for (auto* marcher : marchers)
  {
    marcher->SetView(scene.View, nullptr);
    marcher->AccumulateMoments<4>(scene.TF, scene.Warp, frame.Moments.data());
    frame.Pass1Samples += marcher->GetLastSampleCount();
  }
  for (auto* marcher : marchers)
  {
    marcher->AccumulateColour<4>(
      scene.TF, scene.Warp, frame.Moments.data(), apc::MomentSettings<4>(), frame.Sums.data());
    frame.Pass2Samples += marcher->GetLastSampleCount();
  }
  return frame;
}

// As Render, with the agreed cut: each mesh's pass 1 in its own moments, their profiles
// summed (the processes' allreduce), each mesh cut, then the moments summed and pass 2. With
// bound (a predicted last bin per pixel), pass 1 stops there too, and the tiles of the pixels
// it leaves unresolved are marched again without it and their profiles summed again, as
// vtkAPCCompositePass does on several processes. cut: the agreed cut; unresolved: how many
// pixels the bound left unknown.
Frame RenderPredicted(const Scene& scene, std::vector<apc::VolumeRayMarcher*> marchers,
  const std::vector<uint8_t>* bound, std::vector<uint8_t>& cut, size_t& unresolved)
{
  constexpr int bins = apc::OpaqueBins::kBins;
  Frame frame;
  std::vector<std::vector<double>> own(marchers.size());
  auto sum = [&]
  {
    std::vector<uint16_t> profile(kPixels * bins, 0);
    for (auto* marcher : marchers)
    {
      const apc::VolumeRayMarcher::OpaqueProfile mine = marcher->GetOpaqueProfile();
      EXPECT_EQ(mine.size(), profile.size());
      apc::AddProfiles(profile.data(), mine.data(), std::min(mine.size(), profile.size()));
    }
    return profile;
  };
  for (size_t m = 0; m < marchers.size(); ++m)
  {
    own[m].assign(kPixels * 5, 0.0);
    marchers[m]->SetView(scene.View, nullptr);
    marchers[m]->SetOpaqueBound(bound ? bound->data() : nullptr);
    marchers[m]->AccumulateMoments<4>(scene.TF, scene.Warp, own[m].data());
    marchers[m]->SetOpaqueBound(nullptr);
    frame.Pass1Samples += marchers[m]->GetLastSampleCount();
  }
  std::vector<uint16_t> profile = sum();
  if (bound)
  {
    // As vtkAPCCompositePass sums them: the meshes' summaries combined, then only each
    // pixel's bins up to the earlier of its bound and the earliest own cut; a bounded pass 1
    // leaves every mesh's profile zero past the bound.
    std::vector<uint16_t> partial(kPixels * bins, 0);
    for (size_t p = 0; p < kPixels; ++p)
    {
      uint16_t combined = 0;
      for (size_t m = 0; m < marchers.size(); ++m)
      {
        const uint16_t* mine = marchers[m]->GetOpaqueProfile().data() + p * bins;
        for (int b = apc::BoundedProfileBins((*bound)[p]); b < bins; ++b)
        {
          EXPECT_EQ(mine[b], 0) << "a bounded pass 1 left a sample past its bound";
        }
        const uint16_t own = apc::OpaqueSummary::Of(mine);
        combined = m == 0 ? own : apc::OpaqueSummary::Combine(combined, own);
      }
      const int keep = apc::OpaqueSummary::Bins(apc::OpaqueSummary::Bounded(combined, (*bound)[p]));
      for (auto* marcher : marchers)
      {
        apc::AddProfiles(partial.data() + p * bins, marcher->GetOpaqueProfile().data() + p * bins,
          static_cast<size_t>(keep));
      }
    }
    profile = partial;
  }
  std::vector<uint8_t> open(kPixels, 0);
  unresolved = bound ? apc::MarkUnresolved(bound->data(), profile.data(), kPixels, open.data()) : 0;
  if (unresolved > 0)
  {
    for (size_t m = 0; m < marchers.size(); ++m)
    {
      marchers[m]->RedoOpaqueTiles<4>(scene.TF, scene.Warp, open.data(), own[m].data());
      frame.Pass1Samples += marchers[m]->GetLastRedoSampleCount();
    }
    profile = sum();
  }
  cut.resize(kPixels);
  for (size_t p = 0; p < kPixels; ++p)
  {
    cut[p] = static_cast<uint8_t>(apc::CutBin(profile.data() + p * bins));
  }
  for (size_t m = 0; m < marchers.size(); ++m)
  {
    marchers[m]->ApplyOpaqueCut<4>(scene.TF, scene.Warp, profile.data(), own[m].data());
    for (size_t i = 0; i < own[m].size(); ++i)
    {
      frame.Moments[i] += own[m][i];
    }
  }
  for (auto* marcher : marchers)
  {
    marcher->AccumulateColour<4>(
      scene.TF, scene.Warp, frame.Moments.data(), apc::MomentSettings<4>(), frame.Sums.data());
    frame.Pass2Samples += marcher->GetLastSampleCount();
  }
  return frame;
}

Frame RenderCut(const Scene& scene, std::vector<apc::VolumeRayMarcher*> marchers)
{
  std::vector<uint8_t> cut;
  size_t unresolved = 0;
  return RenderPredicted(scene, marchers, nullptr, cut, unresolved);
}

std::vector<float> Exact(const Scene& scene, apc::VolumeRayMarcher& marcher)
{
  std::vector<float> rgba(kPixels * 4, 0.0f);
  marcher.SetView(scene.View, nullptr);
  marcher.RenderExact(scene.TF, rgba.data());
  return rgba;
}

// What stopping may change: the opacity by at most exp(-threshold) (plus float rounding),
// and no channel farther from the exact blend than the unstopped image is by more than 1/255.
void ExpectWithinBound(const std::vector<float>& stopped, const std::vector<float>& unstopped,
  const std::vector<float>& exact, const char* what)
{
  const double opacityBound = std::exp(-apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance) + 1e-6;
  int covered = 0;
  for (size_t p = 0; p < kPixels; ++p)
  {
    covered += exact[4 * p + 3] > 0.99 ? 1 : 0;
    ASSERT_NEAR(stopped[4 * p + 3], exact[4 * p + 3], opacityBound) << what << " pixel " << p;
    for (int c = 0; c < 4; ++c)
    {
      const size_t i = 4 * p + c;
      ASSERT_LE(std::abs(stopped[i] - exact[i]), std::abs(unstopped[i] - exact[i]) + 1.0 / 255)
        << what << " pixel " << p << " channel " << c;
    }
  }
  EXPECT_GT(covered, static_cast<int>(kPixels / 3)) << "the block should be opaque where seen";
}
}

TEST(OpaqueStop, SkipsWhatIsHiddenWithinBound)
{
  const Scene scene;
  const apc::CellMesh mesh = BlockMesh(-1);
  apc::VolumeRayMarcher marcher;
  marcher.SetMesh(&mesh);
  // Off by default: every sample, as the partition invariance needs.
  ASSERT_EQ(marcher.GetOpaqueAbsorbance(), std::numeric_limits<double>::infinity());
  marcher.SetOpaqueAbsorbance(apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
  const Frame stopped = Render(scene, { &marcher });
  marcher.SetOpaqueAbsorbance(std::numeric_limits<double>::infinity());
  const Frame all = Render(scene, { &marcher });
  const std::vector<float> exact = Exact(scene, marcher);
  EXPECT_EQ(all.Pass1Samples, marcher.GetLastSampleCount()) << "every sample without the stop";
  // Rays through the middle cross ~20 absorbance units and stop at ~9.2; rays near the edges
  // cross less: about half of the samples are left out.
  EXPECT_GT(all.Pass1Samples, 0);
  EXPECT_LT(stopped.Pass1Samples, 0.7 * all.Pass1Samples);
  ExpectWithinBound(stopped.Image(), all.Image(), exact, "one mesh");
}

TEST(OpaqueStop, PassTwoTakesPassOnesSamples)
{
  const Scene scene;
  const apc::CellMesh mesh = BlockMesh(-1);
  apc::VolumeRayMarcher cached;
  cached.SetMesh(&mesh);
  cached.SetOpaqueAbsorbance(apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
  apc::VolumeRayMarcher marched;
  marched.SetMesh(&mesh);
  marched.SetOpaqueAbsorbance(apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
  marched.SetMaxSampleCacheBytes(0); // pass 2 clips and interpolates again
  const Frame replay = Render(scene, { &cached });
  const Frame again = Render(scene, { &marched });
  ASSERT_EQ(cached.GetLastColourCacheShare(), 1.0);
  ASSERT_EQ(marched.GetLastColourCacheShare(), 0.0);
  // The same samples in both passes: pass 1's moments are bit for bit the same, and pass 2
  // marched again stops where pass 1 did (the visible samples it weights are the ones the
  // cache replays; the cache keeps depths and scalars as floats, hence the tolerance).
  EXPECT_EQ(replay.Moments, again.Moments);
  EXPECT_EQ(replay.Pass1Samples, again.Pass2Samples);
  for (size_t i = 0; i < replay.Sums.size(); ++i)
  {
    ASSERT_NEAR(replay.Sums[i], again.Sums[i], 1e-5 * (1 + std::abs(again.Sums[i]))) << i;
  }
}

TEST(OpaqueStop, TwoMeshesKeepTheBound)
{
  const Scene scene;
  const apc::CellMesh whole = BlockMesh(-1);
  const apc::CellMesh even = BlockMesh(0);
  const apc::CellMesh odd = BlockMesh(1);
  apc::VolumeRayMarcher a;
  apc::VolumeRayMarcher b;
  a.SetMesh(&even);
  b.SetMesh(&odd);
  a.SetOpaqueAbsorbance(apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
  b.SetOpaqueAbsorbance(apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
  const Frame stopped = Render(scene, { &a, &b });
  a.SetOpaqueAbsorbance(std::numeric_limits<double>::infinity());
  b.SetOpaqueAbsorbance(std::numeric_limits<double>::infinity());
  const Frame all = Render(scene, { &a, &b });
  apc::VolumeRayMarcher one;
  one.SetMesh(&whole);
  const std::vector<float> exact = Exact(scene, one);
  // Each mesh stops on its own absorbance, a part of the ray's: fewer samples are skipped
  // than with one mesh, but some are.
  EXPECT_LT(stopped.Pass1Samples, all.Pass1Samples);
  ExpectWithinBound(stopped.Image(), all.Image(), exact, "two meshes");
}

TEST(OpaqueStop, HybridMarchesEverySample)
{
  // Hybrid's own transmittance is the exact ordered product of a rank's samples: a pass 1
  // that keeps its own moments takes every sample, and its pass 2 too.
  const Scene scene;
  const apc::CellMesh mesh = BlockMesh(-1);
  apc::VolumeRayMarcher marcher;
  marcher.SetMesh(&mesh);
  marcher.SetOpaqueAbsorbance(apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
  marcher.SetView(scene.View, nullptr);
  std::vector<double> moments(kPixels * 5, 0.0);
  marcher.AccumulateMoments<4>(scene.TF, scene.Warp, moments.data(), true);
  const int64_t hybrid = marcher.GetLastSampleCount();
  std::vector<double> sums(kPixels * 4, 0.0);
  marcher.AccumulateColour<4>(
    scene.TF, scene.Warp, moments.data(), apc::MomentSettings<4>(), sums.data(), true);
  EXPECT_EQ(marcher.GetLastSampleCount(), hybrid);
  std::fill(moments.begin(), moments.end(), 0.0);
  marcher.AccumulateMoments<4>(scene.TF, scene.Warp, moments.data());
  const int64_t stopped = marcher.GetLastSampleCount();
  marcher.SetOpaqueAbsorbance(std::numeric_limits<double>::infinity());
  std::fill(moments.begin(), moments.end(), 0.0);
  marcher.AccumulateMoments<4>(scene.TF, scene.Warp, moments.data());
  EXPECT_EQ(hybrid, marcher.GetLastSampleCount());
  EXPECT_LT(stopped, hybrid);
}

// Pass 2 skips what the global moments hide (VolumeRayMarcher::SetHiddenSampleWeight), on by
// default and independent of the opaque stop (off here): the skipped samples weigh at most
// the hidden weight per pixel in the colour sums (the Paper Sum resolve's values), the
// resolved image moves by less than 1/255, pass 1 is untouched, and a pass 2 that marches
// again skips like one that replays.
TEST(HiddenSamples, PassTwoSkipsWithinBound)
{
  const Scene scene;
  const apc::CellMesh mesh = BlockMesh(-1);
  apc::VolumeRayMarcher marcher;
  marcher.SetMesh(&mesh);
  ASSERT_EQ(marcher.GetHiddenSampleWeight(), apc::VolumeRayMarcher::kDefaultHiddenSampleWeight);
  const Frame skipped = Render(scene, { &marcher });
  const double hiddenShare = marcher.GetLastHiddenShare();
  marcher.SetHiddenSampleWeight(0.0);
  const Frame all = Render(scene, { &marcher });
  EXPECT_EQ(marcher.GetLastHiddenShare(), 0.0);
  // Rays through the middle cross ~20-30 absorbance units; a quarter of all samples lie
  // behind a transmittance of 1e-4 / b0 (measured 0.23).
  EXPECT_GT(hiddenShare, 0.15);
  EXPECT_EQ(skipped.Moments, all.Moments);
  EXPECT_EQ(skipped.Pass2Samples, all.Pass2Samples) << "skipped samples still count as replayed";
  const double bound = apc::VolumeRayMarcher::kDefaultHiddenSampleWeight;
  for (size_t p = 0; p < kPixels; ++p)
  {
    for (int c = 0; c < 4; ++c)
    {
      const double dropped = all.Sums[4 * p + c] - skipped.Sums[4 * p + c];
      ASSERT_GE(dropped, -1e-12) << "pixel " << p << " channel " << c;
      ASSERT_LE(dropped, bound) << "pixel " << p << " channel " << c;
    }
  }
  const std::vector<float> a = skipped.Image();
  const std::vector<float> b = all.Image();
  double change = 0;
  for (size_t i = 0; i < a.size(); ++i)
  {
    change = std::max(change, static_cast<double>(std::abs(a[i] - b[i])));
  }
  std::cout << "hidden share " << hiddenShare << ", largest change of the resolved image " << change
            << "\n";
  EXPECT_LE(change, 1.0 / 255);

  // Marched again (no cache): the same depths, hence about the same samples skipped (the cache
  // holds depths as floats, so a sample right at a pixel's hidden depth may go either way).
  apc::VolumeRayMarcher marched;
  marched.SetMesh(&mesh);
  marched.SetMaxSampleCacheBytes(0);
  const Frame again = Render(scene, { &marched });
  ASSERT_EQ(marched.GetLastColourCacheShare(), 0.0);
  EXPECT_NEAR(marched.GetLastHiddenShare(), hiddenShare, 1e-3);
  for (size_t i = 0; i < again.Sums.size(); ++i)
  {
    ASSERT_NEAR(again.Sums[i], skipped.Sums[i], 1e-5 * (1 + std::abs(skipped.Sums[i]))) << i;
  }
}

// The hidden depth comes from the global moments alone: the block split in two meshes (two
// ranks) skips the samples the whole block skips, and its image equals the whole block's as
// closely as without skipping.
TEST(HiddenSamples, TwoMeshesSkipWhatOneSkips)
{
  const Scene scene;
  const apc::CellMesh whole = BlockMesh(-1);
  const apc::CellMesh even = BlockMesh(0);
  const apc::CellMesh odd = BlockMesh(1);
  apc::VolumeRayMarcher one;
  apc::VolumeRayMarcher a;
  apc::VolumeRayMarcher b;
  one.SetMesh(&whole);
  a.SetMesh(&even);
  b.SetMesh(&odd);
  auto hidden = [](const apc::VolumeRayMarcher& m)
  { return std::llround(m.GetLastHiddenShare() * m.GetLastSampleCount()); };
  auto difference = [](const Frame& x, const Frame& y)
  {
    const std::vector<float> i = x.Image();
    const std::vector<float> j = y.Image();
    double worst = 0;
    for (size_t k = 0; k < i.size(); ++k)
    {
      worst = std::max(worst, static_cast<double>(std::abs(i[k] - j[k])));
    }
    return worst;
  };
  const Frame oneSkipped = Render(scene, { &one });
  const Frame twoSkipped = Render(scene, { &a, &b });
  const long long hiddenOne = hidden(one);
  const long long hiddenTwo = hidden(a) + hidden(b);
  for (auto* m : { &one, &a, &b })
  {
    m->SetHiddenSampleWeight(0.0);
  }
  const Frame oneAll = Render(scene, { &one });
  const Frame twoAll = Render(scene, { &a, &b });
  EXPECT_GT(hiddenOne, 0);
  // The moments' sums differ in their last bits between one and two meshes; a bisection step
  // may then fall on the other side for a pixel or two.
  EXPECT_NEAR(static_cast<double>(hiddenTwo), static_cast<double>(hiddenOne), 1e-4 * hiddenOne);
  const double withSkip = difference(oneSkipped, twoSkipped);
  const double without = difference(oneAll, twoAll);
  std::cout << "one vs two meshes: " << withSkip << " skipping, " << without << " without ("
            << hiddenOne << " vs " << hiddenTwo << " samples skipped)\n";
  EXPECT_LE(withSkip, std::max(2 * without, 1e-6));
}

// With the agreed cut, the block split at random among 2 to 4 processes renders what one
// process renders (float rounding: the cut pixels' moments are summed again from the cache's
// float depths), whether pass 2 replays the cache or marches again, and the image keeps the
// stop's bound against the exact blend.
TEST(OpaqueStop, TheCutKeepsProcessesEqualToOne)
{
  const Scene scene;
  const apc::CellMesh whole = BlockMesh(-1);
  apc::VolumeRayMarcher one;
  one.SetMesh(&whole);
  one.SetOpaqueAbsorbance(apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
  const Frame single = RenderCut(scene, { &one });
  const std::vector<float> image = single.Image();
  one.SetOpaqueAbsorbance(std::numeric_limits<double>::infinity());
  const Frame all = Render(scene, { &one });
  const std::vector<float> exact = Exact(scene, one);
  EXPECT_LT(single.Pass1Samples, 0.8 * all.Pass1Samples);
  ExpectWithinBound(image, all.Image(), exact, "one process, cut");

  for (int parts = 2; parts <= 4; ++parts)
  {
    for (size_t budget : { size_t(1) << 30, size_t(0) })
    {
      std::vector<apc::CellMesh> meshes;
      for (int p = 0; p < parts; ++p)
      {
        meshes.push_back(BlockMesh(p, parts, 31));
      }
      std::vector<std::unique_ptr<apc::VolumeRayMarcher>> marchers;
      std::vector<apc::VolumeRayMarcher*> pointers;
      for (const apc::CellMesh& mesh : meshes)
      {
        marchers.emplace_back(new apc::VolumeRayMarcher);
        marchers.back()->SetMesh(&mesh);
        marchers.back()->SetMaxSampleCacheBytes(budget);
        marchers.back()->SetOpaqueAbsorbance(apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
        pointers.push_back(marchers.back().get());
      }
      const Frame split = RenderCut(scene, pointers);
      EXPECT_LT(split.Pass1Samples, all.Pass1Samples) << parts << " processes stop too";
      for (size_t i = 0; i < single.Moments.size(); ++i)
      {
        ASSERT_NEAR(split.Moments[i], single.Moments[i], 1e-6 * (1 + std::abs(single.Moments[i])))
          << parts << " processes, budget " << budget << ", moment " << i;
      }
      const std::vector<float> splitImage = split.Image();
      for (size_t i = 0; i < image.size(); ++i)
      {
        ASSERT_NEAR(splitImage[i], image[i], 1e-5)
          << parts << " processes, budget " << budget << ", value " << i;
      }
    }
  }
}

// Processes bounded by a predicted cut keep the samples they keep without one: with the
// exact cut as the bound (nothing unresolved, fewer samples), a bound two bins too shallow
// and none at all (the unresolved pixels' tiles are marched again), with and without the
// sample cache. The cut is the same bit for bit, the moments up to the cache's float depths.
TEST(OpaqueStop, APredictedBoundKeepsTheCut)
{
  const Scene scene;
  for (int parts = 2; parts <= 4; ++parts)
  {
    for (size_t budget : { size_t(1) << 30, size_t(0) })
    {
      std::vector<apc::CellMesh> meshes;
      std::vector<std::unique_ptr<apc::VolumeRayMarcher>> marchers;
      std::vector<apc::VolumeRayMarcher*> pointers;
      for (int p = 0; p < parts; ++p)
      {
        meshes.push_back(BlockMesh(p, parts, 5));
      }
      for (const apc::CellMesh& mesh : meshes)
      {
        marchers.emplace_back(new apc::VolumeRayMarcher);
        marchers.back()->SetMesh(&mesh);
        marchers.back()->SetMaxSampleCacheBytes(budget);
        marchers.back()->SetOpaqueAbsorbance(apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
        pointers.push_back(marchers.back().get());
      }
      std::vector<uint8_t> cut;
      size_t unresolved = 0;
      const Frame free = RenderPredicted(scene, pointers, nullptr, cut, unresolved);
      const std::vector<float> image = free.Image();
      std::vector<uint8_t> shallow = cut;
      for (uint8_t& b : shallow)
      {
        b = b >= 2 && b < apc::OpaqueBins::kBins - 1 ? b - 2 : b;
      }
      const std::vector<uint8_t> zero(kPixels, 0);
      const std::vector<uint8_t>* bounds[] = { &cut, &shallow, &zero };
      for (const std::vector<uint8_t>* bound : bounds)
      {
        const char* what = bound == &cut ? "exact" : (bound == &shallow ? "shallow" : "zero");
        std::vector<uint8_t> agreed;
        const Frame f = RenderPredicted(scene, pointers, bound, agreed, unresolved);
        EXPECT_EQ(agreed, cut) << parts << " processes, " << what;
        EXPECT_EQ(unresolved > 0, bound != &cut) << parts << " processes, " << what;
        EXPECT_EQ(f.Pass2Samples, free.Pass2Samples) << parts << " processes, " << what;
        if (bound == &cut)
        {
          EXPECT_LT(f.Pass1Samples, free.Pass1Samples) << parts << " processes";
        }
        for (size_t i = 0; i < f.Moments.size(); ++i)
        {
          ASSERT_NEAR(f.Moments[i], free.Moments[i], 1e-6 * (1 + std::abs(free.Moments[i])))
            << parts << " processes, " << what << ", moment " << i;
        }
        const std::vector<float> bounded = f.Image();
        for (size_t i = 0; i < image.size(); ++i)
        {
          ASSERT_NEAR(bounded[i], image[i], 1e-5) << parts << " processes, " << what << ", " << i;
        }
      }
    }
  }
}

// On several processes the pass sums the processes' profiles in a mesh's own
// (GetOpaqueProfileToSum), which pass 1 may make in memory the caller lends: a pixel whose
// cut a predicted bound left unknown has its tile marched again, and that tile's profile must
// be this mesh's alone again, zero where the tile has no cells to march.
TEST(OpaqueStop, TilesMarchedAgainStartTheirProfilesAfresh)
{
  constexpr int bins = apc::OpaqueBins::kBins;
  constexpr int tile = apc::VolumeRayMarcher::kTileSize;
  const Scene scene;
  const apc::CellMesh mesh = BlockMesh(0, 64, 3); // a few scattered cells: tiles without any
  apc::VolumeRayMarcher marcher;
  marcher.SetMesh(&mesh);
  marcher.SetOpaqueAbsorbance(apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
  marcher.SetView(scene.View, nullptr);
  std::vector<double> moments(kPixels * 5, 0.0);
  marcher.AccumulateMoments<4>(scene.TF, scene.Warp, moments.data());
  const apc::VolumeRayMarcher::OpaqueProfile own = marcher.GetOpaqueProfile();
  const std::vector<uint16_t> fresh(own.data(), own.data() + own.size());
  ASSERT_EQ(fresh.size(), kPixels * bins);
  int emptyTiles = 0;
  for (int tj = 0; tj < kSize; tj += tile)
  {
    for (int ti = 0; ti < kSize; ti += tile)
    {
      bool empty = true;
      for (int j = tj; j < std::min(kSize, tj + tile); ++j)
      {
        for (int i = ti; i < std::min(kSize, ti + tile); ++i)
        {
          const uint16_t* p = fresh.data() + (static_cast<size_t>(j) * kSize + i) * bins;
          empty = empty && std::all_of(p, p + bins, [](uint16_t q) { return q == 0; });
        }
      }
      emptyTiles += empty ? 1 : 0;
    }
  }
  ASSERT_GT(emptyTiles, 0) << "the scene should leave a tile without samples";
  ASSERT_LT(emptyTiles, (kSize / tile) * (kSize / tile)) << "and some with samples";

  // In memory lent by the caller (not zeroed by it): the same profile.
  std::vector<unsigned char> lent(fresh.size() * sizeof(uint16_t), 0xff);
  marcher.LendOpaqueProfileMemory(lent.data(), lent.size());
  std::fill(moments.begin(), moments.end(), 0.0);
  marcher.AccumulateMoments<4>(scene.TF, scene.Warp, moments.data());
  ASSERT_EQ(marcher.GetOpaqueProfile().data(), reinterpret_cast<const uint16_t*>(lent.data()));
  EXPECT_TRUE(std::equal(fresh.begin(), fresh.end(), marcher.GetOpaqueProfile().data()));

  // The processes' sums written over it, then every tile marched again.
  std::fill_n(marcher.GetOpaqueProfileToSum(), fresh.size(), uint16_t(1234));
  std::vector<uint8_t> open(kPixels, 1);
  marcher.RedoOpaqueTiles<4>(scene.TF, scene.Warp, open.data(), moments.data());
  EXPECT_TRUE(std::equal(fresh.begin(), fresh.end(), marcher.GetOpaqueProfile().data()))
    << "a tile marched again kept the sums written in its profile";

  marcher.LendOpaqueProfileMemory(nullptr, 0);
  EXPECT_EQ(marcher.GetOpaqueProfile().size(), 0u) << "withdrawn, the profile in it is forgotten";
  std::fill(moments.begin(), moments.end(), 0.0);
  marcher.AccumulateMoments<4>(scene.TF, scene.Warp, moments.data());
  EXPECT_TRUE(std::equal(fresh.begin(), fresh.end(), marcher.GetOpaqueProfile().data()))
    << "and the marcher's own memory used again";
  EXPECT_NE(marcher.GetOpaqueProfile().data(), reinterpret_cast<const uint16_t*>(lent.data()));
}

// The sample cache's compact form (SampleCache's depth table) changes no bit of a frame: the
// same moments after the cut (summed again from the cached samples of the cut pixels), the
// same colour sums replayed, the same sample counts, on one and on three processes, with and
// without end weights, with and without a predicted bound (whose unresolved tiles are
// recorded again).
TEST(OpaqueStop, TheCompactCacheChangesNoBit)
{
  const Scene scene;
  for (int parts : { 1, 3 })
  {
    for (bool weights : { false, true })
    {
      for (bool bounded : { false, true })
      {
        std::vector<uint8_t> free;
        Frame frames[2];
        for (int compact = 0; compact < 2; ++compact)
        {
          std::vector<apc::CellMesh> meshes;
          for (int p = 0; p < parts; ++p)
          {
            meshes.push_back(parts == 1 ? BlockMesh(-1) : BlockMesh(p, parts, 7));
          }
          std::vector<std::unique_ptr<apc::VolumeRayMarcher>> marchers;
          std::vector<apc::VolumeRayMarcher*> pointers;
          for (const apc::CellMesh& mesh : meshes)
          {
            marchers.emplace_back(new apc::VolumeRayMarcher);
            marchers.back()->SetMesh(&mesh);
            marchers.back()->SetCompactSampleCache(compact == 1);
            marchers.back()->SetSampleEndWeights(weights);
            marchers.back()->SetOpaqueAbsorbance(
              apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
            pointers.push_back(marchers.back().get());
          }
          std::vector<uint8_t> cut;
          size_t unresolved = 0;
          if (bounded)
          {
            // A bound two bins too shallow: pixels left unresolved, their tiles marched again.
            RenderPredicted(scene, pointers, nullptr, free, unresolved);
            for (uint8_t& b : free)
            {
              b = b >= 2 && b < apc::OpaqueBins::kBins - 1 ? b - 2 : b;
            }
          }
          frames[compact] =
            RenderPredicted(scene, pointers, bounded ? &free : nullptr, cut, unresolved);
          EXPECT_EQ(unresolved > 0, bounded);
        }
        const std::string what = std::to_string(parts) + " processes" +
          (weights ? ", end weights" : "") + (bounded ? ", bounded" : "");
        EXPECT_GT(frames[0].Pass2Samples, 0) << what;
        EXPECT_EQ(frames[1].Pass1Samples, frames[0].Pass1Samples) << what;
        EXPECT_EQ(frames[1].Pass2Samples, frames[0].Pass2Samples) << what;
        EXPECT_TRUE(frames[1].Moments == frames[0].Moments) << what;
        EXPECT_TRUE(frames[1].Sums == frames[0].Sums) << what;
      }
    }
  }
}
