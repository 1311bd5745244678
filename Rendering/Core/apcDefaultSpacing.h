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

// The edge of a cube of the cells' own mean volume: cbrt(volume / cells), volume the cells'
// total (CellMesh::GetCellVolume, summed exactly over the processes). Rounded down to
// kSpacingBits significant bits: the lattice does not move when one cell changes a little
// (a deforming mesh keeps its lattice from step to step), and the result is never coarser
// than the exact value. 0 without cells or volume.
constexpr int kSpacingBits = 5;

inline double MeanCellVolumeSize(double volume, double cells)
{
  if (!(cells >= 1) || !(volume > 0) || !std::isfinite(volume))
  {
    return 0.0;
  }
  int exponent = 0;
  const double m = std::frexp(std::cbrt(volume / cells), &exponent);
  return std::ldexp(std::floor(std::ldexp(m, kSpacingBits)), exponent - kSpacingBits);
}

// What a sample distance of 0 stands for: kDefaultSpacingPerCell mean cell sizes (from the
// cells' own volume, MeanCellVolumeSize), but at least kMinDefaultSamples samples along the
// bounding-box diagonal, for a volume whose boundary ends are weighted (Sample End Weights
// Boundary, the default, or All): the weights remove the lattice's staircase where rays
// graze the mesh's boundary, which set the error of the plain lattice, so a coarser lattice
// keeps the same quality. Against the exact picture at a 4x finer lattice (ParaView's default
// ramp) 1.25 mean cell sizes keep the wind data (331,699 cells) at 50 dB, where 1.5 shows a
// ripple and 2 notches along the ground layer the rays graze; the floor is for meshes whose
// cells are large next to the features they draw: the flange (5,712 cells, thin walls; its
// cells fill a quarter of its box) takes it, and shows speckles at 64 samples along its
// diagonal. The plain lattice (Sample End Weights Off, the exact modes, the Hybrid resolve)
// keeps one mean cell size and 128 samples (kPlainSpacingPerCell, kPlainMinDefaultSamples):
// at 1.25 its staircase costs the wind overview 40 dB. docs/evaluation.md, section 4.2, has
// the measurement. The cells' volume, not the box's, keeps a mesh that fills its box sparsely
// from being sampled coarser than its cells; without a volume (flat cells only) the box's mean
// cell size stands in.
constexpr double kDefaultSpacingPerCell = 1.25;
constexpr double kMinDefaultSamples = 96.0;
constexpr double kPlainSpacingPerCell = 1.0;
constexpr double kPlainMinDefaultSamples = 128.0;

// weightedEnds: the volume weights its boundary ends (VolumeRayMarcher::EndWeightsMode
// Boundary or All, in MBOIT without the Hybrid resolve); false for the plain lattice.
inline double DefaultSampleDistance(
  const double bounds[6], double cells, double volume, bool weightedEnds)
{
  const double perCell = weightedEnds ? kDefaultSpacingPerCell : kPlainSpacingPerCell;
  const double samples = weightedEnds ? kMinDefaultSamples : kPlainMinDefaultSamples;
  const double coarsest = BoundsDiagonal(bounds) / samples;
  double cell = MeanCellVolumeSize(volume, cells);
  cell = cell > 0 ? cell : MeanCellSize(bounds, cells);
  return cell > 0 ? std::min(perCell * cell, coarsest) : coarsest;
}

} // namespace apc

#endif
