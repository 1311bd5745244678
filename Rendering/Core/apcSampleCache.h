// Pass 1's samples kept for pass 2, per screen tile, so that pass 2 only re-weights them
// instead of clipping and interpolating again (re-weighting a cached sample costs a small
// fraction of finding and interpolating it).
#ifndef apcSampleCache_h
#define apcSampleCache_h

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace apc
{

class TransferTable;

// One pass-1 sample: its warped depth, its scalar, its pixel in the tile, and the low 16 bits
// of its lattice index (in what was padding), which order the samples of a pixel whose float
// depths tie, for the Hybrid resolve's exact own transmittance.
struct CachedSample
{
  float Z;
  float Scalar;
  uint16_t Pixel;
  uint16_t K16;
};
static_assert(sizeof(CachedSample) == 12, "the lattice bits must not make the cache bigger");

struct SampleCache
{
  std::vector<std::vector<CachedSample>> Tiles;
  // Kept[t]: tile t's samples are all in the cache. The tiles recorded before the budget ran
  // out stay cached; pass 2 replays them and marches only the others again.
  std::vector<uint8_t> Kept;
  std::atomic<size_t> Bytes{ 0 };
  size_t MaxBytes = size_t(1) << 30;
  // Cleared by the first tile that does not fit: no tile records after it.
  std::atomic<bool> Record{ false };
  bool Valid = false;
  // What the samples were taken with: pass 2 replays them only if it uses the same.
  const TransferTable* Table = nullptr;
  double WarpNear = 0;
  double WarpFar = 0;
  int Moments = 0;

  // The samples go, the memory stays: refilling last frame's vectors costs no page faults
  // and no reallocation (at 1024^2 on the gear teeth, ~100 MB a frame).
  void Clear()
  {
    this->Valid = false;
    for (auto& tile : this->Tiles)
    {
      tile.clear();
    }
    std::fill(this->Kept.begin(), this->Kept.end(), uint8_t(0));
  }
  // Ready to record tiles [first, last) of a frame of this many tiles. The memory of the other
  // tiles goes (a large frame is rendered band by band: one band's samples at a time).
  void Empty(size_t tiles, size_t first, size_t last)
  {
    this->Clear();
    this->Tiles.resize(tiles);
    for (size_t t = 0; t < tiles; ++t)
    {
      if ((t < first || t >= last) && this->Tiles[t].capacity() > 0)
      {
        this->Tiles[t] = std::vector<CachedSample>();
      }
    }
    this->Kept.assign(tiles, 0);
    this->Bytes = 0;
    this->Record = this->MaxBytes > 0;
  }
  // Called by a tile that recorded all its samples into Tiles[tile]: keeps them if they fit
  // in the budget, else drops them and stops the recording.
  void Keep(size_t tile)
  {
    std::vector<CachedSample>& recorded = this->Tiles[tile];
    const size_t bytes = recorded.capacity() * sizeof(CachedSample);
    if (this->Bytes.fetch_add(bytes) + bytes > this->MaxBytes)
    {
      this->Bytes.fetch_sub(bytes);
      this->Record = false;
      recorded = std::vector<CachedSample>();
      return;
    }
    this->Kept[tile] = 1;
  }
};

} // namespace apc

#endif
