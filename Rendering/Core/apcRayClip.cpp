// Clipping a tile's rays against one cell several rays at a time (walk::ClipRays). Ray by
// ray, the marcher spent much of its time waiting on each ray's divisions and on branches
// that tell a ray inside the cell from one outside, and one with a sample from one without;
// four rays per instruction keep the divider busy and leave only the rays with a sample to
// the sample loop. Every lane performs the IEEE operations of CellPlanes::Clip and
// Lattice::First in the same order, so the intervals and indices are the same bit for bit and
// neighbouring cells still meet exactly.
#include "apcRayClip.h"

#include <cmath>
#include <limits>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define APC_HAVE_AVX2_CLIP 1
#endif

namespace apc
{
namespace walk
{

bool HasAvx2()
{
#ifdef APC_HAVE_AVX2_CLIP
  static const bool avx2 = __builtin_cpu_supports("avx2");
  return avx2;
#else
  return false;
#endif
}

int ClipRaysScalar(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
  const double* stop, double near, const Lattice* lattice, ClippedRays& out)
{
  int n = 0;
  for (int row = 0; row < rect.Rows; ++row)
  {
    const int begin = rect.First + row * rect.Stride;
    for (int l = begin; l < begin + rect.Width; ++l)
    {
      double& tin = out.Tin[l];
      double& tout = out.Tout[l];
      tin = 0.0;
      tout = rays.End[l];
      if (stop)
      {
        tout = std::min(tout, stop[l]);
        if (near >= stop[l])
        {
          tout = -std::numeric_limits<double>::infinity();
          continue;
        }
      }
      const RaySetup ray{ { rays.Ox[l], rays.Oy[l], rays.Oz[l] },
        { rays.Dx[l], rays.Dy[l], rays.Dz[l] }, rays.End[l], rays.Offset[l] };
      planes.Clip(ray, tin, tout);
      bool keep = tin < tout;
      if (keep && lattice)
      {
        const int64_t k = lattice->First(tin, ray.Offset);
        out.Lattice[l] = static_cast<double>(k);
        keep = lattice->At(k, ray.Offset) < tout;
      }
      out.Hits[n] = static_cast<uint16_t>(l);
      n += keep ? 1 : 0;
    }
  }
  return n;
}

#ifdef APC_HAVE_AVX2_CLIP
namespace
{

// Plane p against four rays from l on (directions dx, dy, dz): the denominator n.d and the
// numerator offset - n.o of Clip's quotient. No FMA: the products and sums must round as
// Clip's do, and ParallelOut's as ClipFour's.
__attribute__((target("avx2"), always_inline)) inline void PlaneTerms(const CellPlanes& planes,
  const TileRays& rays, int l, int p, __m256d dx, __m256d dy, __m256d dz, __m256d& denom,
  __m256d& num)
{
  const __m256d nx = _mm256_set1_pd(planes.Nx[p]);
  const __m256d ny = _mm256_set1_pd(planes.Ny[p]);
  const __m256d nz = _mm256_set1_pd(planes.Nz[p]);
  denom = _mm256_add_pd(
    _mm256_add_pd(_mm256_mul_pd(nx, dx), _mm256_mul_pd(ny, dy)), _mm256_mul_pd(nz, dz));
  if (planes.SharedOrigin)
  {
    num = _mm256_set1_pd(planes.Num[p]);
    return;
  }
  const __m256d dot = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(nx, _mm256_loadu_pd(rays.Ox + l)),
                                      _mm256_mul_pd(ny, _mm256_loadu_pd(rays.Oy + l))),
    _mm256_mul_pd(nz, _mm256_loadu_pd(rays.Oz + l)));
  num = _mm256_sub_pd(_mm256_set1_pd(planes.Offset[p]), dot);
}

// The lanes of four rays from l on that run inside a plane of the cell and are outside it (see
// Clip). Rare (rays parallel to a plane), so ClipFour looks for them only where some lane's
// denominator is zero, with the same products and sums.
__attribute__((target("avx2"))) __m256d ParallelOut(
  const CellPlanes& planes, const TileRays& rays, int l)
{
  const __m256d zero = _mm256_setzero_pd();
  const __m256d dx = _mm256_loadu_pd(rays.Dx + l);
  const __m256d dy = _mm256_loadu_pd(rays.Dy + l);
  const __m256d dz = _mm256_loadu_pd(rays.Dz + l);
  __m256d out = zero;
  for (int p = 0; p < planes.Count; ++p)
  {
    __m256d denom;
    __m256d num;
    PlaneTerms(planes, rays, l, p, dx, dy, dz, denom, num);
    __m256d parallelOut = _mm256_cmp_pd(num, zero, _CMP_LT_OQ);
    if (planes.KeepsParallelRays[p] == 0)
    {
      parallelOut = _mm256_or_pd(parallelOut, _mm256_cmp_pd(num, zero, _CMP_EQ_OQ));
    }
    out = _mm256_or_pd(out, _mm256_and_pd(_mm256_cmp_pd(denom, zero, _CMP_EQ_OQ), parallelOut));
  }
  return out;
}

// The interval of four rays from l on; lanes past the row's end (valid) read no stop.
// Only the planes the cell has: the padding planes of CellPlanes clip nothing. No FMA: the
// products and sums must round as Clip's do.
__attribute__((target("avx2"))) inline void ClipFour(const CellPlanes& planes, const TileRays& rays,
  int l, __m256i valid, const double* stop, double near, __m256d& lo, __m256d& hi)
{
  const __m256d zero = _mm256_setzero_pd();
  const __m256d inf = _mm256_set1_pd(std::numeric_limits<double>::infinity());
  const __m256d minusInf = _mm256_set1_pd(-std::numeric_limits<double>::infinity());
  const __m256d dx = _mm256_loadu_pd(rays.Dx + l);
  const __m256d dy = _mm256_loadu_pd(rays.Dy + l);
  const __m256d dz = _mm256_loadu_pd(rays.Dz + l);
  lo = zero;
  hi = _mm256_loadu_pd(rays.End + l);
  __m256d out = zero;
  __m256d parallel = zero; // lanes running inside some plane (rare: see ParallelOut)
  if (stop)
  {
    // min(tout, stop) as std::min keeps tout on a tie. stop holds no padding.
    const __m256d s = _mm256_maskload_pd(stop + l, valid);
    hi = _mm256_min_pd(s, hi);
    out = _mm256_cmp_pd(_mm256_set1_pd(near), s, _CMP_GE_OQ);
  }
  for (int p = 0; p < planes.Count; ++p)
  {
    __m256d denom;
    __m256d num;
    PlaneTerms(planes, rays, l, p, dx, dy, dz, denom, num);
    const __m256d q = _mm256_div_pd(num, denom);
    const __m256d entering = _mm256_cmp_pd(denom, zero, _CMP_LT_OQ);
    const __m256d leaving = _mm256_cmp_pd(denom, zero, _CMP_GT_OQ);
    lo = _mm256_max_pd(_mm256_blendv_pd(minusInf, q, entering), lo);
    hi = _mm256_min_pd(_mm256_blendv_pd(inf, q, leaving), hi);
    parallel = _mm256_or_pd(parallel, _mm256_cmp_pd(denom, zero, _CMP_EQ_OQ));
  }
  if (_mm256_movemask_pd(parallel) != 0)
  {
    out = _mm256_or_pd(out, ParallelOut(planes, rays, l));
  }
  hi = _mm256_blendv_pd(hi, minusInf, out);
}

// Lattice::First(lo) of four rays, as doubles: the ceiling of the quotient is Lattice::First's
// first guess (truncation, then up for a positive fraction), then one step down and one up
// as its loops take them. A lane those steps do not settle (never seen) is marked in the
// returned mask and left to Lattice::First.
__attribute__((target("avx2"))) inline __m256d FirstFour(
  const Lattice& lattice, __m256d lo, __m256d offset, int& unsettled)
{
  const __m256d one = _mm256_set1_pd(1.0);
  const __m256d spacing = _mm256_set1_pd(lattice.Spacing);
  const __m256d x =
    _mm256_sub_pd(_mm256_mul_pd(lo, _mm256_set1_pd(lattice.InverseSpacing)), offset);
  __m256d k = _mm256_round_pd(x, _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC);
  const __m256d down = _mm256_cmp_pd(
    _mm256_mul_pd(_mm256_add_pd(_mm256_sub_pd(k, one), offset), spacing), lo, _CMP_GE_OQ);
  k = _mm256_sub_pd(k, _mm256_and_pd(down, one));
  const __m256d up =
    _mm256_cmp_pd(_mm256_mul_pd(_mm256_add_pd(k, offset), spacing), lo, _CMP_LT_OQ);
  k = _mm256_add_pd(k, _mm256_and_pd(up, one));
  // Settled: t_(k-1) < lo <= t_k.
  const __m256d below = _mm256_cmp_pd(
    _mm256_mul_pd(_mm256_add_pd(_mm256_sub_pd(k, one), offset), spacing), lo, _CMP_LT_OQ);
  const __m256d above =
    _mm256_cmp_pd(_mm256_mul_pd(_mm256_add_pd(k, offset), spacing), lo, _CMP_GE_OQ);
  unsettled = ~_mm256_movemask_pd(_mm256_and_pd(below, above)) & 0xF;
  return k;
}

} // namespace

__attribute__((target("avx2"))) int ClipRaysAvx2(const CellPlanes& planes, const TileRays& rays,
  const RayRect& rect, const double* stop, double near, const Lattice* lattice, ClippedRays& out)
{
  int n = 0;
  for (int row = 0; row < rect.Rows; ++row)
  {
    const int begin = rect.First + row * rect.Stride;
    const int end = begin + rect.Width;
    for (int l = begin; l < end; l += 4)
    {
      const __m256i valid =
        _mm256_cmpgt_epi64(_mm256_set1_epi64x(end - l), _mm256_setr_epi64x(0, 1, 2, 3));
      __m256d lo;
      __m256d hi;
      ClipFour(planes, rays, l, valid, stop, near, lo, hi);
      _mm256_storeu_pd(out.Tin + l, lo);
      _mm256_storeu_pd(out.Tout + l, hi);
      int keep = _mm256_movemask_pd(_mm256_cmp_pd(lo, hi, _CMP_LT_OQ)) &
        _mm256_movemask_pd(_mm256_castsi256_pd(valid));
      if (lattice && keep)
      {
        const __m256d offset = _mm256_loadu_pd(rays.Offset + l);
        int unsettled = 0;
        const __m256d k = FirstFour(*lattice, lo, offset, unsettled);
        _mm256_storeu_pd(out.Lattice + l, k);
        const __m256d first =
          _mm256_mul_pd(_mm256_add_pd(k, offset), _mm256_set1_pd(lattice->Spacing));
        const int inside = _mm256_movemask_pd(_mm256_cmp_pd(first, hi, _CMP_LT_OQ));
        keep = (keep & inside) | (keep & unsettled);
        for (int m = keep & unsettled; m; m &= m - 1)
        {
          const int r = l + __builtin_ctz(m);
          const int64_t kr = lattice->First(out.Tin[r], rays.Offset[r]);
          out.Lattice[r] = static_cast<double>(kr);
          keep &= lattice->At(kr, rays.Offset[r]) < out.Tout[r] ? ~0 : ~(1 << (r - l));
        }
      }
      for (; keep; keep &= keep - 1)
      {
        out.Hits[n++] = static_cast<uint16_t>(l + __builtin_ctz(keep));
      }
    }
  }
  return n;
}
#else
int ClipRaysAvx2(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
  const double* stop, double near, const Lattice* lattice, ClippedRays& out)
{
  return ClipRaysScalar(planes, rays, rect, stop, near, lattice, out);
}
#endif

int ClipRays(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
  const double* stop, double near, const Lattice* lattice, ClippedRays& out)
{
  return HasAvx2() ? ClipRaysAvx2(planes, rays, rect, stop, near, lattice, out)
                   : ClipRaysScalar(planes, rays, rect, stop, near, lattice, out);
}

} // namespace walk
} // namespace apc
