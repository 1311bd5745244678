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
#include <type_traits>
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

// A compact tile's depth slot for a sample whose depth or weight the slot cannot hold: its
// record is the tile's next escape (CompactSpan::Escapes, in sample order).
constexpr uint16_t kEscapedDepth = 0xFFFF;

// A sample of a compact tile kept whole: a depth that is not the depth table's entry for its
// lattice bits (a pair's middle sample, a jittered ray, a depth outside the table), or an end
// weight other than 1.
struct EscapedSample
{
  float Z;
  float Weight;
  uint16_t K16;
  uint16_t Unused;
};
static_assert(sizeof(EscapedSample) == 12, "an escape is two floats and the lattice bits");

// A tile's samples in compact form (SampleCache::SetDepthTable): each sample's scalar, and
// instead of its depth, its lattice bits and its end weight, the index of its depth in the
// frame's depth table, whose entry is that depth bit for bit and whose index gives back the
// lattice bits (the table's base plus the index, low 16 bits); the few samples the index
// cannot stand for are escapes. 6 bytes a sample instead of 8 + 2 (lattice bits) + 4 (end
// weight): pass 1 writes fewer bytes of fresh memory on the first frame, pass 2 reads fewer.
// Expanded (SampleCache::Expand) into exactly the samples, lattice bits and weights the full
// form holds.
struct CompactSpan
{
  float* Scalars = nullptr;
  uint16_t* Depths = nullptr; // index into the depth table, or kEscapedDepth
  EscapedSample* Escapes = nullptr;
  size_t Size = 0;
  size_t EscapeCount = 0;
  bool Ordered = false;  // kept with its lattice bits (K16)
  bool Weighted = false; // kept with end weights (Weights)
};

// A tile's samples grouped by pixel: pixel p's are Samples[Starts[p] .. Starts[p + 1]), in
// the order pass 1 took them. K16, kept only for a pass 1 that keeps its own moments
// (Hybrid), holds the low 16 bits of each sample's lattice index, which order the samples of
// a pixel whose float depths tie, for the Hybrid resolve's exact own transmittance. The
// samples and K16 live in the cache's arena (huge pages, refilled frame after frame: per-tile
// vectors of K16 took ~13,000 fresh 4 KiB pages on the first 1024^2 wind frame); Starts keeps
// its memory from frame to frame. Weights, kept only for a pass 1 with end weights
// (apcEndWeights.h), holds each sample's weight, by which pass 2 multiplies the absorbance
// it looks up (the same float product pass 1 took). A tile kept in compact form holds its
// samples in Compact instead (Samples, K16 and Weights empty).
struct CachedTile
{
  UninitializedVector<uint32_t> Starts;
  SampleSpan Samples;
  OrderSpan K16;
  WeightSpan Weights;
  CompactSpan Compact;

  // K16's room in the arena after n samples (whole 8-byte words: the arena's unit).
  static size_t OrderBytes(size_t n) { return (n * sizeof(uint16_t) + 7) / 8 * 8; }
  static size_t WeightBytes(size_t n) { return (n * sizeof(float) + 7) / 8 * 8; }
  static size_t EscapeBytes(size_t n) { return (n * sizeof(EscapedSample) + 7) / 8 * 8; }
  // A compact tile's room in the arena: scalars, depth indices, escapes.
  static size_t CompactBytes(size_t n, size_t escapes)
  {
    return WeightBytes(n) + OrderBytes(n) + EscapeBytes(escapes);
  }
  bool IsCompact() const { return this->Compact.Size > 0; }
  // The samples it holds, in either form.
  size_t Count() const { return this->Samples.size() + this->Compact.Size; }
  size_t Bytes() const
  {
    return this->Starts.capacity() * sizeof(uint32_t) +
      this->Samples.size() * sizeof(CachedSample) + OrderBytes(this->K16.size()) +
      WeightBytes(this->Weights.size()) +
      (this->IsCompact() ? CompactBytes(this->Compact.Size, this->Compact.EscapeCount) : 0);
  }
  void Clear()
  {
    this->Starts.clear();
    this->Samples = SampleSpan();
    this->K16 = OrderSpan();
    this->Weights = WeightSpan();
    this->Compact = CompactSpan();
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
  // The frame's depth table (SetDepthTable): DepthTable[i] is the float depth pass 1 records
  // for lattice index DepthBase + i. While it holds entries, tiles are kept in compact form
  // (CompactSpan) unless CompactRecords is off (the full form, for tests and measurements).
  std::vector<float> DepthTable;
  int64_t DepthBase = 0;
  bool CompactRecords = true;

  // The table from a frame's lattice warp (entries: warp of index base + i, as doubles, the
  // depths pass 1 rounds to float). The last index (kEscapedDepth) is never an entry. Set
  // before a frame records and kept until the next: Expand reads what Keep wrote with it.
  void SetDepthTable(const double* entries, int64_t count, int64_t base)
  {
    const size_t n = static_cast<size_t>(
      std::max<int64_t>(0, std::min<int64_t>(count, static_cast<int64_t>(kEscapedDepth))));
    this->DepthTable.resize(n);
    for (size_t i = 0; i < n; ++i)
    {
      this->DepthTable[i] = static_cast<float>(entries[i]);
    }
    this->DepthBase = base;
  }

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
  // A stable counting sort of a tile's n records by pixel (each pixel's samples stay in the
  // order they were taken): starts[p] set from the pixels' counts, then, slot by slot, which
  // record goes where (Slots; starts[p] then ends at pixel p's end), in a thread's own scratch,
  // which stays in the processor's cache. For Keep and KeepCompact alike.
  static const uint32_t* PixelSlots(
    const RecordedSample* recorded, size_t n, const uint32_t* counts, int pixels, uint32_t* starts)
  {
    starts[0] = 0;
    for (int p = 0; p < pixels; ++p)
    {
      starts[p + 1] = starts[p] + counts[p];
    }
    thread_local std::vector<uint32_t> slots;
    if (slots.size() < n)
    {
      slots.resize(std::max(n, 2 * slots.size()));
    }
    Slots(recorded, n, starts, slots.data());
    return slots.data();
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
    if (this->CompactRecords && !this->DepthTable.empty())
    {
      // Compact unless its escapes make it larger (a tile of jittered rays, say). Each
      // record's slot is found once, here, and read back by CopyCompact.
      thread_local UninitializedVector<uint16_t> depthSlots;
      if (depthSlots.size() < n)
      {
        depthSlots.resize(std::max(n, 2 * depthSlots.size()));
      }
      const size_t escapes = this->DepthSlots(recorded, n, weights, depthSlots.data());
      if (CachedTile::CompactBytes(n, escapes) < arenaBytes)
      {
        this->KeepCompact(
          tile, recorded, n, depthSlots.data(), escapes, counts, pixels, withOrder, weights);
        return;
      }
    }
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
    uint32_t* starts = cached.Starts.data();
    const uint32_t* slots = PixelSlots(recorded, n, counts, pixels, starts);
    if (weights)
    {
      if (withOrder)
      {
        Copy<true, true>(recorded, slots, n, cached.Samples.data(), cached.K16.data(), weights,
          cached.Weights.data());
      }
      else
      {
        Copy<false, true>(
          recorded, slots, n, cached.Samples.data(), nullptr, weights, cached.Weights.data());
      }
    }
    else if (withOrder)
    {
      Copy<true>(recorded, slots, n, cached.Samples.data(), cached.K16.data());
    }
    else
    {
      Copy<false>(recorded, slots, n, cached.Samples.data(), nullptr);
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

  // A record's slot in a compact tile: the index of its depth in the depth table, or
  // kEscapedDepth if the entry there is not its depth bit for bit or its weight is not 1 (the
  // table holds at most kEscapedDepth entries, so the low 16 bits of the index find the entry).
  static uint16_t DepthSlot(const RecordedSample& r, const float* table, uint32_t entries,
    uint16_t base16, const float* weight)
  {
    const uint16_t i = static_cast<uint16_t>(r.K16 - base16);
    uint32_t want = 0;
    uint32_t have = 0;
    if (i < entries)
    {
      std::memcpy(&want, &r.Z, sizeof want);
      std::memcpy(&have, table + i, sizeof have);
    }
    uint32_t w = 0x3f800000u; // 1.0f
    if (weight)
    {
      std::memcpy(&w, weight, sizeof w);
    }
    return i < entries && want == have && w == 0x3f800000u ? i : kEscapedDepth;
  }
  // Each of recorded[0, n)'s depth slot (DepthSlot) into depthSlots[0, n), in record order;
  // returns how many are escapes. The records are read in the order they were written, so
  // the loop streams; the slots are read back by the counting sort's order (CopyCompact),
  // which before looked each record's depth up a second time.
  size_t DepthSlots(
    const RecordedSample* recorded, size_t n, const float* weights, uint16_t* depthSlots) const
  {
    const float* table = this->DepthTable.data();
    const uint32_t entries = static_cast<uint32_t>(this->DepthTable.size());
    const uint16_t base16 = static_cast<uint16_t>(this->DepthBase);
    size_t escapes = 0;
    for (size_t r = 0; r < n; ++r)
    {
      const uint16_t slot =
        DepthSlot(recorded[r], table, entries, base16, weights ? weights + r : nullptr);
      depthSlots[r] = slot;
      escapes += slot == kEscapedDepth;
    }
    return escapes;
  }
  // Keep in compact form (the depth table set, the tile's Starts sized, each record's depth
  // slot in depthSlots (DepthSlots), escapes counted).
  void KeepCompact(size_t tile, const RecordedSample* recorded, size_t n,
    const uint16_t* depthSlots, size_t escapes, const uint32_t* counts, int pixels, bool withOrder,
    const float* weights)
  {
    CachedTile& cached = this->Tiles[tile];
    const size_t arenaBytes = CachedTile::CompactBytes(n, escapes);
    const size_t bytes = cached.Bytes() + arenaBytes;
    char* memory = nullptr;
    if (this->Bytes.fetch_add(bytes) + bytes > this->MaxBytes ||
      !(memory = static_cast<char*>(this->Arena.Take(arenaBytes))))
    {
      this->Bytes.fetch_sub(bytes);
      this->Record = false;
      cached.Free();
      return;
    }
    CompactSpan& compact = cached.Compact;
    compact.Scalars = reinterpret_cast<float*>(memory);
    compact.Depths = reinterpret_cast<uint16_t*>(memory + CachedTile::WeightBytes(n));
    compact.Escapes = reinterpret_cast<EscapedSample*>(
      memory + CachedTile::WeightBytes(n) + CachedTile::OrderBytes(n));
    compact.Size = n;
    compact.EscapeCount = escapes;
    compact.Ordered = withOrder;
    compact.Weighted = weights != nullptr;
    uint32_t* starts = cached.Starts.data();
    const uint32_t* slots = PixelSlots(recorded, n, counts, pixels, starts);
    if (weights)
    {
      CopyCompact<true>(recorded, slots, n, compact, depthSlots, weights);
    }
    else
    {
      CopyCompact<false>(recorded, slots, n, compact, depthSlots, nullptr);
    }
    StreamFence();
    for (int p = pixels; p > 0; --p)
    {
      starts[p] = starts[p - 1];
    }
    starts[0] = 0;
    this->Kept[tile] = 1;
  }
  // Copy's compact form: the scalars and depth slots (depthSlots, by record) written front to
  // back by streaming stores (four samples a step: two words of scalars, one of slots), the
  // escapes in order.
  template <bool WithWeights>
  static void CopyCompact(const RecordedSample* recorded, const uint32_t* slots, size_t n,
    CompactSpan& compact, const uint16_t* depthSlots, const float* weights)
  {
    float* scalars = compact.Scalars;
    uint16_t* depths = compact.Depths;
    EscapedSample* escape = compact.Escapes;
    auto slotOf = [&](uint32_t record, const RecordedSample& r)
    {
      const uint16_t slot = depthSlots[record];
      if (slot == kEscapedDepth)
      {
        *escape++ = { r.Z, WithWeights ? weights[record] : 1.0f, r.K16, 0 };
      }
      return slot;
    };
    size_t at = 0;
#ifdef __SSE2__
    for (; at + 4 <= n; at += 4)
    {
      uint64_t depthBits = 0;
      uint32_t scalarBits[4];
      for (size_t j = 0; j < 4; ++j)
      {
        const uint32_t record = slots[at + j];
        const RecordedSample& r = recorded[record];
        std::memcpy(scalarBits + j, &r.Scalar, sizeof(float));
        depthBits |= static_cast<uint64_t>(slotOf(record, r)) << (16 * j);
      }
      _mm_stream_si64(reinterpret_cast<long long*>(scalars + at),
        static_cast<long long>(scalarBits[0] | static_cast<uint64_t>(scalarBits[1]) << 32));
      _mm_stream_si64(reinterpret_cast<long long*>(scalars + at + 2),
        static_cast<long long>(scalarBits[2] | static_cast<uint64_t>(scalarBits[3]) << 32));
      _mm_stream_si64(reinterpret_cast<long long*>(depths + at), static_cast<long long>(depthBits));
    }
#endif
    for (; at < n; ++at)
    {
      const uint32_t record = slots[at];
      const RecordedSample& r = recorded[record];
      scalars[at] = r.Scalar;
      depths[at] = slotOf(record, r);
    }
  }
};

// Expand's samples and end weights (if kept) without the lattice bits, eight at a time
// (apcSampleCacheExpand.cpp); false, and nothing done, where the CPU lacks AVX2.
bool ExpandSamplesAvx2(
  const CompactSpan& compact, const float* table, CachedSample* samples, float* weights);

// A compact tile expanded into the full form (SampleCache::Expand): the samples, lattice bits
// and weights in this thread's scratch, which stays in the processor's cache from tile to tile.
struct ExpandedTile
{
  CachedTile View;
  UninitializedVector<CachedSample> Samples;
  UninitializedVector<uint16_t> Order;
  UninitializedVector<float> Weights;
};

// tile itself if it is in the full form, else its samples, lattice bits (if kept) and end
// weights (if kept) as the full form holds them, bit for bit, in scratch.View (valid until
// scratch's next Expand). table and base: the depth table the tile was kept with
// (SampleCache::DepthTable, DepthBase). withOrder false: no lattice bits in the view (a
// reader that never looks at them, as pass 2's colour, saves writing them).
inline const CachedTile& Expand(const CachedTile& tile, const std::vector<float>& table,
  int64_t base, ExpandedTile& scratch, bool withOrder = true)
{
  if (!tile.IsCompact())
  {
    return tile;
  }
  const CompactSpan& compact = tile.Compact;
  const size_t n = compact.Size;
  if (scratch.Samples.size() < n)
  {
    scratch.Samples.resize(n);
    scratch.Order.resize(n);
  }
  const bool weighted = compact.Weighted;
  if (weighted && scratch.Weights.size() < n)
  {
    scratch.Weights.resize(n);
  }
  const float* z = table.data();
  const uint16_t base16 = static_cast<uint16_t>(base);
  const EscapedSample* escape = compact.Escapes;
  CachedSample* samples = scratch.Samples.data();
  uint16_t* order = scratch.Order.data();
  float* weights = scratch.Weights.data();
  const auto expand = [&](auto ordered)
  {
    for (size_t s = 0; s < n; ++s)
    {
      const uint16_t slot = compact.Depths[s];
      if (slot != kEscapedDepth)
      {
        samples[s] = { z[slot], compact.Scalars[s] };
        if constexpr (decltype(ordered)::value)
        {
          order[s] = static_cast<uint16_t>(base16 + slot);
        }
        if (weighted)
        {
          weights[s] = 1.0f;
        }
      }
      else
      {
        samples[s] = { escape->Z, compact.Scalars[s] };
        if constexpr (decltype(ordered)::value)
        {
          order[s] = escape->K16;
        }
        if (weighted)
        {
          weights[s] = escape->Weight;
        }
        ++escape;
      }
    }
  };
  if (withOrder)
  {
    expand(std::true_type());
  }
  else if (!ExpandSamplesAvx2(compact, z, samples, weights))
  {
    expand(std::false_type());
  }
  CachedTile& view = scratch.View;
  view.Starts.assign(tile.Starts.begin(), tile.Starts.end());
  view.Samples = { samples, n };
  view.K16 = compact.Ordered && withOrder ? OrderSpan{ order, n } : OrderSpan();
  view.Weights = weighted ? WeightSpan{ weights, n } : WeightSpan();
  view.Compact = CompactSpan();
  return view;
}

} // namespace apc

#endif
