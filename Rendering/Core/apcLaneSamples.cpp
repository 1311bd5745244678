#include "apcLaneSamples.h"

#include "apcCellInterpolation.h"
#include "apcLaneGather.h"

#include <immintrin.h>

#include <limits>

namespace apc
{
namespace walk
{

namespace
{

// The scalar forms a cell's lanes take (CellInterpolator's).
enum class Form
{
  ScalarAt,       // LinearScalarAt of any shape but a pyramid
  LinearPyramid,  // LinearScalarAt of a pyramid
  PyramidScalarAt // a twisted pyramid's closed-form inverse
};

// std::max(a, b) is (a < b ? b : a); _mm256_max_pd(x, y) is (x > y ? x : y): with the
// arguments swapped the same value, NaN and signed zeros included.
__attribute__((target("avx2"), always_inline)) inline __m256d StdMax(__m256d a, __m256d b)
{
  return _mm256_max_pd(b, a);
}

// One of LaneCellVectors' broadcast constants.
__attribute__((target("avx2"), always_inline)) inline __m256d V(const double* four)
{
  return _mm256_load_pd(four);
}

// CellInterpolator::PyramidOutside of (q0, q1, q2); sign holds -0.0 (unary minus flips it).
__attribute__((target("avx2"), always_inline)) inline __m256d Outside(
  __m256d q0, __m256d q1, __m256d q2, __m256d one, __m256d zero, __m256d sign)
{
  const __m256d below = _mm256_sub_pd(one, q2);
  return StdMax(StdMax(StdMax(_mm256_xor_pd(q0, sign), _mm256_sub_pd(q0, below)),
                  StdMax(_mm256_xor_pd(q1, sign), _mm256_sub_pd(q1, below))),
    StdMax(_mm256_xor_pd(q2, sign), zero));
}

// CellInterpolator::PyramidScalarAt at a = (a0, a1, a2), lane by lane: the same operations
// in the same order (PyramidCoordinates, PyramidPoint, PyramidOutside, the sum), the choice
// of root by blends; the other root only where some lane's first lies outside.
__attribute__((target("avx2"), always_inline)) inline __m256d PyramidScalar(
  const LaneCellVectors& cell, __m256d a0, __m256d a1, __m256d a2, __m256d one, __m256d zero)
{
  const __m256d sign = _mm256_set1_pd(-0.0);
  const __m256d g[3] = { V(cell.G[0]), V(cell.G[1]), V(cell.G[2]) };
  const __m256d b = _mm256_add_pd(
    _mm256_add_pd(_mm256_sub_pd(one, a2), _mm256_mul_pd(a0, g[1])), _mm256_mul_pd(a1, g[0]));
  const __m256d cc = _mm256_mul_pd(a0, a1);
  const __m256d root = _mm256_sqrt_pd(
    StdMax(_mm256_add_pd(_mm256_mul_pd(b, b), _mm256_mul_pd(V(cell.FourA), cc)), zero));
  const __m256d denom = _mm256_blendv_pd(
    _mm256_sub_pd(b, root), _mm256_add_pd(b, root), _mm256_cmp_pd(b, zero, _CMP_GE_OQ));
  // denom != 0 (true for NaN) ? 2.0 * C / denom : 0.0
  __m256d w = _mm256_and_pd(_mm256_cmp_pd(denom, zero, _CMP_NEQ_UQ),
    _mm256_div_pd(_mm256_mul_pd(_mm256_set1_pd(2.0), cc), denom));
  __m256d q0 = _mm256_sub_pd(a0, _mm256_mul_pd(g[0], w));
  __m256d q1 = _mm256_sub_pd(a1, _mm256_mul_pd(g[1], w));
  __m256d q2 = _mm256_sub_pd(a2, _mm256_mul_pd(g[2], w));
  if (cell.Other)
  {
    const __m256d outside = Outside(q0, q1, q2, one, zero, sign);
    const __m256d far =
      _mm256_cmp_pd(outside, _mm256_set1_pd(apc::CellInterpolator::kPyramidInside), _CMP_GT_OQ);
    if (_mm256_movemask_pd(far) != 0)
    {
      // A strongly twisted pyramid: the other root where its point lies nearer.
      const __m256d other = _mm256_div_pd(_mm256_xor_pd(denom, sign), V(cell.TwoA));
      const __m256d r0 = _mm256_sub_pd(a0, _mm256_mul_pd(g[0], other));
      const __m256d r1 = _mm256_sub_pd(a1, _mm256_mul_pd(g[1], other));
      const __m256d r2 = _mm256_sub_pd(a2, _mm256_mul_pd(g[2], other));
      const __m256d take = _mm256_and_pd(
        far, _mm256_cmp_pd(Outside(r0, r1, r2, one, zero, sign), outside, _CMP_LT_OQ));
      w = _mm256_blendv_pd(w, other, take);
      q0 = _mm256_blendv_pd(q0, r0, take);
      q1 = _mm256_blendv_pd(q1, r1, take);
      q2 = _mm256_blendv_pd(q2, r2, take);
    }
  }
  __m256d v = _mm256_add_pd(V(cell.SC[0]), _mm256_mul_pd(q0, V(cell.SC[1])));
  v = _mm256_add_pd(v, _mm256_mul_pd(q1, V(cell.SC[2])));
  v = _mm256_add_pd(v, _mm256_mul_pd(q2, V(cell.SC[3])));
  return _mm256_add_pd(v, _mm256_mul_pd(w, V(cell.SC[4])));
}

// Only AVX2, no FMA: a fused multiply-add would round once where the scalar loop rounds
// twice.
template <Form How>
__attribute__((target("avx2"), always_inline)) inline int Lanes(
  const LaneCellVectors& cell, const LaneRays& rays, LaneSteps& steps)
{
  // The pair's set-up for four rays at once: dp = Inverse d, row by row as
  // LinearRayDirection sums it. The cell's constants are read from cell where they are used
  // (memory operands), not held in registers across the loop.
  const __m256d dx = _mm256_load_pd(rays.D[0]);
  const __m256d dy = _mm256_load_pd(rays.D[1]);
  const __m256d dz = _mm256_load_pd(rays.D[2]);
  __m256d dp[3];
  for (int i = 0; i < 3; ++i)
  {
    dp[i] = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(V(cell.Inverse[i][0]), dx),
                            _mm256_mul_pd(V(cell.Inverse[i][1]), dy)),
      _mm256_mul_pd(V(cell.Inverse[i][2]), dz));
  }
  const __m256d zero = _mm256_setzero_pd();
  const __m256d one = _mm256_set1_pd(1.0);
  const __m256d inf = _mm256_set1_pd(std::numeric_limits<double>::infinity());
  const __m256d absMask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffLL));
  // Each 64-bit lane's low halves, then its high halves: a double mask as four floats, and
  // a pair's two absorbances as two vectors of four.
  const __m256i halves = _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7);
  const long long* pairs = reinterpret_cast<const long long*>(cell.AbsorbancePairs);
  const __m256d offset = _mm256_load_pd(rays.Offset);
  const __m256d tout = _mm256_load_pd(rays.Tout);
  __m256d k = _mm256_load_pd(rays.K);
  if (cell.Bins)
  {
    // The number of ends at or before K, BinOf's value, is floor((K - Base) / Width) held to
    // 0 .. kBinEnds (the ends are Base + (b + 1) Width): a multiply instead of a compare per
    // end (and instead of a division, whose latency showed). K - Base and Width are integers
    // below 2^53, exact as doubles. Where the quotient matters (about -1 to 16) the product
    // with the rounded inverse lies within 2^-47 of it, and a quotient that is not an integer
    // lies at least 1 / Width from the next one, so the product's floor is the integers' but
    // where the quotient is an integer n and the product rounds below it (width 49, n = 1):
    // then (floor + 1) Width, exact, is at most K - Base, and the bin is one more. Far from
    // the bins the clamp gives the first or last bin either way.
    const __m256d d = _mm256_sub_pd(k, V(cell.BinBase));
    __m256d bin = _mm256_floor_pd(_mm256_mul_pd(d, V(cell.BinInverse)));
    const __m256d up = _mm256_add_pd(bin, _mm256_set1_pd(1.0));
    bin =
      _mm256_blendv_pd(bin, up, _mm256_cmp_pd(_mm256_mul_pd(up, V(cell.BinWidth)), d, _CMP_LE_OQ));
    bin = _mm256_min_pd(
      _mm256_max_pd(bin, _mm256_setzero_pd()), _mm256_set1_pd(static_cast<double>(kBinEnds)));
    _mm256_store_si256(
      reinterpret_cast<__m256i*>(steps.Bin), _mm256_cvtepi32_epi64(_mm256_cvttpd_epi32(bin)));
  }
  int s = 0;
  for (; s < kLaneSteps; ++s, k = _mm256_add_pd(k, one)) // k + 1 is exact: an integer
  {
    // Lattice::At.
    const __m256d t = _mm256_mul_pd(_mm256_add_pd(k, offset), V(cell.Spacing));
    if (_mm256_movemask_pd(_mm256_cmp_pd(t, tout, _CMP_LT_OQ)) == 0)
    {
      break;
    }
    const __m256d r = _mm256_add_pd(V(cell.P0[0]), _mm256_mul_pd(t, dp[0]));
    const __m256d q = _mm256_add_pd(V(cell.P0[1]), _mm256_mul_pd(t, dp[1]));
    const __m256d u = _mm256_add_pd(V(cell.P0[2]), _mm256_mul_pd(t, dp[2]));
    __m256d v;
    if (How == Form::PyramidScalarAt)
    {
      v = PyramidScalar(cell, r, q, u, one, zero);
    }
    else if (How == Form::LinearPyramid)
    {
      // LinearScalarAt of a pyramid, (r, q, u) its (u, v, t): the twist where 1 - t > 0
      // (0 elsewhere, and for NaN), r and s clamped as std::min(std::max(x, 0.0), 1.0).
      const __m256d below = _mm256_sub_pd(one, u);
      const __m256d rr = _mm256_min_pd(one, _mm256_max_pd(zero, _mm256_div_pd(r, below)));
      const __m256d ss = _mm256_min_pd(one, _mm256_max_pd(zero, _mm256_div_pd(q, below)));
      const __m256d twist = _mm256_and_pd(
        _mm256_cmp_pd(below, zero, _CMP_GT_OQ), _mm256_mul_pd(_mm256_mul_pd(rr, ss), below));
      v = _mm256_add_pd(V(cell.SC[0]), _mm256_mul_pd(u, V(cell.SC[3])));
      v = _mm256_add_pd(v, _mm256_mul_pd(r, V(cell.SC[1])));
      v = _mm256_add_pd(v, _mm256_mul_pd(q, V(cell.SC[2])));
      v = _mm256_add_pd(v, _mm256_mul_pd(twist, V(cell.SC[4])));
    }
    else
    {
      // ScalarAt, summed left to right.
      const __m256d rq = _mm256_mul_pd(r, q);
      v = _mm256_add_pd(V(cell.SC[0]), _mm256_mul_pd(r, V(cell.SC[1])));
      v = _mm256_add_pd(v, _mm256_mul_pd(q, V(cell.SC[2])));
      v = _mm256_add_pd(v, _mm256_mul_pd(u, V(cell.SC[3])));
      v = _mm256_add_pd(v, _mm256_mul_pd(rq, V(cell.SC[4])));
      v = _mm256_add_pd(v, _mm256_mul_pd(_mm256_mul_pd(r, u), V(cell.SC[5])));
      v = _mm256_add_pd(v, _mm256_mul_pd(_mm256_mul_pd(q, u), V(cell.SC[6])));
      v = _mm256_add_pd(v, _mm256_mul_pd(_mm256_mul_pd(rq, u), V(cell.SC[7])));
    }
    // std::min(std::max(v, Lo), Hi): max_pd(Lo, v) is (Lo > v ? Lo : v), NaN kept, as
    // std::max(v, Lo); likewise min_pd(Hi, w) and std::min(w, Hi).
    const __m256d scalar = _mm256_min_pd(V(cell.Hi), _mm256_max_pd(V(cell.Lo), v));
    // TransferTable::Lookup: a scalar that is not finite gives 0 (its lane reads entry 0).
    const __m256d finite = _mm256_cmp_pd(_mm256_and_pd(scalar, absMask), inf, _CMP_LT_OQ);
    const __m256d position = _mm256_mul_pd(_mm256_sub_pd(scalar, V(cell.Min)), V(cell.Scale));
    const __m256d above =
      _mm256_blendv_pd(position, V(cell.Last), _mm256_cmp_pd(position, V(cell.Last), _CMP_GT_OQ));
    __m256d x = _mm256_blendv_pd(above, zero, _mm256_cmp_pd(position, zero, _CMP_LT_OQ));
    x = _mm256_and_pd(x, finite);
    const __m128i i = _mm256_cvttpd_epi32(x);
    const __m128 f = _mm256_cvtpd_ps(_mm256_sub_pd(x, _mm256_cvtepi32_pd(i)));
    // Entry i's and entry j's absorbance (j = i + 1, or i for the last entry), one pair each.
    const __m256 e =
      _mm256_permutevar8x32_ps(_mm256_castsi256_ps(_mm256_i32gather_epi64(pairs, i, 8)), halves);
    const __m128 ea = _mm256_castps256_ps128(e);
    const __m128 eb = _mm256_extractf128_ps(e, 1);
    const __m128 absorbance = _mm_add_ps(ea, _mm_mul_ps(f, _mm_sub_ps(eb, ea)));
    const __m128 keep =
      _mm256_castps256_ps128(_mm256_permutevar8x32_ps(_mm256_castpd_ps(finite), halves));
    _mm256_store_pd(steps.T[s], t);
    _mm256_store_pd(steps.Scalar[s], scalar);
    _mm_store_ps(steps.Absorbance[s], _mm_and_ps(absorbance, keep));
  }
  return s;
}

// The same kernel on two groups of four rays at once, eight lanes (AVX-512): group a's lanes
// low, group b's high, each lane's operations those of Lanes above in the same order, so that
// every value is the four-wide kernel's bit for bit. The masks are mask registers where Lanes
// has vector masks: blends and the zeroing of a lane (and_pd with a mask) select the same
// values. Only AVX-512 F and VL instructions (HasAvx512); the file is compiled without
// contraction to FMA, which avx512f brings.
#define APC_LANES512 __attribute__((target("avx512f,avx512vl,avx2")))
#define APC_LANES512_INLINE inline __attribute__((always_inline, target("avx512f,avx512vl,avx2")))

// One of LaneCellVectors' four-lane constants in all eight lanes.
APC_LANES512_INLINE __m512d W(const double* four)
{
  return _mm512_broadcast_f64x4(_mm256_load_pd(four));
}

// Group a's four values low, group b's high.
APC_LANES512_INLINE __m512d Pair(const double* a, const double* b)
{
  return _mm512_insertf64x4(_mm512_castpd256_pd512(_mm256_load_pd(a)), _mm256_load_pd(b), 1);
}

// The low four lanes to a, the high four to b.
APC_LANES512_INLINE void Split(__m512d v, double* a, double* b)
{
  _mm256_store_pd(a, _mm512_castpd512_pd256(v));
  _mm256_store_pd(b, _mm512_extractf64x4_pd(v, 1));
}

APC_LANES512_INLINE __m512d StdMax8(__m512d a, __m512d b)
{
  return _mm512_max_pd(b, a);
}

// x with its sign flipped (xor with -0.0, as _mm256_xor_pd; _mm512_xor_pd would need DQ).
APC_LANES512_INLINE __m512d Negate8(__m512d x)
{
  return _mm512_castsi512_pd(_mm512_xor_si512(
    _mm512_castpd_si512(x), _mm512_set1_epi64(static_cast<long long>(1ULL << 63))));
}

APC_LANES512_INLINE __m512d Outside8(__m512d q0, __m512d q1, __m512d q2, __m512d one, __m512d zero)
{
  const __m512d below = _mm512_sub_pd(one, q2);
  return StdMax8(StdMax8(StdMax8(Negate8(q0), _mm512_sub_pd(q0, below)),
                   StdMax8(Negate8(q1), _mm512_sub_pd(q1, below))),
    StdMax8(Negate8(q2), zero));
}

APC_LANES512_INLINE __m512d PyramidScalar8(
  const LaneCellVectors& cell, __m512d a0, __m512d a1, __m512d a2, __m512d one, __m512d zero)
{
  const __m512d g[3] = { W(cell.G[0]), W(cell.G[1]), W(cell.G[2]) };
  const __m512d b = _mm512_add_pd(
    _mm512_add_pd(_mm512_sub_pd(one, a2), _mm512_mul_pd(a0, g[1])), _mm512_mul_pd(a1, g[0]));
  const __m512d cc = _mm512_mul_pd(a0, a1);
  const __m512d root = _mm512_sqrt_pd(
    StdMax8(_mm512_add_pd(_mm512_mul_pd(b, b), _mm512_mul_pd(W(cell.FourA), cc)), zero));
  const __m512d denom = _mm512_mask_blend_pd(
    _mm512_cmp_pd_mask(b, zero, _CMP_GE_OQ), _mm512_sub_pd(b, root), _mm512_add_pd(b, root));
  __m512d w = _mm512_maskz_mov_pd(_mm512_cmp_pd_mask(denom, zero, _CMP_NEQ_UQ),
    _mm512_div_pd(_mm512_mul_pd(_mm512_set1_pd(2.0), cc), denom));
  __m512d q0 = _mm512_sub_pd(a0, _mm512_mul_pd(g[0], w));
  __m512d q1 = _mm512_sub_pd(a1, _mm512_mul_pd(g[1], w));
  __m512d q2 = _mm512_sub_pd(a2, _mm512_mul_pd(g[2], w));
  if (cell.Other)
  {
    const __m512d outside = Outside8(q0, q1, q2, one, zero);
    const __mmask8 far = _mm512_cmp_pd_mask(
      outside, _mm512_set1_pd(apc::CellInterpolator::kPyramidInside), _CMP_GT_OQ);
    if (far != 0)
    {
      const __m512d other = _mm512_div_pd(Negate8(denom), W(cell.TwoA));
      const __m512d r0 = _mm512_sub_pd(a0, _mm512_mul_pd(g[0], other));
      const __m512d r1 = _mm512_sub_pd(a1, _mm512_mul_pd(g[1], other));
      const __m512d r2 = _mm512_sub_pd(a2, _mm512_mul_pd(g[2], other));
      const __mmask8 take =
        far & _mm512_cmp_pd_mask(Outside8(r0, r1, r2, one, zero), outside, _CMP_LT_OQ);
      w = _mm512_mask_blend_pd(take, w, other);
      q0 = _mm512_mask_blend_pd(take, q0, r0);
      q1 = _mm512_mask_blend_pd(take, q1, r1);
      q2 = _mm512_mask_blend_pd(take, q2, r2);
    }
  }
  __m512d v = _mm512_add_pd(W(cell.SC[0]), _mm512_mul_pd(q0, W(cell.SC[1])));
  v = _mm512_add_pd(v, _mm512_mul_pd(q1, W(cell.SC[2])));
  v = _mm512_add_pd(v, _mm512_mul_pd(q2, W(cell.SC[3])));
  return _mm512_add_pd(v, _mm512_mul_pd(w, W(cell.SC[4])));
}

template <Form How>
APC_LANES512_INLINE int Lanes8(
  const LaneCellVectors& cell, const LaneRays& a, const LaneRays& b, LaneSteps& sa, LaneSteps& sb)
{
  const __m512d dx = Pair(a.D[0], b.D[0]);
  const __m512d dy = Pair(a.D[1], b.D[1]);
  const __m512d dz = Pair(a.D[2], b.D[2]);
  __m512d dp[3];
  for (int i = 0; i < 3; ++i)
  {
    dp[i] = _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(W(cell.Inverse[i][0]), dx),
                            _mm512_mul_pd(W(cell.Inverse[i][1]), dy)),
      _mm512_mul_pd(W(cell.Inverse[i][2]), dz));
  }
  const __m512d zero = _mm512_setzero_pd();
  const __m512d one = _mm512_set1_pd(1.0);
  const __m512d inf = _mm512_set1_pd(std::numeric_limits<double>::infinity());
  const long long* pairs = reinterpret_cast<const long long*>(cell.AbsorbancePairs);
  const __m512d offset = Pair(a.Offset, b.Offset);
  const __m512d tout = Pair(a.Tout, b.Tout);
  __m512d k = Pair(a.K, b.K);
  if (cell.Bins)
  {
    const __m512d d = _mm512_sub_pd(k, W(cell.BinBase));
    __m512d bin = _mm512_roundscale_pd(
      _mm512_mul_pd(d, W(cell.BinInverse)), _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
    const __m512d up = _mm512_add_pd(bin, one);
    bin = _mm512_mask_blend_pd(
      _mm512_cmp_pd_mask(_mm512_mul_pd(up, W(cell.BinWidth)), d, _CMP_LE_OQ), bin, up);
    bin = _mm512_min_pd(_mm512_max_pd(bin, zero), _mm512_set1_pd(static_cast<double>(kBinEnds)));
    const __m512i bins = _mm512_cvtepi32_epi64(_mm512_cvttpd_epi32(bin));
    _mm256_store_si256(reinterpret_cast<__m256i*>(sa.Bin), _mm512_castsi512_si256(bins));
    _mm256_store_si256(reinterpret_cast<__m256i*>(sb.Bin), _mm512_extracti64x4_epi64(bins, 1));
  }
  int s = 0;
  for (; s < kLaneSteps; ++s, k = _mm512_add_pd(k, one))
  {
    const __m512d t = _mm512_mul_pd(_mm512_add_pd(k, offset), W(cell.Spacing));
    if (_mm512_cmp_pd_mask(t, tout, _CMP_LT_OQ) == 0)
    {
      break;
    }
    const __m512d r = _mm512_add_pd(W(cell.P0[0]), _mm512_mul_pd(t, dp[0]));
    const __m512d q = _mm512_add_pd(W(cell.P0[1]), _mm512_mul_pd(t, dp[1]));
    const __m512d u = _mm512_add_pd(W(cell.P0[2]), _mm512_mul_pd(t, dp[2]));
    __m512d v;
    if (How == Form::PyramidScalarAt)
    {
      v = PyramidScalar8(cell, r, q, u, one, zero);
    }
    else if (How == Form::LinearPyramid)
    {
      const __m512d below = _mm512_sub_pd(one, u);
      const __m512d rr = _mm512_min_pd(one, _mm512_max_pd(zero, _mm512_div_pd(r, below)));
      const __m512d ss = _mm512_min_pd(one, _mm512_max_pd(zero, _mm512_div_pd(q, below)));
      const __m512d twist = _mm512_maskz_mov_pd(
        _mm512_cmp_pd_mask(below, zero, _CMP_GT_OQ), _mm512_mul_pd(_mm512_mul_pd(rr, ss), below));
      v = _mm512_add_pd(W(cell.SC[0]), _mm512_mul_pd(u, W(cell.SC[3])));
      v = _mm512_add_pd(v, _mm512_mul_pd(r, W(cell.SC[1])));
      v = _mm512_add_pd(v, _mm512_mul_pd(q, W(cell.SC[2])));
      v = _mm512_add_pd(v, _mm512_mul_pd(twist, W(cell.SC[4])));
    }
    else
    {
      const __m512d rq = _mm512_mul_pd(r, q);
      v = _mm512_add_pd(W(cell.SC[0]), _mm512_mul_pd(r, W(cell.SC[1])));
      v = _mm512_add_pd(v, _mm512_mul_pd(q, W(cell.SC[2])));
      v = _mm512_add_pd(v, _mm512_mul_pd(u, W(cell.SC[3])));
      v = _mm512_add_pd(v, _mm512_mul_pd(rq, W(cell.SC[4])));
      v = _mm512_add_pd(v, _mm512_mul_pd(_mm512_mul_pd(r, u), W(cell.SC[5])));
      v = _mm512_add_pd(v, _mm512_mul_pd(_mm512_mul_pd(q, u), W(cell.SC[6])));
      v = _mm512_add_pd(v, _mm512_mul_pd(_mm512_mul_pd(rq, u), W(cell.SC[7])));
    }
    const __m512d scalar = _mm512_min_pd(W(cell.Hi), _mm512_max_pd(W(cell.Lo), v));
    const __mmask8 finite = _mm512_cmp_pd_mask(_mm512_abs_pd(scalar), inf, _CMP_LT_OQ);
    const __m512d position = _mm512_mul_pd(_mm512_sub_pd(scalar, W(cell.Min)), W(cell.Scale));
    const __m512d above = _mm512_mask_blend_pd(
      _mm512_cmp_pd_mask(position, W(cell.Last), _CMP_GT_OQ), position, W(cell.Last));
    __m512d x = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(position, zero, _CMP_LT_OQ), above, zero);
    x = _mm512_maskz_mov_pd(finite, x);
    const __m256i i = _mm512_cvttpd_epi32(x);
    const __m256 f = _mm512_cvtpd_ps(_mm512_sub_pd(x, _mm512_cvtepi32_pd(i)));
    // Entry i's and entry j's absorbance, one pair each: the low and high halves of each
    // 64-bit lane.
    const __m512i e = _mm512_i32gather_epi64(i, pairs, 8);
    const __m256 ea = _mm256_castsi256_ps(_mm512_cvtepi64_epi32(e));
    const __m256 eb = _mm256_castsi256_ps(_mm512_cvtepi64_epi32(_mm512_srli_epi64(e, 32)));
    const __m256 absorbance =
      _mm256_maskz_mov_ps(finite, _mm256_add_ps(ea, _mm256_mul_ps(f, _mm256_sub_ps(eb, ea))));
    Split(t, sa.T[s], sb.T[s]);
    Split(scalar, sa.Scalar[s], sb.Scalar[s]);
    _mm_store_ps(sa.Absorbance[s], _mm256_castps256_ps128(absorbance));
    _mm_store_ps(sb.Absorbance[s], _mm256_extractf128_ps(absorbance, 1));
  }
  return s;
}

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
  if (cell.Twisted)
  {
    return Lanes<Form::PyramidScalarAt>(cell, rays, steps);
  }
  return cell.Pyramid ? Lanes<Form::LinearPyramid>(cell, rays, steps)
                      : Lanes<Form::ScalarAt>(cell, rays, steps);
}

APC_LANES512 int LaneSamplesAvx512(
  const LaneCellVectors& cell, const LaneRays& a, const LaneRays& b, LaneSteps& sa, LaneSteps& sb)
{
  if (cell.Twisted)
  {
    return Lanes8<Form::PyramidScalarAt>(cell, a, b, sa, sb);
  }
  return cell.Pyramid ? Lanes8<Form::LinearPyramid>(cell, a, b, sa, sb)
                      : Lanes8<Form::ScalarAt>(cell, a, b, sa, sb);
}

__attribute__((target("avx2"))) void SetUpLaneCell(const LaneCell& cell, LaneCellVectors& vectors)
{
  for (int i = 0; i < 3; ++i)
  {
    for (int j = 0; j < 3; ++j)
    {
      Broadcast(cell.Inverse[i][j], vectors.Inverse[i][j]);
    }
    Broadcast(cell.P0[i], vectors.P0[i]);
  }
  // Twisted or not, only the coefficients the cell's form reads.
  const int coefficients = cell.Pyramid || cell.Twisted ? 5 : 8;
  for (int i = 0; i < coefficients; ++i)
  {
    Broadcast(cell.SC[i], vectors.SC[i]);
  }
  vectors.Twisted = cell.Twisted;
  vectors.Pyramid = cell.Pyramid;
  vectors.Other = false;
  if (cell.Twisted)
  {
    // CellInterpolator::PyramidCoordinates' constants.
    const double* g = cell.G;
    const double A = g[2] - g[0] * g[1];
    for (int i = 0; i < 3; ++i)
    {
      Broadcast(g[i], vectors.G[i]);
    }
    Broadcast(4.0 * A, vectors.FourA);
    Broadcast(2.0 * A, vectors.TwoA);
    vectors.Other = A != 0;
  }
  Broadcast(cell.Lo, vectors.Lo);
  Broadcast(cell.Hi, vectors.Hi);
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

} // namespace walk
} // namespace apc
