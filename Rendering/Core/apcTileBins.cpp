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

void BinCells(
  const CellMesh* mesh, const RayCamera& camera, int tileSize, int threads, TileBins& bins)
{
  bins.Grid = TileGrid(tileSize, camera.GetWidth(), camera.GetHeight());
  const int64_t numCells = mesh ? mesh->GetNumberOfCells() : 0;
  bins.Rects.resize(numCells);
  ParallelFor(threads, numCells, 4096,
    [&](int64_t begin, int64_t end)
    {
      for (int64_t cell = begin; cell < end; ++cell)
      {
        bins.Rects[cell] = CoveredPixels(*mesh, camera, cell);
      }
    });

  const TileGrid& grid = bins.Grid;
  BuildCompressedRows<int64_t>(
    grid.Count(),
    [&](auto&& emit)
    {
      for (int64_t cell = 0; cell < numCells; ++cell)
      {
        const auto& r = bins.Rects[cell];
        if (r[0] > r[2] || r[1] > r[3])
        {
          continue;
        }
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

} // namespace apc
