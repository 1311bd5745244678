// The rows of a cell's rectangle cut to the octagon of its planes' polytope (apcCellSpan.h):
// no ray the full-row clip keeps may lie outside it, on random distorted cells (warped faces,
// twisted pyramids), seen from near, far, grazing along a face and from inside.
#include "apcCellMesh.h"
#include "apcCellShapeCheck.h"
#include "apcCellSpan.h"
#include "apcRayCamera.h"
#include "apcRayWalk.h"
#include "apcTestCells.h"
#include "apcTileBins.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

namespace
{

using apc::CellShape;

struct Counts
{
  long long Kept = 0;      // rays of the rectangles the clip keeps
  long long Outside = 0;   // of those, outside their row's span (must stay 0)
  long long Skipped = 0;   // rays of the rectangles the spans leave out
  long long Bounded = 0;   // cells (views) with a bound
  long long Unbounded = 0; // cells (views) without one
};

// One cell of shape, distorted by up to distortion, seen by views random cameras; every ray
// of its rectangle clipped against its planes as the walker's full rows do.
void CheckCell(CellShape shape, double distortion, std::mt19937& rng, int views, Counts& counts)
{
  const apc::CellCorners cell = apctest::DistortedCell(shape, distortion, rng);
  apc::CellMesh mesh;
  const int n = apc::NumberOfCorners(shape);
  int64_t ids[8];
  double centre[3] = { 0, 0, 0 };
  for (int c = 0; c < n; ++c)
  {
    mesh.Points.push_back(cell.X[c]);
    mesh.PointScalars.push_back(static_cast<float>(cell.S[c]));
    ids[c] = c;
    for (int d = 0; d < 3; ++d)
    {
      centre[d] += cell.X[c][d] / n;
    }
  }
  mesh.AddCell(shape, ids);
  ASSERT_TRUE(mesh.Finalize());
  int count = 0;
  const apc::FacePlane* planes = mesh.GetPlanes(0, count);
  if (count == 0)
  {
    return; // left out as flat
  }
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int view = 0; view < views; ++view)
  {
    // A direction from the centre: at 0.3 to 30 cell sizes, or along a face's plane
    // (grazing), or from inside the cell.
    std::array<double, 3> eye;
    const int kind = view % 4;
    std::array<double, 3> dir = { u(rng), u(rng), u(rng) };
    const double length = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    const double distance = kind == 3 ? 0.3 * unit(rng) : 0.5 + 30.0 * std::pow(unit(rng), 2);
    for (int d = 0; d < 3; ++d)
    {
      eye[d] = centre[d] + dir[d] / length * distance;
    }
    if (kind == 2)
    {
      // Into the plane of a random face: the eye on it, the face seen edge-on.
      const apc::FacePlane& f = planes[rng() % count];
      const double nn[3] = { f.Normal[0], f.Normal[1], f.Normal[2] };
      const double side = nn[0] * eye[0] + nn[1] * eye[1] + nn[2] * eye[2] - f.Offset;
      const double norm2 = nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2];
      for (int d = 0; d < 3; ++d)
      {
        eye[d] -= side * nn[d] / norm2;
      }
    }
    const std::array<double, 3> focal = { centre[0] + 0.3 * u(rng), centre[1] + 0.3 * u(rng),
      centre[2] + 0.3 * u(rng) };
    const int size = 96;
    const apc::RayCamera camera(eye, focal, { u(rng), u(rng), 1.0 }, 20.0 + 60.0 * unit(rng), false,
      1.0, size, size, 0.1, 1000);
    apc::TileBins bins;
    apc::BinCells(&mesh, camera, 16, 1, bins);
    ASSERT_EQ(bins.Diagonals.size(), 1u);
    const auto& r = bins.Rects[0];
    const apc::CellDiagonals& diagonals = bins.Diagonals[0];
    const bool bounded = diagonals.U0 != apc::kNoDiagonals.U0;
    ++(bounded ? counts.Bounded : counts.Unbounded);
    apc::walk::CellPlanes clip;
    for (int j = r[1]; j <= r[3]; ++j)
    {
      int lo = r[0];
      int hi = r[2];
      if (bounded)
      {
        apc::RowOf(diagonals, j, lo, hi);
      }
      for (int i = r[0]; i <= r[2]; ++i)
      {
        const apc::Ray ray = camera.PixelRay(i, j);
        const apc::walk::RaySetup setup{ { ray.Origin[0], ray.Origin[1], ray.Origin[2] },
          { ray.Direction[0], ray.Direction[1], ray.Direction[2] }, 1e9, 0.0 };
        clip.Set(planes, count, setup, true);
        double tin = 0;
        double tout = setup.End;
        clip.Clip(setup, tin, tout);
        const bool inSpan = lo <= i && i <= hi;
        counts.Skipped += inSpan ? 0 : 1;
        if (tin < tout)
        {
          ++counts.Kept;
          counts.Outside += inSpan ? 0 : 1;
          EXPECT_TRUE(inSpan) << "shape " << n << " view " << view << " kind " << kind << " pixel "
                              << i << "," << j << " span " << lo << ".." << hi;
        }
      }
    }
  }
}

} // namespace

TEST(CellSpan, NoRayTheClipKeepsLiesOutsideItsRow)
{
  std::mt19937 rng(2026);
  for (CellShape shape :
    { CellShape::Hexahedron, CellShape::Tetra, CellShape::Wedge, CellShape::Pyramid })
  {
    Counts counts;
    for (int c = 0; c < 60; ++c)
    {
      const double distortion = (c % 3) * 0.12; // planar to strongly warped faces
      CheckCell(shape, distortion, rng, 8, counts);
    }
    EXPECT_EQ(counts.Outside, 0) << "shape " << static_cast<int>(shape);
    // Not vacuous: most views are bounded, and the bound leaves rays out.
    EXPECT_GT(counts.Bounded, counts.Unbounded) << "shape " << static_cast<int>(shape);
    EXPECT_GT(counts.Skipped, counts.Kept / 100) << "shape " << static_cast<int>(shape);
    std::printf("shape %d: %lld rays kept, %lld left out, %lld bounded views, %lld without\n",
      static_cast<int>(shape), counts.Kept, counts.Skipped, counts.Bounded, counts.Unbounded);
  }
}

// The reach holds the planes' own vertices: where each corner's planes meet (each three of a
// pyramid apex's four), off the corners on cells with warped faces or twisted pyramids; the
// reach is at least that far.
TEST(CellSpan, ReachCoversThePlanesVertices)
{
  std::mt19937 rng(7);
  for (CellShape shape :
    { CellShape::Hexahedron, CellShape::Tetra, CellShape::Wedge, CellShape::Pyramid })
  {
    int bounded = 0;
    for (int c = 0; c < 50; ++c)
    {
      const apc::CellCorners cell = apctest::DistortedCell(shape, 0.15, rng);
      const int n = apc::NumberOfCorners(shape);
      apc::CellMesh mesh;
      int64_t ids[8];
      for (int i = 0; i < n; ++i)
      {
        mesh.Points.push_back(cell.X[i]);
        mesh.PointScalars.push_back(0.f);
        ids[i] = i;
      }
      mesh.AddCell(shape, ids);
      ASSERT_TRUE(mesh.Finalize());
      const apc::PlaneReach& reach = mesh.GetPlaneReach(0);
      if (!std::isfinite(reach.Reach))
      {
        continue;
      }
      ++bounded;
      int count = 0;
      const apc::FacePlane* planes = mesh.GetPlanes(0, count);
      const auto& faces = apc::FacesOf(shape);
      ASSERT_EQ(count, faces.Count);
      double farthest = 0;
      for (int i = 0; i < n; ++i)
      {
        int on[4];
        int k = 0;
        for (int f = 0; f < faces.Count; ++f)
        {
          for (int s = 0; s < faces.Size[f]; ++s)
          {
            if (faces.Corner[f][s] == i)
            {
              on[k++] = f;
            }
          }
        }
        ASSERT_TRUE(k == 3 || k == 4);
        // Each three of the corner's planes: a point on all three, by alternating projections
        // from the corner.
        for (int skip = k == 4 ? 0 : 3; skip < k; ++skip)
        {
          std::array<double, 3> x = cell.X[i];
          for (int step = 0; step < 200; ++step)
          {
            for (int q = 0; q < k; ++q)
            {
              if (q == skip)
              {
                continue;
              }
              const apc::FacePlane& f = planes[on[q]];
              const double nn[3] = { f.Normal[0], f.Normal[1], f.Normal[2] };
              const double side = nn[0] * x[0] + nn[1] * x[1] + nn[2] * x[2] - f.Offset;
              const double norm2 = nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2];
              for (int d = 0; d < 3; ++d)
              {
                x[d] -= side * nn[d] / norm2;
              }
            }
          }
          farthest = std::max(farthest,
            std::sqrt((x[0] - cell.X[i][0]) * (x[0] - cell.X[i][0]) +
              (x[1] - cell.X[i][1]) * (x[1] - cell.X[i][1]) +
              (x[2] - cell.X[i][2]) * (x[2] - cell.X[i][2])));
        }
      }
      EXPECT_GE(reach.Reach, farthest * (1 - 1e-6)) << "shape " << n;
    }
    EXPECT_GT(bounded, 40) << "shape " << static_cast<int>(shape);
  }
}
