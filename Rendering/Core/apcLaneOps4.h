// Pass 1's lanes' vector operations four lanes wide (AVX2), as the kernels written once over
// the width use them (apcLaneKernel.h, apcLaneMomentsKernel.h): internal to the files that
// compile those kernels for AVX2, included after their "#pragma GCC target("avx2")".
#ifndef apcLaneOps4_h
#define apcLaneOps4_h

#include "apcLaneMoments.h"
#include "apcLaneSamples.h"

#include <immintrin.h>

#include <cstdint>

namespace apc
{
namespace walk
{
namespace
{

#define APC_AVX2 __attribute__((always_inline)) static inline

// The kernel's operations on four lanes, one group of rays: masks as vectors of all ones or
// zero.
struct Ops4
{
  static constexpr int Width = 4;
  using D = __m256d;
  using M = __m256d;      // a compare's lanes, all ones or zero
  using F = __m128;       // a float per lane
  using I = __m128i;      // a 32-bit integer per lane
  using Counts = __m256i; // a 64-bit integer per lane
  using Rays = LaneRays;
  using Steps = LaneSteps;
  using StepsIn = LaneSteps;
  using Out = LaneMoments;
  using Sums = const double* const*; // the four pixels' five sums each
  // One of LaneCellVectors' broadcast constants.
  APC_AVX2 D C(const double* four) { return _mm256_load_pd(four); }
  // A group's field of four doubles (rays.*field), or row s of one (steps.*field)[s].
  template <class G, class F>
  APC_AVX2 D Load(const G& group, F field)
  {
    return _mm256_load_pd(group.*field);
  }
  template <class G, class F>
  APC_AVX2 D Load(const G& group, F field, int s)
  {
    return _mm256_load_pd((group.*field)[s]);
  }
  APC_AVX2 D Load(const double* p) { return _mm256_load_pd(p); }
  APC_AVX2 void Store(double* p, D a) { _mm256_store_pd(p, a); }
  APC_AVX2 D Direction(const Rays& rays, int i) { return _mm256_load_pd(rays.D[i]); }
  template <class G, class F>
  APC_AVX2 void Store(G& group, F field, int s, D a)
  {
    _mm256_store_pd((group.*field)[s], a);
  }
  APC_AVX2 D Set(double a) { return _mm256_set1_pd(a); }
  APC_AVX2 D Zero() { return _mm256_setzero_pd(); }
  APC_AVX2 D Add(D a, D b) { return _mm256_add_pd(a, b); }
  APC_AVX2 D Sub(D a, D b) { return _mm256_sub_pd(a, b); }
  APC_AVX2 D Mul(D a, D b) { return _mm256_mul_pd(a, b); }
  APC_AVX2 D Div(D a, D b) { return _mm256_div_pd(a, b); }
  // (a < b ? a : b) and (a > b ? a : b), as the instructions give them (NaN: b).
  APC_AVX2 D Min(D a, D b) { return _mm256_min_pd(a, b); }
  APC_AVX2 D Max(D a, D b) { return _mm256_max_pd(a, b); }
  APC_AVX2 D Sqrt(D a) { return _mm256_sqrt_pd(a); }
  APC_AVX2 D Floor(D a) { return _mm256_floor_pd(a); }
  // Unary minus: the sign bit flipped.
  APC_AVX2 D Negate(D a) { return _mm256_xor_pd(a, _mm256_set1_pd(-0.0)); }
  APC_AVX2 D Abs(D a)
  {
    return _mm256_and_pd(a, _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffLL)));
  }
  APC_AVX2 M Lt(D a, D b) { return _mm256_cmp_pd(a, b, _CMP_LT_OQ); }
  APC_AVX2 M Le(D a, D b) { return _mm256_cmp_pd(a, b, _CMP_LE_OQ); }
  APC_AVX2 M Gt(D a, D b) { return _mm256_cmp_pd(a, b, _CMP_GT_OQ); }
  APC_AVX2 M Ge(D a, D b) { return _mm256_cmp_pd(a, b, _CMP_GE_OQ); }
  APC_AVX2 M Neq(D a, D b) { return _mm256_cmp_pd(a, b, _CMP_NEQ_UQ); }
  APC_AVX2 M Eq(D a, D b) { return _mm256_cmp_pd(a, b, _CMP_EQ_OQ); }
  APC_AVX2 M Both(M a, M b) { return _mm256_and_pd(a, b); }
  APC_AVX2 bool Any(M m) { return _mm256_movemask_pd(m) != 0; }
  // b where m, else a.
  APC_AVX2 D Blend(D a, D b, M m) { return _mm256_blendv_pd(a, b, m); }
  // a where m, else +0.0.
  APC_AVX2 D Keep(M m, D a) { return _mm256_and_pd(m, a); }
  // The bins (integers 0 .. kBinEnds) as 64-bit integers.
  APC_AVX2 void StoreBins(Steps& steps, D bin)
  {
    _mm256_store_si256(
      reinterpret_cast<__m256i*>(steps.Bin), _mm256_cvtepi32_epi64(_mm256_cvttpd_epi32(bin)));
  }
  // TransferTable::Lookup's entries and interpolation at x (0 .. Last; 0 where not finite),
  // each lane's absorbance stored as a float in step s, +0.0 where finite is not set.
  APC_AVX2 void Absorbances(const float* absorbancePairs, D x, M finite, Steps& steps, int s)
  {
    // Each 64-bit lane's low halves, then its high halves: a double mask as four floats, and
    // a pair's two absorbances as two vectors of four.
    const __m256i halves = _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7);
    const long long* pairs = reinterpret_cast<const long long*>(absorbancePairs);
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
    _mm_store_ps(steps.Absorbance[s], _mm_and_ps(absorbance, keep));
  }

  // The hand-over's (apcLaneMomentsKernel.h).

  // Rows r0 .. r3 to columns: c[j] holds r0[j], r1[j], r2[j], r3[j] (its own inverse).
  APC_AVX2 void Transpose(D r0, D r1, D r2, D r3, D* c)
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
  // The four pixels' sums, moment m of every pixel in b[m].
  APC_AVX2 void LoadSums(Sums sums, D* b)
  {
    Transpose(_mm256_loadu_pd(sums[0]), _mm256_loadu_pd(sums[1]), _mm256_loadu_pd(sums[2]),
      _mm256_loadu_pd(sums[3]), b);
    b[4] = _mm256_setr_pd(sums[0][4], sums[1][4], sums[2][4], sums[3][4]);
  }
  APC_AVX2 F LoadAbsorbance(const StepsIn& steps, int s)
  {
    return _mm_load_ps(steps.Absorbance[s]);
  }
  APC_AVX2 D Widen(F a) { return _mm256_cvtps_pd(a); }
  // entries[index] where take, else 0.
  APC_AVX2 D Gather(const double* entries, D index, M take)
  {
    return _mm256_mask_i32gather_pd(
      _mm256_setzero_pd(), entries, _mm256_cvttpd_epi32(_mm256_and_pd(index, take)), take, 8);
  }
  // A bit per lane where vis is set and inTable is not.
  APC_AVX2 unsigned Missing(M inTable, M vis)
  {
    return static_cast<unsigned>(_mm256_movemask_pd(_mm256_andnot_pd(inTable, vis)));
  }
  APC_AVX2 void StoreZ(Out& out, int s, D z) { _mm_store_ps(out.Z[s], _mm256_cvtpd_ps(z)); }
  APC_AVX2 I Truncate(D a) { return _mm256_cvttpd_epi32(a); }
  APC_AVX2 void StoreQuanta(Out& out, int s, I q)
  {
    _mm_store_si128(reinterpret_cast<__m128i*>(out.Quanta[s]), q);
  }
  APC_AVX2 I NoQuanta() { return _mm_setzero_si128(); }
  APC_AVX2 I AddQuanta(I a, I b) { return _mm_add_epi32(a, b); }
  APC_AVX2 Counts NoCounts() { return _mm256_setzero_si256(); }
  // One more where inside (all ones: -1).
  APC_AVX2 Counts CountIn(Counts count, M inside)
  {
    return _mm256_sub_epi64(count, _mm256_castpd_si256(inside));
  }
  // Bit s set where vis.
  APC_AVX2 Counts Mark(Counts visible, M vis, int s)
  {
    return _mm256_or_si256(
      visible, _mm256_and_si256(_mm256_castpd_si256(vis), _mm256_set1_epi64x(int64_t(1) << s)));
  }
  APC_AVX2 void StoreMoments(Out& out, const D* b, Counts count, Counts visible, I quanta)
  {
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

  // The clip's (apcRayClipKernel.h): a packet of four rays from ray l on.
  using Packet = int;
  // The rays' origins read per plane (memory operands; held across the plane loop they
  // cost the four-wide clip about 5 % more instructions).
  static constexpr bool kOriginsOnce = false;
  static constexpr int kAllLanes = 0xF;
  // v[l .. l + 3].
  APC_AVX2 D Row(const double* v, Packet l) { return _mm256_loadu_pd(v + l); }
  // v[l .. l + 3] where valid, else 0 (nothing read there).
  APC_AVX2 D RowWhere(const double* v, Packet l, M valid)
  {
    return _mm256_maskload_pd(v + l, _mm256_castpd_si256(valid));
  }
  APC_AVX2 D Ceil(D a) { return _mm256_round_pd(a, _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC); }
  APC_AVX2 M None() { return _mm256_setzero_pd(); }
  APC_AVX2 M Or(M a, M b) { return _mm256_or_pd(a, b); }
  // b and not a.
  APC_AVX2 M AndNot(M a, M b) { return _mm256_andnot_pd(a, b); }
  // A bit per lane.
  APC_AVX2 int Bits(M m) { return _mm256_movemask_pd(m); }
};

#undef APC_AVX2

} // namespace
} // namespace walk
} // namespace apc

#endif
