// LaneMomentsAvx2 and LaneWeightedMomentsAvx2 (apcLaneMomentsKernel.h over AVX2's vectors), and
// the end-weighted lanes' rays' gathering.
#include "apcLaneMoments.h"

#include "apcDepthWarp.h"
#include "apcLaneGather.h"
#include "apcLaneSamples.h"
#include "apcOpaqueBins.h"

#include <immintrin.h>

#include <cstdint>

// The headers above are compiled for the default target (their inline functions are shared
// with other files). Every function below, the kernel's templates included, may use AVX2 (only
// called where HasAvx2()).
#pragma GCC push_options
#pragma GCC target("avx2")

#include "apcLaneMomentsKernel.h"
#include "apcLaneOps4.h"

namespace apc
{
namespace walk
{

namespace
{

// End-weighted steps (LaneWeightedMomentsAvx2): each step's float absorbance times its float
// weight, as Moments::RunAddWeighted's, and the record's weight kept.
class StepWeights
{
public:
  __attribute__((always_inline)) StepWeights(const LaneWeights& weights, const LaneRays& rays)
  {
    // The steps of each lane's First and Last index (exact integers, far apart ones meet no
    // step: the conversion's 0x80000000), and their weights. Vector stores of
    // GatherWeightedLaneRays: each load takes its store's value.
    const __m256d k = _mm256_load_pd(rays.K);
    this->FirstStep = _mm256_cvttpd_epi32(_mm256_sub_pd(_mm256_load_pd(weights.First), k));
    this->LastStep = _mm256_cvttpd_epi32(_mm256_sub_pd(_mm256_load_pd(weights.Last), k));
    this->FirstWeight = _mm_load_ps(weights.FirstWeight);
    this->LastWeight = _mm_load_ps(weights.LastWeight);
  }

  // The scalar hand-over's k == first ? first weight : (k == last ? last weight : 1), and its
  // float product.
  __attribute__((always_inline)) __m128 Apply(int s, __m128 absorbance)
  {
    const __m128i step = _mm_set1_epi32(s);
    __m128 weight = _mm_set1_ps(1.0f);
    weight = _mm_blendv_ps(
      weight, this->LastWeight, _mm_castsi128_ps(_mm_cmpeq_epi32(this->LastStep, step)));
    weight = _mm_blendv_ps(
      weight, this->FirstWeight, _mm_castsi128_ps(_mm_cmpeq_epi32(this->FirstStep, step)));
    this->Weight = weight;
    return _mm_mul_ps(absorbance, weight);
  }

  // A record's weight where its step is visible, else 1: the four lanes' low halves of the
  // mask (each lane's 64 bits are all ones or all zeros).
  __attribute__((always_inline)) void Store(LaneMoments& out, int s, __m256d vis) const
  {
    const __m256 mask = _mm256_castpd_ps(vis);
    const __m128 narrow = _mm_shuffle_ps(
      _mm256_castps256_ps128(mask), _mm256_extractf128_ps(mask, 1), _MM_SHUFFLE(2, 0, 2, 0));
    _mm_store_ps(out.Weight[s], _mm_blendv_ps(_mm_set1_ps(1.0f), this->Weight, narrow));
  }

private:
  __m128i FirstStep;
  __m128i LastStep;
  __m128 FirstWeight;
  __m128 LastWeight;
  __m128 Weight; // the last step's
};

} // namespace

__attribute__((target("avx2"))) void GatherWeightedLaneRays(const TileRays& packed,
  const ClippedRays& clipped, const ClippedWeights& ends, const uint16_t* list, int n,
  LaneRays& rays, LaneWeights& weights)
{
  const gather::LaneIndices lanes = gather::Indices(list, n);
  gather::Directions(packed, lanes, rays);
  _mm256_store_pd(rays.Offset, gather::Four(ends.LaneOffset, lanes));
  const __m256d first = gather::Four(ends.First, lanes);
  _mm256_store_pd(rays.K, first);
  gather::Ends(clipped, lanes, n, rays);
  _mm256_store_pd(weights.First, first);
  _mm256_store_pd(weights.Last, gather::Four(ends.Last, lanes));
  // static_cast<float> of each double: the same rounding (to nearest) as _mm256_cvtpd_ps.
  _mm_store_ps(weights.FirstWeight, _mm256_cvtpd_ps(gather::Four(ends.FirstWeight, lanes)));
  _mm_store_ps(weights.LastWeight, _mm256_cvtpd_ps(gather::Four(ends.LastWeight, lanes)));
}

__attribute__((target("avx2"))) void LaneMomentsAvx2(const LaneSteps& steps, int taken,
  const LaneRays& rays, const double* const sums[4], const LatticeDepthWarp& warp,
  double quantaPerAbsorbance, LaneMoments& out)
{
  kernel::Unweighted<Ops4> weigh;
  kernel::Moments<Ops4>(steps, taken, rays, sums, warp, quantaPerAbsorbance, weigh, out);
}

__attribute__((target("avx2"))) void LaneWeightedMomentsAvx2(const LaneSteps& steps, int taken,
  const LaneRays& rays, const double* const sums[4], const LatticeDepthWarp& warp,
  double quantaPerAbsorbance, const LaneWeights& weights, LaneMoments& out)
{
  StepWeights weigh(weights, rays);
  kernel::Moments<Ops4>(steps, taken, rays, sums, warp, quantaPerAbsorbance, weigh, out);
}

} // namespace walk
} // namespace apc

#pragma GCC pop_options
