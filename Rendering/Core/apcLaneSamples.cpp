// LaneSamplesAvx2 (apcLaneKernel.h over AVX2's vectors), the lanes' cell set-up and their
// rays' gathering.
#include "apcLaneSamples.h"

#include "apcCellInterpolation.h"
#include "apcLaneGather.h"
#include "apcLaneMoments.h"

#include <immintrin.h>

#include <cstdint>

// The headers above are compiled for the default target (their inline functions are shared
// with other files). Every function below, the kernel's templates included, may use AVX2 (only
// called where HasAvx2()).
#pragma GCC push_options
#pragma GCC target("avx2")

#include "apcLaneKernel.h"
#include "apcLaneOps4.h"

namespace apc
{
namespace walk
{

namespace
{

// value in each of four lanes.
__attribute__((target("avx2"), always_inline)) inline void Broadcast(double value, double* four)
{
  _mm256_store_pd(four, _mm256_set1_pd(value));
}

} // namespace

__attribute__((target("avx2"))) void GatherLaneRays(
  const TileRays& packed, const ClippedRays& clipped, const uint16_t* list, int n, LaneRays& rays)
{
  const gather::LaneIndices lanes = gather::Indices(list, n);
  gather::Directions(packed, lanes, rays);
  _mm256_store_pd(rays.Offset, gather::Four(packed.Offset, lanes));
  _mm256_store_pd(rays.K, gather::Four(clipped.Lattice, lanes));
  gather::Ends(clipped, lanes, n, rays);
}

__attribute__((target("avx2"))) int LaneSamplesAvx2(
  const LaneCellVectors& cell, const LaneRays& rays, LaneSteps& steps)
{
  using kernel::Form;
  if (cell.Twisted)
  {
    return kernel::Lanes<Form::PyramidScalarAt, Ops4>(cell, rays, steps);
  }
  return cell.Pyramid ? kernel::Lanes<Form::LinearPyramid, Ops4>(cell, rays, steps)
                      : kernel::Lanes<Form::ScalarAt, Ops4>(cell, rays, steps);
}

namespace
{

// The cell's own part of SetUpLaneCell.
__attribute__((target("avx2"), always_inline)) inline void SetUpCellPart(
  const double (&inverse)[3][3], const double* p0, const double* sc, const double* g, bool pyramid,
  bool twisted, double lo, double hi, LaneCellVectors& vectors)
{
  for (int i = 0; i < 3; ++i)
  {
    for (int j = 0; j < 3; ++j)
    {
      Broadcast(inverse[i][j], vectors.Inverse[i][j]);
    }
    Broadcast(p0[i], vectors.P0[i]);
  }
  // Twisted or not, only the coefficients the cell's form reads.
  const int coefficients = pyramid || twisted ? 5 : 8;
  for (int i = 0; i < coefficients; ++i)
  {
    Broadcast(sc[i], vectors.SC[i]);
  }
  vectors.Twisted = twisted;
  vectors.Pyramid = pyramid;
  vectors.Other = false;
  if (twisted)
  {
    // CellInterpolator::PyramidCoordinates' constants.
    const double A = g[2] - g[0] * g[1];
    for (int i = 0; i < 3; ++i)
    {
      Broadcast(g[i], vectors.G[i]);
    }
    Broadcast(4.0 * A, vectors.FourA);
    Broadcast(2.0 * A, vectors.TwoA);
    vectors.Other = A != 0;
  }
  Broadcast(lo, vectors.Lo);
  Broadcast(hi, vectors.Hi);
}

} // namespace

__attribute__((target("avx2"))) void SetUpLaneTile(const LaneCell& cell, LaneCellVectors& vectors)
{
  Broadcast(cell.Spacing, vectors.Spacing);
  Broadcast(cell.Table.Min, vectors.Min);
  Broadcast(cell.Table.Scale, vectors.Scale);
  Broadcast(cell.Table.Last, vectors.Last);
  vectors.AbsorbancePairs = cell.Table.AbsorbancePairs;
  vectors.Bins = cell.BinEnds != nullptr;
  if (vectors.Bins)
  {
    // The ends are Base + (b + 1) Width (integers exact as doubles, and so their differences).
    const double width = cell.BinEnds[1] - cell.BinEnds[0];
    Broadcast(cell.BinEnds[0] - width, vectors.BinBase);
    Broadcast(width, vectors.BinWidth);
    Broadcast(1.0 / width, vectors.BinInverse);
  }
}

__attribute__((target("avx2"))) void SetUpLaneCellOf(const CellInterpolator& interpolator,
  bool twisted, const double p0[3], double lo, double hi, LaneCellVectors& vectors)
{
  SetUpCellPart(interpolator.GetLinearInverse(), p0, interpolator.GetScalarCoefficients(),
    interpolator.GetPyramidG(), interpolator.Shape() == CellShape::Pyramid, twisted, lo, hi,
    vectors);
}

__attribute__((target("avx2"))) void SetUpLaneCell(const LaneCell& cell, LaneCellVectors& vectors)
{
  SetUpCellPart(
    cell.Inverse, cell.P0, cell.SC, cell.G, cell.Pyramid, cell.Twisted, cell.Lo, cell.Hi, vectors);
  SetUpLaneTile(cell, vectors);
}

} // namespace walk
} // namespace apc

#pragma GCC pop_options
