// LaneSamplesAvx2 (apcLaneKernel.h over AVX2's vectors), the lanes' cell set-up and their
// rays' gathering.
#include "apcLaneSamples.h"

#include "apcCellInterpolation.h"
#include "apcLaneGather.h"

#include <immintrin.h>

#include <cstdint>

// The headers above are compiled for the default target (their inline functions are shared
// with other files). Every function below, the kernel's templates included, may use AVX2 (only
// called where HasAvx2()).
#pragma GCC push_options
#pragma GCC target("avx2")

#include "apcLaneKernel.h"

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
  using M = __m256d; // a compare's lanes, all ones or zero
  using Rays = LaneRays;
  using Steps = LaneSteps;
  // One of LaneCellVectors' broadcast constants.
  APC_AVX2 D C(const double* four) { return _mm256_load_pd(four); }
  APC_AVX2 D Load(const Rays& rays, double (LaneRays::*field)[4])
  {
    return _mm256_load_pd(rays.*field);
  }
  APC_AVX2 D Direction(const Rays& rays, int i) { return _mm256_load_pd(rays.D[i]); }
  APC_AVX2 void Store(Steps& steps, double (LaneSteps::*field)[kLaneSteps][4], int s, D a)
  {
    _mm256_store_pd((steps.*field)[s], a);
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
};

#undef APC_AVX2

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
  using kernel::Form;
  if (cell.Twisted)
  {
    return kernel::Lanes<Form::PyramidScalarAt, Ops4>(cell, rays, steps);
  }
  return cell.Pyramid ? kernel::Lanes<Form::LinearPyramid, Ops4>(cell, rays, steps)
                      : kernel::Lanes<Form::ScalarAt, Ops4>(cell, rays, steps);
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

#pragma GCC pop_options
