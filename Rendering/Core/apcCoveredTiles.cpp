// SPDX-License-Identifier: BSD-3-Clause
#include "apcCoveredTiles.h"

#include <algorithm>

namespace apc
{

TileGrid::TileGrid(int width, int i0, int j0, int i1, int j1, int tileSize)
  : Width(width)
  , I0(i0)
  , J0(j0)
  , I1(i1)
  , J1(j1)
  , TileSize(tileSize > 0 ? tileSize : kDefaultTileSize)
{
  if (i1 > i0 && j1 > j0)
  {
    this->TilesX = (i1 - i0 + this->TileSize - 1) / this->TileSize;
    this->TilesY = (j1 - j0 + this->TileSize - 1) / this->TileSize;
  }
}

size_t TileGrid::PixelsIn(const std::vector<unsigned char>& mask, size_t first, size_t last) const
{
  size_t pixels = 0;
  for (size_t t = first; t < mask.size() && t < this->Tiles() && t < last; ++t)
  {
    if (mask[t])
    {
      this->ForEachRow(t, [&](size_t, size_t count) { pixels += count; });
    }
  }
  return pixels;
}

std::vector<size_t> TileGrid::Chunks(const std::vector<unsigned char>& mask, size_t maxPixels) const
{
  std::vector<size_t> bounds{ 0 };
  size_t pixels = 0;
  const size_t tiles = std::min(mask.size(), this->Tiles());
  for (size_t t = 0; t < tiles; ++t)
  {
    if (!mask[t])
    {
      continue;
    }
    size_t inTile = 0;
    this->ForEachRow(t, [&](size_t, size_t count) { inTile += count; });
    if (pixels > 0 && pixels + inTile > maxPixels)
    {
      bounds.push_back(t);
      pixels = 0;
    }
    pixels += inTile;
  }
  bounds.push_back(std::max(tiles, bounds.back()));
  return bounds;
}

PackedWalk::PackedWalk(
  const TileGrid& grid, const std::vector<unsigned char>& mask, size_t first, size_t last)
  : Grid(&grid)
  , Mask(&mask)
  , Tile(first)
  , End(std::min({ last, mask.size(), grid.Tiles() }))
{
  this->EnterTile();
}

void PackedWalk::EnterTile()
{
  while (this->Tile < this->End && !(*this->Mask)[this->Tile])
  {
    ++this->Tile;
  }
  if (this->Tile >= this->End)
  {
    return;
  }
  const TileGrid& g = *this->Grid;
  const int ti = static_cast<int>(this->Tile % g.TilesX);
  const int tj = static_cast<int>(this->Tile / g.TilesX);
  this->I0 = g.I0 + ti * g.TileSize;
  this->I1 = std::min(this->I0 + g.TileSize, g.I1);
  this->J = g.J0 + tj * g.TileSize;
  this->J1 = std::min(this->J + g.TileSize, g.J1);
  this->I = this->I0;
}

void PackedWalk::NextPixel()
{
  ++this->Index;
  this->Value = 0;
  if (++this->I < this->I1)
  {
    return;
  }
  this->I = this->I0;
  if (++this->J < this->J1)
  {
    return;
  }
  ++this->Tile;
  this->EnterTile();
}

} // namespace apc
