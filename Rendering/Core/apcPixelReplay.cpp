#include "apcPixelReplay.h"
#include "apcPixelReplayAvx512.h"

#include <cmath>
#include <cstring>
#include <type_traits>

#if defined(__GNUC__) && defined(__x86_64__)
#include "apcFourMomentLanes.h"
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
// OpacityOfAbsorbance, FourMomentWeightsBody), written for 4 lanes: for one group (__m256d) or
// two (Two), each lane rounding the same either way.

// Two groups of 4 lanes, every operation done on both, one after the other: the two groups'
// chains of dependent operations (divisions, a square root, two polynomials) interleaved in
// the instruction stream, so that the processor's window, which holds about one group's
// instructions, has both in flight (the groups one after the other left it waiting on one).
struct Two
{
  __m256d A, B;
};

#define APC_UNARY(Name, op)                                                                        \
  APC_AVX2_INLINE __m256d Name(__m256d x)                                                          \
  {                                                                                                \
    return op(x);                                                                                  \
  }                                                                                                \
  APC_AVX2_INLINE Two Name(Two x)                                                                  \
  {                                                                                                \
    return { op(x.A), op(x.B) };                                                                   \
  }
#define APC_BINARY(Name, op)                                                                       \
  APC_AVX2_INLINE __m256d Name(__m256d x, __m256d y)                                               \
  {                                                                                                \
    return op(x, y);                                                                               \
  }                                                                                                \
  APC_AVX2_INLINE Two Name(Two x, Two y)                                                           \
  {                                                                                                \
    return { op(x.A, y.A), op(x.B, y.B) };                                                         \
  }
#define APC_TERNARY(Name, op)                                                                      \
  APC_AVX2_INLINE __m256d Name(__m256d x, __m256d y, __m256d z)                                    \
  {                                                                                                \
    return op(x, y, z);                                                                            \
  }                                                                                                \
  APC_AVX2_INLINE Two Name(Two x, Two y, Two z)                                                    \
  {                                                                                                \
    return { op(x.A, y.A, z.A), op(x.B, y.B, z.B) };                                               \
  }
APC_UNARY(Sqrt, _mm256_sqrt_pd)
APC_BINARY(Add, _mm256_add_pd)
APC_BINARY(Sub, _mm256_sub_pd)
APC_BINARY(Mul, _mm256_mul_pd)
APC_BINARY(Div, _mm256_div_pd)
APC_BINARY(Min, _mm256_min_pd)
APC_BINARY(Max, _mm256_max_pd)
APC_BINARY(And, _mm256_and_pd)
APC_BINARY(AndNot, _mm256_andnot_pd)
APC_BINARY(Or, _mm256_or_pd)
APC_TERNARY(Fmadd, _mm256_fmadd_pd)
APC_TERNARY(Fmsub, _mm256_fmsub_pd)
APC_TERNARY(Fnmadd, _mm256_fnmadd_pd)
APC_TERNARY(Blend, _mm256_blendv_pd)
#undef APC_UNARY
#undef APC_BINARY
#undef APC_TERNARY

template <int Predicate>
APC_AVX2_INLINE __m256d Cmp(__m256d x, __m256d y)
{
  return _mm256_cmp_pd(x, y, Predicate);
}
template <int Predicate>
APC_AVX2_INLINE Two Cmp(Two x, Two y)
{
  return { _mm256_cmp_pd(x.A, y.A, Predicate), _mm256_cmp_pd(x.B, y.B, Predicate) };
}
// The lanes' signs, the second group's above the first's.
APC_AVX2_INLINE int Mask(__m256d x)
{
  return _mm256_movemask_pd(x);
}
APC_AVX2_INLINE int Mask(Two x)
{
  return _mm256_movemask_pd(x.A) | (_mm256_movemask_pd(x.B) << 4);
}
template <class V>
constexpr int kAllLanes = std::is_same<V, Two>::value ? 0xFF : 0xF;
// A group's vector in every group.
template <class V>
APC_AVX2_INLINE V Lift(__m256d x);
template <>
APC_AVX2_INLINE __m256d Lift<__m256d>(__m256d x)
{
  return x;
}
template <>
APC_AVX2_INLINE Two Lift<Two>(__m256d x)
{
  return { x, x };
}
template <class V>
APC_AVX2_INLINE V Splat(double x)
{
  return Lift<V>(_mm256_set1_pd(x));
}
template <class V>
APC_AVX2_INLINE V Bits(int64_t x)
{
  return Lift<V>(_mm256_castsi256_pd(_mm256_set1_epi64x(x)));
}
// p 2^k, k in the low bits of shifted (k + 1.5 2^52): added to the exponent's bits.
APC_AVX2_INLINE __m256d TimesPowerOfTwo(__m256d p, __m256d shifted)
{
  const __m256i kBits =
    _mm256_sub_epi64(_mm256_castpd_si256(shifted), _mm256_set1_epi64x(0x4338000000000000));
  return _mm256_castsi256_pd(
    _mm256_add_epi64(_mm256_castpd_si256(p), _mm256_slli_epi64(kBits, 52)));
}
APC_AVX2_INLINE Two TimesPowerOfTwo(Two p, Two shifted)
{
  return { TimesPowerOfTwo(p.A, shifted.A), TimesPowerOfTwo(p.B, shifted.B) };
}

// c[k] x + c[k + 1]
template <class V>
APC_AVX2_INLINE V Pair(const double* c, int k, V x)
{
  return Fmadd(Splat<V>(c[k]), x, Splat<V>(c[k + 1]));
}

// sum c[k] x^k, k < 14 (the high degrees first in c), by Estrin's scheme: a chain of 5
// multiply-adds instead of Horner's 13, so that the loop's few independent samples keep the
// FMA units busy (pass 2 is bound by this latency, not by the number of operations).
template <class V>
APC_AVX2_INLINE V Estrin14(const double* c, V x)
{
  const V x2 = Mul(x, x);
  const V x4 = Mul(x2, x2);
  const V x8 = Mul(x4, x4);
  const V s0 = Fmadd(Pair(c, 10, x), x2, Pair(c, 12, x)); // degrees 0-3
  const V s1 = Fmadd(Pair(c, 6, x), x2, Pair(c, 8, x));   // 4-7
  const V s2 = Fmadd(Pair(c, 2, x), x2, Pair(c, 4, x));   // 8-11
  const V s3 = Pair(c, 0, x);                             // 12-13
  return Fmadd(Fmadd(s3, x4, s2), x8, Fmadd(s1, x4, s0));
}

// exp(x) for x <= 0: x = k ln 2 + r, e^r by its Taylor series to degree 13, 2^k added to the
// exponent; 0 below -708.
template <class V>
APC_AVX2_INLINE V ExpNonPositive4(V x)
{
  static constexpr double kTaylor[] = { 1.0 / 6227020800.0, 1.0 / 479001600.0, 1.0 / 39916800.0,
    1.0 / 3628800.0, 1.0 / 362880.0, 1.0 / 40320.0, 1.0 / 5040.0, 1.0 / 720.0, 1.0 / 120.0,
    1.0 / 24.0, 1.0 / 6.0, 0.5, 1.0, 1.0 };
  const V lowest = Splat<V>(-708.0);
  const V shifter = Splat<V>(6755399441055744.0);
  const V under = Cmp<_CMP_LT_OQ>(x, lowest);
  const V xc = Blend(x, lowest, under);
  const V shifted = Fmadd(xc, Splat<V>(1.4426950408889634), shifter);
  const V k = Sub(shifted, shifter);
  V r = Fnmadd(k, Splat<V>(6.93147180369123816490e-01), xc);
  r = Fnmadd(k, Splat<V>(1.90821492927058770002e-10), r);
  const V p = Estrin14(kTaylor, r);
  return AndNot(under, TimesPowerOfTwo(p, shifted));
}

// 1 - exp(-a) for a >= 0: below 1/2 a times the series of (1 - exp(-a)) / a to degree 16
// (truncation below 1e-19 relative), above it 1 - exp(-a). Only the forms some lane needs are
// evaluated (most samples are faint: the series alone).
template <class V>
APC_AVX2_INLINE V OpacityOfAbsorbance4(V a)
{
  // (-1)^n / (n + 1)!, n = 16 down to 0; degrees 14-16 ahead of Estrin14's 0-13.
  static constexpr double kSeries[] = { 1.0 / 355687428096000.0, -1.0 / 20922789888000.0,
    1.0 / 1307674368000.0, -1.0 / 87178291200.0, 1.0 / 6227020800.0, -1.0 / 479001600.0,
    1.0 / 39916800.0, -1.0 / 3628800.0, 1.0 / 362880.0, -1.0 / 40320.0, 1.0 / 5040.0, -1.0 / 720.0,
    1.0 / 120.0, -1.0 / 24.0, 1.0 / 6.0, -0.5, 1.0 };
  const V one = Splat<V>(1.0);
  const V small = Cmp<_CMP_LT_OQ>(a, Splat<V>(0.5));
  const int smallLanes = Mask(small);
  V series = Splat<V>(0.0);
  if (smallLanes != 0)
  {
    const V a2 = Mul(a, a);
    const V a4 = Mul(a2, a2);
    const V a14 = Mul(Mul(a4, a4), Mul(a4, a2));
    const V high =
      Fmadd(Fmadd(Splat<V>(kSeries[0]), a, Splat<V>(kSeries[1])), a, Splat<V>(kSeries[2]));
    series = Fmadd(high, a14, Estrin14(kSeries + 3, a));
    series = Mul(a, series);
    if (smallLanes == kAllLanes<V>)
    {
      return series;
    }
  }
  const V large = Sub(one, ExpNonPositive4(Sub(Splat<V>(0.0), a)));
  return Blend(large, series, small);
}

template <class V>
struct Lanes
{
  V Weight;
  V Fallback; // lanes the vector arithmetic cannot answer (Query's full path)
};

using Pixel4 = FourMomentLanes;

// alpha T(z) of 4 samples, FourMomentWeightsBody's arithmetic. Where every visible lane has
// c2 > 0 (the sample outside its support points) the nearer root and its kernel (a square root
// and three divisions, a third of the group's chain of dependent operations) are not formed:
// no such lane takes them, and the lanes that are not visible are never read. Shortcut false:
// always formed (the tests' reference).
template <bool Shortcut, class V>
APC_AVX2_INLINE Lanes<V> Weights4(const Pixel4& px, V raw, V absorbance, V visible)
{
  const V one = Splat<V>(1.0);
  const V zero = Splat<V>(0.0);
  const V l3 = Lift<V>(px.L3), l4 = Lift<V>(px.L4);
  const V l6 = Lift<V>(px.L6), l7 = Lift<V>(px.L7);
  const V l8 = Lift<V>(px.L8);
  const V d0 = Lift<V>(px.D0), d1 = Lift<V>(px.D1);
  const V d2 = Lift<V>(px.D2), beta = Lift<V>(px.Beta);
  const V z = Min(Max(raw, Splat<V>(-1.0)), one);
  const V y1 = Fmadd(l4, z, l3);
  const V y2 = Fmadd(Fmadd(l8, z, l7), z, l6);
  const V u1 = Mul(y1, d1);
  const V u2 = Mul(y2, d2);
  const V kernelAtZ = Fmadd(y2, u2, Fmadd(y1, u1, d0));
  const V c2 = u2;
  const V c1 = Fmadd(u2, l7, u1);
  const V c0 = Fmadd(u1, l3, Fmadd(u2, l6, d0));
  const V disc = Fmsub(c1, c1, Mul(Mul(Splat<V>(4.0), c0), c2));
  const V wz = Div(one, kernelAtZ);
  const V pastVertex = Cmp<_CMP_GT_OQ>(Mul(Mul(Splat<V>(2.0), c2), z), Sub(zero, c1));
  const V outside = Blend(Mul(beta, wz), Fnmadd(Lift<V>(px.OneMinusBeta), wz, one), pastVertex);
  const V discPositive = Cmp<_CMP_GT_OQ>(disc, zero);
  const V c2Positive = Cmp<_CMP_GT_OQ>(c2, zero);
  const V largest = Splat<V>(1.7976931348623157e308);
  const V absMask = Bits<V>(0x7FFFFFFFFFFFFFFF);
  V absorbanceInFront = outside;
  V usual = And(Cmp<_CMP_NEQ_UQ>(c2, zero), discPositive);
  if (!Shortcut || Mask(AndNot(c2Positive, visible)) != 0)
  {
    const V root = Sqrt(And(disc, discPositive));
    const V c1Negative = Cmp<_CMP_LT_OQ>(c1, zero);
    const V signedRoot = Blend(root, Sub(zero, root), c1Negative);
    const V q = Mul(Splat<V>(-0.5), Add(c1, signedRoot));
    const V r0 = Div(q, c2);
    const V r1 = Div(c0, q);
    const V lo = Blend(r1, r0, Cmp<_CMP_LT_OQ>(r0, r1));
    const V ylo1 = Fmadd(l4, lo, l3);
    const V ylo2 = Fmadd(Fmadd(l8, lo, l7), lo, l6);
    const V kernelAtLo = Fmadd(Mul(ylo2, ylo2), d2, Fmadd(Mul(ylo1, ylo1), d1, d0));
    const V between = Fmadd(beta, wz, Div(one, kernelAtLo));
    absorbanceInFront = Blend(between, outside, c2Positive);
    const V loFinite = And(Cmp<_CMP_NEQ_UQ>(q, zero), Cmp<_CMP_LE_OQ>(And(lo, absMask), largest));
    usual = And(usual, Or(c2Positive, loFinite));
  }
  usual = And(usual, Cmp<_CMP_LE_OQ>(And(absorbanceInFront, absMask), largest));
  const V b0 = Lift<V>(px.B0);
  // A lane that is not usual takes its weight from the query (Weigh), so its absorbance need
  // not be zeroed first: with the shortcut, the exponential does not wait for usual.
  const V t = ExpNonPositive4(
    Sub(zero, Mul(b0, Shortcut ? absorbanceInFront : And(absorbanceInFront, usual))));
  const V clamped = Min(Max(t, zero), one);
  return { Mul(OpacityOfAbsorbance4(absorbance), clamped), AndNot(usual, Bits<V>(-1)) };
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

// The group's weights alpha T(z) from the vector arithmetic's (weight, fallback): 0 where a
// lane is hidden, past the run or (as ColourSums::Add skips them) NaN or not positive; what
// the vector arithmetic cannot answer comes from the pixel's query.
APC_AVX2_INLINE __m256d Taken(const MomentTransmittance<4>& t, const Group& g, const Looked& s,
  __m256d weights, __m256d fallbackLanes)
{
  const int fallback = _mm256_movemask_pd(_mm256_and_pd(fallbackLanes, g.Visible));
  if (fallback != 0)
  {
    alignas(32) double weight[4];
    alignas(32) double depth[4];
    alignas(32) double absorbance[4];
    _mm256_store_pd(weight, weights);
    _mm256_store_pd(depth, g.Z);
    _mm256_store_pd(absorbance, s.Absorbance);
    for (int k = 0; k < 4; ++k)
    {
      if (fallback & (1 << k))
      {
        weight[k] = -std::expm1(-absorbance[k]) * t.Query(depth[k]).Transmittance;
      }
    }
    weights = _mm256_load_pd(weight);
  }
  const __m256d take =
    _mm256_and_pd(g.Visible, _mm256_cmp_pd(weights, _mm256_setzero_pd(), _CMP_GT_OQ));
  return _mm256_and_pd(weights, take);
}

template <bool Shortcut>
APC_AVX2_INLINE __m256d Weigh(
  const MomentTransmittance<4>& t, const Pixel4& px, const Group& g, const Looked& s)
{
  const auto l = Weights4<Shortcut>(px, g.Z, s.Absorbance, g.Visible);
  return Taken(t, g, s, l.Weight, l.Fallback);
}

// Two groups weighed together (Two): each lane's arithmetic is the one group's, so the same
// bits. A shortcut is taken where both groups may take it.
template <bool Shortcut>
APC_AVX2_INLINE Two WeighTwo(const MomentTransmittance<4>& t, const Pixel4& px, const Group& g1,
  const Looked& s1, const Group& g2, const Looked& s2)
{
  const Lanes<Two> l = Weights4<Shortcut>(
    px, Two{ g1.Z, g2.Z }, Two{ s1.Absorbance, s2.Absorbance }, Two{ g1.Visible, g2.Visible });
  return { Taken(t, g1, s1, l.Weight.A, l.Fallback.A), Taken(t, g2, s2, l.Weight.B, l.Fallback.B) };
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

// 8 samples a step, as two independent groups of 4 weighed together (Two): a group's
// arithmetic is one long chain of dependent operations (divisions, a square root, two
// polynomials), and two of them in flight keep the units busy where one leaves them waiting.
// Weighted: with end weights (a loop of its own: a test of weights per step cost the
// unweighted replay 3 %). Shortcut false: the tests' reference (ReplayKernel::Avx2Full).
template <bool Weighted, bool Shortcut = true>
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
  // Whole steps: no masks.
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
    const Looked s2 =
      Lookup4<Weighted>(table, second.Scalar, Weighted ? weights + at + 4 : nullptr, 4);
    const Two w = WeighTwo<Shortcut>(t, pixel, first, s1, second, s2);
    a.Add(w.A, s1);
    b.Add(w.B, s2);
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
      const Looked s2 =
        Lookup4<Weighted>(table, second.Scalar, Weighted ? weights + at + 4 : nullptr, rest - 4);
      const Two w = WeighTwo<Shortcut>(t, pixel, first, s1, second, s2);
      a.Add(w.A, s1);
      b.Add(w.B, s2);
    }
  }
  else if (rest > 0)
  {
    const Group first = Load(samples + at, rest, hidden);
    skipped += first.Hidden;
    if (_mm256_movemask_pd(first.Visible) != 0)
    {
      const Looked s =
        Lookup4<Weighted>(table, first.Scalar, Weighted ? weights + at : nullptr, rest);
      a.Add(Weigh<Shortcut>(t, pixel, first, s), s);
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
    case ReplayKernel::Avx2Full:
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
    else if (kernel == ReplayKernel::Avx2)
    {
      hidden += weights ? ReplayAvx2<true>(t, px, hiddenFrom, table, samples, n, sums, weights)
                        : ReplayAvx2<false>(t, px, hiddenFrom, table, samples, n, sums, nullptr);
    }
    else
    {
      hidden += weights
        ? ReplayAvx2<true, false>(t, px, hiddenFrom, table, samples, n, sums, weights)
        : ReplayAvx2<false, false>(t, px, hiddenFrom, table, samples, n, sums, nullptr);
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
