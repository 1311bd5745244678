// LaneMomentsAvx512: the lanes' hand-over of two groups of four pixels at once
// (apcLaneMomentsKernel.h over AVX-512's vectors and masks), group a in the low four lanes,
// group b in the high four.
#include "apcLaneMoments.h"

#include "apcDepthWarp.h"
#include "apcLaneSamples.h"
#include "apcOpaqueBins.h"

#include <immintrin.h>

#include <cstdint>

// The headers above are compiled for the default target (their inline functions are shared
// with other files). Every function below, the kernel's templates included, may use AVX-512 F
// and VL (only called where HasAvx512()).
#pragma GCC push_options
#pragma GCC target("avx512f,avx512vl,avx2")

#include "apcLaneMomentsKernel.h"
#include "apcLaneOps8.h"

namespace apc
{
namespace walk
{

void LaneMomentsAvx512(const LaneSteps& sa, const LaneSteps& sb, int taken, const LaneRays& ra,
  const LaneRays& rb, const double* const sumsA[4], const double* const sumsB[4],
  const LatticeDepthWarp& warp, double quantaPerAbsorbance, LaneMoments& oa, LaneMoments& ob)
{
  const Ops8::StepsIn steps{ sa, sb };
  const Ops8::Rays rays{ ra, rb };
  const Ops8::Sums sums{ sumsA, sumsB };
  Ops8::Out out{ oa, ob };
  kernel::Unweighted<Ops8> weigh;
  kernel::Moments<Ops8>(steps, taken, rays, sums, warp, quantaPerAbsorbance, weigh, out);
}

} // namespace walk
} // namespace apc

#pragma GCC pop_options
