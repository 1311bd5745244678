// SPDX-License-Identifier: BSD-3-Clause
#include "apcCoveredTiles.h"

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

size_t TileGrid::PixelsIn(const std::vector<unsigned char>& mask) const
{
  size_t pixels = 0;
  for (size_t t = 0; t < mask.size() && t < this->Tiles(); ++t)
  {
    if (mask[t])
    {
      this->ForEachRow(t, [&](size_t, size_t count) { pixels += count; });
    }
  }
  return pixels;
}

} // namespace apc
