// Four lattice samples of a ray through a nearly affine cell at once (AVX2): their depths,
// clamped scalars and transfer-table absorbances, for the marcher's pass 1, whose visitor
// needs no colour. Per sample, the scalar path (coordinates, the scalar's monomials, the
// clamp, the table's position, entries and interpolation) was a chain of some 55 dependent
// instructions; four lanes run it once. Every lane performs the IEEE operations of
// Lattice::At, the walker's p0 + t dp, CellInterpolator::ScalarAt / LinearScalarAt, the
// clamp and TransferTable::Lookup in the same order, without FMA, so every value is the
// scalar path's bit for bit (TestLinearSamples compares them). Internal to the marcher.
#ifndef apcLinearSamples_h
#define apcLinearSamples_h

#include "apcDepthWarp.h"
#include "apcRayWalk.h"
#include "apcTransferTable.h"

#include <cstdint>
#include <limits>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define APC_HAVE_AVX2_SAMPLES 1
#endif

namespace apc
{
namespace walk
{

// What a cell's linear samples need, copied once per cell: the scalar's monomial
// coefficients (CellInterpolator::ScalarCoefficients) and the cell's scalar range.
struct LinearScalarForm
{
  double SC[8];
  double Lo;
  double Hi;
};

// What pass 1 does with a sample past its look-up, the same for every sample of a frame:
// the lattice depth warp's table and the opaque stop's quanta per unit of absorbance.
struct SampleBookkeeping
{
  LatticeDepthWarp::Layout Warp;
  double QuantaPerAbsorbance;
};

// Four consecutive samples k .. k + 3 of one ray: T (Lattice::At), Scalar (clamped to
// [Lo, Hi]) and Absorbance (TransferTable::Lookup's, 0 for a non-finite scalar); Z, the
// warped depth LatticeDepthWarp's table holds for t, where bit i of Tabled is set (else the
// lane's depth is warped directly); Quanta, OpaqueBins::Quanta(Absorbance).
struct SampleQuad
{
  alignas(32) double T[4];
  alignas(32) double Scalar[4];
  alignas(32) double Z[4];
  alignas(16) float Absorbance[4];
  alignas(16) uint32_t Quanta[4];
  int Tabled;
};

#ifdef APC_HAVE_AVX2_SAMPLES
#define APC_SAMPLES_AVX2 __attribute__((target("avx2")))
#define APC_SAMPLES_AVX2_INLINE inline __attribute__((always_inline, target("avx2")))

APC_SAMPLES_AVX2_INLINE __m256d Times(__m256d x, double c)
{
  return _mm256_mul_pd(x, _mm256_set1_pd(c));
}

// Pyramid: LinearScalarAt's form for a pyramid's (u, v, t); else ScalarAt's.
template <bool Pyramid>
APC_SAMPLES_AVX2_INLINE void LinearSamples4(const Lattice& grid, int64_t k, double offset,
  const double p0[3], const double dp[3], const LinearScalarForm& form,
  const TransferTable::Layout& table, const SampleBookkeeping& after, SampleQuad& out)
{
  // (k + i) as a double is exact (|k| < 2^53), so this is (double(k + i) + offset) * spacing.
  const __m256d kd =
    _mm256_add_pd(_mm256_set1_pd(static_cast<double>(k)), _mm256_set_pd(3.0, 2.0, 1.0, 0.0));
  const __m256d t =
    _mm256_mul_pd(_mm256_add_pd(kd, _mm256_set1_pd(offset)), _mm256_set1_pd(grid.Spacing));
  const __m256d q0 = _mm256_add_pd(_mm256_set1_pd(p0[0]), _mm256_mul_pd(t, _mm256_set1_pd(dp[0])));
  const __m256d q1 = _mm256_add_pd(_mm256_set1_pd(p0[1]), _mm256_mul_pd(t, _mm256_set1_pd(dp[1])));
  const __m256d q2 = _mm256_add_pd(_mm256_set1_pd(p0[2]), _mm256_mul_pd(t, _mm256_set1_pd(dp[2])));
  const double* a = form.SC;
  __m256d v;
  if (Pyramid)
  {
    // a0 + q2 a3 + q0 a1 + q1 a2 + twist a4, twist = r s (1 - q2) where 1 - q2 > 0, r and s
    // the quotients clamped to [0, 1] (std::min(std::max(x, 0), 1): the operand order below
    // keeps a NaN quotient as the scalar form does).
    const __m256d zero = _mm256_setzero_pd();
    const __m256d one = _mm256_set1_pd(1.0);
    const __m256d below = _mm256_sub_pd(one, q2);
    const __m256d r = _mm256_min_pd(one, _mm256_max_pd(zero, _mm256_div_pd(q0, below)));
    const __m256d s = _mm256_min_pd(one, _mm256_max_pd(zero, _mm256_div_pd(q1, below)));
    const __m256d twist = _mm256_and_pd(
      _mm256_cmp_pd(below, zero, _CMP_GT_OQ), _mm256_mul_pd(_mm256_mul_pd(r, s), below));
    v = _mm256_add_pd(_mm256_set1_pd(a[0]), Times(q2, a[3]));
    v = _mm256_add_pd(v, Times(q0, a[1]));
    v = _mm256_add_pd(v, Times(q1, a[2]));
    v = _mm256_add_pd(v, Times(twist, a[4]));
  }
  else
  {
    // ScalarAt: a0 + r a1 + s a2 + t a3 + rs a4 + (r t) a5 + (s t) a6 + (rs t) a7.
    const __m256d rs = _mm256_mul_pd(q0, q1);
    v = _mm256_add_pd(_mm256_set1_pd(a[0]), Times(q0, a[1]));
    v = _mm256_add_pd(v, Times(q1, a[2]));
    v = _mm256_add_pd(v, Times(q2, a[3]));
    v = _mm256_add_pd(v, Times(rs, a[4]));
    v = _mm256_add_pd(v, Times(_mm256_mul_pd(q0, q2), a[5]));
    v = _mm256_add_pd(v, Times(_mm256_mul_pd(q1, q2), a[6]));
    v = _mm256_add_pd(v, Times(_mm256_mul_pd(rs, q2), a[7]));
  }
  // std::min(std::max(v, Lo), Hi): max_pd(Lo, v) is Lo > v ? Lo : v, std::max's value for
  // every v including NaN; min_pd(Hi, m) likewise std::min's.
  const __m256d scalar =
    _mm256_min_pd(_mm256_set1_pd(form.Hi), _mm256_max_pd(_mm256_set1_pd(form.Lo), v));
  // Lookup: a non-finite scalar is transparent (and looks up entry 0, masked below).
  const __m256d absMask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffLL));
  const __m256d finite = _mm256_cmp_pd(_mm256_and_pd(scalar, absMask),
    _mm256_set1_pd(std::numeric_limits<double>::infinity()), _CMP_LT_OQ);
  const __m256d position =
    _mm256_mul_pd(_mm256_sub_pd(scalar, _mm256_set1_pd(table.Min)), _mm256_set1_pd(table.Scale));
  // position < 0 ? 0 : (position > Last ? Last : position), -0 and NaN as the scalar form.
  __m256d x =
    _mm256_min_pd(_mm256_set1_pd(table.Last), _mm256_max_pd(_mm256_setzero_pd(), position));
  x = _mm256_and_pd(finite, x);
  const __m128i i = _mm256_cvttpd_epi32(x);
  const __m128i i1 = _mm_add_epi32(i, _mm_set1_epi32(1));
  const __m128i j = _mm_blendv_epi8(i, i1, _mm_cmpgt_epi32(_mm_set1_epi32(table.Count), i1));
  const __m128 f = _mm256_cvtpd_ps(_mm256_sub_pd(x, _mm256_cvtepi32_pd(i)));
  // Absorbance is the fourth float of each 16-byte entry.
  static_assert(sizeof(TransferSample) == 16, "an entry is four floats");
  const float* absorbances = &table.Entries[0].Absorbance;
  const __m128 ea = _mm_i32gather_ps(absorbances, _mm_slli_epi32(i, 2), 4);
  const __m128 eb = _mm_i32gather_ps(absorbances, _mm_slli_epi32(j, 2), 4);
  const __m128 absorbance = _mm_add_ps(ea, _mm_mul_ps(f, _mm_sub_ps(eb, ea)));
  _mm256_store_pd(out.T, t);
  _mm256_store_pd(out.Scalar, scalar);
  // The mask's low halves, one per lane.
  const __m128 finite4 = _mm256_castps256_ps128(
    _mm256_permutevar8x32_ps(_mm256_castpd_ps(finite), _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6)));
  const __m128 visible = _mm_and_ps(finite4, absorbance);
  _mm_store_ps(out.Absorbance, visible);
  // OpaqueBins::Quanta: q >= kOpaque ? kOpaque : (q > 0 ? q rounded down : 0), NaN to 0.
  const __m256d q =
    _mm256_mul_pd(_mm256_cvtps_pd(visible), _mm256_set1_pd(after.QuantaPerAbsorbance));
  const __m256d qc = _mm256_min_pd(_mm256_max_pd(q, _mm256_setzero_pd()),
    _mm256_set1_pd(static_cast<double>(OpaqueBins::kOpaque)));
  _mm_store_si128(reinterpret_cast<__m128i*>(out.Quanta), _mm256_cvttpd_epi32(qc));
  // LatticeDepthWarp: Z[k - Base] where the index is in the table and t is k * Spacing.
  const LatticeDepthWarp::Layout& warp = after.Warp;
  const __m256i index =
    _mm256_add_epi64(_mm256_set1_epi64x(k - warp.Base), _mm256_setr_epi64x(0, 1, 2, 3));
  const __m256i inTable = _mm256_andnot_si256(_mm256_cmpgt_epi64(_mm256_setzero_si256(), index),
    _mm256_cmpgt_epi64(_mm256_set1_epi64x(warp.Size), index));
  const __m256d tabled = _mm256_and_pd(_mm256_castsi256_pd(inTable),
    _mm256_cmp_pd(t, _mm256_mul_pd(kd, _mm256_set1_pd(warp.Spacing)), _CMP_EQ_OQ));
  _mm256_store_pd(out.Z, _mm256_mask_i64gather_pd(_mm256_setzero_pd(), warp.Z, index, tabled, 8));
  out.Tabled = _mm256_movemask_pd(tabled);
}
#endif

} // namespace walk
} // namespace apc

#endif
