// Clipping a tile's rays against one cell several rays at a time (walk::ClipRays). The
// per-ray form spends most of its time waiting on each ray's divisions and on the branch that
// tells a ray inside the cell from one outside; four rays per instruction keep the divider
// busy and leave only the rays inside to the sample loop. Every lane performs the IEEE
// operations of CellPlanes::Clip in the same order, so the intervals are the same bit for bit
// and neighbouring cells still meet exactly.
#include "apcRayWalk.h"

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

int ClipRaysScalar(const CellPlanes& planes, const TileRays& rays, const double* stop, double near,
  int first, int width, int rows, int stride, double* tin, double* tout, uint16_t* hits)
{
  int n = 0;
  for (int row = 0; row < rows; ++row)
  {
    for (int l = first + row * stride; l < first + row * stride + width; ++l)
    {
      tin[l] = 0.0;
      tout[l] = rays.End[l];
      if (stop)
      {
        tout[l] = std::min(tout[l], stop[l]);
        if (near >= stop[l])
        {
          tout[l] = -std::numeric_limits<double>::infinity();
          continue;
        }
      }
      const RaySetup ray{ { rays.Ox[l], rays.Oy[l], rays.Oz[l] },
        { rays.Dx[l], rays.Dy[l], rays.Dz[l] }, rays.End[l], 0.0 };
      planes.Clip(ray, tin[l], tout[l]);
      hits[n] = static_cast<uint16_t>(l);
      n += tin[l] < tout[l] ? 1 : 0;
    }
  }
  return n;
}

#ifdef APC_HAVE_AVX2_CLIP
// Only the planes the cell has: the padding planes of CellPlanes clip nothing. No FMA: the
// products and sums must round as Clip's do.
__attribute__((target("avx2"))) int ClipRaysAvx2(const CellPlanes& planes, const TileRays& rays,
  const double* stop, double near, int first, int width, int rows, int stride, double* tin,
  double* tout, uint16_t* hits)
{
  const __m256d zero = _mm256_setzero_pd();
  const __m256d inf = _mm256_set1_pd(std::numeric_limits<double>::infinity());
  const __m256d minusInf = _mm256_set1_pd(-std::numeric_limits<double>::infinity());
  const __m256d nearT = _mm256_set1_pd(near);
  int n = 0;
  for (int row = 0; row < rows; ++row)
  {
    const int begin = first + row * stride;
    for (int l = begin; l < begin + width; l += 4)
    {
      const __m256d dx = _mm256_loadu_pd(rays.Dx + l);
      const __m256d dy = _mm256_loadu_pd(rays.Dy + l);
      const __m256d dz = _mm256_loadu_pd(rays.Dz + l);
      __m256d lo = zero;
      __m256d hi = _mm256_loadu_pd(rays.End + l);
      __m256d out = zero;
      if (stop)
      {
        // min(tout, stop) as std::min keeps tout on a tie; the cell lies behind the stop.
        // Only the row's rays are read: stop holds no padding.
        const __m256d s = _mm256_maskload_pd(stop + l,
          _mm256_cmpgt_epi64(
            _mm256_set1_epi64x(begin + width - l), _mm256_setr_epi64x(0, 1, 2, 3)));
        hi = _mm256_min_pd(s, hi);
        out = _mm256_cmp_pd(nearT, s, _CMP_GE_OQ);
      }
      for (int p = 0; p < planes.Count; ++p)
      {
        const __m256d nx = _mm256_set1_pd(planes.Nx[p]);
        const __m256d ny = _mm256_set1_pd(planes.Ny[p]);
        const __m256d nz = _mm256_set1_pd(planes.Nz[p]);
        const __m256d denom = _mm256_add_pd(
          _mm256_add_pd(_mm256_mul_pd(nx, dx), _mm256_mul_pd(ny, dy)), _mm256_mul_pd(nz, dz));
        __m256d num;
        if (planes.SharedOrigin)
        {
          num = _mm256_set1_pd(planes.Num[p]);
        }
        else
        {
          const __m256d dot =
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(nx, _mm256_loadu_pd(rays.Ox + l)),
                            _mm256_mul_pd(ny, _mm256_loadu_pd(rays.Oy + l))),
              _mm256_mul_pd(nz, _mm256_loadu_pd(rays.Oz + l)));
          num = _mm256_sub_pd(_mm256_set1_pd(planes.Offset[p]), dot);
        }
        const __m256d q = _mm256_div_pd(num, denom);
        const __m256d entering = _mm256_cmp_pd(denom, zero, _CMP_LT_OQ);
        const __m256d leaving = _mm256_cmp_pd(denom, zero, _CMP_GT_OQ);
        lo = _mm256_max_pd(_mm256_blendv_pd(minusInf, q, entering), lo);
        hi = _mm256_min_pd(_mm256_blendv_pd(inf, q, leaving), hi);
        // A ray inside the plane's line of sight: see Clip.
        __m256d parallelOut = _mm256_cmp_pd(num, zero, _CMP_LT_OQ);
        if (planes.KeepsParallelRays[p] == 0)
        {
          parallelOut = _mm256_or_pd(parallelOut, _mm256_cmp_pd(num, zero, _CMP_EQ_OQ));
        }
        out = _mm256_or_pd(out, _mm256_and_pd(_mm256_cmp_pd(denom, zero, _CMP_EQ_OQ), parallelOut));
      }
      hi = _mm256_blendv_pd(hi, minusInf, out);
      _mm256_storeu_pd(tin + l, lo);
      _mm256_storeu_pd(tout + l, hi);
      const int valid = begin + width - l >= 4 ? 0xF : (1 << (begin + width - l)) - 1;
      unsigned mask =
        static_cast<unsigned>(_mm256_movemask_pd(_mm256_cmp_pd(lo, hi, _CMP_LT_OQ)) & valid);
      while (mask)
      {
        hits[n++] = static_cast<uint16_t>(l + __builtin_ctz(mask));
        mask &= mask - 1;
      }
    }
  }
  return n;
}
#else
int ClipRaysAvx2(const CellPlanes& planes, const TileRays& rays, const double* stop, double near,
  int first, int width, int rows, int stride, double* tin, double* tout, uint16_t* hits)
{
  return ClipRaysScalar(planes, rays, stop, near, first, width, rows, stride, tin, tout, hits);
}
#endif

int ClipRays(const CellPlanes& planes, const TileRays& rays, const double* stop, double near,
  int first, int width, int rows, int stride, double* tin, double* tout, uint16_t* hits)
{
  return HasAvx2()
    ? ClipRaysAvx2(planes, rays, stop, near, first, width, rows, stride, tin, tout, hits)
    : ClipRaysScalar(planes, rays, stop, near, first, width, rows, stride, tin, tout, hits);
}

} // namespace walk
} // namespace apc
