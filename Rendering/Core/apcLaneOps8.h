// Pass 1's lanes' vector operations eight lanes wide (AVX-512 F and VL) on two groups of four
// lanes side by side, group a low and group b high, as the kernels written once over the width
// use them (apcLaneKernel.h, apcLaneMomentsKernel.h): internal to the files that compile those
// kernels for AVX-512, included after their "#pragma GCC target". Compares give mask registers,
// where AVX2's give vector masks: blends and the zeroing of a lane select the same values.
#ifndef apcLaneOps8_h
#define apcLaneOps8_h

#include "apcLaneMoments.h"
#include "apcLaneSamples.h"

#include "apcLaneOps4.h"

#include <immintrin.h>

#include <cstdint>

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
  // Two groups of four lanes: group a low, group b high.
  template <class T>
  struct Two
  {
    T& A;
    T& B;
  };
  using F = __m256;       // a float per lane
  using I = __m256i;      // a 32-bit integer per lane
  using Counts = __m512i; // a 64-bit integer per lane
  using Rays = Two<const LaneRays>;
  using Steps = Two<LaneSteps>;
  using StepsIn = Two<const LaneSteps>;
  using Out = Two<LaneMoments>;
  using Sums = Two<const double* const* const>; // each group's four pixels' five sums
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
  // Both groups' field of four doubles, or row s of one.
  template <class T, class F>
  APC_AVX512 D Load(const Two<T>& groups, F field)
  {
    return Pair(groups.A.*field, groups.B.*field);
  }
  template <class T, class F>
  APC_AVX512 D Load(const Two<T>& groups, F field, int s)
  {
    return Pair((groups.A.*field)[s], (groups.B.*field)[s]);
  }
  APC_AVX512 D Load(const double* p) { return _mm512_load_pd(p); }
  APC_AVX512 void Store(double* p, D a) { _mm512_store_pd(p, a); }
  APC_AVX512 D Direction(const Rays& rays, int i) { return Pair(rays.A.D[i], rays.B.D[i]); }
  template <class T, class F>
  APC_AVX512 void Store(Two<T>& groups, F field, int s, D a)
  {
    Split(a, (groups.A.*field)[s], (groups.B.*field)[s]);
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
  APC_AVX512 M Eq(D a, D b) { return _mm512_cmp_pd_mask(a, b, _CMP_EQ_OQ); }
  APC_AVX512 M Both(M a, M b) { return static_cast<M>(a & b); }
  APC_AVX512 bool Any(M m) { return m != 0; }
  APC_AVX512 D Blend(D a, D b, M m) { return _mm512_mask_blend_pd(m, a, b); }
  APC_AVX512 D Keep(M m, D a) { return _mm512_maskz_mov_pd(m, a); }
  APC_AVX512 void StoreBins(Steps& steps, D bin)
  {
    StoreSplit(steps.A.Bin, steps.B.Bin, _mm512_cvtepi32_epi64(_mm512_cvttpd_epi32(bin)));
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

  // The hand-over's (apcLaneMomentsKernel.h).

  // The low (high = 0) or high four lanes of v.
  APC_AVX512 __m256d Half(D v, int high)
  {
    return high ? _mm512_extractf64x4_pd(v, 1) : _mm512_castpd512_pd256(v);
  }
  APC_AVX512 D Join(__m256d low, __m256d high)
  {
    return _mm512_insertf64x4(_mm512_castpd256_pd512(low), high, 1);
  }
  // Both groups' pixels' sums, moment m of every pixel in b[m].
  APC_AVX512 void LoadSums(const Sums& sums, D* b)
  {
    __m256d ca[4];
    __m256d cb[4];
    const double* const* a = sums.A;
    const double* const* c = sums.B;
    Ops4::Transpose(_mm256_loadu_pd(a[0]), _mm256_loadu_pd(a[1]), _mm256_loadu_pd(a[2]),
      _mm256_loadu_pd(a[3]), ca);
    Ops4::Transpose(_mm256_loadu_pd(c[0]), _mm256_loadu_pd(c[1]), _mm256_loadu_pd(c[2]),
      _mm256_loadu_pd(c[3]), cb);
    for (int m = 0; m < 4; ++m)
    {
      b[m] = Join(ca[m], cb[m]);
    }
    b[4] = _mm512_setr_pd(a[0][4], a[1][4], a[2][4], a[3][4], c[0][4], c[1][4], c[2][4], c[3][4]);
  }
  APC_AVX512 F LoadAbsorbance(const StepsIn& steps, int s)
  {
    return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(steps.A.Absorbance[s])),
      _mm_load_ps(steps.B.Absorbance[s]), 1);
  }
  APC_AVX512 D Widen(F a) { return _mm512_cvtps_pd(a); }
  APC_AVX512 D Gather(const double* entries, D index, M take)
  {
    return _mm512_mask_i32gather_pd(
      _mm512_setzero_pd(), take, _mm512_cvttpd_epi32(_mm512_maskz_mov_pd(take, index)), entries, 8);
  }
  APC_AVX512 unsigned Missing(M inTable, M vis)
  {
    return static_cast<unsigned>(~inTable & vis) & 0xFFu;
  }
  APC_AVX512 void StoreZ(Out& out, int s, D z)
  {
    const __m256 zf = _mm512_cvtpd_ps(z);
    _mm_store_ps(out.A.Z[s], _mm256_castps256_ps128(zf));
    _mm_store_ps(out.B.Z[s], _mm256_extractf128_ps(zf, 1));
  }
  APC_AVX512 I Truncate(D a) { return _mm512_cvttpd_epi32(a); }
  APC_AVX512 void StoreQuanta(Out& out, int s, I q)
  {
    _mm_store_si128(reinterpret_cast<__m128i*>(out.A.Quanta[s]), _mm256_castsi256_si128(q));
    _mm_store_si128(reinterpret_cast<__m128i*>(out.B.Quanta[s]), _mm256_extracti128_si256(q, 1));
  }
  APC_AVX512 I NoQuanta() { return _mm256_setzero_si256(); }
  APC_AVX512 I AddQuanta(I a, I b) { return _mm256_add_epi32(a, b); }
  APC_AVX512 Counts NoCounts() { return _mm512_setzero_si512(); }
  APC_AVX512 Counts CountIn(Counts count, M inside)
  {
    return _mm512_mask_add_epi64(count, inside, count, _mm512_set1_epi64(1));
  }
  APC_AVX512 Counts Mark(Counts visible, M vis, int s)
  {
    return _mm512_mask_or_epi64(visible, vis, visible, _mm512_set1_epi64(int64_t(1) << s));
  }
  APC_AVX512 void StoreMoments(Out& out, const D* b, Counts count, Counts visible, I quanta)
  {
    LaneMoments* groups[2] = { &out.A, &out.B };
    for (int g = 0; g < 2; ++g)
    {
      __m256d rows[4];
      Ops4::Transpose(Half(b[0], g), Half(b[1], g), Half(b[2], g), Half(b[3], g), rows);
      for (int i = 0; i < 4; ++i)
      {
        _mm256_store_pd(groups[g]->Sums[i], rows[i]);
      }
      _mm256_store_pd(groups[g]->Sum4, Half(b[4], g));
    }
    const __m512i quantaSum = _mm512_cvtepi32_epi64(quanta);
    StoreSplit(out.A.Steps, out.B.Steps, count);
    StoreSplit(out.A.Visible, out.B.Visible, visible);
    StoreSplit(out.A.QuantaSum, out.B.QuantaSum, quantaSum);
  }
  // The low four 64-bit integers to a, the high four to b.
  APC_AVX512 void StoreSplit(int64_t* a, int64_t* b, __m512i v)
  {
    _mm256_store_si256(reinterpret_cast<__m256i*>(a), _mm512_castsi512_si256(v));
    _mm256_store_si256(reinterpret_cast<__m256i*>(b), _mm512_extracti64x4_epi64(v, 1));
  }

  // The clip's (apcRayClipKernel.h): two packets of four rays, from ray L0 on low and from L1
  // on high.
  struct Packet
  {
    int L0;
    int L1;
  };
  // The rays' origins loaded once per packet (per plane, each is two loads and an insert, and
  // the plane loop compiled rolled).
  static constexpr bool kOriginsOnce = true;
  static constexpr int kAllLanes = 0xFF;
  // v[L0 .. L0 + 3] low, v[L1 .. L1 + 3] high.
  APC_AVX512 D Row(const double* v, Packet p)
  {
    return _mm512_insertf64x4(
      _mm512_castpd256_pd512(_mm256_loadu_pd(v + p.L0)), _mm256_loadu_pd(v + p.L1), 1);
  }
  APC_AVX512 D RowWhere(const double* v, Packet p, M valid)
  {
    return _mm512_insertf64x4(
      _mm512_castpd256_pd512(_mm256_maskz_loadu_pd(static_cast<__mmask8>(valid & 0xF), v + p.L0)),
      _mm256_maskz_loadu_pd(static_cast<__mmask8>(valid >> 4), v + p.L1), 1);
  }
  APC_AVX512 D Ceil(D a)
  {
    return _mm512_roundscale_pd(a, _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC);
  }
  APC_AVX512 M None() { return 0; }
  APC_AVX512 M Or(M a, M b) { return static_cast<M>(a | b); }
  APC_AVX512 M AndNot(M a, M b) { return static_cast<M>(~a & b); }
  APC_AVX512 int Bits(M m) { return m; }
};

#undef APC_AVX512

} // namespace
} // namespace walk
} // namespace apc

#endif
