// ClipRaysAvx512: the clip two packets of four rays at a time (apcRayClipKernel.h over
// AVX-512's vectors and masks), packet l0 in the low four lanes, packet l1 in the high four.
#include "apcRayClip.h"

#include "apcLaneMoments.h"
#include "apcLaneSamples.h"

#include <algorithm>
#include <cstdint>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>

// The headers above are compiled for the default target (their inline functions are shared
// with other files). Every function below, the kernels' templates included, may use AVX-512 F
// and VL (only called where HasAvx512()).
#pragma GCC push_options
#pragma GCC target("avx512f,avx512vl,avx2")

#include "apcLaneOps8.h"
#include "apcRayClipKernel.h"

namespace apc
{
namespace walk
{

using kernel::kLaneList;

// ClipRaysAvx2 two packets at a time: the rectangle's packets of four rays (a row's from its
// first ray on, as ClipRaysAvx2 forms them) taken in pairs, across rows too, so that a
// rectangle a packet wide (most of them at 1024²) fills the eight lanes as well.
int ClipRaysAvx512(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
  const double* stop, double near, const Lattice* lattice, ClippedRays& out)
{
  int n = 0;
  // The next packet: its first ray, and how many rays of the row it holds (up to 4).
  int row = 0;
  int next = rect.First;
  int rowEnd = rect.First + rect.Width;
  auto take = [&](int& l, int& count)
  {
    l = next;
    count = std::min(rowEnd - next, 4);
    next += 4;
    if (next >= rowEnd)
    {
      ++row;
      next = rect.First + row * rect.Stride;
      rowEnd = next + rect.Width;
    }
  };
  while (row < rect.Rows)
  {
    int l0;
    int c0;
    take(l0, c0);
    int l1 = l0;
    int c1 = 0;
    if (row < rect.Rows)
    {
      take(l1, c1);
    }
    const __mmask8 valid = static_cast<__mmask8>(((1u << c0) - 1u) | ((1u << c1) - 1u) << 4);
    __m512d lo;
    __m512d hi;
    kernel::ClipPacket<Ops8>(planes, rays, { l0, l1 }, valid, stop, near, lo, hi);
    // Packet l1's valid lanes only: nothing where there is no second packet (l1 = l0), and
    // no lane past its row over one of packet l0's.
    const __mmask8 valid1 = static_cast<__mmask8>(valid >> 4);
    _mm256_storeu_pd(out.Tin + l0, _mm512_castpd512_pd256(lo));
    _mm256_storeu_pd(out.Tout + l0, _mm512_castpd512_pd256(hi));
    _mm256_mask_storeu_pd(out.Tin + l1, valid1, _mm512_extractf64x4_pd(lo, 1));
    _mm256_mask_storeu_pd(out.Tout + l1, valid1, _mm512_extractf64x4_pd(hi, 1));
    int keep = _mm512_cmp_pd_mask(lo, hi, _CMP_LT_OQ) & valid;
    if (lattice)
    {
      const __m512d offset = Ops8::Row(rays.Offset, { l0, l1 });
      int unsettled = 0;
      __m512d first;
      const __m512d k = kernel::FirstIndex<Ops8>(*lattice, lo, offset, first, unsettled);
      _mm256_storeu_pd(out.Lattice + l0, _mm512_castpd512_pd256(k));
      _mm256_mask_storeu_pd(out.Lattice + l1, valid1, _mm512_extractf64x4_pd(k, 1));
      const int inside = _mm512_cmp_pd_mask(first, hi, _CMP_LT_OQ);
      keep = (keep & inside) | (keep & unsettled);
      for (int m = keep & unsettled; m; m &= m - 1)
      {
        const int lane = __builtin_ctz(m);
        const int r = (lane < 4 ? l0 : l1) + (lane & 3);
        const int64_t kr = lattice->First(out.Tin[r], rays.Offset[r]);
        out.Lattice[r] = static_cast<double>(kr);
        keep &= lattice->At(kr, rays.Offset[r]) < out.Tout[r] ? ~0 : ~(1 << lane);
      }
    }
    // Each packet's four 16-bit ray numbers, of which the first popcount are kept.
    const int keep0 = keep & 0xF;
    const int keep1 = keep >> 4;
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out.Hits + n),
      _mm_add_epi16(_mm_set1_epi16(static_cast<short>(l0)),
        _mm_cvtsi64_si128(static_cast<long long>(kLaneList.Lanes[keep0]))));
    n += __builtin_popcount(keep0);
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out.Hits + n),
      _mm_add_epi16(_mm_set1_epi16(static_cast<short>(l1)),
        _mm_cvtsi64_si128(static_cast<long long>(kLaneList.Lanes[keep1]))));
    n += __builtin_popcount(keep1);
  }
  return n;
}

} // namespace walk
} // namespace apc

#pragma GCC pop_options
#else
namespace apc
{
namespace walk
{

int ClipRaysAvx512(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
  const double* stop, double near, const Lattice* lattice, ClippedRays& out)
{
  return ClipRaysScalar(planes, rays, rect, stop, near, lattice, out);
}

} // namespace walk
} // namespace apc
#endif
