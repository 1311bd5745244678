#include "apcPixelReplay.h"
#include "apcPixelReplayAvx512.h"

#include <cmath>
#include <cstring>

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#define APC_HAVE_AVX2_REPLAY 1
#define APC_AVX2 __attribute__((target("avx2,fma")))
#define APC_AVX2_INLINE inline __attribute__((always_inline, target("avx2,fma")))
#endif

namespace apc
{

#ifdef APC_HAVE_AVX2_REPLAY
namespace
{

// The arithmetic of apcMomentTransmittance.cpp's batched weights (ExpNonPositive,
// OpacityOfAbsorbance, FourMomentWeightsBody), written for 4 lanes.

// c[k] x + c[k + 1]
APC_AVX2_INLINE __m256d Pair(const double* c, int k, __m256d x)
{
  return _mm256_fmadd_pd(_mm256_set1_pd(c[k]), x, _mm256_set1_pd(c[k + 1]));
}

// sum c[k] x^k, k < 14 (the high degrees first in c), by Estrin's scheme: a chain of 5
// multiply-adds instead of Horner's 13, so that the loop's few independent samples keep the
// FMA units busy (pass 2 is bound by this latency, not by the number of operations).
APC_AVX2_INLINE __m256d Estrin14(const double* c, __m256d x)
{
  const __m256d x2 = _mm256_mul_pd(x, x);
  const __m256d x4 = _mm256_mul_pd(x2, x2);
  const __m256d x8 = _mm256_mul_pd(x4, x4);
  const __m256d s0 = _mm256_fmadd_pd(Pair(c, 10, x), x2, Pair(c, 12, x)); // degrees 0-3
  const __m256d s1 = _mm256_fmadd_pd(Pair(c, 6, x), x2, Pair(c, 8, x));   // 4-7
  const __m256d s2 = _mm256_fmadd_pd(Pair(c, 2, x), x2, Pair(c, 4, x));   // 8-11
  const __m256d s3 = Pair(c, 0, x);                                       // 12-13
  return _mm256_fmadd_pd(_mm256_fmadd_pd(s3, x4, s2), x8, _mm256_fmadd_pd(s1, x4, s0));
}

// exp(x) for x <= 0: x = k ln 2 + r, e^r by its Taylor series to degree 13, 2^k added to the
// exponent; 0 below -708.
APC_AVX2_INLINE __m256d ExpNonPositive4(__m256d x)
{
  static constexpr double kTaylor[] = { 1.0 / 6227020800.0, 1.0 / 479001600.0, 1.0 / 39916800.0,
    1.0 / 3628800.0, 1.0 / 362880.0, 1.0 / 40320.0, 1.0 / 5040.0, 1.0 / 720.0, 1.0 / 120.0,
    1.0 / 24.0, 1.0 / 6.0, 0.5, 1.0, 1.0 };
  const __m256d lowest = _mm256_set1_pd(-708.0);
  const __m256d shifter = _mm256_set1_pd(6755399441055744.0);
  const __m256d under = _mm256_cmp_pd(x, lowest, _CMP_LT_OQ);
  const __m256d xc = _mm256_blendv_pd(x, lowest, under);
  const __m256d shifted = _mm256_fmadd_pd(xc, _mm256_set1_pd(1.4426950408889634), shifter);
  const __m256d k = _mm256_sub_pd(shifted, shifter);
  __m256d r = _mm256_fnmadd_pd(k, _mm256_set1_pd(6.93147180369123816490e-01), xc);
  r = _mm256_fnmadd_pd(k, _mm256_set1_pd(1.90821492927058770002e-10), r);
  const __m256d p = Estrin14(kTaylor, r);
  const __m256i kBits =
    _mm256_sub_epi64(_mm256_castpd_si256(shifted), _mm256_set1_epi64x(0x4338000000000000));
  const __m256i bits = _mm256_add_epi64(_mm256_castpd_si256(p), _mm256_slli_epi64(kBits, 52));
  return _mm256_andnot_pd(under, _mm256_castsi256_pd(bits));
}

// 1 - exp(-a) for a >= 0: below 1/2 a times the series of (1 - exp(-a)) / a to degree 16
// (truncation below 1e-19 relative), above it 1 - exp(-a). Only the forms some lane needs are
// evaluated (most samples are faint: the series alone).
APC_AVX2_INLINE __m256d OpacityOfAbsorbance4(__m256d a)
{
  // (-1)^n / (n + 1)!, n = 16 down to 0; degrees 14-16 ahead of Estrin14's 0-13.
  static constexpr double kSeries[] = { 1.0 / 355687428096000.0, -1.0 / 20922789888000.0,
    1.0 / 1307674368000.0, -1.0 / 87178291200.0, 1.0 / 6227020800.0, -1.0 / 479001600.0,
    1.0 / 39916800.0, -1.0 / 3628800.0, 1.0 / 362880.0, -1.0 / 40320.0, 1.0 / 5040.0, -1.0 / 720.0,
    1.0 / 120.0, -1.0 / 24.0, 1.0 / 6.0, -0.5, 1.0 };
  const __m256d one = _mm256_set1_pd(1.0);
  const __m256d small = _mm256_cmp_pd(a, _mm256_set1_pd(0.5), _CMP_LT_OQ);
  const int smallLanes = _mm256_movemask_pd(small);
  __m256d series = _mm256_setzero_pd();
  if (smallLanes != 0)
  {
    const __m256d a2 = _mm256_mul_pd(a, a);
    const __m256d a4 = _mm256_mul_pd(a2, a2);
    const __m256d a14 = _mm256_mul_pd(_mm256_mul_pd(a4, a4), _mm256_mul_pd(a4, a2));
    const __m256d high =
      _mm256_fmadd_pd(_mm256_fmadd_pd(_mm256_set1_pd(kSeries[0]), a, _mm256_set1_pd(kSeries[1])), a,
        _mm256_set1_pd(kSeries[2]));
    series = _mm256_fmadd_pd(high, a14, Estrin14(kSeries + 3, a));
    series = _mm256_mul_pd(a, series);
    if (smallLanes == 0xF)
    {
      return series;
    }
  }
  const __m256d large = _mm256_sub_pd(one, ExpNonPositive4(_mm256_sub_pd(_mm256_setzero_pd(), a)));
  return _mm256_blendv_pd(large, series, small);
}

struct Lanes
{
  __m256d Weight;
  __m256d Fallback; // lanes the vector arithmetic cannot answer (Query's full path)
};

// A pixel's constants in every lane, set once a pixel: set in each group, they were loaded,
// broadcast and spilled again in every group (the loop has more live vectors than registers).
struct Pixel4
{
  __m256d L3, L4, L6, L7, L8, D0, D1, D2, Beta, OneMinusBeta, B0;

  APC_AVX2_INLINE explicit Pixel4(const FourMomentPixel& px)
    : L3(_mm256_set1_pd(px.L3))
    , L4(_mm256_set1_pd(px.L4))
    , L6(_mm256_set1_pd(px.L6))
    , L7(_mm256_set1_pd(px.L7))
    , L8(_mm256_set1_pd(px.L8))
    , D0(_mm256_set1_pd(px.D0))
    , D1(_mm256_set1_pd(px.D1))
    , D2(_mm256_set1_pd(px.D2))
    , Beta(_mm256_set1_pd(px.Beta))
    , OneMinusBeta(_mm256_sub_pd(_mm256_set1_pd(1.0), this->Beta))
    , B0(_mm256_set1_pd(px.B0))
  {
  }
};

// alpha T(z) of 4 samples, FourMomentWeightsBody's arithmetic. Where every visible lane has
// c2 > 0 (the sample outside its support points) the nearer root and its kernel (a square root
// and three divisions) are not formed: no such lane takes them, and the lanes that are not
// visible are never read.
APC_AVX2_INLINE Lanes Weights4(const Pixel4& px, __m256d raw, __m256d absorbance, __m256d visible)
{
  const __m256d one = _mm256_set1_pd(1.0);
  const __m256d zero = _mm256_setzero_pd();
  const __m256d l3 = px.L3, l4 = px.L4;
  const __m256d l6 = px.L6, l7 = px.L7;
  const __m256d l8 = px.L8;
  const __m256d d0 = px.D0, d1 = px.D1;
  const __m256d d2 = px.D2, beta = px.Beta;
  const __m256d z = _mm256_min_pd(_mm256_max_pd(raw, _mm256_set1_pd(-1.0)), one);
  const __m256d y1 = _mm256_fmadd_pd(l4, z, l3);
  const __m256d y2 = _mm256_fmadd_pd(_mm256_fmadd_pd(l8, z, l7), z, l6);
  const __m256d u1 = _mm256_mul_pd(y1, d1);
  const __m256d u2 = _mm256_mul_pd(y2, d2);
  const __m256d kernelAtZ = _mm256_fmadd_pd(y2, u2, _mm256_fmadd_pd(y1, u1, d0));
  const __m256d c2 = u2;
  const __m256d c1 = _mm256_fmadd_pd(u2, l7, u1);
  const __m256d c0 = _mm256_fmadd_pd(u1, l3, _mm256_fmadd_pd(u2, l6, d0));
  const __m256d disc =
    _mm256_fmsub_pd(c1, c1, _mm256_mul_pd(_mm256_mul_pd(_mm256_set1_pd(4.0), c0), c2));
  const __m256d wz = _mm256_div_pd(one, kernelAtZ);
  const __m256d pastVertex = _mm256_cmp_pd(
    _mm256_mul_pd(_mm256_mul_pd(_mm256_set1_pd(2.0), c2), z), _mm256_sub_pd(zero, c1), _CMP_GT_OQ);
  const __m256d outside = _mm256_blendv_pd(
    _mm256_mul_pd(beta, wz), _mm256_fnmadd_pd(px.OneMinusBeta, wz, one), pastVertex);
  const __m256d discPositive = _mm256_cmp_pd(disc, zero, _CMP_GT_OQ);
  const __m256d c2Positive = _mm256_cmp_pd(c2, zero, _CMP_GT_OQ);
  const __m256d largest = _mm256_set1_pd(1.7976931348623157e308);
  const __m256d absMask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7FFFFFFFFFFFFFFF));
  __m256d absorbanceInFront = outside;
  __m256d usual = _mm256_and_pd(_mm256_cmp_pd(c2, zero, _CMP_NEQ_UQ), discPositive);
  if (_mm256_movemask_pd(_mm256_andnot_pd(c2Positive, visible)) != 0)
  {
    const __m256d root = _mm256_sqrt_pd(_mm256_and_pd(disc, discPositive));
    const __m256d c1Negative = _mm256_cmp_pd(c1, zero, _CMP_LT_OQ);
    const __m256d signedRoot = _mm256_blendv_pd(root, _mm256_sub_pd(zero, root), c1Negative);
    const __m256d q = _mm256_mul_pd(_mm256_set1_pd(-0.5), _mm256_add_pd(c1, signedRoot));
    const __m256d r0 = _mm256_div_pd(q, c2);
    const __m256d r1 = _mm256_div_pd(c0, q);
    const __m256d lo = _mm256_blendv_pd(r1, r0, _mm256_cmp_pd(r0, r1, _CMP_LT_OQ));
    const __m256d ylo1 = _mm256_fmadd_pd(l4, lo, l3);
    const __m256d ylo2 = _mm256_fmadd_pd(_mm256_fmadd_pd(l8, lo, l7), lo, l6);
    const __m256d kernelAtLo = _mm256_fmadd_pd(
      _mm256_mul_pd(ylo2, ylo2), d2, _mm256_fmadd_pd(_mm256_mul_pd(ylo1, ylo1), d1, d0));
    const __m256d between = _mm256_fmadd_pd(beta, wz, _mm256_div_pd(one, kernelAtLo));
    absorbanceInFront = _mm256_blendv_pd(between, outside, c2Positive);
    const __m256d loFinite = _mm256_and_pd(_mm256_cmp_pd(q, zero, _CMP_NEQ_UQ),
      _mm256_cmp_pd(_mm256_and_pd(lo, absMask), largest, _CMP_LE_OQ));
    usual = _mm256_and_pd(usual, _mm256_or_pd(c2Positive, loFinite));
  }
  usual = _mm256_and_pd(
    usual, _mm256_cmp_pd(_mm256_and_pd(absorbanceInFront, absMask), largest, _CMP_LE_OQ));
  const __m256d b0 = px.B0;
  const __m256d t = ExpNonPositive4(
    _mm256_sub_pd(zero, _mm256_mul_pd(b0, _mm256_and_pd(absorbanceInFront, usual))));
  const __m256d clamped = _mm256_min_pd(_mm256_max_pd(t, zero), one);
  return { _mm256_mul_pd(OpacityOfAbsorbance4(absorbance), clamped),
    _mm256_andnot_pd(usual, _mm256_castsi256_pd(_mm256_set1_epi64x(-1))) };
}

// TransferTable::Lookup of 4 scalars: the absorbances widened to double, the colours kept as
// floats (r and g in one vector, b) until they are summed, so that they hold two registers
// instead of three while the weights are formed.
struct Looked
{
  __m256 RG;
  __m128 B;
  __m256d Absorbance;

  APC_AVX2_INLINE __m256d R() const { return _mm256_cvtps_pd(_mm256_castps256_ps128(this->RG)); }
  APC_AVX2_INLINE __m256d G() const { return _mm256_cvtps_pd(_mm256_extractf128_ps(this->RG, 1)); }
  APC_AVX2_INLINE __m256d Blue() const { return _mm256_cvtps_pd(this->B); }
};

APC_AVX2_INLINE __m256 EntryAt(const char* pairs, uint32_t offset)
{
  return _mm256_load_ps(reinterpret_cast<const float*>(pairs + offset));
}

// Weighted: times the samples' end weights (apcEndWeights.h; lanes of them from weights,
// none read past), each a float product as pass 1 took it, formed on the float absorbance
// before it is widened (a product of the widened one, narrowed and widened again, lay on
// the group's chain of dependent operations).
template <bool Weighted = false>
APC_AVX2_INLINE Looked Lookup4(
  const TransferTable::Layout& table, __m256d scalar, const float* weights = nullptr, int lanes = 4)
{
  const __m256d zero = _mm256_setzero_pd();
  const __m256d absMask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7FFFFFFFFFFFFFFF));
  const __m256d finite = _mm256_cmp_pd(
    _mm256_and_pd(scalar, absMask), _mm256_set1_pd(1.7976931348623157e308), _CMP_LE_OQ);
  __m256d x =
    _mm256_mul_pd(_mm256_sub_pd(scalar, _mm256_set1_pd(table.Min)), _mm256_set1_pd(table.Scale));
  const __m256d last = _mm256_set1_pd(table.Last);
  // Lookup's clamps, x > last ? last : x and x < 0 ? 0 : x, as min and max take their
  // operands (the first where the comparison holds, else the second: a NaN stays).
  x = _mm256_max_pd(zero, _mm256_min_pd(last, x));
  x = _mm256_and_pd(x, finite); // a non-finite scalar: entry 0, made transparent below
  const __m128i i = _mm256_cvttpd_epi32(x);
  const __m128 f = _mm256_cvtpd_ps(_mm256_sub_pd(x, _mm256_cvtepi32_pd(i)));
  // Each lane's entry and its difference to the next in one aligned 32-byte load (its byte
  // offset shifted four lanes at a time and taken as unsigned: no shift or sign extension a
  // lane), two lanes' halves paired into one vector each, so that two lanes interpolate in
  // one product and one sum.
  const char* pairs = reinterpret_cast<const char*>(table.EntryDifferences);
  const __m128i offsets = _mm_slli_epi32(i, 5);
  const __m256 p0 = EntryAt(pairs, static_cast<uint32_t>(_mm_cvtsi128_si32(offsets)));
  const __m256 p1 = EntryAt(pairs, static_cast<uint32_t>(_mm_extract_epi32(offsets, 1)));
  const __m256 p2 = EntryAt(pairs, static_cast<uint32_t>(_mm_extract_epi32(offsets, 2)));
  const __m256 p3 = EntryAt(pairs, static_cast<uint32_t>(_mm_extract_epi32(offsets, 3)));
  const __m256 f8 = _mm256_castps128_ps256(f);
  __m256 step01 =
    _mm256_mul_ps(_mm256_permutevar8x32_ps(f8, _mm256_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1)),
      _mm256_permute2f128_ps(p0, p1, 0x31));
  __m256 step23 =
    _mm256_mul_ps(_mm256_permutevar8x32_ps(f8, _mm256_setr_epi32(2, 2, 2, 2, 3, 3, 3, 3)),
      _mm256_permute2f128_ps(p2, p3, 0x31));
  // Rounded before the add, as Lookup's baseline code does: no contraction into an FMA,
  // so that the colours and absorbances are Lookup's to the bit.
  __asm__("" : "+x"(step01), "+x"(step23));
  const __m256 e01 = _mm256_add_ps(_mm256_permute2f128_ps(p0, p1, 0x20), step01);
  const __m256 e23 = _mm256_add_ps(_mm256_permute2f128_ps(p2, p3, 0x20), step23);
  // Lanes 0-3's (r, g, b, a) to channels: (r0 r2 g0 g2 | r1 r3 g1 g3), then in lane order.
  const __m256i order = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
  const __m256 rg = _mm256_permutevar8x32_ps(_mm256_unpacklo_ps(e01, e23), order);
  const __m256 ba = _mm256_permutevar8x32_ps(_mm256_unpackhi_ps(e01, e23), order);
  __m128 absorbance = _mm256_extractf128_ps(ba, 1);
  if (Weighted)
  {
    const __m128 w = lanes >= 4
      ? _mm_loadu_ps(weights)
      : _mm_maskload_ps(
          weights, _mm_cmpgt_epi32(_mm_set1_epi32(lanes), _mm_setr_epi32(0, 1, 2, 3)));
    absorbance = _mm_mul_ps(absorbance, w);
  }
  return { rg, _mm256_castps256_ps128(ba), _mm256_and_pd(_mm256_cvtps_pd(absorbance), finite) };
}

APC_AVX2_INLINE double Total(__m256d v)
{
  const __m128d pairs = _mm_add_pd(_mm256_castpd256_pd128(v), _mm256_extractf128_pd(v, 1));
  return _mm_cvtsd_f64(_mm_add_sd(pairs, _mm_unpackhi_pd(pairs, pairs)));
}

// Up to 4 records (depth, scalar) of a run from samples on: the depths and scalars widened to
// double, and which lanes hold a sample in front of the hidden depth. Past the run's end, the
// load is masked (nothing read) and the lanes are left out.
struct Group
{
  __m256d Z;
  __m256d Scalar;
  __m256d Visible;
  int Hidden;
};

APC_AVX2_INLINE Group Load(const CachedSample* samples, int lanes, __m256d hiddenFrom)
{
  const float* record = reinterpret_cast<const float*>(samples);
  __m256 raw;
  if (lanes >= 4)
  {
    lanes = 4;
    raw = _mm256_loadu_ps(record);
  }
  else
  {
    const __m256i mask =
      _mm256_cmpgt_epi32(_mm256_set1_epi32(2 * lanes), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    raw = _mm256_maskload_ps(record, mask);
  }
  const __m256 split = _mm256_permutevar8x32_ps(raw, _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7));
  Group g;
  g.Z = _mm256_cvtps_pd(_mm256_castps256_ps128(split));
  g.Scalar = _mm256_cvtps_pd(_mm256_extractf128_ps(split, 1));
  const __m256d valid =
    _mm256_cmp_pd(_mm256_setr_pd(0, 1, 2, 3), _mm256_set1_pd(lanes), _CMP_LT_OQ);
  g.Visible = _mm256_and_pd(valid, _mm256_cmp_pd(g.Z, hiddenFrom, _CMP_NGE_UQ));
  g.Hidden = lanes - __builtin_popcount(_mm256_movemask_pd(g.Visible));
  return g;
}

// Load of 4 records, none past the run.
APC_AVX2_INLINE Group LoadFour(const CachedSample* samples, __m256d hiddenFrom)
{
  const __m256 raw = _mm256_loadu_ps(reinterpret_cast<const float*>(samples));
  const __m256 split = _mm256_permutevar8x32_ps(raw, _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7));
  Group g;
  g.Z = _mm256_cvtps_pd(_mm256_castps256_ps128(split));
  g.Scalar = _mm256_cvtps_pd(_mm256_extractf128_ps(split, 1));
  g.Visible = _mm256_cmp_pd(g.Z, hiddenFrom, _CMP_NGE_UQ);
  g.Hidden = 4 - __builtin_popcount(_mm256_movemask_pd(g.Visible));
  return g;
}

// The group's weights alpha T(z), 0 where a lane is hidden, past the run or (as
// ColourSums::Add skips them) NaN or not positive; what the vector arithmetic cannot answer
// comes from the pixel's query.
APC_AVX2_INLINE __m256d Weigh(
  const MomentTransmittance<4>& t, const Pixel4& px, const Group& g, const Looked& s)
{
  Lanes l = Weights4(px, g.Z, s.Absorbance, g.Visible);
  const int fallback = _mm256_movemask_pd(_mm256_and_pd(l.Fallback, g.Visible));
  if (fallback != 0)
  {
    alignas(32) double weight[4];
    alignas(32) double depth[4];
    alignas(32) double absorbance[4];
    _mm256_store_pd(weight, l.Weight);
    _mm256_store_pd(depth, g.Z);
    _mm256_store_pd(absorbance, s.Absorbance);
    for (int k = 0; k < 4; ++k)
    {
      if (fallback & (1 << k))
      {
        weight[k] = -std::expm1(-absorbance[k]) * t.Query(depth[k]).Transmittance;
      }
    }
    l.Weight = _mm256_load_pd(weight);
  }
  const __m256d take =
    _mm256_and_pd(g.Visible, _mm256_cmp_pd(l.Weight, _mm256_setzero_pd(), _CMP_GT_OQ));
  return _mm256_and_pd(l.Weight, take);
}

struct Sums4
{
  __m256d R, G, B, W;

  APC_AVX2_INLINE void Add(__m256d weight, const Looked& s)
  {
    this->R = _mm256_fmadd_pd(weight, s.R(), this->R);
    this->G = _mm256_fmadd_pd(weight, s.G(), this->G);
    this->B = _mm256_fmadd_pd(weight, s.Blue(), this->B);
    this->W = _mm256_add_pd(this->W, weight);
  }
};

// 8 samples a step, as two independent groups of 4: a group's arithmetic is one long chain
// of dependent operations (divisions, a square root, two polynomials), and two of them in
// flight keep the units busy where one leaves them waiting. Weighted: with end weights (a
// loop of its own: a test of weights per step cost the unweighted replay 3 %).
template <bool Weighted>
APC_AVX2 int ReplayAvx2(const MomentTransmittance<4>& t, const FourMomentPixel& px,
  double hiddenFrom, const TransferTable::Layout& table, const CachedSample* samples, int n,
  double sums[4], const float* weights)
{
  const Pixel4 pixel(px);
  const __m256d hidden = _mm256_set1_pd(hiddenFrom);
  const __m256d zero = _mm256_setzero_pd();
  Sums4 a{ zero, zero, zero, zero };
  Sums4 b = a;
  int skipped = 0;
  int at = 0;
  // Whole steps: no masks. Each group looked up, weighed and summed before the next is looked
  // up, so that one group's temporaries are live at a time (the processor still overlaps the
  // two chains).
  for (; n - at > 8; at += 8)
  {
    const Group first = LoadFour(samples + at, hidden);
    const Group second = LoadFour(samples + at + 4, hidden);
    skipped += first.Hidden + second.Hidden;
    if ((_mm256_movemask_pd(first.Visible) | _mm256_movemask_pd(second.Visible)) == 0)
    {
      continue;
    }
    const Looked s1 = Lookup4<Weighted>(table, first.Scalar, Weighted ? weights + at : nullptr, 4);
    a.Add(Weigh(t, pixel, first, s1), s1);
    const Looked s2 =
      Lookup4<Weighted>(table, second.Scalar, Weighted ? weights + at + 4 : nullptr, 4);
    b.Add(Weigh(t, pixel, second, s2), s2);
  }
  // The last step's 1-8 samples: one group (masked) up to 4, else a whole one and a masked one.
  const int rest = n - at;
  if (rest > 4)
  {
    const Group first = LoadFour(samples + at, hidden);
    const Group second = Load(samples + at + 4, rest - 4, hidden);
    skipped += first.Hidden + second.Hidden;
    if ((_mm256_movemask_pd(first.Visible) | _mm256_movemask_pd(second.Visible)) != 0)
    {
      const Looked s1 =
        Lookup4<Weighted>(table, first.Scalar, Weighted ? weights + at : nullptr, 4);
      a.Add(Weigh(t, pixel, first, s1), s1);
      const Looked s2 =
        Lookup4<Weighted>(table, second.Scalar, Weighted ? weights + at + 4 : nullptr, rest - 4);
      b.Add(Weigh(t, pixel, second, s2), s2);
    }
  }
  else if (rest > 0)
  {
    const Group first = Load(samples + at, rest, hidden);
    skipped += first.Hidden;
    if (_mm256_movemask_pd(first.Visible) != 0)
    {
      const Looked s = Lookup4<Weighted>(table, first.Scalar, Weighted ? weights + at : nullptr, rest);
      a.Add(Weigh(t, pixel, first, s), s);
    }
  }
  sums[0] += Total(_mm256_add_pd(a.R, b.R));
  sums[1] += Total(_mm256_add_pd(a.G, b.G));
  sums[2] += Total(_mm256_add_pd(a.B, b.B));
  sums[3] += Total(_mm256_add_pd(a.W, b.W));
  return skipped;
}

template <bool Weighted>
APC_AVX2 void LookupFour(const TransferTable::Layout& table, const double scalars[4],
  const float* weights, int lanes, double out[16])
{
  const Looked s = Lookup4<Weighted>(table, _mm256_loadu_pd(scalars), weights, lanes);
  _mm256_storeu_pd(out, s.R());
  _mm256_storeu_pd(out + 4, s.G());
  _mm256_storeu_pd(out + 8, s.Blue());
  _mm256_storeu_pd(out + 12, s.Absorbance);
}

} // namespace
#endif

namespace
{
bool HasAvx2Replay()
{
#ifdef APC_HAVE_AVX2_REPLAY
  static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return has;
#else
  return false;
#endif
}
} // namespace

bool HasReplayKernel(ReplayKernel kernel)
{
  switch (kernel)
  {
    case ReplayKernel::Avx512:
      return HasAvx512Replay();
    case ReplayKernel::Avx2:
      return HasAvx2Replay();
    case ReplayKernel::Best:
      break;
  }
  return HasAvx512Replay() || HasAvx2Replay();
}

bool ReplayFourMomentPixel(const MomentTransmittance<4>& t, double hiddenFrom,
  const TransferTable::Layout& table, const CachedSample* samples, int n, double sums[4],
  int64_t& hidden, const float* weights, ReplayKernel kernel)
{
#ifdef APC_HAVE_AVX2_REPLAY
  // Chosen once: the widest kernel the CPU runs.
  static const ReplayKernel best = HasAvx512Replay()
    ? ReplayKernel::Avx512
    : (HasAvx2Replay() ? ReplayKernel::Avx2 : ReplayKernel::Best);
  if (kernel == ReplayKernel::Best)
  {
    kernel = best;
  }
  else if (!HasReplayKernel(kernel))
  {
    return false;
  }
  FourMomentPixel px;
  if (kernel != ReplayKernel::Best && t.GetFourMomentPixel(px))
  {
    if (kernel == ReplayKernel::Avx512)
    {
      hidden += ReplayFourMomentAvx512(t, px, hiddenFrom, table, samples, n, sums, weights);
    }
    else
    {
      hidden += weights ? ReplayAvx2<true>(t, px, hiddenFrom, table, samples, n, sums, weights)
                        : ReplayAvx2<false>(t, px, hiddenFrom, table, samples, n, sums, nullptr);
    }
    return true;
  }
#endif
  (void)t;
  (void)hiddenFrom;
  (void)table;
  (void)samples;
  (void)n;
  (void)sums;
  (void)hidden;
  (void)weights;
  (void)kernel;
  return false;
}

bool ReplayLookupFour(const TransferTable::Layout& table, const double scalars[4],
  const float* weights, int lanes, double out[16])
{
#ifdef APC_HAVE_AVX2_REPLAY
  if (HasAvx2Replay())
  {
    if (weights)
    {
      LookupFour<true>(table, scalars, weights, lanes, out);
    }
    else
    {
      LookupFour<false>(table, scalars, nullptr, lanes, out);
    }
    return true;
  }
#endif
  (void)table;
  (void)scalars;
  (void)weights;
  (void)lanes;
  (void)out;
  return false;
}

} // namespace apc
