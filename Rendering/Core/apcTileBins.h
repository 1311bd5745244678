// Screen tiles and the cells each one must march: the marcher's per-view set-up. Work is
// organised by cell, not by ray: every cell is binned once per view into the tiles its
// projection covers, so no per-ray cell search is needed (a VTK cell locator query per ray,
// FindCellsAlongLine, costs minutes per 1024^2 frame on a mesh of a few hundred thousand
// cells).
#ifndef apcTileBins_h
#define apcTileBins_h

#include "apcUninitialized.h"

#include <array>
#include <cstdint>
#include <vector>

namespace apc
{

class CellMesh;
class RayCamera;

// Pixel rectangle [I0, I1) x [J0, J1) of tile Index, and where its pixels live in the image.
struct TileRect
{
  int I0, J0, I1, J1;
  int64_t Index;

  int Width() const { return this->I1 - this->I0; }
  int Pixels() const { return (this->I1 - this->I0) * (this->J1 - this->J0); }
  // The image index (j * imageWidth + i) of the tile's local pixel p (row-major in the tile).
  int64_t ImagePixel(int p, int imageWidth) const
  {
    const int i = this->I0 + p % this->Width();
    const int j = this->J0 + p / this->Width();
    return static_cast<int64_t>(j) * imageWidth + i;
  }
};

// Square tiles of Size pixels over a Width x Height image, row-major from the bottom left.
struct TileGrid
{
  int Size = 16;
  int Width = 0;
  int Height = 0;
  int TilesX = 0;
  int TilesY = 0;

  TileGrid() = default;
  TileGrid(int size, int width, int height);
  int64_t Count() const { return static_cast<int64_t>(this->TilesX) * this->TilesY; }
  TileRect Tile(int64_t index) const;
};

// Cells per tile for one view. The per-cell arrays are written whole by every binning
// (uninitialised vectors, in huge pages when large: apcUninitialized.h).
struct TileBins
{
  TileGrid Grid;
  // Per cell: the covered pixel centres i0, j0, i1, j1 (inclusive); empty if i0 > i1.
  UninitializedVector<std::array<int, 4>> Rects;
  // Per cell: a lower bound of the ray parameter t of any of its points on any ray (the
  // smallest depth of its corners along the view direction, which is t for a parallel camera
  // and at most t for a perspective one), so that a ray already opaque before it can skip it
  // without clipping.
  UninitializedVector<double> Near;
  // Per cell: an upper bound of the ray parameter t of any of its points on any ray (the
  // largest distance of its corners from the eye), so that the marcher knows which cells
  // may hold a ray's last samples before its end (Sample End Weights = Boundary).
  UninitializedVector<double> Far;
  // Compressed rows: tile t's cells are Cells[Start[t] .. Start[t + 1]), nearest first (by
  // Near, binned to a few thousand depths): a ray meets its front cells first and is opaque
  // sooner.
  std::vector<int64_t> Start{ 0 };
  UninitializedVector<int64_t> Cells;

  // Per point: where BinCells projected it (X NaN: behind the eye or not finite), its depth
  // along the view direction and its squared distance from the eye, each corner's numbers
  // once per view instead of once per cell holding it (about eight on a hexahedral mesh).
  struct ProjectedPoint
  {
    double X, Y, Depth, Distance2;
  };
  UninitializedVector<ProjectedPoint> Projected;
  // The covering cells front to back with their tiles (first and last column, row): the
  // tiles' lists are filled from it in one sequential pass, without a random read per cell.
  struct SortedCell
  {
    int64_t Cell;
    std::array<int, 4> Tiles;
  };
  UninitializedVector<SortedCell> Sorted;

  bool Empty(int64_t tile) const { return this->Start[tile] == this->Start[tile + 1]; }
};

// Bins mesh's cells for camera into tiles of tileSize pixels. A cell reaching behind the eye
// gets the whole screen (conservative), one wholly behind it none. threads: 0 = the default
// (apcParallel.h).
void BinCells(
  const CellMesh* mesh, const RayCamera& camera, int tileSize, int threads, TileBins& bins);

// The bins BinCells gives camera.Decimated(step, offset) (width x height pixels), from fine,
// BinCells' bins of camera: the decimated pixel (i, j) casts the ray of camera's pixel
// (i * step + offset, j * step + offset), so a cell covers the decimated pixels whose
// undecimated ones it covers, and its Near (the same eye and view direction) is fine's. No
// corner is projected again: a first frame's probe (apcOpaquePrediction.h) bins no cell twice.
// False (bins untouched) if a decimated pixel lies past camera's image.
bool DecimateBins(const TileBins& fine, int step, int offset, int width, int height, int tileSize,
  int threads, TileBins& bins);

} // namespace apc

#endif
