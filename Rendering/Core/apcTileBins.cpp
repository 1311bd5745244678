#include "apcTileBins.h"

#include "apcCellMesh.h"
#include "apcCompressedRows.h"
#include "apcParallel.h"
#include "apcRayCamera.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

namespace apc
{

TileGrid::TileGrid(int size, int width, int height)
  : Size(size)
  , Width(width)
  , Height(height)
  , TilesX((width + size - 1) / size)
  , TilesY((height + size - 1) / size)
{
}

TileRect TileGrid::Tile(int64_t index) const
{
  const int tx = static_cast<int>(index % this->TilesX);
  const int ty = static_cast<int>(index / this->TilesX);
  return { tx * this->Size, ty * this->Size, std::min(this->Width, (tx + 1) * this->Size),
    std::min(this->Height, (ty + 1) * this->Size), index };
}

namespace
{
// Depths the cells are binned to for their front-to-back order within a tile: about a
// tenth of a cell apart on the meshes at hand, and a counting sort over them costs far less
// than a comparison sort of the cells.
constexpr int kDepthBins = 1 << 14;

// How many cells ahead BinCells fetches the corners' projections.
constexpr int64_t kPrefetchCells = 16;

using ProjectedPoint = TileBins::ProjectedPoint;

// A point's pixel coordinates (X NaN if the camera cannot project it), its depth along the
// view direction and its squared distance from the eye.
ProjectedPoint ProjectPoint(const RayCamera& camera, const std::array<double, 3>& x)
{
  const auto& eye = camera.GetPosition();
  const auto& forward = camera.GetViewDirection();
  ProjectedPoint p;
  if (!camera.Project(x, p.X, p.Y))
  {
    p.X = std::numeric_limits<double>::quiet_NaN();
    p.Y = 0;
  }
  const double d[3] = { x[0] - eye[0], x[1] - eye[1], x[2] - eye[2] };
  p.Depth = d[0] * forward[0] + d[1] * forward[1] + d[2] * forward[2];
  p.Distance2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  return p;
}

bool Covers(const std::array<int, 4>& r)
{
  return r[0] <= r[2] && r[1] <= r[3];
}

// The pixel centres a cell's projected corners cover, and its Near and Far: the smallest
// depth of its corners along the view direction, a lower bound of t over the cell (a linear
// function takes its minimum over a convex cell at a corner, and t is that depth for a
// parallel camera and at least it for a perspective one, whose rays are unit vectors from the
// eye), and the largest distance of its corners from the eye, an upper bound of t over the
// cell (the distance is convex, and at least t for either camera).
void BinCell(const CellMesh& mesh, const ProjectedPoint* points, double w, double h, int64_t cell,
  std::array<int, 4>& rect, double& nearT, double& farT)
{
  const int64_t* ids = mesh.GetCellPoints(cell);
  const int corners = static_cast<int>(mesh.GetShape(cell));
  double x0 = std::numeric_limits<double>::infinity();
  double y0 = x0;
  double x1 = -x0;
  double y1 = -x0;
  double nearest = x0;
  double farthest = 0;
  int behind = 0;
  for (int c = 0; c < corners; ++c)
  {
    const ProjectedPoint& p = points[ids[c]];
    if (p.X == p.X)
    {
      x0 = std::min(x0, p.X);
      x1 = std::max(x1, p.X);
      y0 = std::min(y0, p.Y);
      y1 = std::max(y1, p.Y);
    }
    else
    {
      ++behind;
    }
    nearest = std::min(nearest, p.Depth);
    farthest = std::max(farthest, p.Distance2);
  }
  nearT = nearest;
  farT = std::sqrt(farthest);
  if (behind == corners)
  {
    rect = { 1, 1, 0, 0 };
    return;
  }
  if (behind > 0)
  {
    x0 = y0 = -1.0;
    x1 = w;
    y1 = h;
  }
  // Pixel centres sit at integers: the covered ones are ceil(x0) .. floor(x1).
  rect = { static_cast<int>(std::max(0.0, std::ceil(x0))),
    static_cast<int>(std::max(0.0, std::ceil(y0))),
    static_cast<int>(std::min(w - 1.0, std::floor(x1))),
    static_cast<int>(std::min(h - 1.0, std::floor(y1))) };
}

// The smallest and largest Near of the cells that cover a pixel, merged from the chunks of a
// parallel loop (the same whatever order the chunks arrive in).
struct NearRange
{
  double Lo = std::numeric_limits<double>::infinity();
  double Hi = -std::numeric_limits<double>::infinity();
  std::mutex Mutex;

  void Merge(double lo, double hi)
  {
    std::lock_guard<std::mutex> lock(this->Mutex);
    this->Lo = std::min(this->Lo, lo);
    this->Hi = std::max(this->Hi, hi);
  }
};

// Tiles' cell lists from the per-cell Rects and Near already in bins, on bins.Grid; lo and hi:
// the range of Near over the cells that cover a pixel. A tile lists its cells nearest first
// (Near binned to kDepthBins depths, ties in cell order: a stable counting sort, so the order
// is the same whenever the view is). Three passes: the depth bins' and the tiles' counts in
// cell order, the covering cells with their tiles sorted front to back, and the tiles' lists
// filled from those in order.
void BinByRects(TileBins& bins, double lo, double hi)
{
  const TileGrid& grid = bins.Grid;
  const int64_t numCells = static_cast<int64_t>(bins.Rects.size());
  const double scale = hi > lo ? (kDepthBins - 1) / (hi - lo) : 0.0;
  auto binOf = [&](int64_t cell)
  {
    const double x = (bins.Near[cell] - lo) * scale;
    return x > 0 ? std::min(static_cast<int64_t>(x), int64_t(kDepthBins - 1)) : int64_t(0);
  };
  // A covering cell's rectangle lies inside the image: its tiles by look-up, not division.
  std::vector<int> tileOfColumn(std::max(grid.Width, 0));
  std::vector<int> tileOfRow(std::max(grid.Height, 0));
  for (size_t i = 0; i < tileOfColumn.size(); ++i)
  {
    tileOfColumn[i] = static_cast<int>(i) / grid.Size;
  }
  for (size_t j = 0; j < tileOfRow.size(); ++j)
  {
    tileOfRow[j] = static_cast<int>(j) / grid.Size;
  }
  std::vector<int64_t> depthStart(kDepthBins + 1, 0);
  std::vector<int64_t>& tileStart = bins.Start;
  tileStart.assign(static_cast<size_t>(grid.Count()) + 1, 0);
  for (int64_t cell = 0; cell < numCells; ++cell)
  {
    const auto& r = bins.Rects[cell];
    if (Covers(r))
    {
      ++depthStart[binOf(cell) + 1];
      const int tx0 = tileOfColumn[r[0]];
      const int tx1 = tileOfColumn[r[2]];
      for (int ty = tileOfRow[r[1]]; ty <= tileOfRow[r[3]]; ++ty)
      {
        int64_t* row = tileStart.data() + 1 + static_cast<int64_t>(ty) * grid.TilesX;
        for (int tx = tx0; tx <= tx1; ++tx)
        {
          ++row[tx];
        }
      }
    }
  }
  PrefixSum(depthStart);
  PrefixSum(tileStart);
  bins.Sorted.resize(static_cast<size_t>(depthStart.back()));
  for (int64_t cell = 0; cell < numCells; ++cell)
  {
    const auto& r = bins.Rects[cell];
    if (Covers(r))
    {
      bins.Sorted[depthStart[binOf(cell)]++] = { cell,
        { tileOfColumn[r[0]], tileOfRow[r[1]], tileOfColumn[r[2]], tileOfRow[r[3]] } };
    }
  }
  bins.Cells.resize(static_cast<size_t>(tileStart.back()));
  std::vector<int64_t> fill(tileStart.begin(), tileStart.end() - 1);
  int64_t* cells = bins.Cells.data();
  for (const TileBins::SortedCell& sorted : bins.Sorted)
  {
    const auto& t = sorted.Tiles;
    for (int ty = t[1]; ty <= t[3]; ++ty)
    {
      int64_t* row = fill.data() + static_cast<int64_t>(ty) * grid.TilesX;
      for (int tx = t[0]; tx <= t[2]; ++tx)
      {
        cells[row[tx]++] = sorted.Cell;
      }
    }
  }
}

// The decimated pixels k (k * step + offset in [first, last]) of an inclusive range of
// undecimated pixel centres, clamped to [0, pixels): floor division, for ranges reaching left
// of offset.
std::array<int, 2> DecimatedRange(int first, int last, int step, int offset, int pixels)
{
  auto floorDiv = [](int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); };
  return { std::max(0, -floorDiv(-(first - offset), step)),
    std::min(pixels - 1, floorDiv(last - offset, step)) };
}
}

void BinCells(
  const CellMesh* mesh, const RayCamera& camera, int tileSize, int threads, TileBins& bins)
{
  bins.Grid = TileGrid(tileSize, camera.GetWidth(), camera.GetHeight());
  const int64_t numCells = mesh ? mesh->GetNumberOfCells() : 0;
  const int64_t numPoints = mesh ? static_cast<int64_t>(mesh->Points.size()) : 0;
  bins.Rects.resize(numCells);
  bins.Near.resize(numCells);
  bins.Far.resize(numCells);
  bins.Projected.resize(numPoints);
  ParallelFor(threads, numPoints, 4096,
    [&](int64_t begin, int64_t end)
    {
      for (int64_t point = begin; point < end; ++point)
      {
        bins.Projected[point] = ProjectPoint(camera, mesh->Points[point]);
      }
    });
  const double w = camera.GetWidth();
  const double h = camera.GetHeight();
  NearRange range;
  ParallelFor(threads, numCells, 4096,
    [&](int64_t begin, int64_t end)
    {
      double lo = std::numeric_limits<double>::infinity();
      double hi = -lo;
      const TileBins::ProjectedPoint* points = bins.Projected.data();
      for (int64_t cell = begin; cell < end; ++cell)
      {
        // The corners' entries are scattered over the points: ask for them a few cells ahead
        // (the cells' ids come in order).
        if (cell + kPrefetchCells < end)
        {
          const int64_t* ids = mesh->GetCellPoints(cell + kPrefetchCells);
          const int corners = static_cast<int>(mesh->GetShape(cell + kPrefetchCells));
          for (int c = 0; c < corners; ++c)
          {
            __builtin_prefetch(points + ids[c]);
          }
        }
        BinCell(*mesh, points, w, h, cell, bins.Rects[cell], bins.Near[cell], bins.Far[cell]);
        if (Covers(bins.Rects[cell]))
        {
          lo = std::min(lo, bins.Near[cell]);
          hi = std::max(hi, bins.Near[cell]);
        }
      }
      range.Merge(lo, hi);
    });
  BinByRects(bins, range.Lo, range.Hi);
}

bool DecimateBins(const TileBins& fine, int step, int offset, int width, int height, int tileSize,
  int threads, TileBins& bins)
{
  const TileGrid& from = fine.Grid;
  // A decimated pixel past the undecimated image (ProbeSize keeps at least one) has a ray no
  // undecimated rectangle says anything about.
  if (step < 1 || offset < 0 || width < 1 || height < 1 ||
    static_cast<int64_t>(width - 1) * step + offset >= from.Width ||
    static_cast<int64_t>(height - 1) * step + offset >= from.Height)
  {
    return false;
  }
  bins.Grid = TileGrid(tileSize, width, height);
  const int64_t numCells = static_cast<int64_t>(fine.Rects.size());
  bins.Rects.resize(numCells);
  bins.Near.resize(numCells);
  bins.Far.resize(numCells);
  NearRange range;
  ParallelFor(threads, numCells, 4096,
    [&](int64_t begin, int64_t end)
    {
      double lo = std::numeric_limits<double>::infinity();
      double hi = -lo;
      for (int64_t cell = begin; cell < end; ++cell)
      {
        const auto& r = fine.Rects[cell];
        std::array<int, 4>& to = bins.Rects[cell];
        if (!Covers(r))
        {
          to = { 1, 1, 0, 0 };
        }
        else
        {
          const std::array<int, 2> i = DecimatedRange(r[0], r[2], step, offset, width);
          const std::array<int, 2> j = DecimatedRange(r[1], r[3], step, offset, height);
          to = i[0] <= i[1] && j[0] <= j[1] ? std::array<int, 4>{ i[0], j[0], i[1], j[1] }
                                            : std::array<int, 4>{ 1, 1, 0, 0 };
        }
        bins.Near[cell] = fine.Near[cell];
        bins.Far[cell] = fine.Far[cell];
        if (Covers(to))
        {
          lo = std::min(lo, fine.Near[cell]);
          hi = std::max(hi, fine.Near[cell]);
        }
      }
      range.Merge(lo, hi);
    });
  BinByRects(bins, range.Lo, range.Hi);
  return true;
}

} // namespace apc
