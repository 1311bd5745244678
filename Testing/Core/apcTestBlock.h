// A block of distorted hexahedra and twisted pyramids shared by the marcher tests that compare
// the lanes with the scalar loop (TestEndWeights, TestLaneMoments), and the frame they render
// of it.
#ifndef apcTestBlock_h
#define apcTestBlock_h

#include "apcCellMesh.h"
#include "apcDepthWarp.h"
#include "apcMomentTransmittance.h"
#include "apcRayCamera.h"
#include "apcTransferTable.h"
#include "apcVolumeRayMarcher.h"

#include <gtest/gtest.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <random>
#include <vector>

namespace apctest
{

// 8 x 4 x 8 hexahedra of edge 0.25 from (-1, -0.5, -1), every corner moved by up to 15 % of an
// edge, and in every other cell six pyramids about the cell's centre instead (their bases the
// hexahedron's faces, so some twisted: the lanes' closed form); random point scalars.
inline apc::CellMesh DistortedBlock(std::mt19937& rng)
{
  constexpr int kNx = 8, kNy = 4, kNz = 8;
  constexpr double kH = 0.25;
  constexpr double kLo[3] = { -1.0, -0.5, -1.0 };
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> value(0.0, 1.0);
  apc::CellMesh mesh;
  for (int k = 0; k <= kNz; ++k)
  {
    for (int j = 0; j <= kNy; ++j)
    {
      for (int i = 0; i <= kNx; ++i)
      {
        mesh.Points.push_back({ kLo[0] + i * kH + 0.15 * kH * u(rng),
          kLo[1] + j * kH + 0.15 * kH * u(rng), kLo[2] + k * kH + 0.15 * kH * u(rng) });
        mesh.PointScalars.push_back(static_cast<float>(value(rng)));
      }
    }
  }
  auto id = [](int i, int j, int k)
  { return static_cast<int64_t>((k * (kNy + 1) + j) * (kNx + 1) + i); };
  constexpr int kFaces[6][4] = { { 0, 1, 2, 3 }, { 4, 5, 6, 7 }, { 0, 1, 5, 4 }, { 1, 2, 6, 5 },
    { 2, 3, 7, 6 }, { 3, 0, 4, 7 } };
  for (int k = 0; k < kNz; ++k)
  {
    for (int j = 0; j < kNy; ++j)
    {
      for (int i = 0; i < kNx; ++i)
      {
        const int64_t ids[8] = { id(i, j, k), id(i + 1, j, k), id(i + 1, j + 1, k), id(i, j + 1, k),
          id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1) };
        if ((i + j + k) % 2 == 0)
        {
          mesh.AddCell(apc::CellShape::Hexahedron, ids);
          continue;
        }
        std::array<double, 3> centre = { 0, 0, 0 };
        for (int64_t p : ids)
        {
          for (int d = 0; d < 3; ++d)
          {
            centre[d] += mesh.Points[p][d] / 8;
          }
        }
        const int64_t apex = static_cast<int64_t>(mesh.Points.size());
        mesh.Points.push_back(centre);
        mesh.PointScalars.push_back(static_cast<float>(value(rng)));
        for (const auto& face : kFaces)
        {
          // The base's normal (right-handed) towards the apex, as VTK's pyramid has it.
          const auto& p0 = mesh.Points[ids[face[0]]];
          const auto& p1 = mesh.Points[ids[face[1]]];
          const auto& p3 = mesh.Points[ids[face[3]]];
          const double a[3] = { p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2] };
          const double b[3] = { p3[0] - p0[0], p3[1] - p0[1], p3[2] - p0[2] };
          const double n[3] = { a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0] };
          const double towards =
            n[0] * (centre[0] - p0[0]) + n[1] * (centre[1] - p0[1]) + n[2] * (centre[2] - p0[2]);
          int64_t pyramid[5];
          for (int c = 0; c < 4; ++c)
          {
            pyramid[c] = ids[face[towards > 0 ? c : 3 - c]];
          }
          pyramid[4] = apex;
          mesh.AddCell(apc::CellShape::Pyramid, pyramid);
        }
      }
    }
  }
  EXPECT_TRUE(mesh.Finalize());
  return mesh;
}

// What a frame of the marcher leaves to compare: pass 1's moments (after the cut with the
// stop), the opaque profile, pass 2's colour from the cache and both passes' sample counts.
struct BlockFrame
{
  std::vector<double> Moments;
  std::vector<uint16_t> Profile;
  std::vector<double> Colour;
  int64_t Pass1Samples = 0;
  int64_t Pass2Samples = 0;
};

// Renders mesh as a frame does, 4 moments, the cache on (pass 2 must replay it all), with the
// opaque stop where stop is set; configure sets what the test compares (lanes, jitter, weights).
inline BlockFrame RenderBlockFrame(const apc::CellMesh& mesh, const apc::TransferTable& table,
  const apc::RayCamera& camera, size_t pixels, bool stop,
  const std::function<void(apc::VolumeRayMarcher&)>& configure)
{
  const apc::LogDepthWarp warp(2.0, 7.0);
  apc::VolumeRayMarcher marcher;
  marcher.SetMesh(&mesh);
  marcher.SetView(camera, nullptr);
  configure(marcher);
  marcher.SetMaxSampleCacheBytes(size_t(1) << 30);
  if (stop)
  {
    marcher.SetOpaqueAbsorbance(apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
  }
  BlockFrame out;
  out.Moments.assign(pixels * 5, 0.0);
  marcher.AccumulateMoments<4>(table, warp, out.Moments.data());
  out.Pass1Samples = marcher.GetLastSampleCount();
  if (stop)
  {
    const apc::VolumeRayMarcher::OpaqueProfile profile = marcher.GetOpaqueProfile();
    out.Profile.assign(profile.data(), profile.data() + profile.size());
    std::vector<double> own = out.Moments;
    marcher.ApplyOpaqueCut<4>(table, warp, out.Profile.data(), own.data());
    out.Moments = own;
  }
  out.Colour.assign(pixels * 4, 0.0);
  marcher.AccumulateColour<4>(
    table, warp, out.Moments.data(), apc::MomentSettings<4>(), out.Colour.data());
  out.Pass2Samples = marcher.GetLastSampleCount();
  EXPECT_EQ(marcher.GetLastColourCacheShare(), 1.0);
  return out;
}

} // namespace apctest

#endif
