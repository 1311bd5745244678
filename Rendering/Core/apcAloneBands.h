// SPDX-License-Identifier: BSD-3-Clause
// The band size APC mode renders a frame in on one process.
//
// APC mode renders a large image band by band (vtkAPCCompositePass::SetMaxBandPixels), and a
// band's pass 1 caches its samples for pass 2, so the sample cache holds one band's samples.
// Several processes pay collectives for every band and wait for the slowest process in each,
// so they keep the agreed size. One process pays nothing per band, so it takes bands of a few
// hundred marcher tiles a thread, whatever the setting: its cache then holds a band's samples
// instead of the frame's and is reused band after band. The image is the same; the memory a
// first frame touches for the first time (slow to back on some virtual machines) is a band's.
#ifndef apcAloneBands_h
#define apcAloneBands_h

#include <algorithm>
#include <cstddef>

namespace apc
{

// At least this many pixels a band (a 1024-wide image: 8 marcher tile rows).
constexpr size_t kAloneBandPixels = size_t(1) << 17;
// At least this many marcher tiles a thread, so that a band's tiles keep the threads busy to
// its end and one process's pass 1 still marches tiles without the opaque stop first
// (VolumeRayMarcher::kTilesPerThreadWithoutStop, a quarter of this).
constexpr int kAloneBandTilesPerThread = 256;

// The band size, in pixels, of one process rendering with `threads` threads (< 1: one) and
// square marcher tiles of `tileSize` pixels a side: the setting, or less.
inline size_t AloneBandPixels(size_t setting, int threads, int tileSize)
{
  const size_t tilePixels = static_cast<size_t>(tileSize) * static_cast<size_t>(tileSize);
  const size_t perThreads =
    static_cast<size_t>(std::max(threads, 1)) * kAloneBandTilesPerThread * tilePixels;
  return std::min(setting, std::max(kAloneBandPixels, perThreads));
}

} // namespace apc

#endif
