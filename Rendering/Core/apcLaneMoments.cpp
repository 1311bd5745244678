#include "apcLaneMoments.h"

#include "apcLaneGather.h"
#include "apcOpaqueBins.h"

#include <immintrin.h>

namespace apc
{
namespace walk
{

namespace
{

// Rows r0 .. r3 to columns: c[j] holds r0[j], r1[j], r2[j], r3[j] (its own inverse).
__attribute__((target("avx2"), always_inline)) inline void Transpose(
  __m256d r0, __m256d r1, __m256d r2, __m256d r3, __m256d* c)
{
  const __m256d t0 = _mm256_unpacklo_pd(r0, r1);
  const __m256d t1 = _mm256_unpackhi_pd(r0, r1);
  const __m256d t2 = _mm256_unpacklo_pd(r2, r3);
  const __m256d t3 = _mm256_unpackhi_pd(r2, r3);
  c[0] = _mm256_permute2f128_pd(t0, t2, 0x20);
  c[1] = _mm256_permute2f128_pd(t1, t3, 0x20);
  c[2] = _mm256_permute2f128_pd(t0, t2, 0x31);
  c[3] = _mm256_permute2f128_pd(t1, t3, 0x31);
}

// Only AVX2, no FMA: each product and sum must round as Moments::RunAdd's do. Weighted: each
// step's float absorbance times its float weight first (weights), as RunAddWeighted's.
template <bool Weighted>
__attribute__((target("avx2"), always_inline)) inline void Moments(const LaneSteps& steps,
  int taken, const LaneRays& rays, const double* const sums[4], const LatticeDepthWarp& warp,
  double quantaPerAbsorbance, const LaneWeights* weights, LaneMoments& out)
{
  // The four pixels' sums, one pixel per lane.
  __m256d b[5];
  Transpose(_mm256_loadu_pd(sums[0]), _mm256_loadu_pd(sums[1]), _mm256_loadu_pd(sums[2]),
    _mm256_loadu_pd(sums[3]), b);
  b[4] = _mm256_setr_pd(sums[0][4], sums[1][4], sums[2][4], sums[3][4]);
  const __m256d zero = _mm256_setzero_pd();
  const __m256d one = _mm256_set1_pd(1.0);
  const __m256d tout = _mm256_load_pd(rays.Tout);
  // LatticeDepthWarp's table: index k - Base in [0, size) and t == k spacing (the lattice's
  // own depth, not a jittered one); the integers are exact as doubles.
  const double* entries = warp.GetEntries();
  const __m256d base = _mm256_set1_pd(static_cast<double>(warp.GetBase()));
  const __m256d size = _mm256_set1_pd(static_cast<double>(warp.GetNumberOfEntries()));
  const __m256d spacing = _mm256_set1_pd(warp.GetSpacing());
  const __m256d perAbsorbance = _mm256_set1_pd(quantaPerAbsorbance);
  const __m256d opaque = _mm256_set1_pd(static_cast<double>(OpaqueBins::kOpaque));
  __m256d k = _mm256_load_pd(rays.K);
  __m256i count = _mm256_setzero_si256();
  __m256i visible = _mm256_setzero_si256();
  __m128i quanta = _mm_setzero_si128();
  // Weighted: the steps of each lane's First and Last index (exact integers, far apart ones
  // meet no step: the conversion's 0x80000000), and their weights.
  __m128i firstStep = _mm_setzero_si128();
  __m128i lastStep = _mm_setzero_si128();
  __m128 firstWeight = _mm_setzero_ps();
  __m128 lastWeight = _mm_setzero_ps();
  const __m128 oneFloat = _mm_set1_ps(1.0f);
  if constexpr (Weighted)
  {
    // Vector stores of GatherWeightedLaneRays: each load takes its store's value.
    firstStep = _mm256_cvttpd_epi32(_mm256_sub_pd(_mm256_load_pd(weights->First), k));
    lastStep = _mm256_cvttpd_epi32(_mm256_sub_pd(_mm256_load_pd(weights->Last), k));
    firstWeight = _mm_load_ps(weights->FirstWeight);
    lastWeight = _mm_load_ps(weights->LastWeight);
  }
  for (int s = 0; s < taken; ++s, k = _mm256_add_pd(k, one)) // k + 1 is exact: an integer
  {
    const __m256d t = _mm256_load_pd(steps.T[s]);
    const __m256d inside = _mm256_cmp_pd(t, tout, _CMP_LT_OQ);
    __m128 absorbance = _mm_load_ps(steps.Absorbance[s]);
    __m128 weight = oneFloat;
    if constexpr (Weighted)
    {
      // The scalar hand-over's k == first ? first weight : (k == last ? last weight : 1),
      // and its float product.
      const __m128i step = _mm_set1_epi32(s);
      weight = _mm_blendv_ps(weight, lastWeight, _mm_castsi128_ps(_mm_cmpeq_epi32(lastStep, step)));
      weight =
        _mm_blendv_ps(weight, firstWeight, _mm_castsi128_ps(_mm_cmpeq_epi32(firstStep, step)));
      absorbance = _mm_mul_ps(absorbance, weight);
    }
    __m256d a = _mm256_cvtps_pd(absorbance);
    const __m256d vis = _mm256_and_pd(inside, _mm256_cmp_pd(a, zero, _CMP_GT_OQ));
    if constexpr (Weighted)
    {
      // A record's weight where its step is visible, else 1: the four lanes' low halves of
      // the mask (each lane's 64 bits are all ones or all zeros).
      const __m256 mask = _mm256_castpd_ps(vis);
      const __m128 narrow = _mm_shuffle_ps(
        _mm256_castps256_ps128(mask), _mm256_extractf128_ps(mask, 1), _MM_SHUFFLE(2, 0, 2, 0));
      _mm_store_ps(out.Weight[s], _mm_blendv_ps(oneFloat, weight, narrow));
    }
    // A step that is not visible adds a * z^m = +0 (z = 0): the sums stay as they are.
    a = _mm256_and_pd(a, vis);
    const __m256d index = _mm256_sub_pd(k, base);
    const __m256d inTable = _mm256_and_pd(
      _mm256_and_pd(_mm256_cmp_pd(index, zero, _CMP_GE_OQ), _mm256_cmp_pd(index, size, _CMP_LT_OQ)),
      _mm256_cmp_pd(t, _mm256_mul_pd(k, spacing), _CMP_EQ_OQ));
    const __m256d take = _mm256_and_pd(inTable, vis);
    __m256d z = _mm256_mask_i32gather_pd(
      zero, entries, _mm256_cvttpd_epi32(_mm256_and_pd(index, take)), take, 8);
    const int miss = _mm256_movemask_pd(_mm256_andnot_pd(inTable, vis));
    if (miss != 0)
    {
      // A jittered ray's depth, or an index outside the table: the warp itself.
      alignas(32) double zs[4];
      alignas(32) double ts[4];
      _mm256_store_pd(zs, z);
      _mm256_store_pd(ts, t);
      for (int m = miss; m; m &= m - 1)
      {
        const int i = __builtin_ctz(m);
        zs[i] = warp.GetWarp()(ts[i]);
      }
      z = _mm256_load_pd(zs);
    }
    // AccumulateCheckedPowerMoments: w = a, then w *= z for each higher moment.
    b[0] = _mm256_add_pd(b[0], a);
    __m256d w = _mm256_mul_pd(a, z);
    b[1] = _mm256_add_pd(b[1], w);
    w = _mm256_mul_pd(w, z);
    b[2] = _mm256_add_pd(b[2], w);
    w = _mm256_mul_pd(w, z);
    b[3] = _mm256_add_pd(b[3], w);
    w = _mm256_mul_pd(w, z);
    b[4] = _mm256_add_pd(b[4], w);
    _mm_store_ps(out.Z[s], _mm256_cvtpd_ps(z));
    // OpaqueBins::Quanta: q >= kOpaque ? kOpaque : (q > 0 ? truncated q : 0).
    __m256d q = _mm256_mul_pd(a, perAbsorbance);
    q = _mm256_blendv_pd(q, opaque, _mm256_cmp_pd(q, opaque, _CMP_GE_OQ));
    q = _mm256_and_pd(q, _mm256_cmp_pd(q, zero, _CMP_GT_OQ));
    const __m128i qi = _mm256_cvttpd_epi32(q);
    _mm_store_si128(reinterpret_cast<__m128i*>(out.Quanta[s]), qi);
    quanta = _mm_add_epi32(quanta, qi); // at most kLaneSteps times kOpaque: no overflow
    count = _mm256_sub_epi64(count, _mm256_castpd_si256(inside));
    visible = _mm256_or_si256(
      visible, _mm256_and_si256(_mm256_castpd_si256(vis), _mm256_set1_epi64x(int64_t(1) << s)));
  }
  __m256d rows[4];
  Transpose(b[0], b[1], b[2], b[3], rows);
  for (int i = 0; i < 4; ++i)
  {
    _mm256_store_pd(out.Sums[i], rows[i]);
  }
  _mm256_store_pd(out.Sum4, b[4]);
  _mm256_store_si256(reinterpret_cast<__m256i*>(out.Steps), count);
  _mm256_store_si256(reinterpret_cast<__m256i*>(out.Visible), visible);
  _mm256_store_si256(reinterpret_cast<__m256i*>(out.QuantaSum), _mm256_cvtepi32_epi64(quanta));
}

// Moments<false> on two groups of four lanes at once (AVX-512): group a's pixels in lanes 0-3,
// group b's in 4-7, each lane's operations Moments' in the same order (masks where it has
// vector masks), so that every sum, depth, quanta and count is the four-wide hand-over's.
#define APC_MOMENTS512 __attribute__((target("avx512f,avx512vl,avx2")))

APC_MOMENTS512 inline __m512d Join(__m256d low, __m256d high)
{
  return _mm512_insertf64x4(_mm512_castpd256_pd512(low), high, 1);
}

// The low (high = 0) or high four lanes of v.
APC_MOMENTS512 inline __m256d Half(__m512d v, int high)
{
  return high ? _mm512_extractf64x4_pd(v, 1) : _mm512_castpd512_pd256(v);
}

} // namespace

APC_MOMENTS512 void LaneMomentsAvx512(const LaneSteps& sa, const LaneSteps& sb, int taken,
  const LaneRays& ra, const LaneRays& rb, const double* const sumsA[4],
  const double* const sumsB[4], const LatticeDepthWarp& warp, double quantaPerAbsorbance,
  LaneMoments& oa, LaneMoments& ob)
{
  __m256d ca[4];
  __m256d cb[4];
  Transpose(_mm256_loadu_pd(sumsA[0]), _mm256_loadu_pd(sumsA[1]), _mm256_loadu_pd(sumsA[2]),
    _mm256_loadu_pd(sumsA[3]), ca);
  Transpose(_mm256_loadu_pd(sumsB[0]), _mm256_loadu_pd(sumsB[1]), _mm256_loadu_pd(sumsB[2]),
    _mm256_loadu_pd(sumsB[3]), cb);
  __m512d b[5];
  for (int m = 0; m < 4; ++m)
  {
    b[m] = Join(ca[m], cb[m]);
  }
  b[4] = _mm512_setr_pd(sumsA[0][4], sumsA[1][4], sumsA[2][4], sumsA[3][4], sumsB[0][4],
    sumsB[1][4], sumsB[2][4], sumsB[3][4]);
  const __m512d zero = _mm512_setzero_pd();
  const __m512d one = _mm512_set1_pd(1.0);
  const __m512d tout = Join(_mm256_load_pd(ra.Tout), _mm256_load_pd(rb.Tout));
  const double* entries = warp.GetEntries();
  const __m512d base = _mm512_set1_pd(static_cast<double>(warp.GetBase()));
  const __m512d size = _mm512_set1_pd(static_cast<double>(warp.GetNumberOfEntries()));
  const __m512d spacing = _mm512_set1_pd(warp.GetSpacing());
  const __m512d perAbsorbance = _mm512_set1_pd(quantaPerAbsorbance);
  const __m512d opaque = _mm512_set1_pd(static_cast<double>(OpaqueBins::kOpaque));
  __m512d k = Join(_mm256_load_pd(ra.K), _mm256_load_pd(rb.K));
  __m512i count = _mm512_setzero_si512();
  __m512i visible = _mm512_setzero_si512();
  __m256i quanta = _mm256_setzero_si256();
  for (int s = 0; s < taken; ++s, k = _mm512_add_pd(k, one))
  {
    const __m512d t = Join(_mm256_load_pd(sa.T[s]), _mm256_load_pd(sb.T[s]));
    const __mmask8 inside = _mm512_cmp_pd_mask(t, tout, _CMP_LT_OQ);
    const __m256 absorbance = _mm256_insertf128_ps(
      _mm256_castps128_ps256(_mm_load_ps(sa.Absorbance[s])), _mm_load_ps(sb.Absorbance[s]), 1);
    __m512d a = _mm512_cvtps_pd(absorbance);
    const __mmask8 vis = inside & _mm512_cmp_pd_mask(a, zero, _CMP_GT_OQ);
    a = _mm512_maskz_mov_pd(vis, a);
    const __m512d index = _mm512_sub_pd(k, base);
    const __mmask8 inTable = _mm512_cmp_pd_mask(index, zero, _CMP_GE_OQ) &
      _mm512_cmp_pd_mask(index, size, _CMP_LT_OQ) &
      _mm512_cmp_pd_mask(t, _mm512_mul_pd(k, spacing), _CMP_EQ_OQ);
    const __mmask8 take = inTable & vis;
    __m512d z = _mm512_mask_i32gather_pd(
      zero, take, _mm512_cvttpd_epi32(_mm512_maskz_mov_pd(take, index)), entries, 8);
    const unsigned miss = static_cast<unsigned>(~inTable & vis) & 0xFFu;
    if (miss != 0)
    {
      // A jittered ray's depth, or an index outside the table: the warp itself.
      alignas(64) double zs[8];
      alignas(64) double ts[8];
      _mm512_store_pd(zs, z);
      _mm512_store_pd(ts, t);
      for (unsigned m = miss; m; m &= m - 1)
      {
        const int i = __builtin_ctz(m);
        zs[i] = warp.GetWarp()(ts[i]);
      }
      z = _mm512_load_pd(zs);
    }
    b[0] = _mm512_add_pd(b[0], a);
    __m512d w = _mm512_mul_pd(a, z);
    b[1] = _mm512_add_pd(b[1], w);
    w = _mm512_mul_pd(w, z);
    b[2] = _mm512_add_pd(b[2], w);
    w = _mm512_mul_pd(w, z);
    b[3] = _mm512_add_pd(b[3], w);
    w = _mm512_mul_pd(w, z);
    b[4] = _mm512_add_pd(b[4], w);
    const __m256 zf = _mm512_cvtpd_ps(z);
    _mm_store_ps(oa.Z[s], _mm256_castps256_ps128(zf));
    _mm_store_ps(ob.Z[s], _mm256_extractf128_ps(zf, 1));
    __m512d q = _mm512_mul_pd(a, perAbsorbance);
    q = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(q, opaque, _CMP_GE_OQ), q, opaque);
    q = _mm512_maskz_mov_pd(_mm512_cmp_pd_mask(q, zero, _CMP_GT_OQ), q);
    const __m256i qi = _mm512_cvttpd_epi32(q);
    _mm_store_si128(reinterpret_cast<__m128i*>(oa.Quanta[s]), _mm256_castsi256_si128(qi));
    _mm_store_si128(reinterpret_cast<__m128i*>(ob.Quanta[s]), _mm256_extracti128_si256(qi, 1));
    quanta = _mm256_add_epi32(quanta, qi); // at most kLaneSteps times kOpaque: no overflow
    count = _mm512_mask_add_epi64(count, inside, count, _mm512_set1_epi64(1));
    visible =
      _mm512_mask_or_epi64(visible, vis, visible, _mm512_set1_epi64(static_cast<int64_t>(1) << s));
  }
  LaneMoments* out[2] = { &oa, &ob };
  for (int g = 0; g < 2; ++g)
  {
    __m256d rows[4];
    Transpose(Half(b[0], g), Half(b[1], g), Half(b[2], g), Half(b[3], g), rows);
    for (int i = 0; i < 4; ++i)
    {
      _mm256_store_pd(out[g]->Sums[i], rows[i]);
    }
    _mm256_store_pd(out[g]->Sum4, Half(b[4], g));
  }
  const __m512i quantaSum = _mm512_cvtepi32_epi64(quanta);
  _mm256_store_si256(reinterpret_cast<__m256i*>(oa.Steps), _mm512_castsi512_si256(count));
  _mm256_store_si256(reinterpret_cast<__m256i*>(ob.Steps), _mm512_extracti64x4_epi64(count, 1));
  _mm256_store_si256(reinterpret_cast<__m256i*>(oa.Visible), _mm512_castsi512_si256(visible));
  _mm256_store_si256(reinterpret_cast<__m256i*>(ob.Visible), _mm512_extracti64x4_epi64(visible, 1));
  _mm256_store_si256(reinterpret_cast<__m256i*>(oa.QuantaSum), _mm512_castsi512_si256(quantaSum));
  _mm256_store_si256(
    reinterpret_cast<__m256i*>(ob.QuantaSum), _mm512_extracti64x4_epi64(quantaSum, 1));
}

namespace
{
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
  Moments<false>(steps, taken, rays, sums, warp, quantaPerAbsorbance, nullptr, out);
}

__attribute__((target("avx2"))) void LaneWeightedMomentsAvx2(const LaneSteps& steps, int taken,
  const LaneRays& rays, const double* const sums[4], const LatticeDepthWarp& warp,
  double quantaPerAbsorbance, const LaneWeights& weights, LaneMoments& out)
{
  Moments<true>(steps, taken, rays, sums, warp, quantaPerAbsorbance, &weights, out);
}

} // namespace walk
} // namespace apc
