// What the marcher does with the samples of one tile, one visitor per kind of image: the
// exact ordered blend, MBOIT's moments (pass 1) and colour sums (pass 2), segment counts and
// sort-last segments. A visitor sees BeginTile, then Segment (each ray/cell interval) and
// Sample (each lattice sample, with its transfer-function value) in any order, then EndTile,
// where it adds its tile into the image. Internal to the core's marcher.
#ifndef apcRayVisitors_h
#define apcRayVisitors_h

#include "apcDepthWarp.h"
#include "apcHybridTransmittance.h"
#include "apcMomentTransmittance.h"
#include "apcPowerMoments.h"
#include "apcRaySegments.h"
#include "apcResolve.h"
#include "apcSampleCache.h"
#include "apcTileBins.h"
#include "apcTransferTable.h"

#include <algorithm>
#include <atomic>
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
  void Segment(int, double, double) {}
};

struct SampleRecord
{
  int64_t K;
  float Absorbance;
  std::array<float, 3> Colour;
};

// Each pixel's samples of one tile, in arrival order; the base of the visitors that need
// whole rays in depth order.
struct PixelSampleLists : NoSegments
{
  std::vector<std::vector<SampleRecord>> Pixels;

  void BeginTile(const TileRect& tile) { ClearPixelLists(this->Pixels, tile.Pixels()); }
  void Sample(int pixel, int64_t k, double, double, const TransferSample& s)
  {
    this->Pixels[pixel].push_back({ k, s.Absorbance, s.Colour });
  }
  // Pixel p's samples in depth (lattice) order.
  std::vector<SampleRecord>& Sorted(int p)
  {
    auto& samples = this->Pixels[p];
    std::sort(samples.begin(), samples.end(),
      [](const SampleRecord& a, const SampleRecord& b) { return a.K < b.K; });
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
  double* Output;
  double* Own = nullptr;
  int Width;
  const LogDepthWarp* Warp;
  SampleCache* Cache;
  std::vector<double> Sums;
  // The tile's samples are recorded here, in the tile's own vector from the last frame taken
  // out of the cache at BeginTile and put back at EndTile: its capacity fits a static view's
  // samples, so recording neither grows nor copies. Pushing into the cache's vectors in place
  // made threads on neighbouring tiles write the same cache lines (the vectors' ends), which
  // cost pass 1 a sixth of its speed on 2 threads.
  std::vector<CachedSample> Recorded;
  bool Recording = false;

  Moments(double* output, int width, const LogDepthWarp* warp, SampleCache* cache)
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
      this->Recorded.swap(this->Cache->Tiles[tile.Index]);
    }
    this->Recorded.clear();
  }
  void Sample(int pixel, int64_t k, double t, double scalar, const TransferSample& s)
  {
    const double z = (*this->Warp)(t);
    AccumulatePowerMoments<N>(this->Sums.data() + pixel * (N + 1), z, s.Absorbance);
    if (this->Recording)
    {
      this->Recorded.push_back({ static_cast<float>(z), static_cast<float>(scalar),
        static_cast<uint16_t>(pixel), static_cast<uint16_t>(k) });
    }
  }
  void EndTile(const TileRect& tile)
  {
    if (this->Recording)
    {
      this->Cache->Tiles[tile.Index].swap(this->Recorded);
      if (this->Cache->Record)
      {
        this->Cache->Keep(tile.Index);
      }
      else
      {
        // Another tile found the budget spent: this one is not kept (and keeps no memory).
        this->Cache->Tiles[tile.Index] = std::vector<CachedSample>();
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

// MBOIT pass 2: colour weighted by alpha * T(z), T reconstructed from the global moments.
// Samples behind a pixel's hidden depth (MomentTransmittance::HiddenDepth(HiddenWeight)) are
// skipped: they weigh at most HiddenWeight together, and the depth comes from the global
// moments alone, so every process skips the same samples.
template <int N>
struct Colour : NoSegments
{
  static constexpr bool StopsWhenOpaque = true;
  // A cached sample as pass 2 reads it, grouped by pixel.
  struct DepthAndScalar
  {
    float Z;
    float Scalar;
  };

  double* Output;
  int Width;
  const LogDepthWarp* Warp;
  const double* GlobalMoments;
  MomentSettings<N> Settings;
  double HiddenWeight = 0;                // 0: every sample is weighted
  std::atomic<int64_t>* Hidden = nullptr; // samples skipped, added once per tile
  std::vector<MomentTransmittance<N>> Transmittance;
  std::vector<double> HiddenFrom; // per pixel of a marched tile; NaN until its first sample
  std::vector<ColourSums> Sums;
  int64_t TileHidden = 0;
  // ReplayTile's pixel grouping, kept from tile to tile.
  std::vector<uint32_t> Starts;
  std::vector<DepthAndScalar> Grouped;
  // One pixel's visible samples for MomentTransmittance::Weights.
  std::vector<double> Depths;
  std::vector<double> Absorbances;
  std::vector<std::array<float, 3>> Colours;
  std::vector<double> Weights;

  Colour(double* output, int width, const LogDepthWarp* warp, const double* moments,
    const MomentSettings<N>& settings)
    : Output(output)
    , Width(width)
    , Warp(warp)
    , GlobalMoments(moments)
    , Settings(settings)
  {
  }
  const double* MomentsOf(const TileRect& tile, int p) const
  {
    return this->GlobalMoments + (N + 1) * tile.ImagePixel(p, this->Width);
  }
  double HiddenDepth(const MomentTransmittance<N>& t) const
  {
    return this->HiddenWeight > 0 ? t.HiddenDepth(this->HiddenWeight)
                                  : std::numeric_limits<double>::infinity();
  }
  void BeginTile(const TileRect& tile)
  {
    this->Transmittance.clear();
    this->Transmittance.reserve(tile.Pixels());
    for (int p = 0; p < tile.Pixels(); ++p)
    {
      this->Transmittance.emplace_back(this->MomentsOf(tile, p), this->Settings);
    }
    this->HiddenFrom.assign(tile.Pixels(), std::numeric_limits<double>::quiet_NaN());
    this->Sums.assign(tile.Pixels(), ColourSums());
    this->TileHidden = 0;
  }
  void Sample(int pixel, int64_t, double t, double, const TransferSample& s)
  {
    double& hiddenFrom = this->HiddenFrom[pixel];
    if (std::isnan(hiddenFrom))
    {
      hiddenFrom = this->HiddenDepth(this->Transmittance[pixel]);
    }
    const double z = (*this->Warp)(t);
    if (z >= hiddenFrom)
    {
      ++this->TileHidden;
      return;
    }
    Add(this->Sums[pixel], this->Transmittance[pixel], z, s);
  }
  static void Add(ColourSums& sums, const MomentTransmittance<N>& transmittance, double z,
    const TransferSample& s)
  {
    const double alpha = -std::expm1(-static_cast<double>(s.Absorbance));
    sums.Add(alpha * transmittance(z),
      { static_cast<double>(s.Colour[0]), static_cast<double>(s.Colour[1]),
        static_cast<double>(s.Colour[2]) });
  }
  void EndTile(const TileRect& tile)
  {
    for (int p = 0; p < tile.Pixels(); ++p)
    {
      this->Write(tile, p, this->Sums[p]);
    }
    this->CountHidden();
  }
  void Write(const TileRect& tile, int p, const ColourSums& sums) const
  {
    double* out = this->Output + 4 * tile.ImagePixel(p, this->Width);
    for (int c = 0; c < 4; ++c)
    {
      out[c] += sums.Sums[c];
    }
  }
  void CountHidden()
  {
    if (this->Hidden && this->TileHidden > 0)
    {
      this->Hidden->fetch_add(this->TileHidden, std::memory_order_relaxed);
    }
    this->TileHidden = 0;
  }

  // Pass 2 of a tile from pass 1's cached samples. They are grouped by pixel first (a stable
  // counting sort, so each pixel sums in the order it did before), so that a pixel's
  // reconstruction is set up once, only for pixels with samples, and stays in registers.
  void ReplayTile(
    const TileRect& tile, const std::vector<CachedSample>& recorded, const TransferTable& table)
  {
    this->Group(tile, recorded);
    this->TileHidden = 0;
    for (int p = 0; p < tile.Pixels(); ++p)
    {
      const uint32_t begin = this->Starts[p];
      const uint32_t end = this->Starts[p + 1];
      if (begin == end)
      {
        continue;
      }
      const MomentTransmittance<N> transmittance(this->MomentsOf(tile, p), this->Settings);
      const double hiddenFrom = this->HiddenDepth(transmittance);
      // The pixel's visible samples looked up, then weighted all at once (vectorised).
      const size_t most = end - begin;
      if (this->Depths.size() < most)
      {
        this->Depths.resize(most);
        this->Absorbances.resize(most);
        this->Colours.resize(most);
        this->Weights.resize(most);
      }
      int count = 0;
      for (uint32_t i = begin; i < end; ++i)
      {
        const DepthAndScalar sample = this->Grouped[i];
        if (sample.Z >= hiddenFrom)
        {
          continue;
        }
        const TransferSample s = table.Lookup(sample.Scalar);
        this->Depths[count] = sample.Z;
        this->Absorbances[count] = s.Absorbance;
        this->Colours[count] = s.Colour;
        ++count;
      }
      this->TileHidden += static_cast<int64_t>(most) - count;
      transmittance.Weights(
        this->Depths.data(), this->Absorbances.data(), this->Weights.data(), count);
      ColourSums sums;
      for (int i = 0; i < count; ++i)
      {
        const std::array<float, 3>& c = this->Colours[i];
        sums.Add(this->Weights[i],
          { static_cast<double>(c[0]), static_cast<double>(c[1]), static_cast<double>(c[2]) });
      }
      this->Write(tile, p, sums);
    }
    this->CountHidden();
  }
  void Group(const TileRect& tile, const std::vector<CachedSample>& recorded)
  {
    const int pixels = tile.Pixels();
    this->Starts.assign(static_cast<size_t>(pixels) + 1, 0);
    for (const CachedSample& sample : recorded)
    {
      ++this->Starts[sample.Pixel + 1];
    }
    for (int p = 0; p < pixels; ++p)
    {
      this->Starts[p + 1] += this->Starts[p];
    }
    this->Grouped.resize(recorded.size());
    for (const CachedSample& sample : recorded)
    {
      this->Grouped[this->Starts[sample.Pixel]++] = { sample.Z, sample.Scalar };
    }
    // Starts[p] now holds pixel p's end: shift back to the starts.
    for (int p = pixels; p > 0; --p)
    {
      this->Starts[p] = this->Starts[p - 1];
    }
    this->Starts[0] = 0;
  }
};

// A pass-1 sample's place along its ray when only the cache holds it: its float depth (as an
// integer that orders like the float), then the low bits of its lattice index for depths that
// rounded to the same float. Consecutive samples differ in k by 1, so ties never span a wrap
// of the 16 bits unless 65536 samples share one float depth.
inline int64_t ReplayOrder(const CachedSample& sample)
{
  uint32_t bits = 0;
  std::memcpy(&bits, &sample.Z, sizeof(bits));
  bits = (bits & 0x80000000u) ? ~bits : (bits | 0x80000000u);
  return (static_cast<int64_t>(bits) << 16) | sample.K16;
}

// Hybrid pass 2 (apcHybridTransmittance.h): each pixel's own samples collected, sorted by
// their place along the ray and weighted by alpha T_own T_others, T_own the exact ordered
// product of the own samples in front, T_others reconstructed from global - own moments.
template <int N>
struct HybridColour : NoSegments
{
  static constexpr bool StopsWhenOpaque = true;
  struct OwnSample
  {
    int64_t Order; // lattice index k, or ReplayOrder for cached samples
    double Z;
    float Absorbance;
    std::array<float, 3> Colour;
  };

  double* Output;
  int Width;
  const LogDepthWarp* Warp;
  const double* GlobalMoments;
  const double* OwnMoments;
  MomentSettings<N> Settings;
  std::vector<std::vector<OwnSample>> Pixels;

  HybridColour(double* output, int width, const LogDepthWarp* warp, const double* global,
    const double* own, const MomentSettings<N>& settings)
    : Output(output)
    , Width(width)
    , Warp(warp)
    , GlobalMoments(global)
    , OwnMoments(own)
    , Settings(settings)
  {
  }
  void BeginTile(const TileRect& tile) { ClearPixelLists(this->Pixels, tile.Pixels()); }
  void Sample(int pixel, int64_t k, double t, double, const TransferSample& s)
  {
    this->Pixels[pixel].push_back({ k, (*this->Warp)(t), s.Absorbance, s.Colour });
  }
  void Replay(const CachedSample& sample, const TransferSample& s)
  {
    this->Pixels[sample.Pixel].push_back({ ReplayOrder(sample), sample.Z, s.Absorbance, s.Colour });
  }
  void ReplayTile(
    const TileRect& tile, const std::vector<CachedSample>& recorded, const TransferTable& table)
  {
    this->BeginTile(tile);
    for (const CachedSample& sample : recorded)
    {
      this->Replay(sample, table.Lookup(sample.Scalar));
    }
    this->EndTile(tile);
  }
  void EndTile(const TileRect& tile)
  {
    for (int p = 0; p < tile.Pixels(); ++p)
    {
      auto& samples = this->Pixels[p];
      if (samples.empty())
      {
        continue;
      }
      std::sort(samples.begin(), samples.end(),
        [](const OwnSample& a, const OwnSample& b) { return a.Order < b.Order; });
      const size_t at = static_cast<size_t>(tile.ImagePixel(p, this->Width));
      const OthersTransmittance<N> others(
        this->GlobalMoments + (N + 1) * at, this->OwnMoments + (N + 1) * at, this->Settings);
      OwnTransmittance own;
      ColourSums sums;
      for (const OwnSample& s : samples)
      {
        const double weight = own.Weight(static_cast<double>(s.Absorbance));
        sums.Add(others.IsEmpty() ? weight : weight * others(s.Z),
          { static_cast<double>(s.Colour[0]), static_cast<double>(s.Colour[1]),
            static_cast<double>(s.Colour[2]) });
      }
      double* out = this->Output + 4 * at;
      for (int c = 0; c < 4; ++c)
      {
        out[c] += sums.Sums[c];
      }
    }
  }
};

// Number of disjoint intervals of each ray inside the cells.
struct SegmentCounts
{
  static constexpr bool StopsWhenOpaque = false;
  static constexpr bool WantsSegments = true;
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
