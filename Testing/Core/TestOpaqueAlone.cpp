// One process with one mesh (VolumeRayMarcher::SetOpaqueStopAlone): pass 1 marches each tile
// without the opaque stop's bookkeeping first and keeps it where no ray came near the
// threshold. Checked against the same marcher with the stop as before (not alone), through
// the cut and pass 2: the moments, colour sums and sample counts must be the same, bit for
// bit, in a faint view (every tile kept without the stop), an opaque one and a mixed one
// (tiles marched again with the stop), on one thread and on several.
#include "apcCellMesh.h"
#include "apcDepthWarp.h"
#include "apcOpaqueBins.h"
#include "apcRayCamera.h"
#include "apcTransferTable.h"
#include "apcVolumeRayMarcher.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <random>
#include <vector>

namespace
{
constexpr int kSize = 128; // 64 tiles: enough for one thread to march without the stop
constexpr size_t kPixels = static_cast<size_t>(kSize) * kSize;
constexpr int kCells = 8; // per side

// An n^3 block of hexahedra over [-1,1]^3, interior corners moved by up to a tenth of a cell,
// scalars in [0.05, 0.95] varying along every axis.
apc::CellMesh BlockMesh()
{
  apc::CellMesh mesh;
  std::mt19937 rng(11);
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
        mesh.Points.push_back(x);
        mesh.PointScalars.push_back(
          static_cast<float>(0.5 + 0.3 * std::sin(2 * x[0]) * std::cos(3 * x[2]) + 0.15 * x[1]));
      }
    }
  }
  auto id = [](int i, int j, int k)
  { return static_cast<int64_t>((k * (kCells + 1) + j) * (kCells + 1) + i); };
  for (int k = 0; k < kCells; ++k)
  {
    for (int j = 0; j < kCells; ++j)
    {
      for (int i = 0; i < kCells; ++i)
      {
        const int64_t ids[8] = { id(i, j, k), id(i + 1, j, k), id(i + 1, j + 1, k), id(i, j + 1, k),
          id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1) };
        mesh.AddCell(apc::CellShape::Hexahedron, ids);
      }
    }
  }
  EXPECT_TRUE(mesh.Finalize());
  return mesh;
}

// opacities: alpha per unit distance 0.1 at scalars 0, 0.5 and 1.
apc::TransferTable Table(const std::vector<double>& opacities)
{
  std::vector<std::array<float, 3>> colours = { { 0.1f, 0.2f, 0.9f }, { 0.9f, 0.9f, 0.9f },
    { 0.9f, 0.1f, 0.1f } };
  return apc::TransferTable(0.0, 1.0, colours, opacities, 0.02, 0.1);
}

struct Frame
{
  std::vector<double> Moments = std::vector<double>(kPixels * 5, 0.0);
  std::vector<double> Sums = std::vector<double>(kPixels * 4, 0.0);
  int64_t Pass1Samples = 0;
  int64_t Pass2Samples = 0;
  int64_t Unstopped = 0;
  double LargestB0 = 0;
};

// One process's frame as vtkAPCCompositePass renders it with the stop: pass 1, the cut from
// its own profile, pass 2.
Frame Render(const apc::CellMesh& mesh, const apc::TransferTable& table, bool alone, int threads)
{
  const apc::RayCamera camera(
    { 1.2, 0.9, 4.0 }, { 0, 0, 0 }, { 0, 1, 0 }, 40.0, false, 1.0, kSize, kSize, 0.1, 20.0);
  const apc::LogDepthWarp warp(2.0, 7.5);
  apc::VolumeRayMarcher marcher;
  marcher.SetNumberOfThreads(threads);
  marcher.SetMesh(&mesh);
  marcher.SetOpaqueAbsorbance(apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
  marcher.SetOpaqueStopAlone(alone);
  marcher.SetView(camera, nullptr);
  Frame frame;
  marcher.AccumulateMoments<4>(table, warp, frame.Moments.data());
  frame.Pass1Samples = marcher.GetLastSampleCount();
  frame.Unstopped = marcher.GetLastUnstoppedTileCount();
  const apc::VolumeRayMarcher::OpaqueProfile view = marcher.GetOpaqueProfile();
  const std::vector<uint16_t> profile(view.data(), view.data() + view.size());
  EXPECT_EQ(profile.size(), kPixels * apc::OpaqueBins::kBins);
  marcher.ApplyOpaqueCut<4>(table, warp, profile.data(), frame.Moments.data());
  frame.Pass1Samples += marcher.GetLastCutSampleCount();
  marcher.AccumulateColour<4>(
    table, warp, frame.Moments.data(), apc::MomentSettings<4>(), frame.Sums.data());
  frame.Pass2Samples = marcher.GetLastSampleCount();
  for (size_t p = 0; p < kPixels; ++p)
  {
    frame.LargestB0 = std::max(frame.LargestB0, frame.Moments[5 * p]);
  }
  return frame;
}

// Alone and not alone give the same frame, bit for bit; returns the alone one.
Frame ExpectSame(const apc::TransferTable& table, int threads, const char* what)
{
  const apc::CellMesh mesh = BlockMesh();
  const Frame before = Render(mesh, table, false, threads);
  const Frame alone = Render(mesh, table, true, threads);
  EXPECT_EQ(before.Unstopped, 0) << what;
  EXPECT_EQ(alone.Pass2Samples, before.Pass2Samples) << what;
  size_t differ = 0;
  for (size_t i = 0; i < before.Moments.size(); ++i)
  {
    differ += alone.Moments[i] != before.Moments[i] ? 1 : 0;
  }
  for (size_t i = 0; i < before.Sums.size(); ++i)
  {
    differ += alone.Sums[i] != before.Sums[i] ? 1 : 0;
  }
  EXPECT_EQ(differ, 0u) << what << ": values that differ";
  std::cout << what << ", " << threads << " thread(s): largest b0 " << before.LargestB0
            << ", pass-1 samples " << before.Pass1Samples << " -> " << alone.Pass1Samples
            << ", tiles kept without the stop " << alone.Unstopped << std::endl;
  return alone;
}

// Rays up to about two thirds of the threshold.
const std::vector<double> kFaint = { 0.08, 0.16, 0.3 };
const std::vector<double> kOpaque = { 0.3, 0.6, 0.9 };
// Opaque where the scalar is high, clear where it is low: some rays opaque, some not.
const std::vector<double> kMixed = { 0.0, 0.0, 0.95 };
}

TEST(OpaqueAlone, AFaintViewIsMarchedWithoutTheStopAndGivesTheStopsFrame)
{
  for (int threads : { 1, 3 })
  {
    const Frame alone = ExpectSame(Table(kFaint), threads, "faint");
    EXPECT_LT(alone.LargestB0, apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
    // On one thread every tile with samples is kept unstopped (the block covers the middle of
    // the view); three threads would need more tiles (kTilesPerThreadWithoutStop).
    if (threads == 1)
    {
      EXPECT_GT(alone.Unstopped, 16);
    }
  }
}

TEST(OpaqueAlone, OpaqueAndMixedViewsGiveTheStopsFrame)
{
  for (int threads : { 1, 3 })
  {
    const Frame opaque = ExpectSame(Table(kOpaque), threads, "opaque");
    EXPECT_GE(opaque.LargestB0, apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance * 0.99);
    const Frame mixed = ExpectSame(Table(kMixed), threads, "mixed");
    EXPECT_GE(mixed.LargestB0, apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance * 0.99);
  }
}

TEST(OpaqueAlone, TheStopStillCutsAlone)
{
  // Alone with an opaque view takes the samples of the stop, far fewer than without it (a
  // tile per thread marched twice at most).
  const apc::CellMesh mesh = BlockMesh();
  const apc::TransferTable table = Table(kOpaque);
  const Frame alone = Render(mesh, table, true, 1);
  apc::VolumeRayMarcher all;
  all.SetMesh(&mesh);
  all.SetNumberOfThreads(1);
  all.SetView(apc::RayCamera({ 1.2, 0.9, 4.0 }, { 0, 0, 0 }, { 0, 1, 0 }, 40.0, false, 1.0, kSize,
                kSize, 0.1, 20.0),
    nullptr);
  std::vector<double> moments(kPixels * 5, 0.0);
  all.AccumulateMoments<4>(table, apc::LogDepthWarp(2.0, 7.5), moments.data());
  EXPECT_LT(alone.Pass2Samples, all.GetLastSampleCount() * 3 / 4);
}
