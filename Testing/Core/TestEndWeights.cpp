// The end weights (apcEndWeights.h, VolumeRayMarcher::SetSampleEndWeights): a (cell, ray)
// pair's weights sum to its length over the spacing, two pairs meeting at a shared face weigh
// 2 there, a pair without a lattice point gets one sample of its own length; and on a slab of
// constant absorbance seen at a grazing angle every ray's optical depth is sigma times its
// exact length inside in pass 1's moments (the exact blend keeps the plain lattice), and the
// same for the slab cut into two meshes (two ranks), also at the opaque cut and in pass 2 from
// the cache. Without the weights the lattice misses up to one sample
// per boundary crossing (the silhouette's staircase), which the last test checks is the case.
#include "apcCellMesh.h"
#include "apcDepthWarp.h"
#include "apcEndWeights.h"
#include "apcOpaqueBins.h"
#include "apcRayCamera.h"
#include "apcTestBlock.h"
#include "apcTestEndWeights.h"
#include "apcTransferTable.h"
#include "apcVolumeRayMarcher.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <vector>

namespace
{

using apc::walk::EndWeights;
using apc::walk::EndWeightsOf;
using apc::walk::Lattice;

using apctest::Sum;

TEST(EndWeights, SumToTheLengthAndToTwoAcrossASharedFace)
{
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (double offset : { 0.0, 0.37 })
  {
    const Lattice lattice(0.013);
    int mids = 0;
    for (int i = 0; i < 20000; ++i)
    {
      const double tin = 1.0 + 3.0 * u(rng);
      const double length = 0.05 * u(rng) * u(rng); // many pairs shorter than the spacing
      const double tout = tin + length;
      if (!(tin < tout))
      {
        continue;
      }
      const EndWeights w = EndWeightsOf(lattice, tin, tout, offset);
      EXPECT_NEAR(Sum(w), length / lattice.Spacing, 1e-9);
      if (w.Mid)
      {
        // No lattice point inside: one sample at the middle, counted as the point before.
        ++mids;
        EXPECT_GT(w.MidT, tin);
        EXPECT_LT(w.MidT, tout);
        EXPECT_LT(lattice.At(w.First, offset), tin);
        EXPECT_GE(lattice.At(w.First + 1, offset), tout);
        EXPECT_NEAR(w.MidWeight, (tout - tin) / lattice.Spacing, 1e-12);
        continue;
      }
      EXPECT_GE(lattice.At(w.First, offset), tin);
      EXPECT_LT(lattice.At(w.First - 1, offset), tin);
      EXPECT_LT(lattice.At(w.Last, offset), tout);
      EXPECT_GE(lattice.At(w.Last + 1, offset), tout);
      // The pair [tout, tout + 0.02) behind it shares the face at tout.
      const EndWeights next = EndWeightsOf(lattice, tout, tout + 0.02, offset);
      ASSERT_FALSE(next.Mid);
      ASSERT_EQ(next.First, w.Last + 1);
      if (w.First < w.Last && next.First < next.Last)
      {
        EXPECT_NEAR(w.LastWeight + next.FirstWeight, 2.0, 1e-9);
      }
    }
    EXPECT_GT(mids, 1000); // the sample-less pairs were tried
  }
}

// A slab of hexahedra, [-1, 1] x [-0.5, 0.5] x [-1, 1] in cells of 0.25, constant point
// scalars; with parts = 2 only the cells of one of two interleaved parts (part).
constexpr int kNx = 8, kNy = 4, kNz = 8;
constexpr double kH = 0.25;
constexpr double kLo[3] = { -1.0, -0.5, -1.0 };
constexpr double kHi[3] = { 1.0, 0.5, 1.0 };

apc::CellMesh Slab(int part, int parts)
{
  apc::CellMesh mesh;
  for (int k = 0; k <= kNz; ++k)
  {
    for (int j = 0; j <= kNy; ++j)
    {
      for (int i = 0; i <= kNx; ++i)
      {
        mesh.Points.push_back({ kLo[0] + i * kH, kLo[1] + j * kH, kLo[2] + k * kH });
        mesh.PointScalars.push_back(0.5f);
      }
    }
  }
  auto id = [](int i, int j, int k)
  { return static_cast<int64_t>((k * (kNy + 1) + j) * (kNx + 1) + i); };
  for (int k = 0; k < kNz; ++k)
  {
    for (int j = 0; j < kNy; ++j)
    {
      for (int i = 0; i < kNx; ++i)
      {
        if (parts > 1 && (i + j + k) % parts != part)
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

constexpr int kSize = 64;
constexpr double kSpacing = 0.1;

// Looking down at the slab's top face (y = 0.5) at about 7 degrees: its rays graze it.
apc::RayCamera Camera()
{
  return apc::RayCamera(
    { 0.2, 0.95, 4.0 }, { 0.0, 0.45, 0.0 }, { 0, 1, 0 }, 40.0, false, 1.0, kSize, kSize, 0.1, 20.0);
}

// The ray's exact length inside the slab (t >= 0).
double LengthInside(const apc::Ray& ray)
{
  double tin = 0;
  double tout = std::numeric_limits<double>::infinity();
  for (int d = 0; d < 3; ++d)
  {
    const double a = (kLo[d] - ray.Origin[d]) / ray.Direction[d];
    const double b = (kHi[d] - ray.Origin[d]) / ray.Direction[d];
    tin = std::max(tin, std::min(a, b));
    tout = std::min(tout, std::max(a, b));
  }
  return std::max(0.0, tout - tin);
}

struct Depths
{
  std::vector<double> Moments;     // pass 1's b0 per pixel: the summed absorbance
  std::vector<double> ExactDepths; // -ln(1 - alpha) of the exact blend per pixel
  std::vector<double> Expected;    // sigma times the length inside
  double SampleAbsorbance = 0;     // of one unweighted sample: sigma times the spacing
  std::vector<double> Colour;      // pass 2's colour sums (4 per pixel)
  int64_t Pass2Samples = 0;
  double CacheShare = 0; // of pass 2's samples replayed from the cache (the last mesh's)
};

// stop: the opaque stop at a denser slab, with the cut agreed from every mesh's profile
// (as vtkAPCCompositePass does); the moments are then those left after the cut. cache: pass 2
// replays pass 1's cached samples (else it marches again).
Depths Render(bool weights, int parts, bool stop = false, bool cache = true)
{
  const apc::TransferTable table(
    0.0, 1.0, { { 1.f, 1.f, 1.f }, { 1.f, 1.f, 1.f } }, { 0.4, 0.4 }, kSpacing, stop ? 0.03 : 1.0);
  const apc::RayCamera camera = Camera();
  const double sigma = table.Lookup(0.5).Absorbance / kSpacing; // per unit length
  const apc::LogDepthWarp warp(2.0, 7.0);
  const size_t pixels = static_cast<size_t>(kSize) * kSize;
  Depths out;
  out.SampleAbsorbance = table.Lookup(0.5).Absorbance;
  out.Moments.assign(pixels, 0.0);
  std::vector<double> moments(pixels * 5, 0.0);
  std::vector<float> rgba(pixels * 4, 0.f);
  std::vector<apc::CellMesh> meshes;
  for (int part = 0; part < parts; ++part)
  {
    meshes.push_back(Slab(part, parts));
  }
  std::vector<std::unique_ptr<apc::VolumeRayMarcher>> marchers;
  std::vector<std::vector<double>> own;
  std::vector<uint16_t> profile(pixels * apc::OpaqueBins::kBins, 0);
  for (const apc::CellMesh& mesh : meshes)
  {
    marchers.push_back(std::make_unique<apc::VolumeRayMarcher>());
    apc::VolumeRayMarcher& marcher = *marchers.back();
    marcher.SetMesh(&mesh);
    marcher.SetView(camera, nullptr);
    marcher.SetSampleEndWeights(weights);
    marcher.SetMaxSampleCacheBytes(cache ? size_t(1) << 30 : 0);
    if (stop)
    {
      marcher.SetOpaqueAbsorbance(apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
    }
    own.emplace_back(pixels * 5, 0.0);
    marcher.AccumulateMoments<4>(table, warp, own.back().data());
    if (stop)
    {
      EXPECT_EQ(marcher.GetOpaqueProfile().size(), profile.size());
      apc::AddProfiles(profile.data(), marcher.GetOpaqueProfile().data(), profile.size());
    }
    if (parts == 1 && !stop)
    {
      marcher.RenderExact(table, rgba.data());
    }
  }
  for (size_t m = 0; m < marchers.size(); ++m)
  {
    if (stop)
    {
      marchers[m]->ApplyOpaqueCut<4>(table, warp, profile.data(), own[m].data());
    }
    for (size_t v = 0; v < moments.size(); ++v)
    {
      moments[v] += own[m][v];
    }
  }
  out.Colour.assign(pixels * 4, 0.0);
  for (auto& marcher : marchers)
  {
    marcher->AccumulateColour<4>(
      table, warp, moments.data(), apc::MomentSettings<4>(), out.Colour.data());
    out.Pass2Samples += marcher->GetLastSampleCount();
    out.CacheShare = marcher->GetLastColourCacheShare();
  }
  for (size_t p = 0; p < pixels; ++p)
  {
    out.Moments[p] = moments[5 * p];
    out.ExactDepths.push_back(-std::log1p(-static_cast<double>(rgba[4 * p + 3])));
    const int i = static_cast<int>(p % kSize);
    const int j = static_cast<int>(p / kSize);
    out.Expected.push_back(sigma * LengthInside(camera.PixelRay(i, j)));
  }
  return out;
}

TEST(EndWeights, GrazingSlabHasTheExactOpticalDepth)
{
  const Depths d = Render(true, 1);
  const Depths plain = Render(false, 1);
  int inside = 0;
  for (size_t p = 0; p < d.Expected.size(); ++p)
  {
    inside += d.Expected[p] > 0 ? 1 : 0;
    // Each weighted absorbance is rounded to float once: a few 1e-8 of the depth.
    EXPECT_NEAR(d.Moments[p], d.Expected[p], 1e-6 * d.Expected[p] + 1e-12) << "pixel " << p;
    // The exact blend keeps the plain lattice (visitors::PixelSampleLists): the same as
    // without the weights (a float opacity).
    EXPECT_NEAR(d.ExactDepths[p], plain.ExactDepths[p], 1e-6 * (1 + d.Expected[p]))
      << "pixel " << p;
  }
  EXPECT_GT(inside, 1000);
}

TEST(EndWeights, TwoMeshesSumWhatOneSums)
{
  const Depths one = Render(true, 1);
  const Depths two = Render(true, 2);
  for (size_t p = 0; p < one.Moments.size(); ++p)
  {
    // The same weighted samples, summed in another order.
    EXPECT_NEAR(two.Moments[p], one.Moments[p], 1e-12 * (1 + one.Moments[p])) << "pixel " << p;
  }
}

TEST(EndWeights, TwoMeshesKeepWhatOneKeepsAtTheOpaqueCut)
{
  // Where the stop cuts a pair, its samples keep the whole pair's weights: one mesh and two
  // interleaved ones (each stopping at its own samples first) keep the same weighted samples.
  const Depths one = Render(true, 1, true);
  const Depths two = Render(true, 2, true);
  int cut = 0;
  for (size_t p = 0; p < one.Moments.size(); ++p)
  {
    EXPECT_NEAR(two.Moments[p], one.Moments[p], 1e-12 * (1 + one.Moments[p])) << "pixel " << p;
    // Unstopped rays keep their exact depth; stopped ones keep at least the threshold.
    if (one.Expected[p] < 0.9 * apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance)
    {
      EXPECT_NEAR(one.Moments[p], one.Expected[p], 1e-6 * one.Expected[p] + 1e-12);
    }
    else if (one.Moments[p] < one.Expected[p] - 1.0)
    {
      ++cut;
      EXPECT_GE(one.Moments[p], 0.99 * apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
    }
  }
  EXPECT_GT(cut, 100); // the stop cut rays
}

TEST(EndWeights, PassTwoReplaysWhatItWouldMarch)
{
  // The cache keeps each sample's weight: pass 2 from the cache takes the samples and
  // weighted absorbances a pass 2 marching again takes, with and without the opaque cut
  // (which drops cached samples and their weights). The sums differ by the cache's float
  // depths (about 1e-9 here), by their order and FMA rounding; an unweighted replay would
  // differ by the weights themselves (up to a half of a sample's opacity).
  for (bool stop : { false, true })
  {
    const Depths replayed = Render(true, 2, stop, true);
    const Depths marched = Render(true, 2, stop, false);
    EXPECT_EQ(replayed.CacheShare, 1.0);
    EXPECT_EQ(marched.CacheShare, 0.0);
    EXPECT_EQ(replayed.Pass2Samples, marched.Pass2Samples);
    for (size_t v = 0; v < replayed.Colour.size(); ++v)
    {
      EXPECT_NEAR(replayed.Colour[v], marched.Colour[v], 1e-9 + 1e-6 * marched.Colour[v])
        << "value " << v << (stop ? " with the stop" : "");
    }
  }
}

TEST(EndWeights, WithoutThemTheLatticeMissesUpToASample)
{
  // The scene is one where the weights matter: the plain lattice's depth is off by up to
  // sigma times the spacing (a staircase along the grazing face).
  const Depths d = Render(false, 1);
  double worst = 0;
  for (size_t p = 0; p < d.Expected.size(); ++p)
  {
    worst = std::max(worst, std::abs(d.Moments[p] - d.Expected[p]));
  }
  EXPECT_GT(worst, 0.5 * d.SampleAbsorbance);
}

using Frame = apctest::BlockFrame;

using Mode = apc::VolumeRayMarcher::EndWeightsMode;

Frame RenderBlock(const apc::CellMesh& mesh, bool lanes, Mode weights, bool stop, double spacing)
{
  const apc::TransferTable table(0.0, 1.0,
    { { 1.f, 0.f, 0.f }, { 0.f, 1.f, 0.f }, { 0.f, 0.f, 1.f }, { 1.f, 1.f, 0.f } },
    { 0.05, 0.6, 0.0, 0.9 }, spacing, stop ? 0.02 : 1.0);
  return apctest::RenderBlockFrame(mesh, table, Camera(), static_cast<size_t>(kSize) * kSize, stop,
    [&](apc::VolumeRayMarcher& marcher)
    {
      marcher.SetEndWeightsMode(weights);
      marcher.SetSampleLanes(lanes);
    });
}

TEST(EndWeights, LanesTakeTheScalarLoopsWeightedSamples)
{
  // The lanes' hand-over weights each pair's first and last step and sends pairs without a
  // lattice point to the scalar loop: pass 1's moments, the opaque profile and cut, and
  // pass 2 from the cache (its records and weights) equal the scalar loop's bit for bit. At
  // the finer spacing pairs hold more than a call's kLaneSteps samples.
  std::mt19937 rng(11);
  for (int mesh = 0; mesh < 4; ++mesh)
  {
    const apc::CellMesh block = apctest::DistortedBlock(rng);
    const double spacing = mesh < 2 ? kSpacing : kSpacing / 5;
    for (bool stop : { false, true })
    {
      const Frame lanes = RenderBlock(block, true, Mode::All, stop, spacing);
      const Frame scalar = RenderBlock(block, false, Mode::All, stop, spacing);
      const Frame plain = RenderBlock(block, true, Mode::Off, stop, spacing);
      EXPECT_GT(lanes.Pass1Samples, plain.Pass1Samples); // middle samples were taken
      EXPECT_EQ(lanes.Pass1Samples, scalar.Pass1Samples);
      EXPECT_EQ(lanes.Pass2Samples, scalar.Pass2Samples);
      EXPECT_TRUE(lanes.Profile == scalar.Profile);
      int differ = 0;
      for (size_t v = 0; v < lanes.Moments.size(); ++v)
      {
        differ += lanes.Moments[v] != scalar.Moments[v] ? 1 : 0;
      }
      for (size_t v = 0; v < lanes.Colour.size(); ++v)
      {
        differ += lanes.Colour[v] != scalar.Colour[v] ? 1 : 0;
      }
      EXPECT_EQ(differ, 0) << "mesh " << mesh << (stop ? " with the stop" : "");
      EXPECT_GT(lanes.Moments[5 * (kSize * kSize / 2 + kSize / 2)], 0.0);
    }
  }
}

TEST(EndWeights, BoundaryCellsInTheLanesTakeTheScalarLoopsSamples)
{
  // Boundary: the cells with a boundary face go through the lanes (their pairs' weights
  // found ray by ray, the pairs with a weighted end, plain ends, middle samples and dropped
  // slivers mixed in one cell) and give what the scalar weighted loop gives, bit for bit:
  // pass 1's moments, the opaque profile and cut, pass 2 from the cache.
  std::mt19937 rng(23);
  for (int mesh = 0; mesh < 4; ++mesh)
  {
    apc::CellMesh block = apctest::DistortedBlock(rng);
    block.FindBoundaryPlanes();
    const double spacing = mesh < 2 ? kSpacing : kSpacing / 5;
    for (bool stop : { false, true })
    {
      const Frame lanes = RenderBlock(block, true, Mode::Boundary, stop, spacing);
      const Frame scalar = RenderBlock(block, false, Mode::Boundary, stop, spacing);
      const Frame plain = RenderBlock(block, true, Mode::Off, stop, spacing);
      const Frame all = RenderBlock(block, true, Mode::All, stop, spacing);
      // Boundary's samples are neither the plain lattice's nor All's.
      EXPECT_NE(lanes.Pass1Samples, plain.Pass1Samples);
      EXPECT_LT(lanes.Pass1Samples, all.Pass1Samples);
      EXPECT_EQ(lanes.Pass1Samples, scalar.Pass1Samples);
      EXPECT_EQ(lanes.Pass2Samples, scalar.Pass2Samples);
      EXPECT_TRUE(lanes.Profile == scalar.Profile);
      int differ = 0;
      for (size_t v = 0; v < lanes.Moments.size(); ++v)
      {
        differ += lanes.Moments[v] != scalar.Moments[v] ? 1 : 0;
      }
      for (size_t v = 0; v < lanes.Colour.size(); ++v)
      {
        differ += lanes.Colour[v] != scalar.Colour[v] ? 1 : 0;
      }
      EXPECT_EQ(differ, 0) << "mesh " << mesh << (stop ? " with the stop" : "");
      EXPECT_GT(lanes.Moments[5 * (kSize * kSize / 2 + kSize / 2)], 0.0);
    }
  }
}

TEST(EndWeights, BoundaryCellsInTheLanesHoldingTheEyeTakeTheScalarLoopsSamples)
{
  // Boundary with the eye inside the mesh: the pairs of the cell that holds it start at
  // t = 0, weighted there (BoundaryPairWeights), in the lanes as in the scalar loop, though
  // the cell may have no boundary face; the lanes' shortcut for pairs with plain ends must not
  // take them.
  std::mt19937 rng(31);
  int differentFromPlain = 0;
  for (int mesh = 0; mesh < 4; ++mesh)
  {
    apc::CellMesh block = apctest::DistortedBlock(rng);
    block.FindBoundaryPlanes();
    const double spacing = mesh < 2 ? kSpacing : kSpacing / 5;
    // Eyes in cells of the middle (no boundary face) and near the side, looking across.
    const double eye[2][3] = { { 0.13, 0.07, 0.41 }, { -0.62, -0.09, 0.33 } };
    for (const auto& e : eye)
    {
      const apc::RayCamera camera({ e[0], e[1], e[2] }, { e[0] + 0.3, e[1] - 0.1, e[2] - 2.0 },
        { 0, 1, 0 }, 60.0, false, 1.0, kSize, kSize, 0.01, 20.0);
      const apc::TransferTable table(0.0, 1.0,
        { { 1.f, 0.f, 0.f }, { 0.f, 1.f, 0.f }, { 0.f, 0.f, 1.f }, { 1.f, 1.f, 0.f } },
        { 0.05, 0.6, 0.0, 0.9 }, spacing, 1.0);
      auto render = [&](bool lanes, Mode weights)
      {
        return apctest::RenderBlockFrame(block, table, camera, static_cast<size_t>(kSize) * kSize,
          false,
          [&](apc::VolumeRayMarcher& marcher)
          {
            marcher.SetEndWeightsMode(weights);
            marcher.SetSampleLanes(lanes);
          });
      };
      const auto lanes = render(true, Mode::Boundary);
      const auto scalar = render(false, Mode::Boundary);
      const auto plain = render(true, Mode::Off);
      EXPECT_EQ(lanes.Pass1Samples, scalar.Pass1Samples);
      int differ = 0;
      int fromPlain = 0;
      for (size_t v = 0; v < lanes.Moments.size(); ++v)
      {
        differ += lanes.Moments[v] != scalar.Moments[v] ? 1 : 0;
        fromPlain += lanes.Moments[v] != plain.Moments[v] ? 1 : 0;
      }
      for (size_t v = 0; v < lanes.Colour.size(); ++v)
      {
        differ += lanes.Colour[v] != scalar.Colour[v] ? 1 : 0;
      }
      EXPECT_EQ(differ, 0) << "mesh " << mesh << " eye " << e[0];
      differentFromPlain += fromPlain > 0 ? 1 : 0;
    }
  }
  // The eye's weighted start shows: Boundary is not the plain lattice here.
  EXPECT_EQ(differentFromPlain, 8);
}

} // namespace
