// LaneSamplesAvx512: pass 1's lanes kernel on two groups of four rays at once (apcLaneKernel.h
// over AVX-512's vectors and masks), group a in the low four lanes, group b in the high four.
#include "apcLaneSamples.h"

#include "apcCellInterpolation.h"

#include <immintrin.h>

#include <cstdint>

// The headers above are compiled for the default target (their inline functions are shared
// with other files). Every function below, the kernel's templates included, may use AVX-512 F
// and VL (only called where HasAvx512()).
#pragma GCC push_options
#pragma GCC target("avx512f,avx512vl,avx2")

#include "apcLaneKernel.h"

namespace apc
{
namespace walk
{

namespace
{

#define APC_AVX512 __attribute__((always_inline)) static inline

// The kernel's operations on eight lanes: one zmm of doubles, compares in a mask register
// (blends and the zeroing of a lane select the same values as AVX2's vector masks), the rays
// loaded from two groups and the steps stored back to each group's own.
struct Ops8
{
  static constexpr int Width = 8;
  using D = __m512d;
  using M = __mmask8;
  struct Rays
  {
    const LaneRays& A;
    const LaneRays& B;
  };
  struct Steps
  {
    LaneSteps& A;
    LaneSteps& B;
  };
  // Group a's four values low, group b's high.
  APC_AVX512 D Pair(const double* a, const double* b)
  {
    return _mm512_insertf64x4(_mm512_castpd256_pd512(_mm256_load_pd(a)), _mm256_load_pd(b), 1);
  }
  // The low four lanes to a, the high four to b.
  APC_AVX512 void Split(D v, double* a, double* b)
  {
    _mm256_store_pd(a, _mm512_castpd512_pd256(v));
    _mm256_store_pd(b, _mm512_extractf64x4_pd(v, 1));
  }
  // One of LaneCellVectors' four-lane constants in all eight lanes.
  APC_AVX512 D C(const double* four) { return _mm512_broadcast_f64x4(_mm256_load_pd(four)); }
  APC_AVX512 D Load(const Rays& rays, double (LaneRays::*field)[4])
  {
    return Pair(rays.A.*field, rays.B.*field);
  }
  APC_AVX512 D Direction(const Rays& rays, int i) { return Pair(rays.A.D[i], rays.B.D[i]); }
  APC_AVX512 void Store(Steps& steps, double (LaneSteps::*field)[kLaneSteps][4], int s, D a)
  {
    Split(a, (steps.A.*field)[s], (steps.B.*field)[s]);
  }
  APC_AVX512 D Set(double a) { return _mm512_set1_pd(a); }
  APC_AVX512 D Zero() { return _mm512_setzero_pd(); }
  APC_AVX512 D Add(D a, D b) { return _mm512_add_pd(a, b); }
  APC_AVX512 D Sub(D a, D b) { return _mm512_sub_pd(a, b); }
  APC_AVX512 D Mul(D a, D b) { return _mm512_mul_pd(a, b); }
  APC_AVX512 D Div(D a, D b) { return _mm512_div_pd(a, b); }
  APC_AVX512 D Min(D a, D b) { return _mm512_min_pd(a, b); }
  APC_AVX512 D Max(D a, D b) { return _mm512_max_pd(a, b); }
  APC_AVX512 D Sqrt(D a) { return _mm512_sqrt_pd(a); }
  APC_AVX512 D Floor(D a)
  {
    return _mm512_roundscale_pd(a, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
  }
  APC_AVX512 D Negate(D a)
  {
    // _mm512_xor_pd is AVX512DQ's; the integer xor is the same bits.
    return _mm512_castsi512_pd(_mm512_xor_si512(
      _mm512_castpd_si512(a), _mm512_set1_epi64(static_cast<long long>(1ULL << 63))));
  }
  APC_AVX512 D Abs(D a) { return _mm512_abs_pd(a); }
  APC_AVX512 M Lt(D a, D b) { return _mm512_cmp_pd_mask(a, b, _CMP_LT_OQ); }
  APC_AVX512 M Le(D a, D b) { return _mm512_cmp_pd_mask(a, b, _CMP_LE_OQ); }
  APC_AVX512 M Gt(D a, D b) { return _mm512_cmp_pd_mask(a, b, _CMP_GT_OQ); }
  APC_AVX512 M Ge(D a, D b) { return _mm512_cmp_pd_mask(a, b, _CMP_GE_OQ); }
  APC_AVX512 M Neq(D a, D b) { return _mm512_cmp_pd_mask(a, b, _CMP_NEQ_UQ); }
  APC_AVX512 M Both(M a, M b) { return static_cast<M>(a & b); }
  APC_AVX512 bool Any(M m) { return m != 0; }
  APC_AVX512 D Blend(D a, D b, M m) { return _mm512_mask_blend_pd(m, a, b); }
  APC_AVX512 D Keep(M m, D a) { return _mm512_maskz_mov_pd(m, a); }
  APC_AVX512 void StoreBins(Steps& steps, D bin)
  {
    const __m512i bins = _mm512_cvtepi32_epi64(_mm512_cvttpd_epi32(bin));
    _mm256_store_si256(reinterpret_cast<__m256i*>(steps.A.Bin), _mm512_castsi512_si256(bins));
    _mm256_store_si256(reinterpret_cast<__m256i*>(steps.B.Bin), _mm512_extracti64x4_epi64(bins, 1));
  }
  APC_AVX512 void Absorbances(const float* absorbancePairs, D x, M finite, Steps& steps, int s)
  {
    const long long* pairs = reinterpret_cast<const long long*>(absorbancePairs);
    const __m256i i = _mm512_cvttpd_epi32(x);
    const __m256 f = _mm512_cvtpd_ps(_mm512_sub_pd(x, _mm512_cvtepi32_pd(i)));
    // Entry i's and entry j's absorbance, one pair each: the low and high halves of each
    // 64-bit lane.
    const __m512i e = _mm512_i32gather_epi64(i, pairs, 8);
    const __m256 ea = _mm256_castsi256_ps(_mm512_cvtepi64_epi32(e));
    const __m256 eb = _mm256_castsi256_ps(_mm512_cvtepi64_epi32(_mm512_srli_epi64(e, 32)));
    const __m256 absorbance =
      _mm256_maskz_mov_ps(finite, _mm256_add_ps(ea, _mm256_mul_ps(f, _mm256_sub_ps(eb, ea))));
    _mm_store_ps(steps.A.Absorbance[s], _mm256_castps256_ps128(absorbance));
    _mm_store_ps(steps.B.Absorbance[s], _mm256_extractf128_ps(absorbance, 1));
  }
};

#undef APC_AVX512

} // namespace

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
