// Applying the agreed opaque cut (apcOpaqueBins.h) to a tile pass 1 kept in the sample cache
// (internal to apcVolumeRayMarcher.cpp): the samples of a pixel past its cut leave the cache,
// so that pass 2 replays exactly the samples the moments hold, and that pixel's moments are
// summed again from the samples it keeps.
#ifndef apcOpaqueCut_h
#define apcOpaqueCut_h

#include "apcOpaqueBins.h"
#include "apcPowerMoments.h"
#include "apcSampleCache.h"
#include "apcTileBins.h"
#include "apcTransferTable.h"

#include <algorithm>
#include <cstdint>

namespace apc
{

// True if a pixel of tile (in band coordinates, band rows width pixels wide) summed a sample
// past its cut.
inline bool TileCrossesCut(
  const TileRect& tile, int width, const uint8_t* cut, const uint8_t* lastBin)
{
  for (int p = 0; p < tile.Pixels(); ++p)
  {
    const int64_t pixel = tile.ImagePixel(p, width);
    if (lastBin[pixel] > cut[pixel])
    {
      return true;
    }
  }
  return false;
}

// Drops the cached samples past each pixel's cut, in place and keeping each pixel's order,
// and overwrites the moments (N + 1 per pixel of the band) of each pixel that loses any with
// those of the samples it keeps. The cache must hold lattice bits (K16).
template <int N>
void CutCompactTile(CachedTile& cached, const TileRect& tile, int width, const OpaqueBins& bins,
  const uint8_t* cut, const uint8_t* lastBin, const TransferTable& table, double* moments,
  const float* depthTable, int64_t depthBase);

// A compact tile (CompactSpan) is cut in its own form; depthTable and depthBase: the cache's
// depth table it was kept with.
template <int N>
void CutCachedTile(CachedTile& cached, const TileRect& tile, int width, const OpaqueBins& bins,
  const uint8_t* cut, const uint8_t* lastBin, const TransferTable& table, double* moments,
  const float* depthTable = nullptr, int64_t depthBase = 0)
{
  if (cached.IsCompact())
  {
    CutCompactTile<N>(
      cached, tile, width, bins, cut, lastBin, table, moments, depthTable, depthBase);
    return;
  }
  uint32_t* starts = cached.Starts.data();
  CachedSample* samples = cached.Samples.data();
  uint16_t* order = cached.K16.data();
  float* weights = cached.Weights.empty() ? nullptr : cached.Weights.data(); // end weights
  uint32_t kept = 0;
  for (int p = 0; p < tile.Pixels(); ++p)
  {
    const int64_t pixel = tile.ImagePixel(p, width);
    const uint32_t begin = starts[p];
    const uint32_t end = starts[p + 1];
    starts[p] = kept;
    if (lastBin[pixel] <= cut[pixel])
    {
      std::copy(samples + begin, samples + end, samples + kept);
      std::copy(order + begin, order + end, order + kept);
      if (weights)
      {
        std::copy(weights + begin, weights + end, weights + kept);
      }
      kept += end - begin;
      continue;
    }
    double sums[N + 1] = {};
    for (uint32_t s = begin; s < end; ++s)
    {
      if (bins.OfLow16(order[s]) > cut[pixel])
      {
        continue;
      }
      float absorbance = table.Lookup(samples[s].Scalar).Absorbance;
      if (weights)
      {
        absorbance *= weights[s]; // the product pass 1 took
        weights[kept] = weights[s];
      }
      AccumulatePowerMoments<N>(sums, samples[s].Z, absorbance);
      samples[kept] = samples[s];
      order[kept] = order[s];
      ++kept;
    }
    std::copy(sums, sums + N + 1, moments + (N + 1) * pixel);
  }
  starts[tile.Pixels()] = kept;
  cached.Samples.Size = kept;
  cached.K16.resize(kept);
  cached.Weights.resize(kept);
}

// CutCachedTile of a compact tile: the same samples dropped and the same moments summed (each
// sample's depth, lattice bits and weight as Expand gives them), the kept ones moved down in
// place with their escapes.
template <int N>
void CutCompactTile(CachedTile& cached, const TileRect& tile, int width, const OpaqueBins& bins,
  const uint8_t* cut, const uint8_t* lastBin, const TransferTable& table, double* moments,
  const float* depthTable, int64_t depthBase)
{
  CompactSpan& compact = cached.Compact;
  uint32_t* starts = cached.Starts.data();
  float* scalars = compact.Scalars;
  uint16_t* depths = compact.Depths;
  EscapedSample* escapes = compact.Escapes;
  const uint16_t base16 = static_cast<uint16_t>(depthBase);
  uint32_t kept = 0;
  size_t escapeRead = 0;
  size_t escapeKept = 0;
  for (int p = 0; p < tile.Pixels(); ++p)
  {
    const int64_t pixel = tile.ImagePixel(p, width);
    const uint32_t begin = starts[p];
    const uint32_t end = starts[p + 1];
    starts[p] = kept;
    const bool whole = lastBin[pixel] <= cut[pixel];
    double sums[N + 1] = {};
    for (uint32_t s = begin; s < end; ++s)
    {
      const uint16_t slot = depths[s];
      const bool escaped = slot == kEscapedDepth;
      const EscapedSample escape = escaped ? escapes[escapeRead++] : EscapedSample{};
      if (!whole)
      {
        const uint16_t k16 = escaped ? escape.K16 : static_cast<uint16_t>(base16 + slot);
        if (bins.OfLow16(k16) > cut[pixel])
        {
          continue;
        }
        float absorbance = table.Lookup(scalars[s]).Absorbance;
        if (compact.Weighted)
        {
          absorbance *= escaped ? escape.Weight : 1.0f; // the product pass 1 took
        }
        AccumulatePowerMoments<N>(sums, escaped ? escape.Z : depthTable[slot], absorbance);
      }
      scalars[kept] = scalars[s];
      depths[kept] = slot;
      if (escaped)
      {
        escapes[escapeKept++] = escape;
      }
      ++kept;
    }
    if (!whole)
    {
      std::copy(sums, sums + N + 1, moments + (N + 1) * pixel);
    }
  }
  starts[tile.Pixels()] = kept;
  compact.Size = kept;
  compact.EscapeCount = escapeKept;
}

} // namespace apc

#endif
