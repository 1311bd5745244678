// The sort-last segments of the core ray marcher (VolumeRayMarcher::RenderSegments), on which
// the exact distributed baseline (vtkAPCCompositePass SEGMENTS) rests:
// - blending the segments of all pieces of a split, sorted by their first lattice index,
//   gives the exact image of the whole mesh (puzzle pieces, jagged pieces that interleave in
//   depth, a transfer function with transparent ranges, rays stopped by opaque geometry);
// - the segments of different pieces never interleave along a ray;
// - on the gear teeth seen down the slab axis each piece has SlabsPerPiece segments per
//   pixel, K * SlabsPerPiece in all, and the whole grid one.

#include "apcTestGrids.h"
#include "apcTestImages.h"
#include "apcTestPuzzles.h"
#include "apcTestTransferFunctions.h"

#include "apcCellMesh.h"
#include "apcCellMeshFromVTK.h"
#include "apcRayCamera.h"
#include "apcSegmentTransfer.h"
#include "apcTransferTable.h"
#include "apcVolumeRayMarcher.h"

#include "vtkExtractCells.h"
#include "vtkIdList.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

namespace
{
struct SplitResult
{
  double MaxDiff = 0;
  double MaxAlpha = 0;
  int Interleaved = 0; // pixels where two pieces' k ranges overlap
  apc::SegmentStatistics Stats;
};

// Renders the whole mesh exactly and each piece's segments, merges the pieces' segments per
// pixel and blends them; rayEnds (or null) stops the rays.
SplitResult CompositeSplit(vtkUnstructuredGrid* whole,
  const std::vector<vtkSmartPointer<vtkUnstructuredGrid>>& pieceGrids, const apc::RayCamera& camera,
  bool transparentBelow, const float* rayEnds = nullptr)
{
  const apc::CellMesh wholeMesh = apctest::ToMesh(whole);
  const auto& b = wholeMesh.GetBounds();
  const double diagonal = std::sqrt(
    (b[1] - b[0]) * (b[1] - b[0]) + (b[3] - b[2]) * (b[3] - b[2]) + (b[5] - b[4]) * (b[5] - b[4]));
  const apc::TransferTable table = apctest::RampTable(diagonal / 300, transparentBelow);
  const int w = camera.GetWidth();
  const int h = camera.GetHeight();
  const size_t pixels = static_cast<size_t>(w) * h;

  std::vector<float> exact(4 * pixels, 0.f);
  apc::VolumeRayMarcher marcher;
  marcher.SetMesh(&wholeMesh);
  marcher.SetView(camera, rayEnds);
  marcher.RenderExact(table, exact.data());

  std::vector<std::vector<apc::RaySegment>> perPixel(pixels);
  for (const auto& grid : pieceGrids)
  {
    const apc::CellMesh mesh = apctest::ToMesh(grid);
    marcher.SetMesh(&mesh);
    marcher.SetView(camera, rayEnds);
    apc::SegmentImage segments;
    marcher.RenderSegments(table, segments);
    EXPECT_EQ(segments.Width, w);
    EXPECT_EQ(segments.Height, h);
    for (size_t p = 0; p < pixels; ++p)
    {
      for (int64_t s = segments.Offsets[p]; s < segments.Offsets[p + 1]; ++s)
      {
        const apc::RaySegment& seg = segments.Segments[s];
        EXPECT_LE(seg.KFirst, seg.KLast);
        EXPECT_LE(seg.Transmittance, 1.f);
        if (s > segments.Offsets[p])
        {
          // A piece's own runs are separated by at least one lattice point of another piece.
          EXPECT_GT(seg.KFirst, segments.Segments[s - 1].KLast + 1);
        }
        perPixel[p].push_back(seg);
      }
    }
  }

  // The merged lists as one image, as a strip owner holds them after the exchange.
  apc::SegmentImage merged;
  merged.Reset(w, h);
  SplitResult result;
  for (size_t p = 0; p < pixels; ++p)
  {
    auto& list = perPixel[p];
    std::sort(list.begin(), list.end(),
      [](const apc::RaySegment& x, const apc::RaySegment& y) { return x.KFirst < y.KFirst; });
    for (size_t s = 1; s < list.size(); ++s)
    {
      if (list[s].KFirst <= list[s - 1].KLast)
      {
        ++result.Interleaved;
        break;
      }
    }
    merged.Offsets[p + 1] = merged.Offsets[p] + static_cast<int64_t>(list.size());
    // Reversed, so that the compositor's own sort is exercised.
    merged.Segments.insert(merged.Segments.end(), list.rbegin(), list.rend());
  }
  result.Stats = apc::GetSegmentStatistics(merged);
  std::vector<float> composited(4 * pixels, 0.f);
  apc::CompositeSegmentImage(merged, composited.data());
  result.MaxDiff = apctest::MaxAbsDiff(exact, composited);
  result.MaxAlpha = apctest::MaxChannel(exact, 4, 3);
  return result;
}

// Each segment's colour and transmittance are rounded to float once and the blend runs in double,
// against the exact image's one rounding to float: a few float ulps of values <= 1. 1e-6 is that
// with room; a lost, duplicated or misordered run moves pixels by ~1e-3 or more.
constexpr double kBound = 1e-6;

void Report(const std::string& name, const SplitResult& r)
{
  std::cout << name << ": max |segments - exact| = " << r.MaxDiff << " (max alpha " << r.MaxAlpha
            << "), segments per non-empty pixel: mean " << r.Stats.Average() << ", max "
            << r.Stats.MaxPerPixel << " over " << r.Stats.NonEmptyPixels << " pixels\n";
  EXPECT_LE(r.MaxDiff, kBound) << name;
  EXPECT_GT(r.MaxAlpha, 0.2) << name << ": something visible";
  EXPECT_EQ(r.Interleaved, 0) << name << ": pieces' runs interleave";
}

std::vector<vtkSmartPointer<vtkUnstructuredGrid>> HashPieces(vtkUnstructuredGrid* grid, int k)
{
  return apctest::SplitCells(
    grid, k, [k](vtkIdType c) { return static_cast<int>(apctest::CellHash(c) % k); });
}

double Smooth(double x, double y, double z)
{
  return 0.5 + 0.45 * std::sin(2.1 * x + 0.4) * std::cos(1.7 * y - 0.3) * std::cos(1.3 * z + 0.2);
}

TEST(RaySegments, WholeMeshIsExact)
{
  auto grid = apctest::MixedBlock(8, Smooth);
  const SplitResult r = CompositeSplit(grid, { grid }, apctest::ObliqueCamera(64), true);
  Report("mixed block, one piece", r);
  // A convex mesh: at most one run per ray (fewer where a whole run is transparent).
  EXPECT_EQ(r.Stats.MaxPerPixel, 1);
}

TEST(RaySegments, PuzzlePiecesCompositeToExact)
{
  for (int field : { vtkAPCPuzzleSource::SPHERES, vtkAPCPuzzleSource::SMOOTH })
  {
    for (int k : { 2, 3, 5 })
    {
      auto whole = apctest::PuzzleGrid(field, k, 2, 12);
      std::vector<vtkSmartPointer<vtkUnstructuredGrid>> pieces;
      for (int p = 0; p < k; ++p)
      {
        pieces.push_back(apctest::PuzzlePiece(field, k, 2, 12, p));
      }
      for (bool transparent : { false, true })
      {
        Report("puzzle field " + std::to_string(field) + " K=" + std::to_string(k) +
            (transparent ? " (transparent below 0.2)" : ""),
          CompositeSplit(whole, pieces, apctest::ObliqueCamera(80), transparent));
      }
    }
  }
}

TEST(RaySegments, JaggedPiecesCompositeToExact)
{
  auto grid = apctest::MixedBlock(12, Smooth);
  for (int k : { 2, 3, 5 })
  {
    const SplitResult r =
      CompositeSplit(grid, HashPieces(grid, k), apctest::ObliqueCamera(80), true);
    Report("mixed block, cells hashed into " + std::to_string(k) + " pieces", r);
    EXPECT_GT(r.Stats.Average(), 3.0) << "hashed pieces must interleave along the rays";
  }
}

TEST(RaySegments, OpaqueGeometryStopsTheSegments)
{
  const int size = 64;
  const apc::RayCamera camera = apctest::ObliqueCamera(size);
  std::vector<float> rayEnds(size * size);
  for (int j = 0; j < size; ++j)
  {
    for (int i = 0; i < size; ++i)
    {
      // Rays end inside the data, at distances that vary across the image.
      rayEnds[j * size + i] = static_cast<float>(6.0 + 0.02 * (i - j));
    }
  }
  auto whole = apctest::PuzzleGrid(vtkAPCPuzzleSource::SMOOTH, 3, 2, 12);
  std::vector<vtkSmartPointer<vtkUnstructuredGrid>> pieces;
  for (int p = 0; p < 3; ++p)
  {
    pieces.push_back(apctest::PuzzlePiece(vtkAPCPuzzleSource::SMOOTH, 3, 2, 12, p));
  }
  const SplitResult stopped = CompositeSplit(whole, pieces, camera, false, rayEnds.data());
  Report("puzzle K=3, rays stopped inside the data", stopped);
  const SplitResult free = CompositeSplit(whole, pieces, camera, false);
  EXPECT_LT(stopped.Stats.Segments, free.Stats.Segments) << "the ray ends must cut segments";
}

// Gear teeth seen along the slab axis (parallel, looking down -z, every ray through all
// slabs): each piece's SlabsPerPiece slabs are separated by the other pieces' slabs, each
// thicker than the sample spacing, so every pixel has exactly SlabsPerPiece runs per piece,
// K * SlabsPerPiece in all. Integer counts: exact. So are the transfers of direct send and
// binary swap (apc::CountSegmentTransfer).
TEST(RaySegments, GearTeethSegmentCounts)
{
  const int size = 24;
  const int slabs = 3;
  const apc::RayCamera camera(
    { 0, 0, 5 }, { 0, 0, 0 }, { 0, 1, 0 }, 30.0, true, 0.9, size, size, 0.1, 100.0);
  const apc::TransferTable table = apctest::RampTable(0.01, false);
  for (int k : { 1, 2, 3, 4, 5 })
  {
    apc::VolumeRayMarcher marcher;
    int64_t total = 0;
    std::vector<apc::SegmentImage> images(k);
    for (int p = 0; p < k; ++p)
    {
      auto grid = apctest::PuzzlePiece(vtkAPCPuzzleSource::SANDWICH, k, slabs, 4, p);
      const apc::CellMesh mesh = apctest::ToMesh(grid);
      marcher.SetMesh(&mesh);
      marcher.SetView(camera, nullptr);
      apc::SegmentImage& segments = images[p];
      marcher.RenderSegments(table, segments);
      const apc::SegmentStatistics stats = apc::GetSegmentStatistics(segments);
      // One piece alone is one run per pixel: its slabs touch.
      const int64_t expected = k == 1 ? 1 : slabs;
      EXPECT_EQ(stats.NonEmptyPixels, size * size) << "K=" << k << " piece " << p;
      EXPECT_EQ(stats.Segments, expected * size * size) << "K=" << k << " piece " << p;
      EXPECT_EQ(stats.MaxPerPixel, expected) << "K=" << k << " piece " << p;
      total += stats.Segments;
    }
    std::cout << "gear teeth K=" << k << ", " << slabs
              << " slabs per piece: " << static_cast<double>(total) / (size * size)
              << " segments per pixel\n";
    EXPECT_EQ(total, (k == 1 ? 1 : k * slabs) * size * size) << "K=" << k;

    // Exchanging them: the owner's own runs stay (direct send); binary swap merges the touching
    // slabs of consecutive pieces, so each block of 2^r pieces still sends `slabs` runs.
    std::vector<const apc::SegmentImage*> ranks;
    for (const auto& image : images)
    {
      ranks.push_back(&image);
    }
    const apc::SegmentTransferCounts transfer = apc::CountSegmentTransfer(ranks);
    const int64_t pixels = size * size;
    EXPECT_EQ(transfer.NonEmptyPixels, pixels);
    EXPECT_EQ(transfer.DirectSend, (k == 1 ? 0 : slabs * (k - 1)) * pixels) << "K=" << k;
    if (k == 2 || k == 4)
    {
      const int64_t log2k = k == 2 ? 1 : 2;
      EXPECT_EQ(transfer.BinarySwap, slabs * (k - 1) * pixels) << "K=" << k;
      EXPECT_EQ(transfer.BinarySwapUnmerged, slabs * k * log2k / 2 * pixels) << "K=" << k;
    }
  }
}
}
