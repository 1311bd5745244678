// SPDX-License-Identifier: BSD-3-Clause
// A per-pixel offset of the sample lattice. With one lattice t_k = k h for every ray, thin
// layers cut at a grazing angle alias into parallel bands (wood grain), the same in every
// frame; shifting each pixel's lattice by a fraction of h that varies from pixel to pixel
// turns the bands into fine noise. The offset depends only on the pixel, so every rank
// samples the same points of a ray and each sample is still taken exactly once whatever
// the partition.
#ifndef apcLatticeJitter_h
#define apcLatticeJitter_h

#include <cmath>

namespace apc
{

// Interleaved gradient noise (Jimenez, "Next Generation Post Processing in Call of Duty:
// Advanced Warfare", SIGGRAPH 2014): in [0, 1), and neighbouring pixels' values are far
// apart, which spreads the error at high frequencies where it is least visible.
inline double LatticeOffset(int i, int j)
{
  const double f = 0.06711056 * i + 0.00583715 * j;
  const double g = 52.9829189 * (f - std::floor(f));
  return g - std::floor(g);
}

} // namespace apc

#endif
