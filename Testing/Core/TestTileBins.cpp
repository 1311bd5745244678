// BinCells projects each point once per view and takes a cell's rectangle, Near and Far from its
// corners' projections; the tiles' lists come from three passes over the cells. The reference
// here projects every corner of every cell again, as a cell at a time would, and fills the
// lists with the compressed rows' builder from a front-to-back order of the cells: the same
// Rects, Near, Far, Start and Cells, bit for bit, on random meshes (corners behind the eye, on
// it, not finite, cells off screen) and random cameras (perspective and parallel, cropped,
// decimated, shifted window centres), on one thread and several.
#include "apcCellMesh.h"
#include "apcCompressedRows.h"
#include "apcRayCamera.h"
#include "apcTileBins.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace
{

struct Reference
{
  apc::TileGrid Grid;
  std::vector<std::array<int, 4>> Rects;
  std::vector<double> Near;
  std::vector<double> Far;
  std::vector<int64_t> Start;
  std::vector<int64_t> Cells;
};

// Every corner of the cell projected.
std::array<int, 4> ReferenceRect(
  const apc::CellMesh& mesh, const apc::RayCamera& camera, int64_t cell)
{
  const double w = camera.GetWidth();
  const double h = camera.GetHeight();
  const int64_t* ids = mesh.GetCellPoints(cell);
  const int corners = static_cast<int>(mesh.GetShape(cell));
  double x0 = std::numeric_limits<double>::infinity();
  double y0 = x0;
  double x1 = -x0;
  double y1 = -x0;
  int behind = 0;
  for (int c = 0; c < corners; ++c)
  {
    double px, py;
    if (camera.Project(mesh.Points[ids[c]], px, py))
    {
      x0 = std::min(x0, px);
      x1 = std::max(x1, px);
      y0 = std::min(y0, py);
      y1 = std::max(y1, py);
    }
    else
    {
      ++behind;
    }
  }
  if (behind == corners)
  {
    return { 1, 1, 0, 0 };
  }
  if (behind > 0)
  {
    x0 = y0 = -1.0;
    x1 = w;
    y1 = h;
  }
  return { static_cast<int>(std::max(0.0, std::ceil(x0))),
    static_cast<int>(std::max(0.0, std::ceil(y0))),
    static_cast<int>(std::min(w - 1.0, std::floor(x1))),
    static_cast<int>(std::min(h - 1.0, std::floor(y1))) };
}

Reference ReferenceBins(const apc::CellMesh& mesh, const apc::RayCamera& camera, int tileSize)
{
  Reference bins;
  bins.Grid = apc::TileGrid(tileSize, camera.GetWidth(), camera.GetHeight());
  const int64_t numCells = mesh.GetNumberOfCells();
  const auto& eye = camera.GetPosition();
  const auto& forward = camera.GetViewDirection();
  for (int64_t cell = 0; cell < numCells; ++cell)
  {
    bins.Rects.push_back(ReferenceRect(mesh, camera, cell));
    const int64_t* ids = mesh.GetCellPoints(cell);
    double nearest = std::numeric_limits<double>::infinity();
    double farthest = 0;
    for (int c = 0; c < static_cast<int>(mesh.GetShape(cell)); ++c)
    {
      const auto& x = mesh.Points[ids[c]];
      const double d[3] = { x[0] - eye[0], x[1] - eye[1], x[2] - eye[2] };
      nearest = std::min(nearest, d[0] * forward[0] + d[1] * forward[1] + d[2] * forward[2]);
      farthest = std::max(farthest, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    }
    bins.Near.push_back(nearest);
    bins.Far.push_back(std::sqrt(farthest));
  }
  // Front to back: Near binned to 2^14 depths over the covering cells' range, stable.
  auto covers = [&](int64_t cell)
  {
    const auto& r = bins.Rects[cell];
    return r[0] <= r[2] && r[1] <= r[3];
  };
  constexpr int kDepthBins = 1 << 14;
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  for (int64_t cell = 0; cell < numCells; ++cell)
  {
    if (covers(cell))
    {
      lo = std::min(lo, bins.Near[cell]);
      hi = std::max(hi, bins.Near[cell]);
    }
  }
  const double scale = hi > lo ? (kDepthBins - 1) / (hi - lo) : 0.0;
  std::vector<int64_t> depthStart;
  std::vector<int64_t> order;
  apc::BuildCompressedRows<int64_t>(
    kDepthBins,
    [&](auto&& emit)
    {
      for (int64_t cell = 0; cell < numCells; ++cell)
      {
        if (covers(cell))
        {
          const double x = (bins.Near[cell] - lo) * scale;
          emit(
            x > 0 ? std::min(static_cast<int64_t>(x), int64_t(kDepthBins - 1)) : int64_t(0), cell);
        }
      }
    },
    depthStart, order);
  const apc::TileGrid& grid = bins.Grid;
  apc::BuildCompressedRows<int64_t>(
    grid.Count(),
    [&](auto&& emit)
    {
      for (int64_t cell : order)
      {
        const auto& r = bins.Rects[cell];
        for (int ty = r[1] / grid.Size; ty <= r[3] / grid.Size; ++ty)
        {
          for (int tx = r[0] / grid.Size; tx <= r[2] / grid.Size; ++tx)
          {
            emit(static_cast<int64_t>(ty) * grid.TilesX + tx, cell);
          }
        }
      }
    },
    bins.Start, bins.Cells);
  return bins;
}

// Points in a box about the origin (a few far out, a few not finite), cells of every shape on
// random points near each other (and a few spanning the box).
apc::CellMesh RandomMesh(std::mt19937& rng, int numPoints, int numCells)
{
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> percent(0, 99);
  apc::CellMesh mesh;
  for (int p = 0; p < numPoints; ++p)
  {
    const double scale = percent(rng) < 4 ? 40.0 : 1.0;
    mesh.Points.push_back({ scale * u(rng), scale * u(rng), scale * u(rng) });
    mesh.PointScalars.push_back(0.5f);
  }
  // Sorted along x so that neighbouring ids are neighbouring points: small cells.
  std::sort(mesh.Points.begin(), mesh.Points.end(),
    [](const auto& a, const auto& b) { return a[0] < b[0]; });
  for (int p = 0; p < numPoints; ++p)
  {
    const int kind = percent(rng);
    if (kind == 0)
    {
      mesh.Points[p][p % 3] = std::numeric_limits<double>::quiet_NaN();
    }
    else if (kind == 1)
    {
      mesh.Points[p][p % 3] = (p & 1 ? 1 : -1) * std::numeric_limits<double>::infinity();
    }
  }
  const apc::CellShape shapes[4] = { apc::CellShape::Tetra, apc::CellShape::Pyramid,
    apc::CellShape::Wedge, apc::CellShape::Hexahedron };
  std::uniform_int_distribution<int> shape(0, 3);
  std::uniform_int_distribution<int> anyPoint(0, numPoints - 1);
  std::uniform_int_distribution<int> near(-12, 12);
  for (int c = 0; c < numCells; ++c)
  {
    const apc::CellShape s = shapes[shape(rng)];
    const int base = anyPoint(rng);
    const bool spanning = percent(rng) < 2;
    int64_t ids[8];
    for (int k = 0; k < apc::NumberOfCorners(s); ++k)
    {
      ids[k] = spanning ? anyPoint(rng) : std::min(std::max(base + near(rng), 0), numPoints - 1);
    }
    mesh.AddCell(s, ids);
  }
  return mesh;
}

// A camera looking from a random place (inside the box at times: corners behind the eye and at
// it) at a random point.
apc::RayCamera RandomCamera(std::mt19937& rng, const apc::CellMesh& mesh)
{
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> percent(0, 99);
  std::uniform_int_distribution<int> size(1, 90);
  const double distance = percent(rng) < 30 ? 0.8 : 5.0;
  std::array<double, 3> eye = { distance * u(rng), distance * u(rng), distance * u(rng) };
  if (percent(rng) < 10)
  {
    eye = mesh.Points[percent(rng) % mesh.Points.size()]; // on a corner
    if (!(std::isfinite(eye[0]) && std::isfinite(eye[1]) && std::isfinite(eye[2])))
    {
      eye = { 0.1, 0.2, 0.3 };
    }
  }
  const std::array<double, 3> focal = { 0.5 * u(rng), 0.5 * u(rng), 0.5 * u(rng) };
  const bool parallel = percent(rng) < 30;
  const int width = size(rng);
  const int height = size(rng);
  const std::array<double, 2> centre =
    percent(rng) < 30 ? std::array<double, 2>{ u(rng), u(rng) } : std::array<double, 2>{ 0, 0 };
  apc::RayCamera camera(eye, focal, { u(rng), 1.0, u(rng) }, 20.0 + 60.0 * (u(rng) + 1.0), parallel,
    0.2 + (u(rng) + 1.0), width, height, 0.05, 50.0, centre);
  const int kind = percent(rng);
  if (kind < 25)
  {
    std::uniform_int_distribution<int> at(0, std::max(0, width / 2));
    camera = camera.Cropped(at(rng), at(rng), std::max(1, width / 2), std::max(1, height - 3));
  }
  else if (kind < 45)
  {
    const int step = 1 + percent(rng) % 5;
    camera = camera.Decimated(step, percent(rng) % step);
  }
  return camera;
}

bool SameDoubles(const double* a, const double* b, size_t n)
{
  return std::memcmp(a, b, n * sizeof(double)) == 0;
}

void ExpectSameBins(const apc::CellMesh& mesh, const apc::RayCamera& camera, int tileSize,
  int threads, apc::TileBins& bins, const char* what)
{
  const Reference expected = ReferenceBins(mesh, camera, tileSize);
  apc::BinCells(&mesh, camera, tileSize, threads, bins);
  const size_t n = static_cast<size_t>(mesh.GetNumberOfCells());
  ASSERT_EQ(bins.Rects.size(), n) << what;
  ASSERT_EQ(bins.Grid.TilesX, expected.Grid.TilesX) << what;
  ASSERT_EQ(bins.Grid.TilesY, expected.Grid.TilesY) << what;
  ASSERT_TRUE(std::equal(bins.Rects.begin(), bins.Rects.end(), expected.Rects.begin())) << what;
  ASSERT_TRUE(SameDoubles(bins.Near.data(), expected.Near.data(), n)) << what;
  ASSERT_TRUE(SameDoubles(bins.Far.data(), expected.Far.data(), n)) << what;
  ASSERT_EQ(bins.Start, expected.Start) << what;
  ASSERT_TRUE(
    std::equal(bins.Cells.begin(), bins.Cells.end(), expected.Cells.begin(), expected.Cells.end()))
    << what;
}

} // namespace

TEST(TileBins, AreThePerCornerReferencesOnRandomMeshesAndCameras)
{
  std::mt19937 rng(1401);
  int behindCells = 0;
  int offScreenCells = 0;
  int64_t entries = 0;
  // One bins reused across views: what a frame leaves behind must not leak into the next.
  apc::TileBins bins;
  for (int m = 0; m < 6; ++m)
  {
    const apc::CellMesh mesh = RandomMesh(rng, 200 + 300 * m, 300 + 400 * m);
    for (int v = 0; v < 40; ++v)
    {
      const apc::RayCamera camera = RandomCamera(rng, mesh);
      const int tileSize = v % 3 == 0 ? 1 : v % 3 == 1 ? 4 : 16;
      ExpectSameBins(mesh, camera, tileSize, 1, bins, "one thread");
      entries += static_cast<int64_t>(bins.Cells.size());
      for (const auto& r : bins.Rects)
      {
        behindCells += r == std::array<int, 4>{ 1, 1, 0, 0 } ? 1 : 0;
        offScreenCells += r[0] > r[2] || r[1] > r[3] ? 1 : 0;
      }
    }
  }
  // The views exercised what they are for.
  EXPECT_GT(behindCells, 1000);
  EXPECT_GT(offScreenCells, 5000);
  EXPECT_GT(entries, 100000);
}

TEST(TileBins, AreThePerCornerReferencesOnSeveralThreads)
{
  std::mt19937 rng(1402);
  // Enough points and cells for several chunks of the parallel loops.
  const apc::CellMesh mesh = RandomMesh(rng, 20000, 30000);
  apc::TileBins bins;
  for (int v = 0; v < 12; ++v)
  {
    const apc::RayCamera camera = RandomCamera(rng, mesh);
    ExpectSameBins(mesh, camera, 16, 3, bins, "three threads");
  }
}

TEST(TileBins, OfNoCellsAreEmpty)
{
  const apc::CellMesh mesh;
  const apc::RayCamera camera(
    { 0, 0, 5 }, { 0, 0, 0 }, { 0, 1, 0 }, 30.0, false, 1.0, 40, 20, 0.1, 10.0);
  apc::TileBins bins;
  apc::BinCells(&mesh, camera, 16, 1, bins);
  EXPECT_TRUE(bins.Cells.empty());
  EXPECT_EQ(bins.Start.size(), static_cast<size_t>(bins.Grid.Count() + 1));
  apc::BinCells(nullptr, camera, 16, 1, bins);
  EXPECT_TRUE(bins.Rects.empty());
  EXPECT_TRUE(bins.Cells.empty());
}
