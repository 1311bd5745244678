// SPDX-License-Identifier: BSD-3-Clause
// The compact wire of the compositing pass (the paper's OSPRay implementation sends only
// non-empty tiles): a pixel rectangle cut into square tiles, one occupancy byte per tile, and
// the marked tiles' pixels packed one after the other. Processes agree on the union of their
// masks first (a bytewise MAX allreduce), so every process packs the same tiles in the same
// order and the packed buffers can be summed element by element.
#ifndef apcCoveredTiles_h
#define apcCoveredTiles_h

#include <algorithm>
#include <cstddef>
#include <vector>

namespace apc
{

// Tiles of TileSize x TileSize pixels over the rectangle [I0, I1) x [J0, J1) of an image whose
// rows are Width pixels long; the last column and row of tiles are clipped to the rectangle.
class TileGrid
{
public:
  static constexpr int kDefaultTileSize = 8;

  TileGrid() = default;
  TileGrid(int width, int i0, int j0, int i1, int j1, int tileSize = kDefaultTileSize);

  size_t Tiles() const { return static_cast<size_t>(this->TilesX) * this->TilesY; }

  // A byte per tile, 1 where pixelIsCovered(pixel index in the image) holds for a pixel of it.
  template <class Predicate>
  std::vector<unsigned char> Mark(Predicate pixelIsCovered) const;

  // The pixels of the marked tiles among tiles [first, last): the length, in pixels, of a
  // packed buffer.
  size_t PixelsIn(const std::vector<unsigned char>& mask, size_t first = 0,
    size_t last = static_cast<size_t>(-1)) const;

  // Copies the marked tiles' pixels (components values each) among tiles [first, last) from
  // the full image to packed, tile by tile in row-major tile order, and back.
  template <class Packed, class Full>
  void Pack(const std::vector<unsigned char>& mask, const Full* full, int components,
    Packed* packed, size_t first = 0, size_t last = static_cast<size_t>(-1)) const;
  template <class Packed, class Full>
  void Unpack(const std::vector<unsigned char>& mask, const Packed* packed, int components,
    Full* full, size_t first = 0, size_t last = static_cast<size_t>(-1)) const;

  // Calls visit(pixel index in the image) for each pixel of the marked tiles among tiles
  // [first, last), in the order Pack packs them: for packed buffers whose pixels hold
  // different numbers of values, or values made from the image's as they are packed.
  template <class Visit>
  void ForEachPacked(const std::vector<unsigned char>& mask, Visit visit, size_t first = 0,
    size_t last = static_cast<size_t>(-1)) const;

  // The tiles cut into consecutive ranges [bounds[c], bounds[c + 1]) whose marked tiles hold
  // at most maxPixels pixels (at least one marked tile each): the chunks a large image is
  // packed and summed in, so that the packed copies stay a bounded size whatever the view.
  std::vector<size_t> Chunks(const std::vector<unsigned char>& mask, size_t maxPixels) const;

private:
  friend class PackedWalk;

  // Calls visit(row start in the image, pixels in the row) for each row of tile t.
  template <class Visit>
  void ForEachRow(size_t t, Visit visit) const;

  int Width = 0;
  int I0 = 0, J0 = 0, I1 = 0, J1 = 0;
  int TileSize = kDefaultTileSize;
  int TilesX = 0, TilesY = 0;
};

// The packed values of the marked tiles among tiles [first, last), in the order Pack packs
// them, walked a piece at a time: so that a packed buffer is made, sent and taken back one
// message at a time in a buffer of one message's size, not the whole chunk's (at 1024^2 the
// moments' wire is 20 MB a buffer, memory a first frame pages in afresh). Pieces may end
// inside a pixel; the next piece goes on from there.
class PackedWalk
{
public:
  PackedWalk(const TileGrid& grid, const std::vector<unsigned char>& mask, size_t first = 0,
    size_t last = static_cast<size_t>(-1));

  // Walks the next n values (fewer where the walk ends) and returns how many it walked: the
  // walk's i-th pixel (its index in the image: pixel) holds values(i) values, and visit(pixel,
  // i, k0, k1, at) is called for its values [k0, k1) in this piece, which sit at [at, at + k1 -
  // k0) of the piece. Pixels with no values are passed over.
  template <class Values, class Visit>
  size_t Next(size_t n, Values values, Visit visit);

  // The same for pixels of components values each, a row's run at a time: visit(start,
  // count, at) for values [start, start + count) of the full image (pixel * components + k),
  // which sit at [at, at + count) of the piece. For plain copies, which then run over whole
  // rows as Pack's do.
  template <class Visit>
  size_t NextSpans(size_t n, int components, Visit visit);

  bool Done() const { return this->Tile >= this->End; }

private:
  void EnterTile(); // the rows of tile Tile, or the next marked tile after it
  void NextPixel();

  const TileGrid* Grid;
  const std::vector<unsigned char>* Mask;
  size_t Tile;
  size_t End;
  int I = 0, J = 0;   // the pixel walked (column, row of the image)
  int I0 = 0, I1 = 0; // the tile's columns
  int J1 = 0;         // its rows' end
  size_t Index = 0;   // the pixel's index in the walk
  size_t Value = 0;   // its values walked already
};

//------------------------------------------------------------------------------
template <class Values, class Visit>
size_t PackedWalk::Next(size_t n, Values values, Visit visit)
{
  size_t at = 0;
  while (at < n && !this->Done())
  {
    const size_t count = static_cast<size_t>(values(this->Index));
    if (this->Value < count)
    {
      const size_t k1 = std::min(count, this->Value + (n - at));
      visit(static_cast<size_t>(this->J) * this->Grid->Width + this->I, this->Index, this->Value,
        k1, at);
      at += k1 - this->Value;
      this->Value = k1;
      if (k1 < count)
      {
        break; // the piece ends inside this pixel
      }
    }
    this->NextPixel();
  }
  return at;
}

template <class Visit>
size_t PackedWalk::NextSpans(size_t n, int components, Visit visit)
{
  const size_t c = static_cast<size_t>(components);
  size_t at = 0;
  while (at < n && !this->Done())
  {
    const size_t row = static_cast<size_t>(this->I1 - this->I) * c - this->Value;
    const size_t take = std::min(row, n - at);
    const size_t pixel = static_cast<size_t>(this->J) * this->Grid->Width + this->I;
    visit(pixel * c + this->Value, take, at);
    at += take;
    const size_t walked = this->Value + take;
    this->I += static_cast<int>(walked / c);
    this->Index += walked / c;
    this->Value = walked % c;
    if (this->I == this->I1)
    {
      // The row's last pixel is whole: NextPixel moves on from it.
      --this->I;
      --this->Index;
      this->NextPixel();
    }
  }
  return at;
}

template <class Visit>
void TileGrid::ForEachRow(size_t t, Visit visit) const
{
  const int ti = static_cast<int>(t % this->TilesX);
  const int tj = static_cast<int>(t / this->TilesX);
  const int i0 = this->I0 + ti * this->TileSize;
  const int i1 = i0 + this->TileSize < this->I1 ? i0 + this->TileSize : this->I1;
  const int j0 = this->J0 + tj * this->TileSize;
  const int j1 = j0 + this->TileSize < this->J1 ? j0 + this->TileSize : this->J1;
  for (int j = j0; j < j1; ++j)
  {
    visit(static_cast<size_t>(j) * this->Width + i0, static_cast<size_t>(i1 - i0));
  }
}

template <class Predicate>
std::vector<unsigned char> TileGrid::Mark(Predicate pixelIsCovered) const
{
  std::vector<unsigned char> mask(this->Tiles(), 0);
  for (size_t t = 0; t < mask.size(); ++t)
  {
    this->ForEachRow(t,
      [&](size_t first, size_t count)
      {
        for (size_t p = first; p < first + count && !mask[t]; ++p)
        {
          mask[t] = pixelIsCovered(p) ? 1 : 0;
        }
      });
  }
  return mask;
}

template <class Visit>
void TileGrid::ForEachPacked(
  const std::vector<unsigned char>& mask, Visit visit, size_t first, size_t last) const
{
  for (size_t t = first; t < mask.size() && t < last; ++t)
  {
    if (mask[t])
    {
      this->ForEachRow(t,
        [&](size_t start, size_t count)
        {
          for (size_t p = start; p < start + count; ++p)
          {
            visit(p);
          }
        });
    }
  }
}

template <class Packed, class Full>
void TileGrid::Pack(const std::vector<unsigned char>& mask, const Full* full, int components,
  Packed* packed, size_t first, size_t last) const
{
  for (size_t t = first; t < mask.size() && t < last; ++t)
  {
    if (mask[t])
    {
      this->ForEachRow(t,
        [&](size_t first, size_t count)
        {
          const Full* row = full + first * components;
          for (size_t v = 0; v < count * components; ++v)
          {
            *packed++ = static_cast<Packed>(row[v]);
          }
        });
    }
  }
}

template <class Packed, class Full>
void TileGrid::Unpack(const std::vector<unsigned char>& mask, const Packed* packed, int components,
  Full* full, size_t first, size_t last) const
{
  for (size_t t = first; t < mask.size() && t < last; ++t)
  {
    if (mask[t])
    {
      this->ForEachRow(t,
        [&](size_t first, size_t count)
        {
          Full* row = full + first * components;
          for (size_t v = 0; v < count * components; ++v)
          {
            row[v] = static_cast<Full>(*packed++);
          }
        });
    }
  }
}

} // namespace apc

#endif
