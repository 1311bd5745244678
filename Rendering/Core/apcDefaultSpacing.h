// SPDX-License-Identifier: BSD-3-Clause
// The sample distance used when none is set: the data's mean cell size (about one sample per
// cell a ray crosses), but never fewer than a floor of samples along the bounding-box
// diagonal. A fixed fraction of the diagonal alone samples a fine mesh too sparsely.
//
// Both inputs are the same on every process (the union of the processes' bounds and the
// sum of their cell counts, an exact integer sum), so every process computes the same
// distance and the sample lattice stays shared across ranks, whatever the partition.
#ifndef apcDefaultSpacing_h
#define apcDefaultSpacing_h

#include <algorithm>
#include <cmath>

namespace apc
{

// The edge of a cube that fills the bounding box evenly with the cells: cbrt(box volume /
// cells). 0 if there are no cells or the box is flat.
inline double MeanCellSize(const double bounds[6], double cells)
{
  const double volume = (bounds[1] - bounds[0]) * (bounds[3] - bounds[2]) * (bounds[5] - bounds[4]);
  if (!(cells >= 1) || !(volume > 0))
  {
    return 0.0;
  }
  return std::cbrt(volume / cells);
}

inline double BoundsDiagonal(const double bounds[6])
{
  const double dx = bounds[1] - bounds[0];
  const double dy = bounds[3] - bounds[2];
  const double dz = bounds[5] - bounds[4];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

// What a sample distance of 0 stands for: one mean cell size, but at least kMinDefaultSamples
// samples along the bounding-box diagonal. The floor is for meshes whose cells are large next
// to the features they draw: the flange (5,712 cells, thin walls, a quarter of its box filled)
// shows lattice bands at one sample per mean cell size (33 dB against the exact picture) and
// needs about 160 samples along its diagonal for 40 dB; the wind data (331,699 cells) keeps
// 40.7 dB at one per cell. The mean cell size governs meshes of more than ~10^6 cells, which
// it samples more finely than the floor. docs/evaluation.md, section 4.2, has the measurement.
constexpr double kDefaultSpacingPerCell = 1.0;
constexpr double kMinDefaultSamples = 192.0;

inline double DefaultSampleDistance(const double bounds[6], double cells)
{
  const double coarsest = BoundsDiagonal(bounds) / kMinDefaultSamples;
  const double cell = MeanCellSize(bounds, cells);
  return cell > 0 ? std::min(kDefaultSpacingPerCell * cell, coarsest) : coarsest;
}

} // namespace apc

#endif
