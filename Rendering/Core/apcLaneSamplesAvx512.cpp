// LaneSamplesAvx512: pass 1's lanes kernel on two groups of four rays at once (apcLaneKernel.h
// over AVX-512's vectors and masks), group a in the low four lanes, group b in the high four.
#include "apcLaneSamples.h"

#include "apcCellInterpolation.h"
#include "apcLaneMoments.h"

#include <immintrin.h>

#include <cstdint>

// The headers above are compiled for the default target (their inline functions are shared
// with other files). Every function below, the kernel's templates included, may use AVX-512 F
// and VL (only called where HasAvx512()).
#pragma GCC push_options
#pragma GCC target("avx512f,avx512vl,avx2")

#include "apcLaneKernel.h"
#include "apcLaneOps8.h"

namespace apc
{
namespace walk
{

int LaneSamplesAvx512(
  const LaneCellVectors& cell, const LaneRays& a, const LaneRays& b, LaneSteps& sa, LaneSteps& sb)
{
  using kernel::Form;
  const Ops8::Rays rays{ a, b };
  Ops8::Steps steps{ sa, sb };
  if (cell.Twisted)
  {
    return kernel::Lanes<Form::PyramidScalarAt, Ops8>(cell, rays, steps);
  }
  return cell.Pyramid ? kernel::Lanes<Form::LinearPyramid, Ops8>(cell, rays, steps)
                      : kernel::Lanes<Form::ScalarAt, Ops8>(cell, rays, steps);
}

} // namespace walk
} // namespace apc

#pragma GCC pop_options
