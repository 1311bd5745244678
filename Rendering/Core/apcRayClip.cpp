// Clipping a tile's rays against one cell several rays at a time (walk::ClipRays). Ray by
// ray, the marcher spent much of its time waiting on each ray's divisions and on branches
// that tell a ray inside the cell from one outside, and one with a sample from one without;
// four rays per instruction keep the divider busy and leave only the rays with a sample to
// the sample loop. Every lane performs the IEEE operations of CellPlanes::Clip and
// Lattice::First in the same order, so the intervals and indices are the same bit for bit and
// neighbouring cells still meet exactly. The packet's clip and first indices are written once
// over the width (apcRayClipKernel.h); the eight-wide clip is in apcRayClipAvx512.cpp.
#include "apcRayClip.h"

#include "apcLaneMoments.h" // apcLaneOps4.h's, for the default target
#include "apcLaneSamples.h"

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

bool HasAvx512()
{
#ifdef APC_HAVE_AVX2_CLIP
  // Both the instructions and the operating system's saving of their registers (libgcc's
  // test of XCR0).
  static const bool avx512 =
    __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
  return avx512;
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

void BoundaryEndsScalar(const CellPlanes& planes, const TileRays& rays, const ClippedRays& out,
  const uint16_t* hits, int count, uint8_t* ends)
{
  for (int h = 0; h < count; ++h)
  {
    const int l = hits[h];
    const RaySetup ray{ { rays.Ox[l], rays.Oy[l], rays.Oz[l] },
      { rays.Dx[l], rays.Dy[l], rays.Dz[l] }, rays.End[l], rays.Offset[l] };
    bool in = false;
    bool leaves = false;
    planes.BoundaryEnds(ray, out.Tin[l], out.Tout[l], in, leaves);
    ends[h] = static_cast<uint8_t>((in ? 1 : 0) | (leaves ? 2 : 0));
  }
}

namespace
{

void Store(const EndWeights& w, int l, double offset, ClippedWeights& out)
{
  out.LaneOffset[l] = w.Mid ? w.MidOffset : offset;
  out.First[l] = static_cast<double>(w.First);
  out.Last[l] = static_cast<double>(w.Last);
  out.FirstWeight[l] = w.Mid ? w.MidWeight : w.FirstWeight;
  out.LastWeight[l] = w.Mid ? w.MidWeight : w.LastWeight;
  out.Mid[l] = w.Mid ? 1.0 : 0.0;
  out.MidT[l] = w.MidT;
}

// The weights of ray l's pair from tin, whose clipped end tout the stop may have cut: then
// the pair's own end is clipped again from the ray's end, as the scalar walker did.
void WeightsOf(const CellPlanes& planes, const TileRays& rays, int l, const double* stop,
  const Lattice& lattice, double tin, double tout, ClippedWeights& out)
{
  double end = tout;
  if (stop && tout == stop[l])
  {
    const RaySetup ray{ { rays.Ox[l], rays.Oy[l], rays.Oz[l] },
      { rays.Dx[l], rays.Dy[l], rays.Dz[l] }, rays.End[l], rays.Offset[l] };
    double start = 0;
    end = rays.End[l];
    planes.Clip(ray, start, end);
  }
  Store(EndWeightsOf(lattice, tin, end, rays.Offset[l]), l, rays.Offset[l], out);
}

} // namespace

int ClipRaysWeightedScalar(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
  const double* stop, double near, const Lattice& lattice, ClippedRays& out,
  ClippedWeights& weights)
{
  const int kept = ClipRaysScalar(planes, rays, rect, stop, near, nullptr, out);
  int n = 0;
  weights.MidCount = 0;
  for (int h = 0; h < kept; ++h)
  {
    const int l = out.Hits[h];
    WeightsOf(planes, rays, l, stop, lattice, out.Tin[l], out.Tout[l], weights);
    if (weights.Mid[l] != 0)
    {
      weights.MidHits[weights.MidCount++] = static_cast<uint16_t>(l);
    }
    else
    {
      out.Hits[n++] = static_cast<uint16_t>(l); // n <= h: a kept ray not yet read
    }
  }
  return n;
}

#ifdef APC_HAVE_AVX2_CLIP
} // namespace walk
} // namespace apc

// The headers above are compiled for the default target (their inline functions are shared
// with other files). Every function below, the kernels' templates included, may use AVX2 (only
// called where HasAvx2()).
#pragma GCC push_options
#pragma GCC target("avx2")

#include "apcLaneOps4.h"
#include "apcRayClipKernel.h"

namespace apc
{
namespace walk
{

namespace
{

using kernel::kLaneList;

// The clip's kernels four rays wide (apcRayClipKernel.h).
__attribute__((always_inline)) inline void ClipFour(const CellPlanes& planes, const TileRays& rays,
  int l, __m256i valid, const double* stop, double near, __m256d& lo, __m256d& hi)
{
  kernel::ClipPacket<Ops4>(planes, rays, l, _mm256_castsi256_pd(valid), stop, near, lo, hi);
}

__attribute__((always_inline)) inline __m256d FirstFour(
  const Lattice& lattice, __m256d lo, __m256d offset, __m256d& tk, int& unsettled)
{
  return kernel::FirstIndex<Ops4>(lattice, lo, offset, tk, unsettled);
}

} // namespace

// Four of the hits at a time, each lane a ray gathered by its index (the last group repeats
// its last ray); per boundary plane BoundaryEnds' quotient with PlaneTerms' operations (the
// same products, sums and division), the entering ones' maximum against tin, the leaving
// ones' minimum against tout. An entering plane's quotient is never NaN (its denominator is
// below 0), so the maximum's order does not matter; nor does a zero's sign to the compares.
__attribute__((target("avx2"))) void BoundaryEndsAvx2(const CellPlanes& planes,
  const TileRays& rays, const ClippedRays& out, const uint16_t* hits, int count, uint8_t* ends)
{
  const __m256d zero = _mm256_setzero_pd();
  const __m256d inf = _mm256_set1_pd(std::numeric_limits<double>::infinity());
  const __m256d minusInf = _mm256_set1_pd(-std::numeric_limits<double>::infinity());
  const unsigned mask = planes.BoundaryMask & ((1u << planes.Count) - 1u);
  for (int h = 0; h < count; h += 4)
  {
    int r[4];
    for (int j = 0; j < 4; ++j)
    {
      r[j] = hits[std::min(h + j, count - 1)];
    }
    const __m256d dx = _mm256_setr_pd(rays.Dx[r[0]], rays.Dx[r[1]], rays.Dx[r[2]], rays.Dx[r[3]]);
    const __m256d dy = _mm256_setr_pd(rays.Dy[r[0]], rays.Dy[r[1]], rays.Dy[r[2]], rays.Dy[r[3]]);
    const __m256d dz = _mm256_setr_pd(rays.Dz[r[0]], rays.Dz[r[1]], rays.Dz[r[2]], rays.Dz[r[3]]);
    __m256d loB = minusInf;
    __m256d hiB = inf;
    for (unsigned m = mask; m; m &= m - 1)
    {
      const int p = __builtin_ctz(m);
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
        const __m256d ox =
          _mm256_setr_pd(rays.Ox[r[0]], rays.Ox[r[1]], rays.Ox[r[2]], rays.Ox[r[3]]);
        const __m256d oy =
          _mm256_setr_pd(rays.Oy[r[0]], rays.Oy[r[1]], rays.Oy[r[2]], rays.Oy[r[3]]);
        const __m256d oz =
          _mm256_setr_pd(rays.Oz[r[0]], rays.Oz[r[1]], rays.Oz[r[2]], rays.Oz[r[3]]);
        const __m256d dot = _mm256_add_pd(
          _mm256_add_pd(_mm256_mul_pd(nx, ox), _mm256_mul_pd(ny, oy)), _mm256_mul_pd(nz, oz));
        num = _mm256_sub_pd(_mm256_set1_pd(planes.Offset[p]), dot);
      }
      const __m256d q = _mm256_div_pd(num, denom);
      loB =
        _mm256_max_pd(_mm256_blendv_pd(minusInf, q, _mm256_cmp_pd(denom, zero, _CMP_LT_OQ)), loB);
      hiB = _mm256_min_pd(_mm256_blendv_pd(inf, q, _mm256_cmp_pd(denom, zero, _CMP_GT_OQ)), hiB);
    }
    const __m256d tin = _mm256_setr_pd(out.Tin[r[0]], out.Tin[r[1]], out.Tin[r[2]], out.Tin[r[3]]);
    const __m256d tout =
      _mm256_setr_pd(out.Tout[r[0]], out.Tout[r[1]], out.Tout[r[2]], out.Tout[r[3]]);
    const int in = _mm256_movemask_pd(_mm256_cmp_pd(loB, tin, _CMP_GE_OQ));
    const int leaves = _mm256_movemask_pd(_mm256_cmp_pd(hiB, tout, _CMP_LE_OQ));
    for (int j = 0; j < 4; ++j)
    {
      ends[h + j] = static_cast<uint8_t>((in >> j & 1) | (leaves >> j & 1) << 1);
    }
  }
}

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
      // Every packet's first indices, kept rays or not (a lane not kept is not read): about
      // half of the packets keep no ray, in an order the processor could not predict, and
      // the branch around them cost more than the arithmetic it skipped.
      if (lattice)
      {
        const __m256d offset = _mm256_loadu_pd(rays.Offset + l);
        int unsettled = 0;
        __m256d first;
        const __m256d k = FirstFour(*lattice, lo, offset, first, unsettled);
        _mm256_storeu_pd(out.Lattice + l, k);
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
      // Four 16-bit ray numbers l + lane, of which the first popcount(keep) are kept.
      const __m128i hits = _mm_add_epi16(_mm_set1_epi16(static_cast<short>(l)),
        _mm_cvtsi64_si128(static_cast<long long>(kLaneList.Lanes[keep])));
      _mm_storel_epi64(reinterpret_cast<__m128i*>(out.Hits + n), hits);
      n += __builtin_popcount(keep);
    }
  }
  return n;
}

// ClipRaysAvx2 without a lattice, and the end weights of the kept rays' pairs: EndWeightsOf's
// operations, four rays at a time. Where some lane's interval ends at its stop, the packet is
// clipped again without the stop for the pair's own end (ClipFour's arithmetic is Clip's);
// a lane FirstFour does not settle goes ray by ray.
__attribute__((target("avx2"))) int ClipRaysWeightedAvx2(const CellPlanes& planes,
  const TileRays& rays, const RayRect& rect, const double* stop, double near,
  const Lattice& lattice, ClippedRays& out, ClippedWeights& weights)
{
  const __m256d one = _mm256_set1_pd(1.0);
  const __m256d half = _mm256_set1_pd(0.5);
  const __m256d spacing = _mm256_set1_pd(lattice.Spacing);
  const __m256d inverse = _mm256_set1_pd(lattice.InverseSpacing);
  int n = 0;
  int mids = 0;
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
      int midLanes = 0;
      const int keep = _mm256_movemask_pd(_mm256_cmp_pd(lo, hi, _CMP_LT_OQ)) &
        _mm256_movemask_pd(_mm256_castsi256_pd(valid));
      if (keep)
      {
        __m256d full = hi;
        if (stop)
        {
          const __m256d atStop = _mm256_cmp_pd(hi, _mm256_maskload_pd(stop + l, valid), _CMP_EQ_OQ);
          if (_mm256_movemask_pd(atStop) & keep)
          {
            __m256d lo2;
            __m256d hi2;
            ClipFour(planes, rays, l, valid, nullptr, near, lo2, hi2);
            full = _mm256_blendv_pd(hi, hi2, atStop);
          }
        }
        const __m256d offset = _mm256_loadu_pd(rays.Offset + l);
        int unsettledIn = 0;
        int unsettledOut = 0;
        __m256d tFirst;
        __m256d tEnd;
        const __m256d first = FirstFour(lattice, lo, offset, tFirst, unsettledIn);
        const __m256d last =
          _mm256_sub_pd(FirstFour(lattice, full, offset, tEnd, unsettledOut), one);
        const __m256d mid = _mm256_cmp_pd(last, first, _CMP_LT_OQ);
        const __m256d single = _mm256_cmp_pd(last, first, _CMP_LE_OQ); // or Mid
        const __m256d length = _mm256_mul_pd(_mm256_sub_pd(full, lo), inverse);
        const __m256d tLast = _mm256_mul_pd(_mm256_add_pd(last, offset), spacing);
        const __m256d firstWeight =
          _mm256_add_pd(_mm256_mul_pd(_mm256_sub_pd(tFirst, lo), inverse), half);
        const __m256d lastWeight =
          _mm256_add_pd(_mm256_mul_pd(_mm256_sub_pd(full, tLast), inverse), half);
        // EndWeightsOf's middle: MidOffset from the index before the pair, MidT = At(that
        // index, MidOffset).
        const __m256d before = _mm256_sub_pd(first, _mm256_and_pd(mid, one));
        const __m256d midOffset = _mm256_sub_pd(
          _mm256_mul_pd(_mm256_mul_pd(half, _mm256_add_pd(lo, full)), inverse), before);
        _mm256_storeu_pd(weights.First + l, before);
        _mm256_storeu_pd(weights.LaneOffset + l, _mm256_blendv_pd(offset, midOffset, mid));
        _mm256_storeu_pd(weights.Last + l, last);
        _mm256_storeu_pd(weights.FirstWeight + l, _mm256_blendv_pd(firstWeight, length, single));
        _mm256_storeu_pd(weights.LastWeight + l, _mm256_blendv_pd(lastWeight, length, single));
        _mm256_storeu_pd(weights.Mid + l, _mm256_and_pd(mid, one));
        _mm256_storeu_pd(
          weights.MidT + l, _mm256_mul_pd(_mm256_add_pd(before, midOffset), spacing));
        midLanes = _mm256_movemask_pd(mid) & keep;
        for (int m = keep & (unsettledIn | unsettledOut); m; m &= m - 1)
        {
          const int lane = __builtin_ctz(m);
          const int r = l + lane;
          WeightsOf(planes, rays, r, stop, lattice, out.Tin[r], out.Tout[r], weights);
          midLanes = (midLanes & ~(1 << lane)) | (weights.Mid[r] != 0 ? 1 << lane : 0);
        }
      }
      // Four 16-bit ray numbers l + lane, of which the first popcount(lanes) are taken.
      const __m128i base = _mm_set1_epi16(static_cast<short>(l));
      const int sampled = keep & ~midLanes;
      _mm_storel_epi64(reinterpret_cast<__m128i*>(out.Hits + n),
        _mm_add_epi16(base, _mm_cvtsi64_si128(static_cast<long long>(kLaneList.Lanes[sampled]))));
      _mm_storel_epi64(reinterpret_cast<__m128i*>(weights.MidHits + mids),
        _mm_add_epi16(base, _mm_cvtsi64_si128(static_cast<long long>(kLaneList.Lanes[midLanes]))));
      n += __builtin_popcount(sampled);
      mids += __builtin_popcount(midLanes);
    }
  }
  weights.MidCount = mids;
  return n;
}

} // namespace walk
} // namespace apc

#pragma GCC pop_options

namespace apc
{
namespace walk
{
#else
void BoundaryEndsAvx2(const CellPlanes& planes, const TileRays& rays, const ClippedRays& out,
  const uint16_t* hits, int count, uint8_t* ends)
{
  BoundaryEndsScalar(planes, rays, out, hits, count, ends);
}
int ClipRaysAvx2(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
  const double* stop, double near, const Lattice* lattice, ClippedRays& out)
{
  return ClipRaysScalar(planes, rays, rect, stop, near, lattice, out);
}
int ClipRaysWeightedAvx2(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
  const double* stop, double near, const Lattice& lattice, ClippedRays& out,
  ClippedWeights& weights)
{
  return ClipRaysWeightedScalar(planes, rays, rect, stop, near, lattice, out, weights);
}
#endif

int ClipRays(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
  const double* stop, double near, const Lattice* lattice, ClippedRays& out)
{
  if (HasAvx512())
  {
    return ClipRaysAvx512(planes, rays, rect, stop, near, lattice, out);
  }
  return HasAvx2() ? ClipRaysAvx2(planes, rays, rect, stop, near, lattice, out)
                   : ClipRaysScalar(planes, rays, rect, stop, near, lattice, out);
}

void BoundaryEnds(const CellPlanes& planes, const TileRays& rays, const ClippedRays& out,
  const uint16_t* hits, int count, uint8_t* ends)
{
  if (HasAvx2())
  {
    BoundaryEndsAvx2(planes, rays, out, hits, count, ends);
  }
  else
  {
    BoundaryEndsScalar(planes, rays, out, hits, count, ends);
  }
}

int ClipRaysWeighted(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
  const double* stop, double near, const Lattice& lattice, ClippedRays& out,
  ClippedWeights& weights)
{
  return HasAvx2() ? ClipRaysWeightedAvx2(planes, rays, rect, stop, near, lattice, out, weights)
                   : ClipRaysWeightedScalar(planes, rays, rect, stop, near, lattice, out, weights);
}

} // namespace walk
} // namespace apc
