// MBOIT pass 2's visitors (see apcRayVisitors.h): the colour sums weighted by the transmittance
// reconstructed from the global moments, and Hybrid's, weighted by a process's own samples
// exactly and the others' by moments. Internal to the core's marcher.
#ifndef apcColourVisitors_h
#define apcColourVisitors_h

#include "apcHybridTransmittance.h"
#include "apcMomentTransmittance.h"
#include "apcPixelReplay.h"
#include "apcRayVisitors.h"
#include "apcResolve.h"

#include <algorithm>
#include <array>
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

// MBOIT pass 2: colour weighted by alpha * T(z), T reconstructed from the global moments.
// Samples behind a pixel's hidden depth (MomentTransmittance::HiddenDepth(HiddenWeight)) are
// skipped: they weigh at most HiddenWeight together, and the depth comes from the global
// moments alone, so every process skips the same samples.
template <int N>
struct Colour : NoSegments
{
  static constexpr bool StopsWhenOpaque = true;
  static constexpr bool ReadsCacheOrder = false; // ReplayTile never reads the lattice bits

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
  // A pixel's cached samples' nearest and farthest depth, for the hidden depth's bisection,
  // which ends as soon as no sample lies between its bounds (the same samples skipped, fewer
  // queries).
  struct SampleRange
  {
    const CachedSample* First;
    const CachedSample* Last;
    // Four samples a step into four pairs of bounds, four chains instead of one. The bounds
    // are those of one pass to the value (a NaN depth is never taken, as std::min and max
    // skip it); a zero may come out with the other sign, which no comparison tells apart.
    std::pair<double, double> operator()() const
    {
      constexpr float inf = std::numeric_limits<float>::infinity();
      float nearest[4] = { inf, inf, inf, inf };
      float farthest[4] = { -inf, -inf, -inf, -inf };
      const CachedSample* s = this->First;
      for (; this->Last - s >= 4; s += 4)
      {
        for (int k = 0; k < 4; ++k)
        {
          nearest[k] = std::min(nearest[k], s[k].Z);
          farthest[k] = std::max(farthest[k], s[k].Z);
        }
      }
      for (int k = 0; s != this->Last; ++s, ++k)
      {
        nearest[k] = std::min(nearest[k], s->Z);
        farthest[k] = std::max(farthest[k], s->Z);
      }
      return std::make_pair(static_cast<double>(std::min(
                              std::min(nearest[0], nearest[1]), std::min(nearest[2], nearest[3]))),
        static_cast<double>(
          std::max(std::max(farthest[0], farthest[1]), std::max(farthest[2], farthest[3]))));
    }
  };
  // The replayed pixels' indices in the image, and their runs of cached samples.
  std::vector<int64_t> Replayed;
  std::vector<SampleRange> Ranges;
  std::vector<double> HiddenFroms;
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

  // Pass 2 of a tile from pass 1's cached samples, grouped by pixel (in the order each pixel
  // took them, so it sums in the order it would marching again): a pixel's reconstruction is
  // set up once, only for pixels with samples, and its hidden depth found once, the tile's
  // pixels' bisections together (MomentTransmittance::HiddenDepths).
  void ReplayTile(const TileRect& tile, const CachedTile& recorded, const TransferTable& table)
  {
    this->TileHidden = 0;
    const uint32_t* starts = recorded.Starts.data();
    const CachedSample* samples = recorded.Samples.data();
    // End weights (apcEndWeights.h): each looked-up absorbance times its sample's weight.
    const float* weights = recorded.Weights.empty() ? nullptr : recorded.Weights.data();
    this->Transmittance.clear();
    // Written field by field: a pushed-back temporary, stored in halves and copied whole,
    // stalled on the store's forwarding each pixel.
    const size_t most = static_cast<size_t>(tile.Pixels());
    if (this->Replayed.size() < most)
    {
      this->Replayed.resize(most);
      this->Ranges.resize(most);
      this->HiddenFroms.resize(most);
    }
    int count = 0;
    // Row by row: the image index without a division a pixel.
    const int columns = tile.Width();
    for (int j = tile.J0, p = 0; j < tile.J1; ++j)
    {
      const int64_t row = static_cast<int64_t>(j) * this->Width + tile.I0;
      for (int i = 0; i < columns; ++i, ++p)
      {
        const uint32_t begin = starts[p];
        const uint32_t end = starts[p + 1];
        if (begin == end)
        {
          continue;
        }
        this->Transmittance.emplace_back(this->GlobalMoments + (N + 1) * (row + i), this->Settings);
        this->Replayed[count] = row + i;
        SampleRange& range = this->Ranges[count];
        range.First = samples + begin;
        range.Last = samples + end;
        ++count;
      }
    }
    std::fill_n(this->HiddenFroms.begin(), count, std::numeric_limits<double>::infinity());
    if (this->HiddenWeight > 0)
    {
      MomentTransmittance<N>::HiddenDepths(this->Transmittance.data(), this->HiddenWeight,
        this->Ranges.data(), this->HiddenFroms.data(), count);
    }
    for (int r = 0; r < count; ++r)
    {
      const int64_t image = this->Replayed[r];
      const SampleRange& range = this->Ranges[r];
      const ptrdiff_t begin = range.First - samples;
      const MomentTransmittance<N>& transmittance = this->Transmittance[r];
      const double hiddenFrom = this->HiddenFroms[r];
      ColourSums sums;
      if constexpr (N == 4)
      {
        // Looked up, weighted and summed 4 samples at a time (apcPixelReplay.h).
        if (ReplayFourMomentPixel(transmittance, hiddenFrom, table.GetLayout(), range.First,
              static_cast<int>(range.Last - range.First), sums.Data(), this->TileHidden,
              weights ? weights + begin : nullptr))
        {
          this->WriteAt(image, sums);
          continue;
        }
      }
      this->ReplayGeneric(transmittance, hiddenFrom, range.First, range.Last,
        weights ? weights + begin : nullptr, table, sums);
      this->WriteAt(image, sums);
    }
    this->CountHidden();
  }
  void WriteAt(int64_t image, const ColourSums& sums) const
  {
    double* out = this->Output + 4 * image;
    for (int c = 0; c < 4; ++c)
    {
      out[c] += sums.Sums[c];
    }
  }
  // The pixel's visible samples looked up, then weighted all at once (vectorised).
  void ReplayGeneric(const MomentTransmittance<N>& transmittance, double hiddenFrom,
    const CachedSample* first, const CachedSample* last, const float* weights,
    const TransferTable& table, ColourSums& sums)
  {
    const size_t most = static_cast<size_t>(last - first);
    if (this->Depths.size() < most)
    {
      this->Depths.resize(most);
      this->Absorbances.resize(most);
      this->Colours.resize(most);
      this->Weights.resize(most);
    }
    int count = 0;
    for (const CachedSample* sample = first; sample != last; ++sample)
    {
      if (sample->Z >= hiddenFrom)
      {
        continue;
      }
      TransferSample s = table.Lookup(sample->Scalar);
      if (weights)
      {
        s.Absorbance *= weights[sample - first];
      }
      this->Depths[count] = sample->Z;
      this->Absorbances[count] = s.Absorbance;
      this->Colours[count] = s.Colour;
      ++count;
    }
    this->TileHidden += static_cast<int64_t>(most) - count;
    transmittance.Weights(
      this->Depths.data(), this->Absorbances.data(), this->Weights.data(), count);
    for (int i = 0; i < count; ++i)
    {
      const std::array<float, 3>& c = this->Colours[i];
      sums.Add(this->Weights[i],
        { static_cast<double>(c[0]), static_cast<double>(c[1]), static_cast<double>(c[2]) });
    }
  }
};

// A pass-1 sample's place along its ray when only the cache holds it: its float depth (as an
// integer that orders like the float), then the low bits of its lattice index for depths that
// rounded to the same float. Consecutive samples differ in k by 1, so ties never span a wrap
// of the 16 bits unless 65536 samples share one float depth.
inline int64_t ReplayOrder(float z, uint16_t k16)
{
  uint32_t bits = 0;
  std::memcpy(&bits, &z, sizeof(bits));
  bits = (bits & 0x80000000u) ? ~bits : (bits | 0x80000000u);
  return (static_cast<int64_t>(bits) << 16) | k16;
}

// Hybrid pass 2 (apcHybridTransmittance.h): each pixel's own samples collected, sorted by
// their place along the ray (ties by their values) and weighted by alpha T_own T_others,
// T_own the exact ordered product of the own samples in front, T_others reconstructed from
// global - own moments.
template <int N>
struct HybridColour : NoSegments
{
  static constexpr bool StopsWhenOpaque = true;
  static constexpr bool ReadsCacheOrder = true; // ties ordered by their lattice bits
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
  // A cache recorded without the lattice bits (never by a pass 1 that kept its own moments)
  // orders tied depths as they were taken.
  void ReplayTile(const TileRect& tile, const CachedTile& recorded, const TransferTable& table)
  {
    this->BeginTile(tile);
    const bool ordered = recorded.K16.size() == recorded.Samples.size();
    for (int p = 0; p < tile.Pixels(); ++p)
    {
      for (uint32_t i = recorded.Starts[p]; i < recorded.Starts[p + 1]; ++i)
      {
        const CachedSample& sample = recorded.Samples[i];
        TransferSample s = table.Lookup(sample.Scalar);
        if (!recorded.Weights.empty())
        {
          s.Absorbance *= recorded.Weights[i]; // end weights, as pass 1 took them
        }
        this->Pixels[p].push_back({ ReplayOrder(sample.Z, ordered ? recorded.K16[i] : 0), sample.Z,
          s.Absorbance, s.Colour });
      }
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
      // Samples of one lattice point (overlapping cells) in SampleBefore's order, so that the
      // exact product T_own does not depend on the order the cells delivered them in.
      std::sort(samples.begin(), samples.end(),
        [](const OwnSample& a, const OwnSample& b)
        {
          return a.Order != b.Order ? a.Order < b.Order
                                    : ValuesBefore(a.Absorbance, a.Colour, b.Absorbance, b.Colour);
        });
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

} // namespace visitors
} // namespace apc

#endif
