// A first frame's probe (apcOpaquePrediction.h) marches every step-th ray of the frame's
// camera. Its marcher takes its bins from the frame's (DecimateBins) instead of binning every
// cell again: the same bins, and so the same samples, as binning for the decimated camera.
#include "apcCellMesh.h"
#include "apcDepthWarp.h"
#include "apcRayCamera.h"
#include "apcTestBlock.h"
#include "apcTileBins.h"
#include "apcTransferTable.h"
#include "apcVolumeRayMarcher.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

namespace
{

// Cameras onto the block: outside it (perspective and parallel, cropped or not) and one inside
// it, whose cells reaching behind the eye get the whole screen.
std::vector<apc::RayCamera> Cameras()
{
  const apc::RayCamera outside(
    { 0.2, 0.95, 4.0 }, { 0.0, 0.45, 0.0 }, { 0, 1, 0 }, 40.0, false, 1.0, 70, 53, 0.1, 20.0);
  const apc::RayCamera parallel(
    { 0.3, 2.0, 3.0 }, { 0.0, 0.0, 0.0 }, { 0, 1, 0 }, 40.0, true, 0.8, 61, 64, 0.1, 20.0);
  const apc::RayCamera inside(
    { 0.1, 0.05, 0.2 }, { 1.0, 0.2, -0.5 }, { 0, 1, 0 }, 60.0, false, 1.0, 48, 40, 0.01, 20.0);
  return { outside, outside.Cropped(9, 5, 45, 37), parallel, parallel.Cropped(3, 11, 50, 29),
    inside };
}

} // namespace

TEST(DecimatedBins, AreTheBinsOfTheDecimatedCamera)
{
  std::mt19937 rng(11);
  const apc::CellMesh mesh = apctest::DistortedBlock(rng);
  int compared = 0;
  for (const apc::RayCamera& camera : Cameras())
  {
    apc::TileBins fine;
    apc::BinCells(&mesh, camera, 16, 1, fine);
    for (int step : { 1, 2, 3, 4, 8 })
    {
      for (int offset : { 0, step / 2, step - 1 })
      {
        const apc::RayCamera coarse = camera.Decimated(step, offset);
        apc::TileBins expected;
        apc::BinCells(&mesh, coarse, 4, 1, expected);
        apc::TileBins derived;
        ASSERT_TRUE(apc::DecimateBins(
          fine, step, offset, coarse.GetWidth(), coarse.GetHeight(), 4, 1, derived));
        ASSERT_EQ(derived.Grid.TilesX, expected.Grid.TilesX);
        ASSERT_EQ(derived.Grid.TilesY, expected.Grid.TilesY);
        for (int64_t cell = 0; cell < mesh.GetNumberOfCells(); ++cell)
        {
          const auto& a = derived.Rects[cell];
          const auto& b = expected.Rects[cell];
          // An empty rectangle is empty however it is written.
          const bool emptyA = a[0] > a[2] || a[1] > a[3];
          const bool emptyB = b[0] > b[2] || b[1] > b[3];
          ASSERT_EQ(emptyA, emptyB)
            << "cell " << cell << ", step " << step << ", offset " << offset;
          if (!emptyA)
          {
            ASSERT_EQ(a, b) << "cell " << cell << ", step " << step << ", offset " << offset;
          }
          ASSERT_EQ(derived.Near[cell], expected.Near[cell]);
          ASSERT_EQ(derived.Far[cell], expected.Far[cell]);
        }
        EXPECT_EQ(derived.Start, expected.Start);
        EXPECT_TRUE(derived.Cells == expected.Cells);
        compared += derived.Cells.empty() ? 0 : 1;
      }
    }
  }
  EXPECT_EQ(compared, 75); // every camera sees cells at every step
}

TEST(DecimatedBins, AreRefusedPastTheUndecimatedImage)
{
  std::mt19937 rng(12);
  const apc::CellMesh mesh = apctest::DistortedBlock(rng);
  const apc::RayCamera camera(
    { 0.2, 0.95, 4.0 }, { 0.0, 0.45, 0.0 }, { 0, 1, 0 }, 40.0, false, 1.0, 5, 40, 0.1, 20.0);
  apc::TileBins fine;
  apc::BinCells(&mesh, camera, 16, 1, fine);
  apc::TileBins derived;
  // 5 columns probed every 8th from 5: ProbeSize keeps one, past the image.
  EXPECT_FALSE(apc::DecimateBins(fine, 8, 5, 1, 5, 16, 1, derived));
  EXPECT_TRUE(apc::DecimateBins(fine, 8, 4, 1, 5, 16, 1, derived));
}

// The probe's marcher with the frame's bins decimated takes the samples a marcher binning the
// decimated camera itself takes: the same moments, profile and count, bit for bit.
TEST(DecimatedBins, TheProbeTakesTheSameSamples)
{
  std::mt19937 rng(13);
  const apc::CellMesh mesh = apctest::DistortedBlock(rng);
  const apc::TransferTable table(0.0, 1.0,
    { { 1.f, 0.f, 0.f }, { 0.f, 1.f, 0.f }, { 0.f, 0.f, 1.f } }, { 0.2, 0.9, 0.5 }, 0.05, 0.02);
  const apc::LogDepthWarp warp(2.0, 7.0);
  for (const apc::RayCamera& camera : Cameras())
  {
    apc::VolumeRayMarcher frame;
    frame.SetMesh(&mesh);
    frame.SetView(camera, nullptr);
    for (int step : { 2, 4 })
    {
      const int offset = step / 2;
      const apc::RayCamera coarse = camera.Decimated(step, offset);
      const size_t pixels = static_cast<size_t>(coarse.GetWidth()) * coarse.GetHeight();
      auto probe = [&](bool decimated, std::vector<double>& moments, std::vector<uint16_t>& profile)
      {
        apc::VolumeRayMarcher marcher;
        marcher.SetMesh(&mesh);
        marcher.SetOpaqueAbsorbance(apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
        marcher.SetMaxSampleCacheBytes(0);
        if (decimated)
        {
          marcher.SetDecimatedView(frame, step, offset, {});
        }
        else
        {
          marcher.SetView(coarse, nullptr);
        }
        moments.assign(pixels * 5, 0.0);
        marcher.AccumulateMoments<4>(table, warp, moments.data());
        const apc::VolumeRayMarcher::OpaqueProfile own = marcher.GetOpaqueProfile();
        profile.assign(own.data(), own.data() + own.size());
        return marcher.GetLastSampleCount();
      };
      std::vector<double> momentsA, momentsB;
      std::vector<uint16_t> profileA, profileB;
      const int64_t samplesA = probe(true, momentsA, profileA);
      const int64_t samplesB = probe(false, momentsB, profileB);
      EXPECT_GT(samplesA, 100);
      EXPECT_EQ(samplesA, samplesB);
      EXPECT_TRUE(momentsA == momentsB);
      EXPECT_TRUE(profileA == profileB);
    }
  }
}
