#include "apcTileBins.h"

#include "apcCellMesh.h"
#include "apcCompressedRows.h"
#include "apcParallel.h"
#include "apcRayCamera.h"

#include <algorithm>
#include <cmath>
#include <limits>

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

// The smallest depth of a cell's corners along the view direction: a lower bound of t over
// the cell (a linear function takes its minimum over a convex cell at a corner, and t is that
// depth for a parallel camera and at least it for a perspective one, whose rays are unit
// vectors from the eye). And the largest distance of its corners from the eye: an upper bound
// of t over the cell (the distance is convex, and at least t for either camera).
std::array<double, 2> NearFar(const CellMesh& mesh, const RayCamera& camera, int64_t cell)
{
  const auto& eye = camera.GetPosition();
  const auto& forward = camera.GetViewDirection();
  const int64_t* ids = mesh.GetCellPoints(cell);
  const int corners = static_cast<int>(mesh.GetShape(cell));
  double nearest = std::numeric_limits<double>::infinity();
  double farthest = 0;
  for (int c = 0; c < corners; ++c)
  {
    const auto& x = mesh.Points[ids[c]];
    const double d[3] = { x[0] - eye[0], x[1] - eye[1], x[2] - eye[2] };
    nearest = std::min(nearest, d[0] * forward[0] + d[1] * forward[1] + d[2] * forward[2]);
    farthest = std::max(farthest, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  }
  return { nearest, std::sqrt(farthest) };
}

// The cells that cover a pixel, nearest first (Near binned to kDepthBins depths; a stable
// counting sort, so the order is the same whenever the view is).
std::vector<int64_t> FrontToBackOrder(const TileBins& bins)
{
  const int64_t numCells = static_cast<int64_t>(bins.Rects.size());
  auto covers = [&bins](int64_t cell)
  {
    const auto& r = bins.Rects[cell];
    return r[0] <= r[2] && r[1] <= r[3];
  };
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
  auto binOf = [&](int64_t cell)
  {
    const double x = (bins.Near[cell] - lo) * scale;
    return x > 0 ? std::min(static_cast<int64_t>(x), int64_t(kDepthBins - 1)) : int64_t(0);
  };
  std::vector<int64_t> start;
  std::vector<int64_t> order;
  BuildCompressedRows<int64_t>(
    kDepthBins,
    [&](auto&& emit)
    {
      for (int64_t cell = 0; cell < numCells; ++cell)
      {
        if (covers(cell))
        {
          emit(binOf(cell), cell);
        }
      }
    },
    start, order);
  return order;
}

// The pixel centres a cell's projected corners cover.
std::array<int, 4> CoveredPixels(const CellMesh& mesh, const RayCamera& camera, int64_t cell)
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
  // Pixel centres sit at integers: the covered ones are ceil(x0) .. floor(x1).
  return { static_cast<int>(std::max(0.0, std::ceil(x0))),
    static_cast<int>(std::max(0.0, std::ceil(y0))),
    static_cast<int>(std::min(w - 1.0, std::floor(x1))),
    static_cast<int>(std::min(h - 1.0, std::floor(y1))) };
}
}

namespace
{
// Tiles' cell lists from the per-cell Rects and Near already in bins, on bins.Grid.
void BinByRects(TileBins& bins)
{
  const TileGrid& grid = bins.Grid;
  const std::vector<int64_t> order = FrontToBackOrder(bins);
  BuildCompressedRows<int64_t>(
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
  bins.Rects.resize(numCells);
  bins.Near.resize(numCells);
  bins.Far.resize(numCells);
  ParallelFor(threads, numCells, 4096,
    [&](int64_t begin, int64_t end)
    {
      for (int64_t cell = begin; cell < end; ++cell)
      {
        bins.Rects[cell] = CoveredPixels(*mesh, camera, cell);
        const std::array<double, 2> nearFar = NearFar(*mesh, camera, cell);
        bins.Near[cell] = nearFar[0];
        bins.Far[cell] = nearFar[1];
      }
    });
  BinByRects(bins);
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
  ParallelFor(threads, numCells, 4096,
    [&](int64_t begin, int64_t end)
    {
      for (int64_t cell = begin; cell < end; ++cell)
      {
        const auto& r = fine.Rects[cell];
        std::array<int, 4>& to = bins.Rects[cell];
        if (r[0] > r[2] || r[1] > r[3])
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
      }
    });
  BinByRects(bins);
  return true;
}

} // namespace apc
