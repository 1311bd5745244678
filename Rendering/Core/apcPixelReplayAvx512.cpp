#include "apcPixelReplayAvx512.h"

#include <cmath>

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#define APC_HAVE_AVX512_REPLAY 1
#define APC_AVX512 __attribute__((target("avx512f,avx512dq,avx512vl,avx2,fma")))
#define APC_AVX512_INLINE                                                                          \
  inline __attribute__((always_inline, target("avx512f,avx512dq,avx512vl,avx2,fma")))
#endif

namespace apc
{

#ifdef APC_HAVE_AVX512_REPLAY
namespace
{

// apcPixelReplay.cpp's arithmetic, operation for operation, on 8 lanes: every lane rounds as
// the AVX2 replay's lane does (the same operations in the same order; masks where it blends).

APC_AVX512_INLINE __m512d Pair(const double* c, int k, __m512d x)
{
  return _mm512_fmadd_pd(_mm512_set1_pd(c[k]), x, _mm512_set1_pd(c[k + 1]));
}

APC_AVX512_INLINE __m512d Estrin14(const double* c, __m512d x)
{
  const __m512d x2 = _mm512_mul_pd(x, x);
  const __m512d x4 = _mm512_mul_pd(x2, x2);
  const __m512d x8 = _mm512_mul_pd(x4, x4);
  const __m512d s0 = _mm512_fmadd_pd(Pair(c, 10, x), x2, Pair(c, 12, x));
  const __m512d s1 = _mm512_fmadd_pd(Pair(c, 6, x), x2, Pair(c, 8, x));
  const __m512d s2 = _mm512_fmadd_pd(Pair(c, 2, x), x2, Pair(c, 4, x));
  const __m512d s3 = Pair(c, 0, x);
  return _mm512_fmadd_pd(_mm512_fmadd_pd(s3, x4, s2), x8, _mm512_fmadd_pd(s1, x4, s0));
}

APC_AVX512_INLINE __m512d ExpNonPositive8(__m512d x)
{
  static constexpr double kTaylor[] = { 1.0 / 6227020800.0, 1.0 / 479001600.0, 1.0 / 39916800.0,
    1.0 / 3628800.0, 1.0 / 362880.0, 1.0 / 40320.0, 1.0 / 5040.0, 1.0 / 720.0, 1.0 / 120.0,
    1.0 / 24.0, 1.0 / 6.0, 0.5, 1.0, 1.0 };
  const __m512d lowest = _mm512_set1_pd(-708.0);
  const __m512d shifter = _mm512_set1_pd(6755399441055744.0);
  const __mmask8 under = _mm512_cmp_pd_mask(x, lowest, _CMP_LT_OQ);
  const __m512d xc = _mm512_mask_blend_pd(under, x, lowest);
  const __m512d shifted = _mm512_fmadd_pd(xc, _mm512_set1_pd(1.4426950408889634), shifter);
  const __m512d k = _mm512_sub_pd(shifted, shifter);
  __m512d r = _mm512_fnmadd_pd(k, _mm512_set1_pd(6.93147180369123816490e-01), xc);
  r = _mm512_fnmadd_pd(k, _mm512_set1_pd(1.90821492927058770002e-10), r);
  const __m512d p = Estrin14(kTaylor, r);
  const __m512i kBits =
    _mm512_sub_epi64(_mm512_castpd_si512(shifted), _mm512_set1_epi64(0x4338000000000000));
  const __m512i bits = _mm512_add_epi64(_mm512_castpd_si512(p), _mm512_slli_epi64(kBits, 52));
  return _mm512_maskz_mov_pd(static_cast<__mmask8>(~under), _mm512_castsi512_pd(bits));
}

APC_AVX512_INLINE __m512d OpacityOfAbsorbance8(__m512d a)
{
  static constexpr double kSeries[] = { 1.0 / 355687428096000.0, -1.0 / 20922789888000.0,
    1.0 / 1307674368000.0, -1.0 / 87178291200.0, 1.0 / 6227020800.0, -1.0 / 479001600.0,
    1.0 / 39916800.0, -1.0 / 3628800.0, 1.0 / 362880.0, -1.0 / 40320.0, 1.0 / 5040.0, -1.0 / 720.0,
    1.0 / 120.0, -1.0 / 24.0, 1.0 / 6.0, -0.5, 1.0 };
  const __m512d one = _mm512_set1_pd(1.0);
  const __mmask8 small = _mm512_cmp_pd_mask(a, _mm512_set1_pd(0.5), _CMP_LT_OQ);
  __m512d series = _mm512_setzero_pd();
  if (small != 0)
  {
    const __m512d a2 = _mm512_mul_pd(a, a);
    const __m512d a4 = _mm512_mul_pd(a2, a2);
    const __m512d a14 = _mm512_mul_pd(_mm512_mul_pd(a4, a4), _mm512_mul_pd(a4, a2));
    const __m512d high =
      _mm512_fmadd_pd(_mm512_fmadd_pd(_mm512_set1_pd(kSeries[0]), a, _mm512_set1_pd(kSeries[1])), a,
        _mm512_set1_pd(kSeries[2]));
    series = _mm512_fmadd_pd(high, a14, Estrin14(kSeries + 3, a));
    series = _mm512_mul_pd(a, series);
    if (small == 0xFF)
    {
      return series;
    }
  }
  const __m512d large = _mm512_sub_pd(one, ExpNonPositive8(_mm512_sub_pd(_mm512_setzero_pd(), a)));
  return _mm512_mask_blend_pd(small, large, series);
}

struct Lanes
{
  __m512d Weight;
  __mmask8 Fallback; // lanes the vector arithmetic cannot answer (Query's full path)
};

APC_AVX512_INLINE Lanes Weights8(const FourMomentPixel& px, __m512d raw, __m512d absorbance)
{
  const __m512d one = _mm512_set1_pd(1.0);
  const __m512d zero = _mm512_setzero_pd();
  const __m512d l3 = _mm512_set1_pd(px.L3), l4 = _mm512_set1_pd(px.L4);
  const __m512d l6 = _mm512_set1_pd(px.L6), l7 = _mm512_set1_pd(px.L7);
  const __m512d l8 = _mm512_set1_pd(px.L8);
  const __m512d d0 = _mm512_set1_pd(px.D0), d1 = _mm512_set1_pd(px.D1);
  const __m512d d2 = _mm512_set1_pd(px.D2), beta = _mm512_set1_pd(px.Beta);
  const __m512d z = _mm512_min_pd(_mm512_max_pd(raw, _mm512_set1_pd(-1.0)), one);
  const __m512d y1 = _mm512_fmadd_pd(l4, z, l3);
  const __m512d y2 = _mm512_fmadd_pd(_mm512_fmadd_pd(l8, z, l7), z, l6);
  const __m512d u1 = _mm512_mul_pd(y1, d1);
  const __m512d u2 = _mm512_mul_pd(y2, d2);
  const __m512d kernelAtZ = _mm512_fmadd_pd(y2, u2, _mm512_fmadd_pd(y1, u1, d0));
  const __m512d c2 = u2;
  const __m512d c1 = _mm512_fmadd_pd(u2, l7, u1);
  const __m512d c0 = _mm512_fmadd_pd(u1, l3, _mm512_fmadd_pd(u2, l6, d0));
  const __m512d disc =
    _mm512_fmsub_pd(c1, c1, _mm512_mul_pd(_mm512_mul_pd(_mm512_set1_pd(4.0), c0), c2));
  const __m512d wz = _mm512_div_pd(one, kernelAtZ);
  const __mmask8 pastVertex = _mm512_cmp_pd_mask(
    _mm512_mul_pd(_mm512_mul_pd(_mm512_set1_pd(2.0), c2), z), _mm512_sub_pd(zero, c1), _CMP_GT_OQ);
  const __m512d outside = _mm512_mask_blend_pd(
    pastVertex, _mm512_mul_pd(beta, wz), _mm512_fnmadd_pd(_mm512_sub_pd(one, beta), wz, one));
  const __mmask8 discPositive = _mm512_cmp_pd_mask(disc, zero, _CMP_GT_OQ);
  const __m512d root = _mm512_sqrt_pd(_mm512_maskz_mov_pd(discPositive, disc));
  const __mmask8 c1Negative = _mm512_cmp_pd_mask(c1, zero, _CMP_LT_OQ);
  const __m512d signedRoot = _mm512_mask_blend_pd(c1Negative, root, _mm512_sub_pd(zero, root));
  const __m512d q = _mm512_mul_pd(_mm512_set1_pd(-0.5), _mm512_add_pd(c1, signedRoot));
  const __m512d r0 = _mm512_div_pd(q, c2);
  const __m512d r1 = _mm512_div_pd(c0, q);
  const __m512d lo = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(r0, r1, _CMP_LT_OQ), r1, r0);
  const __m512d ylo1 = _mm512_fmadd_pd(l4, lo, l3);
  const __m512d ylo2 = _mm512_fmadd_pd(_mm512_fmadd_pd(l8, lo, l7), lo, l6);
  const __m512d kernelAtLo = _mm512_fmadd_pd(
    _mm512_mul_pd(ylo2, ylo2), d2, _mm512_fmadd_pd(_mm512_mul_pd(ylo1, ylo1), d1, d0));
  const __m512d between = _mm512_fmadd_pd(beta, wz, _mm512_div_pd(one, kernelAtLo));
  const __mmask8 c2Positive = _mm512_cmp_pd_mask(c2, zero, _CMP_GT_OQ);
  const __m512d absorbanceInFront = _mm512_mask_blend_pd(c2Positive, between, outside);
  const __m512d largest = _mm512_set1_pd(1.7976931348623157e308);
  const __mmask8 loFinite = _mm512_cmp_pd_mask(q, zero, _CMP_NEQ_UQ) &
    _mm512_cmp_pd_mask(_mm512_abs_pd(lo), largest, _CMP_LE_OQ);
  __mmask8 usual = _mm512_cmp_pd_mask(c2, zero, _CMP_NEQ_UQ) & discPositive;
  usual &= c2Positive | loFinite;
  usual &= _mm512_cmp_pd_mask(_mm512_abs_pd(absorbanceInFront), largest, _CMP_LE_OQ);
  const __m512d b0 = _mm512_set1_pd(px.B0);
  const __m512d t = ExpNonPositive8(
    _mm512_sub_pd(zero, _mm512_mul_pd(b0, _mm512_maskz_mov_pd(usual, absorbanceInFront))));
  const __m512d clamped = _mm512_min_pd(_mm512_max_pd(t, zero), one);
  return { _mm512_mul_pd(OpacityOfAbsorbance8(absorbance), clamped),
    static_cast<__mmask8>(~usual) };
}

struct Looked
{
  __m512d R, G, B, Absorbance;
};

// 4 entries interpolated as TransferTable::Lookup does, as the AVX2 replay's Lookup4:
// e[k] = a + f (b - a) with the product rounded before the add.
APC_AVX512_INLINE void Interpolate4(
  const float* entries, const int* ii, const int* jj, const float* ff, __m128 e[4])
{
  for (int k = 0; k < 4; ++k)
  {
    const __m128 a = _mm_loadu_ps(entries + 4 * ii[k]);
    const __m128 b = _mm_loadu_ps(entries + 4 * jj[k]);
    __m128 step = _mm_mul_ps(_mm_set1_ps(ff[k]), _mm_sub_ps(b, a));
    __asm__("" : "+x"(step)); // no contraction into an FMA: Lookup's rounding
    e[k] = _mm_add_ps(a, step);
  }
  _MM_TRANSPOSE4_PS(e[0], e[1], e[2], e[3]);
}

template <bool Weighted>
APC_AVX512_INLINE Looked Lookup8(
  const TransferTable::Layout& table, __m512d scalar, const float* weights, int lanes)
{
  const __m512d zero = _mm512_setzero_pd();
  const __mmask8 finite =
    _mm512_cmp_pd_mask(_mm512_abs_pd(scalar), _mm512_set1_pd(1.7976931348623157e308), _CMP_LE_OQ);
  __m512d x =
    _mm512_mul_pd(_mm512_sub_pd(scalar, _mm512_set1_pd(table.Min)), _mm512_set1_pd(table.Scale));
  const __m512d last = _mm512_set1_pd(table.Last);
  x = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(x, last, _CMP_GT_OQ), x, last);
  x = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(x, zero, _CMP_LT_OQ), x, zero);
  x = _mm512_maskz_mov_pd(finite, x); // a non-finite scalar: entry 0, made transparent below
  const __m256i i = _mm512_cvttpd_epi32(x);
  const __m256i j =
    _mm256_min_epi32(_mm256_add_epi32(i, _mm256_set1_epi32(1)), _mm256_set1_epi32(table.Count - 1));
  const __m256 f = _mm512_cvtpd_ps(_mm512_sub_pd(x, _mm512_cvtepi32_pd(i)));
  alignas(32) int ii[8];
  alignas(32) int jj[8];
  alignas(32) float ff[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(ii), i);
  _mm256_store_si256(reinterpret_cast<__m256i*>(jj), j);
  _mm256_store_ps(ff, f);
  const float* entries = reinterpret_cast<const float*>(table.Entries);
  static_assert(sizeof(TransferSample) == 4 * sizeof(float), "an entry is r, g, b, absorbance");
  __m128 lo[4];
  __m128 hi[4];
  Interpolate4(entries, ii, jj, ff, lo);
  Interpolate4(entries, ii + 4, jj + 4, ff + 4, hi);
  __m256 absorbance = _mm256_set_m128(hi[3], lo[3]);
  if (Weighted)
  {
    const __m256 w = lanes >= 8
      ? _mm256_loadu_ps(weights)
      : _mm256_maskz_loadu_ps(static_cast<__mmask8>((1u << lanes) - 1), weights);
    absorbance = _mm256_mul_ps(absorbance, w);
  }
  return { _mm512_cvtps_pd(_mm256_set_m128(hi[0], lo[0])),
    _mm512_cvtps_pd(_mm256_set_m128(hi[1], lo[1])), _mm512_cvtps_pd(_mm256_set_m128(hi[2], lo[2])),
    _mm512_maskz_mov_pd(finite, _mm512_cvtps_pd(absorbance)) };
}

struct Group
{
  __m512d Z;
  __m512d Scalar;
  __mmask8 Visible;
  int Hidden;
};

// Up to 8 records of a run from samples on; past the run's end nothing is read.
APC_AVX512_INLINE Group Load(const CachedSample* samples, int lanes, __m512d hiddenFrom)
{
  const float* record = reinterpret_cast<const float*>(samples);
  __m512 raw;
  if (lanes >= 8)
  {
    lanes = 8;
    raw = _mm512_loadu_ps(record);
  }
  else
  {
    raw = _mm512_maskz_loadu_ps(static_cast<__mmask16>((1u << (2 * lanes)) - 1), record);
  }
  const __m512 split = _mm512_permutexvar_ps(
    _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 1, 3, 5, 7, 9, 11, 13, 15), raw);
  Group g;
  g.Z = _mm512_cvtps_pd(_mm512_castps512_ps256(split));
  g.Scalar = _mm512_cvtps_pd(_mm256_castpd_ps(_mm512_extractf64x4_pd(_mm512_castps_pd(split), 1)));
  const __mmask8 valid = static_cast<__mmask8>((1u << lanes) - 1);
  g.Visible = valid & _mm512_cmp_pd_mask(g.Z, hiddenFrom, _CMP_NGE_UQ);
  g.Hidden = lanes - __builtin_popcount(g.Visible);
  return g;
}

APC_AVX512_INLINE __m512d Weigh(
  const MomentTransmittance<4>& t, const FourMomentPixel& px, const Group& g, const Looked& s)
{
  Lanes l = Weights8(px, g.Z, s.Absorbance);
  const unsigned fallback = l.Fallback & g.Visible;
  if (fallback != 0)
  {
    alignas(64) double weight[8];
    alignas(64) double depth[8];
    alignas(64) double absorbance[8];
    _mm512_store_pd(weight, l.Weight);
    _mm512_store_pd(depth, g.Z);
    _mm512_store_pd(absorbance, s.Absorbance);
    for (int k = 0; k < 8; ++k)
    {
      if (fallback & (1u << k))
      {
        weight[k] = -std::expm1(-absorbance[k]) * t.Query(depth[k]).Transmittance;
      }
    }
    l.Weight = _mm512_load_pd(weight);
  }
  const __mmask8 take = g.Visible & _mm512_cmp_pd_mask(l.Weight, _mm512_setzero_pd(), _CMP_GT_OQ);
  return _mm512_maskz_mov_pd(take, l.Weight);
}

struct Sums8
{
  __m512d R, G, B, W;

  APC_AVX512_INLINE void Add(__m512d weight, const Looked& s)
  {
    this->R = _mm512_fmadd_pd(weight, s.R, this->R);
    this->G = _mm512_fmadd_pd(weight, s.G, this->G);
    this->B = _mm512_fmadd_pd(weight, s.B, this->B);
    this->W = _mm512_add_pd(this->W, weight);
  }
};

// The AVX2 replay's Total of its two groups' sums added lane by lane.
APC_AVX512_INLINE double Total(__m512d v)
{
  const __m256d halves = _mm256_add_pd(_mm512_castpd512_pd256(v), _mm512_extractf64x4_pd(v, 1));
  const __m128d pairs =
    _mm_add_pd(_mm256_castpd256_pd128(halves), _mm256_extractf128_pd(halves, 1));
  return _mm_cvtsd_f64(_mm_add_sd(pairs, _mm_unpackhi_pd(pairs, pairs)));
}

// 16 samples a step, as two independent groups of 8 (two chains of dependent operations in
// flight, as the AVX2 replay's two groups of 4), both summed into the same 8-lane sums, the
// first group first: lane k then sums samples k, k + 8, k + 16, ..., as the AVX2 replay's
// first group (k < 4) or second group (k >= 4) does. A masked or hidden lane adds +0.
template <bool Weighted>
APC_AVX512 int Replay(const MomentTransmittance<4>& t, const FourMomentPixel& px, double hiddenFrom,
  const TransferTable::Layout& table, const CachedSample* samples, int n, double sums[4],
  const float* weights)
{
  const __m512d hidden = _mm512_set1_pd(hiddenFrom);
  const __m512d zero = _mm512_setzero_pd();
  Sums8 a{ zero, zero, zero, zero };
  int skipped = 0;
  for (int at = 0; at < n; at += 16)
  {
    const Group first = Load(samples + at, n - at, hidden);
    skipped += first.Hidden;
    if (n - at <= 8)
    {
      if (first.Visible != 0)
      {
        const Looked s =
          Lookup8<Weighted>(table, first.Scalar, Weighted ? weights + at : nullptr, n - at);
        a.Add(Weigh(t, px, first, s), s);
      }
      break;
    }
    const Group second = Load(samples + at + 8, n - at - 8, hidden);
    skipped += second.Hidden;
    if ((first.Visible | second.Visible) == 0)
    {
      continue;
    }
    const Looked s1 = Lookup8<Weighted>(table, first.Scalar, Weighted ? weights + at : nullptr, 8);
    const Looked s2 =
      Lookup8<Weighted>(table, second.Scalar, Weighted ? weights + at + 8 : nullptr, n - at - 8);
    const __m512d w1 = Weigh(t, px, first, s1);
    const __m512d w2 = Weigh(t, px, second, s2);
    a.Add(w1, s1);
    a.Add(w2, s2);
  }
  sums[0] += Total(a.R);
  sums[1] += Total(a.G);
  sums[2] += Total(a.B);
  sums[3] += Total(a.W);
  return skipped;
}

} // namespace
#endif

bool HasAvx512Replay()
{
#ifdef APC_HAVE_AVX512_REPLAY
  static const bool has = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
    __builtin_cpu_supports("avx512vl");
  return has;
#else
  return false;
#endif
}

int ReplayFourMomentAvx512(const MomentTransmittance<4>& t, const FourMomentPixel& px,
  double hiddenFrom, const TransferTable::Layout& table, const CachedSample* samples, int n,
  double sums[4], const float* weights)
{
#ifdef APC_HAVE_AVX512_REPLAY
  return weights ? Replay<true>(t, px, hiddenFrom, table, samples, n, sums, weights)
                 : Replay<false>(t, px, hiddenFrom, table, samples, n, sums, nullptr);
#else
  (void)t;
  (void)px;
  (void)hiddenFrom;
  (void)table;
  (void)samples;
  (void)n;
  (void)sums;
  (void)weights;
  return 0;
#endif
}

} // namespace apc
