// What the marcher does with the samples of one tile, one visitor per kind of image: the
// exact ordered blend, MBOIT's moments (pass 1) and colour sums (pass 2), segment counts and
// sort-last segments. A visitor sees BeginTile, then Segment (each ray/cell interval) and
// Sample (each lattice sample, with its transfer-function value) in any order, then EndTile,
// where it adds its tile into the image. Internal to the core's marcher.
#ifndef apcRayVisitors_h
#define apcRayVisitors_h

#include "apcDepthWarp.h"
#include "apcLaneMoments.h"
#include "apcPowerMoments.h"
#include "apcRaySegments.h"
#include "apcSampleCache.h"
#include "apcTileBins.h"
#include "apcTransferTable.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

namespace apc
{
namespace visitors
{

// One empty list per pixel of a tile; the lists keep their memory from tile to tile.
template <class List>
void ClearPixelLists(std::vector<List>& lists, int pixels)
{
  lists.resize(static_cast<size_t>(pixels));
  for (List& list : lists)
  {
    list.clear();
  }
}

// What a visitor needs from the walker. Transparent samples are passed on only if asked.
struct NoSegments
{
  static constexpr bool WantsSegments = false;
  static constexpr bool WantsSamples = true;
  static constexpr bool WantsTransparentSamples = false;
  // The MBOIT passes leave out what lies behind an opaque ray (VolumeRayMarcher::
  // SetOpaqueAbsorbance); the exact blend, the reference, takes every sample.
  static constexpr bool StopsWhenOpaque = false;
  // With end weights (apcEndWeights.h) the walker weights this visitor's samples.
  static constexpr bool TakesEndWeights = true;
  void Segment(int, double, double) {}
};

struct SampleRecord
{
  int64_t K;
  float Absorbance;
  std::array<float, 3> Colour;
};

// Depth order, and a fixed order among samples of one lattice point. Where cells overlap
// (faces that are not planar, pieces that overlap by rounding), two or three cells can sample
// the same lattice point, each with its own interpolated value. Blended in arrival order,
// which depends on the threads and on which cells a rank holds, such a pixel's colour changed
// from run to run and with the number of ranks; ordered by their values, such samples blend
// the same way on every run and rank count. The values are compared as bit patterns: a strict
// weak order even for NaN. ValuesBefore orders two samples of one lattice point (the exact
// blend's, the segments' and Hybrid's own samples), SampleBefore any two samples of a ray.
inline bool ValuesBefore(float absorbanceA, const std::array<float, 3>& colourA, float absorbanceB,
  const std::array<float, 3>& colourB)
{
  auto bits = [](float v)
  {
    uint32_t u;
    std::memcpy(&u, &v, sizeof u);
    return u;
  };
  const std::array<uint32_t, 4> x = { bits(absorbanceA), bits(colourA[0]), bits(colourA[1]),
    bits(colourA[2]) };
  const std::array<uint32_t, 4> y = { bits(absorbanceB), bits(colourB[0]), bits(colourB[1]),
    bits(colourB[2]) };
  return x < y;
}

inline bool SampleBefore(const SampleRecord& a, const SampleRecord& b)
{
  if (a.K != b.K)
  {
    return a.K < b.K;
  }
  return ValuesBefore(a.Absorbance, a.Colour, b.Absorbance, b.Colour);
}

// Each pixel's samples of one tile, in arrival order; the base of the visitors that need
// whole rays in depth order. These take the plain lattice, end weights or not: sort-last
// segments are runs of consecutive lattice points, and the middle sample of a pair without a
// lattice point, of a cell on another process, would have to go inside another process's run
// (end weights without those samples lose the slivers' length inside the mesh too); the exact
// blend takes what the segments take, so that the segments still equal it on every partition.
struct PixelSampleLists : NoSegments
{
  static constexpr bool TakesEndWeights = false;
  std::vector<std::vector<SampleRecord>> Pixels;

  void BeginTile(const TileRect& tile) { ClearPixelLists(this->Pixels, tile.Pixels()); }
  void Sample(int pixel, int64_t k, double, double, const TransferSample& s)
  {
    this->Pixels[pixel].push_back({ k, s.Absorbance, s.Colour });
  }
  // Pixel p's samples in depth (lattice) order, SampleBefore's.
  std::vector<SampleRecord>& Sorted(int p)
  {
    auto& samples = this->Pixels[p];
    std::sort(samples.begin(), samples.end(), SampleBefore);
    return samples;
  }
};

// Front-to-back blending of samples in depth order: the exact reference arithmetic, shared by
// the exact mode and the segments so that one segment equals the exact blend of its run.
struct FrontToBack
{
  double Transmittance = 1.0;
  double Colour[3] = { 0, 0, 0 };

  void Add(const SampleRecord& s)
  {
    const double alpha = -std::expm1(-static_cast<double>(s.Absorbance));
    for (int c = 0; c < 3; ++c)
    {
      this->Colour[c] += this->Transmittance * alpha * s.Colour[c];
    }
    this->Transmittance *= 1.0 - alpha;
  }
};

// Exact mode: each pixel's samples, sorted by lattice index and blended front to back.
struct Exact : PixelSampleLists
{
  float* Output;
  int Width;

  Exact(float* output, int width)
    : Output(output)
    , Width(width)
  {
  }
  void EndTile(const TileRect& tile)
  {
    for (int p = 0; p < tile.Pixels(); ++p)
    {
      if (this->Pixels[p].empty())
      {
        continue;
      }
      FrontToBack blend;
      for (const SampleRecord& s : this->Sorted(p))
      {
        blend.Add(s);
      }
      float* out = this->Output + 4 * tile.ImagePixel(p, this->Width);
      for (int c = 0; c < 3; ++c)
      {
        out[c] += static_cast<float>(blend.Colour[c]);
      }
      out[3] += static_cast<float>(1.0 - blend.Transmittance);
    }
  }
};

// MBOIT pass 1: power moments of the warped depth, and the samples kept for pass 2. Own, if
// set, gets the same sums (the Hybrid resolve's own moments).
template <int N>
struct Moments : NoSegments
{
  static constexpr bool StopsWhenOpaque = true;
  // Sample reads a TransferSample's absorbance, not its colour (the walker's lanes fill no
  // colour).
  static constexpr bool SamplesAbsorbanceOnly = true;
  double* Output;
  double* Own = nullptr;
  int Width;
  const LatticeDepthWarp* Warp;
  SampleCache* Cache;
  std::vector<double> Sums;
  // The tile's samples are recorded in this thread's own buffer (the cache's, kept from tile
  // to tile and frame to frame: it grows only until it holds the largest tile), with each
  // pixel's count, and grouped by pixel into the cache at EndTile. Pushing into the cache's
  // memory in place made threads on neighbouring tiles write the same cache lines, which cost
  // pass 1 a sixth of its speed on 2 threads.
  RecordBuffer* Buffer = nullptr;
  bool Recording = false;
  bool KeepOrder = false; // the cache keeps the lattice bits (the opaque cut reads them)
  bool Weighted = false;  // the samples come with end weights (WeightedSample), kept too

  Moments(double* output, int width, const LatticeDepthWarp* warp, SampleCache* cache)
    : Output(output)
    , Width(width)
    , Warp(warp)
    , Cache(cache)
  {
  }
  void BeginTile(const TileRect& tile)
  {
    this->Sums.assign(tile.Pixels() * (N + 1), 0.0);
    this->Recording = this->Cache && this->Cache->Record;
    if (this->Recording)
    {
      this->Buffer = &this->Cache->Buffers.local();
      this->Buffer->Used = 0;
      this->Buffer->Counts.assign(tile.Pixels(), 0);
    }
  }
  // The walker passes only visible samples (absorbance > 0; StopsWhenOpaque visitors take
  // no transparent ones), a table's absorbance is finite and the warp's depth lies in
  // [-1, 1]: AccumulatePowerMoments' checks would change nothing.
  [[gnu::always_inline]] void Sample(
    int pixel, int64_t k, double t, double scalar, const TransferSample& s)
  {
    const double z = (*this->Warp)(k, t);
    AccumulateCheckedPowerMoments<N>(this->Sums.data() + pixel * (N + 1), z, s.Absorbance);
    if (this->Recording)
    {
      // Written field by field in place: a record built on the stack and copied was read
      // back across its two 16-bit stores, which stalls store forwarding (a tenth of pass 1).
      RecordedSample& record = *this->Buffer->Room(1);
      ++this->Buffer->Used;
      record.Z = static_cast<float>(z);
      record.Scalar = static_cast<float>(scalar);
      record.Pixel = static_cast<uint16_t>(pixel);
      record.K16 = static_cast<uint16_t>(k);
      ++this->Buffer->Counts[pixel];
    }
  }
  // A sample with end weights (apcEndWeights.h): s's absorbance is already weight times the
  // table's; the cache keeps the weight, so that pass 2 takes the same product.
  [[gnu::always_inline]] void WeightedSample(
    int pixel, int64_t k, double t, double scalar, const TransferSample& s, float weight)
  {
    if (this->Recording)
    {
      this->Buffer->Weigh(weight);
    }
    this->Sample(pixel, k, t, scalar, s);
  }
  // A run of one pixel's samples at once (the walker's lanes): RunBegin, RunAdd for each
  // sample in lattice order, visible or not (absorbance 0: it adds nothing), and RunEnd to
  // keep what the run added (without it the run leaves nothing behind). The same sums,
  // records and counts, bit for bit, as Sample for each visible one in order: the pixel's
  // sums are read once and added to in the same order (adding an invisible sample's +-0
  // leaves a sum as it is: the sums start at +0 and never become -0), and the records are
  // written without a test of the buffer's room or of visibility per sample.
  struct Run
  {
    double B[N + 1];
    RecordedSample* Record;
    float* Weight; // with end weights (RunAddWeighted), each record's weight
    uint32_t Kept;
  };
  // A run of at most n samples of pixel; weighted: of end-weighted samples (RunAddWeighted).
  [[gnu::always_inline]] void RunBegin(Run& run, int pixel, int n, bool weighted = false)
  {
    const double* sums = this->Sums.data() + pixel * (N + 1);
    for (int m = 0; m <= N; ++m)
    {
      run.B[m] = sums[m];
    }
    run.Record = this->Recording ? this->Buffer->Room(static_cast<size_t>(n)) : nullptr;
    run.Weight = nullptr;
    if (weighted && run.Record)
    {
      // The weights' room follows the records' (RecordBuffer::Weigh).
      RecordBuffer& buffer = *this->Buffer;
      buffer.WeighUpTo(buffer.Recorded.size());
      buffer.WeighedEnd = std::max(buffer.WeighedEnd, buffer.Used + static_cast<size_t>(n));
      run.Weight = buffer.Weights.data() + buffer.Used;
    }
    run.Kept = 0;
  }
  // RunAdd of a sample with end weights (as WeightedSample): absorbance is already weight
  // times the table's; the record's weight is kept.
  [[gnu::always_inline]] void RunAddWeighted(
    Run& run, int pixel, int64_t k, double t, double scalar, float absorbance, float weight) const
  {
    if (run.Weight)
    {
      // Past the kept records the weights stay 1 (an invisible step's is not kept): with
      // Boundary a plain sample may be recorded there next, and weighs nothing itself.
      run.Weight[run.Kept] = absorbance > 0 ? weight : 1.0f;
    }
    this->RunAdd(run, pixel, k, t, scalar, absorbance);
  }
  [[gnu::always_inline]] void RunAdd(
    Run& run, int pixel, int64_t k, double t, double scalar, float absorbance) const
  {
    const double z = (*this->Warp)(k, t);
    AccumulateCheckedPowerMoments<N>(run.B, z, absorbance);
    if (run.Record)
    {
      RecordedSample& record = run.Record[run.Kept];
      record.Z = static_cast<float>(z);
      record.Scalar = static_cast<float>(scalar);
      record.Pixel = static_cast<uint16_t>(pixel);
      record.K16 = static_cast<uint16_t>(k);
    }
    run.Kept += absorbance > 0 ? 1u : 0u;
  }
  // A run not kept (RunEnd not called): the weights it wrote 1 again, for the plain samples
  // that may be recorded there next (Boundary).
  void RunDrop(const Run& run) const
  {
    if (run.Weight)
    {
      std::fill(run.Weight, run.Weight + run.Kept, 1.0f);
    }
  }
  [[gnu::always_inline]] void RunEnd(const Run& run, int pixel)
  {
    double* sums = this->Sums.data() + pixel * (N + 1);
    for (int m = 0; m <= N; ++m)
    {
      sums[m] = run.B[m];
    }
    if (run.Record)
    {
      this->Buffer->Used += run.Kept;
      this->Buffer->Counts[pixel] += run.Kept;
    }
  }
  // The lanes' hand-over four pixels at a time (walk::LaneMomentsAvx2, for 4 moments): the
  // walker reads each pixel's sums here and hands back each lane's run it keeps with
  // LaneRunEnd.
  static constexpr bool TakesLaneMoments = N == 4;
  const double* PixelSums(int pixel) const { return this->Sums.data() + pixel * (N + 1); }
  // Keeps lane's run of m (steps from lattice index k, pixel's; the call took taken steps): its
  // sums, and the records of its visible steps in order, as RunBegin, RunAdd per step and
  // RunEnd would. Weighted (walk::LaneWeightedMomentsAvx2's m): with each record's weight, as
  // RunBegin(weighted) and RunAddWeighted per step would.
  template <bool Weighted = false>
  [[gnu::always_inline]] void LaneRunEnd(int pixel, const walk::LaneMoments& m, int lane, int64_t k,
    const walk::LaneSteps& steps, int taken)
  {
    static_assert(N == 4, "the lanes' sums are four moments'");
    const uint64_t visible = static_cast<uint64_t>(m.Visible[lane]);
    if (visible == 0)
    {
      return; // adds nothing (+0 to each sum) and records nothing
    }
    double* sums = this->Sums.data() + pixel * (N + 1);
    for (int j = 0; j < 4; ++j)
    {
      sums[j] = m.Sums[lane][j];
    }
    sums[4] = m.Sum4[lane];
    if (this->Recording)
    {
      // Every step of the call written, the next record's place advanced only past a visible
      // one (as RunAdd does): the call's step count is the same in its four lanes, where a
      // loop over each lane's visible steps ended at a count the processor could not predict.
      RecordedSample* record = this->Buffer->Room(static_cast<size_t>(taken));
      float* weight = nullptr;
      if constexpr (Weighted)
      {
        // The weights' room follows the records' (RunBegin's); past the kept records the
        // weights stay 1 (an invisible step's record weight is 1).
        RecordBuffer& buffer = *this->Buffer;
        buffer.WeighUpTo(buffer.Recorded.size());
        buffer.WeighedEnd = std::max(buffer.WeighedEnd, buffer.Used + static_cast<size_t>(taken));
        weight = buffer.Weights.data() + buffer.Used;
      }
      uint32_t kept = 0;
      for (int s = 0; s < taken; ++s)
      {
        record[kept].Z = m.Z[s][lane];
        record[kept].Scalar = static_cast<float>(steps.Scalar[s][lane]);
        record[kept].Pixel = static_cast<uint16_t>(pixel);
        record[kept].K16 = static_cast<uint16_t>(k + s);
        if constexpr (Weighted)
        {
          weight[kept] = m.Weight[s][lane];
        }
        kept += static_cast<uint32_t>(visible >> s & 1);
      }
      this->Buffer->Used += kept;
      this->Buffer->Counts[pixel] += kept;
    }
  }
  void EndTile(const TileRect& tile)
  {
    if (this->Recording)
    {
      if (this->Cache->Record)
      {
        if (this->Weighted)
        {
          this->Buffer->WeighUpTo(this->Buffer->Used);
        }
        // Own moments mean a Hybrid pass 2, which orders tied depths by the lattice bits.
        this->Cache->Keep(tile.Index, this->Buffer->Recorded.data(), this->Buffer->Used,
          this->Buffer->Counts.data(), tile.Pixels(), this->Own != nullptr || this->KeepOrder,
          this->Weighted ? this->Buffer->Weights.data() : nullptr);
      }
      else
      {
        // Another tile found the budget spent: this one is not kept (and keeps no memory).
        this->Cache->Tiles[tile.Index].Free();
      }
      if (this->Weighted)
      {
        this->Buffer->ResetWeights();
      }
    }
    for (int p = 0; p < tile.Pixels(); ++p)
    {
      const size_t at = (N + 1) * tile.ImagePixel(p, this->Width);
      AddPowerMoments<N>(this->Output + at, this->Sums.data() + p * (N + 1));
      if (this->Own)
      {
        AddPowerMoments<N>(this->Own + at, this->Sums.data() + p * (N + 1));
      }
    }
  }
};

// Number of disjoint intervals of each ray inside the cells.
struct SegmentCounts
{
  static constexpr bool StopsWhenOpaque = false;
  static constexpr bool WantsSegments = true;
  static constexpr bool TakesEndWeights = false; // no samples
  static constexpr bool WantsSamples = false;
  static constexpr bool WantsTransparentSamples = false;
  int32_t* Output;
  int Width;
  double Tolerance;
  std::vector<std::vector<std::pair<double, double>>> Pixels;

  SegmentCounts(int32_t* output, int width, double tolerance)
    : Output(output)
    , Width(width)
    , Tolerance(tolerance)
  {
  }
  void BeginTile(const TileRect& tile) { ClearPixelLists(this->Pixels, tile.Pixels()); }
  void Segment(int pixel, double tin, double tout) { this->Pixels[pixel].emplace_back(tin, tout); }
  void Sample(int, int64_t, double, double, const TransferSample&) {}
  void EndTile(const TileRect& tile)
  {
    for (int p = 0; p < tile.Pixels(); ++p)
    {
      auto& intervals = this->Pixels[p];
      std::sort(intervals.begin(), intervals.end());
      int32_t count = 0;
      double end = -std::numeric_limits<double>::infinity();
      for (const auto& interval : intervals)
      {
        // Neighbouring cells share their face planes exactly, so a gap below a tiny fraction
        // of the mesh size is rounding, not empty space.
        if (interval.first > end + this->Tolerance)
        {
          ++count;
        }
        end = std::max(end, interval.second);
      }
      this->Output[tile.ImagePixel(p, this->Width)] += count;
    }
  }
};

// The segments of one tile, pixel by pixel in the tile's order.
struct TileSegments
{
  std::vector<int32_t> Counts;
  std::vector<RaySegment> Segments;
};

// Sort-last segments: each pixel's samples sorted by k and cut into runs of consecutive k.
// Transparent samples are taken too (they keep a run going), so that a run ends only where
// the ray leaves this mesh's cells, whatever the transfer function.
struct Runs : PixelSampleLists
{
  static constexpr bool WantsTransparentSamples = true;
  std::vector<TileSegments>* Tiles;

  explicit Runs(std::vector<TileSegments>* tiles)
    : Tiles(tiles)
  {
  }
  void EndTile(const TileRect& tile)
  {
    TileSegments& out = (*this->Tiles)[tile.Index];
    out.Counts.assign(tile.Pixels(), 0);
    out.Segments.clear();
    for (int p = 0; p < tile.Pixels(); ++p)
    {
      if (!this->Pixels[p].empty())
      {
        out.Counts[p] = this->CutRuns(this->Sorted(p), out.Segments);
      }
    }
  }
  // Appends the visible runs of one pixel's sorted samples; returns how many.
  static int32_t CutRuns(const std::vector<SampleRecord>& samples, std::vector<RaySegment>& out)
  {
    int32_t count = 0;
    RaySegment run{ samples.front().K, samples.front().K, { 0, 0, 0 }, 1.0f };
    FrontToBack blend;
    bool visible = false;
    auto flush = [&]
    {
      if (visible)
      {
        run.Colour = { static_cast<float>(blend.Colour[0]), static_cast<float>(blend.Colour[1]),
          static_cast<float>(blend.Colour[2]) };
        run.Transmittance = static_cast<float>(blend.Transmittance);
        out.push_back(run);
        ++count;
      }
    };
    for (const SampleRecord& s : samples)
    {
      if (s.K > run.KLast + 1)
      {
        flush();
        run.KFirst = s.K;
        blend = FrontToBack();
        visible = false;
      }
      run.KLast = s.K;
      // Not (a > 0) also covers NaN scalars, whose colour must not reach the sums.
      if (!(s.Absorbance > 0))
      {
        continue;
      }
      blend.Add(s);
      visible = true;
    }
    flush();
    return count;
  }
};

} // namespace visitors
} // namespace apc

#endif
