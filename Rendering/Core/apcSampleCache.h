// Pass 1's samples kept for pass 2, per screen tile and grouped by pixel, so that pass 2 only
// re-weights them instead of clipping and interpolating again (re-weighting a cached sample
// costs a small fraction of finding and interpolating it).
#ifndef apcSampleCache_h
#define apcSampleCache_h

#include "apcSampleArena.h"
#include "apcUninitialized.h"

#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace apc
{

class TransferTable;

// The budget of a process whose user set none: a quarter of its node's physical memory,
// divided among the processes on the node (at least one), so that the ranks of a node
// together never let their caches take more than that. A quarter leaves the meshes, the
// buffers and other programs room, and holds a 1024^2 view of a million-cell mesh on one
// rank of a small workstation. Unknown memory (0): 1 GiB.
inline size_t NodeShareOfMemory(uint64_t nodeBytes, int processesOnNode)
{
  if (nodeBytes == 0)
  {
    return size_t(1) << 30;
  }
  return static_cast<size_t>(nodeBytes / 4 / static_cast<uint64_t>(std::max(1, processesOnNode)));
}

// One pass-1 sample as the cache keeps it: its warped depth and its scalar (the transfer
// table interpolates between entries, so the scalar itself, not an entry index, is what pass
// 2 needs to look up the same colour and absorbance). Its pixel is its place in the tile.
struct CachedSample
{
  float Z;
  float Scalar;
};
static_assert(sizeof(CachedSample) == 8, "a cached sample is two floats");

// A tile's records in the cache's arena.
struct SampleSpan
{
  CachedSample* Data = nullptr;
  size_t Size = 0;

  CachedSample* data() const { return this->Data; }
  size_t size() const { return this->Size; }
  bool empty() const { return this->Size == 0; }
  CachedSample& operator[](size_t i) const { return this->Data[i]; }
};

// A tile's lattice bits (CachedTile::K16) in the cache's arena, after its samples.
struct OrderSpan
{
  uint16_t* Data = nullptr;
  size_t Size = 0;

  uint16_t* data() const { return this->Data; }
  size_t size() const { return this->Size; }
  uint16_t& operator[](size_t i) const { return this->Data[i]; }
  void resize(size_t n) { this->Size = std::min(n, this->Size); } // only ever shrinks
};

// A tile's end weights (CachedTile::Weights) in the cache's arena, after its lattice bits.
struct WeightSpan
{
  float* Data = nullptr;
  size_t Size = 0;

  float* data() const { return this->Data; }
  size_t size() const { return this->Size; }
  bool empty() const { return this->Size == 0; }
  float& operator[](size_t i) const { return this->Data[i]; }
  void resize(size_t n) { this->Size = std::min(n, this->Size); } // only ever shrinks
};

// A tile's samples grouped by pixel: pixel p's are Samples[Starts[p] .. Starts[p + 1]), in
// the order pass 1 took them. K16, kept only for a pass 1 that keeps its own moments
// (Hybrid), holds the low 16 bits of each sample's lattice index, which order the samples of
// a pixel whose float depths tie, for the Hybrid resolve's exact own transmittance. The
// samples and K16 live in the cache's arena (huge pages, refilled frame after frame: per-tile
// vectors of K16 took ~13,000 fresh 4 KiB pages on the first 1024^2 wind frame); Starts keeps
// its memory from frame to frame. Weights, kept only for a pass 1 with end weights
// (apcEndWeights.h), holds each sample's weight, by which pass 2 multiplies the absorbance
// it looks up (the same float product pass 1 took).
struct CachedTile
{
  UninitializedVector<uint32_t> Starts;
  SampleSpan Samples;
  OrderSpan K16;
  WeightSpan Weights;

  // K16's room in the arena after n samples (whole 8-byte words: the arena's unit).
  static size_t OrderBytes(size_t n) { return (n * sizeof(uint16_t) + 7) / 8 * 8; }
  static size_t WeightBytes(size_t n) { return (n * sizeof(float) + 7) / 8 * 8; }
  size_t Bytes() const
  {
    return this->Starts.capacity() * sizeof(uint32_t) +
      this->Samples.size() * sizeof(CachedSample) + OrderBytes(this->K16.size()) +
      WeightBytes(this->Weights.size());
  }
  void Clear()
  {
    this->Starts.clear();
    this->Samples = SampleSpan();
    this->K16 = OrderSpan();
    this->Weights = WeightSpan();
  }
  void Free() { *this = CachedTile(); }
};

// A sample as pass 1 records it while its tile is marched, before the tile's samples are
// grouped by pixel into the cache.
struct RecordedSample
{
  float Z;
  float Scalar;
  uint16_t Pixel;
  uint16_t K16;
};

// A thread's samples of the tile it marches, before they are grouped by pixel, with each
// pixel's count. Owned by the cache so that it keeps its memory from frame to frame. The
// records are not value-initialised: a zeroed record (a store of bytes, which may alias any
// object) made the marcher reload its visitor's and the depth warp's fields for every sample.
// Recorded's size is the room: the tile's records are its first Used, so that a run of
// samples (Moments::RunBegin) takes room for all of them with one test, and a tile starts
// without writing the room it reuses.
struct RecordBuffer
{
  UninitializedVector<RecordedSample> Recorded;
  size_t Used = 0;
  std::vector<uint32_t> Counts;
  // With end weights: each record's weight, by index (Weigh), apart from the records so that
  // a pass 1 without them writes and moves no more bytes per sample.
  UninitializedVector<float> Weights;

  // Record Used's weight (before Room(1) takes it).
  void Weigh(float weight)
  {
    this->WeighUpTo(this->Used + 1);
    this->Weights[this->Used] = weight;
    this->WeighedEnd = std::max(this->WeighedEnd, this->Used + 1);
  }
  // Weights for at least the first n records, those not weighed yet 1: with Sample End
  // Weights = Boundary the cells away from the boundary record plain samples (weight 1,
  // never weighed) between the weighted ones.
  void WeighUpTo(size_t n)
  {
    if (this->Weights.size() < n)
    {
      const size_t old = this->Weights.size();
      this->Weights.resize(std::max(this->Recorded.size(), n));
      std::fill(
        this->Weights.begin() + static_cast<std::ptrdiff_t>(old), this->Weights.end(), 1.0f);
    }
  }
  // After a tile: the weights it wrote 1 again for the next.
  void ResetWeights()
  {
    std::fill(this->Weights.begin(),
      this->Weights.begin() +
        static_cast<std::ptrdiff_t>(std::min(this->WeighedEnd, this->Weights.size())),
      1.0f);
    this->WeighedEnd = 0;
  }
  // One past the last weight written since ResetWeights.
  size_t WeighedEnd = 0;

  // Room for n records past the Used ones (grown, keeping those, where there is less).
  RecordedSample* Room(size_t n)
  {
    if (this->Recorded.size() - this->Used < n)
    {
      this->Grow(n);
    }
    return this->Recorded.data() + this->Used;
  }
  [[gnu::noinline]] void Grow(size_t n)
  {
    this->Recorded.resize(std::max(2 * this->Recorded.size(), this->Used + n + 4096));
  }
};

struct SampleCache
{
  std::vector<CachedTile> Tiles;
  SampleArena Arena;
  tbb::enumerable_thread_specific<RecordBuffer> Buffers;
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
      tile.Clear();
    }
    std::fill(this->Kept.begin(), this->Kept.end(), uint8_t(0));
  }
  // Ready to record tiles [first, last) of a frame of this many tiles. The other tiles' memory
  // goes (a large frame is rendered band by band: one band's samples at a time, each band
  // in the arena's pages the one before touched).
  void Empty(size_t tiles, size_t first, size_t last)
  {
    this->Clear();
    this->Tiles.resize(tiles);
    for (size_t t = 0; t < tiles; ++t)
    {
      if ((t < first || t >= last) && this->Tiles[t].Bytes() > 0)
      {
        this->Tiles[t].Free();
      }
    }
    this->Kept.assign(tiles, 0);
    this->Bytes = 0;
    if (this->MaxBytes > 0)
    {
      this->Arena.Reserve(this->MaxBytes);
    }
    this->Arena.Reset();
    this->Record = this->MaxBytes > 0 && this->Arena.Capacity() > 0;
  }
  // Gives every byte back (a lower budget).
  void Release()
  {
    this->Tiles = std::vector<CachedTile>();
    this->Kept.clear();
    this->Valid = false;
    this->Arena.Release();
    this->Buffers.clear();
  }
  // The counting sort's slots: slots[at] is the record that goes to slot at (starts[p] ends at
  // pixel p's end). A (cell, ray) pair's samples arrive together, so the records come in runs
  // of one pixel: a run's slot is kept in a register, not incremented in starts[] per sample,
  // whose store and reload chained every sample of a run to the one before.
  static void Slots(const RecordedSample* recorded, size_t n, uint32_t* starts, uint32_t* slots)
  {
    uint32_t r = 0;
    const uint32_t end = static_cast<uint32_t>(n);
    while (r < end)
    {
      const uint16_t pixel = recorded[r].Pixel;
      uint32_t at = starts[pixel];
      do
      {
        slots[at++] = r++;
      } while (r < end && recorded[r].Pixel == pixel);
      starts[pixel] = at;
    }
  }
  // The records in slot order, written front to back. The cache's memory is far larger than
  // the processor's caches, so its lines are not there when a frame writes them again: the
  // records scattered straight to their pixels' slots (a stream per pixel) waited on a read
  // of each line before its write. Written in order, by streaming stores, whole lines go out
  // without being read. The caller fences (StreamFence) before the samples are read.
  template <bool WithOrder, bool WithWeights = false>
  static void Copy(const RecordedSample* recorded, const uint32_t* slots, size_t n,
    CachedSample* samples, uint16_t* order, const float* weights = nullptr,
    float* weightsOut = nullptr)
  {
    static_assert(offsetof(RecordedSample, Z) == offsetof(CachedSample, Z) &&
        offsetof(RecordedSample, Scalar) == offsetof(CachedSample, Scalar),
      "a record begins with its cached sample");
    size_t at = 0;
#ifdef __SSE2__
    // Four samples (and their four lattice bits: 8 bytes, at an 8-byte boundary since the
    // arena's unit is 8 bytes) at a time.
    for (; at + 4 <= n; at += 4)
    {
      uint64_t k16 = 0;
      for (size_t j = 0; j < 4; ++j)
      {
        const RecordedSample& r = recorded[slots[at + j]];
        long long bits;
        std::memcpy(&bits, &r, sizeof bits);
        _mm_stream_si64(reinterpret_cast<long long*>(samples + at + j), bits);
        k16 |= static_cast<uint64_t>(r.K16) << (16 * j);
        if (WithWeights)
        {
          weightsOut[at + j] = weights[slots[at + j]];
        }
      }
      if (WithOrder)
      {
        _mm_stream_si64(reinterpret_cast<long long*>(order + at), static_cast<long long>(k16));
      }
    }
#endif
    for (; at < n; ++at)
    {
      const RecordedSample& r = recorded[slots[at]];
      samples[at] = { r.Z, r.Scalar };
      if (WithOrder)
      {
        order[at] = r.K16;
      }
      if (WithWeights)
      {
        weightsOut[at] = weights[slots[at]];
      }
    }
  }
  // Orders Copy's streaming stores before any later store (the tile's Kept flag, and what
  // the threads' join publishes).
  static void StreamFence()
  {
#ifdef __SSE2__
    _mm_sfence();
#endif
  }
  // Groups a marched tile's recorded samples by pixel into Tiles[tile] (counts[p]: pixel p's
  // samples among them; withOrder: keep the lattice bits; weights, if not null: each record's
  // end weight, kept too) if they fit in the budget; else frees the tile's memory and stops
  // the recording.
  void Keep(size_t tile, const std::vector<RecordedSample>& recorded, const uint32_t* counts,
    int pixels, bool withOrder)
  {
    this->Keep(tile, recorded.data(), recorded.size(), counts, pixels, withOrder);
  }
  // The same for the records recorded[0, n).
  void Keep(size_t tile, const RecordedSample* recorded, size_t n, const uint32_t* counts,
    int pixels, bool withOrder, const float* weights = nullptr)
  {
    CachedTile& cached = this->Tiles[tile];
    if (n == 0)
    {
      // Nothing to replay: no memory (a tile of transparent or no cells, on every mesh).
      cached.Free();
      this->Kept[tile] = 1;
      return;
    }
    cached.Clear();
    cached.Starts.resize(static_cast<size_t>(pixels) + 1);
    const size_t orderBytes = withOrder ? CachedTile::OrderBytes(n) : 0;
    const size_t weightBytes = weights ? CachedTile::WeightBytes(n) : 0;
    const size_t arenaBytes = n * sizeof(CachedSample) + orderBytes + weightBytes;
    const size_t bytes = cached.Bytes() + arenaBytes;
    CachedSample* memory = nullptr;
    if (this->Bytes.fetch_add(bytes) + bytes > this->MaxBytes ||
      !(memory = static_cast<CachedSample*>(this->Arena.Take(arenaBytes))))
    {
      this->Bytes.fetch_sub(bytes);
      this->Record = false;
      cached.Free();
      return;
    }
    cached.Samples = { memory, n };
    if (withOrder)
    {
      cached.K16 = { reinterpret_cast<uint16_t*>(memory + n), n };
    }
    if (weights)
    {
      cached.Weights = { reinterpret_cast<float*>(reinterpret_cast<char*>(memory + n) + orderBytes),
        n };
    }
    // A stable counting sort: each pixel's samples stay in the order they were taken.
    uint32_t* starts = cached.Starts.data();
    starts[0] = 0;
    for (int p = 0; p < pixels; ++p)
    {
      starts[p + 1] = starts[p] + counts[p];
    }
    // Slot by slot: which record goes where (in a thread's own scratch, which stays in the
    // processor's cache), then the records in that order.
    thread_local std::vector<uint32_t> slots;
    if (slots.size() < n)
    {
      slots.resize(std::max(n, 2 * slots.size()));
    }
    Slots(recorded, n, starts, slots.data());
    if (weights)
    {
      if (withOrder)
      {
        Copy<true, true>(recorded, slots.data(), n, cached.Samples.data(), cached.K16.data(),
          weights, cached.Weights.data());
      }
      else
      {
        Copy<false, true>(recorded, slots.data(), n, cached.Samples.data(), nullptr, weights,
          cached.Weights.data());
      }
    }
    else if (withOrder)
    {
      Copy<true>(recorded, slots.data(), n, cached.Samples.data(), cached.K16.data());
    }
    else
    {
      Copy<false>(recorded, slots.data(), n, cached.Samples.data(), nullptr);
    }
    StreamFence();
    // starts[p] now holds pixel p's end: shift back to the starts.
    for (int p = pixels; p > 0; --p)
    {
      starts[p] = starts[p - 1];
    }
    starts[0] = 0;
    this->Kept[tile] = 1;
  }
};

} // namespace apc

#endif
