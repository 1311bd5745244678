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
// products and sums must round as Clip's do. A packet left early holds empty intervals that
// need not be Clip's (ClipRays keeps no ray of it either way).
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
    // A lane out here (the cell lies behind where its ray is opaque) ends empty whatever the
    // planes give: a packet whose valid lanes are all out needs no plane (such packets come
    // in runs, where a tile's rays turned opaque in front of the cell), and the test after
    // the third plane below counts only the others as open.
    if (_mm256_movemask_pd(_mm256_andnot_pd(out, _mm256_castsi256_pd(valid))) == 0)
    {
      hi = minusInf;
      return;
    }
  }
  // The valid lanes not out: the only ones that can keep a ray.
  const __m256d open = _mm256_andnot_pd(out, _mm256_castsi256_pd(valid));
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
    // lo only grows and hi only falls from plane to plane: where no valid lane is open after
    // three planes, the packet keeps no ray whatever the others give (about half of the
    // packets keep none at 1024²). Once per packet: a test after every plane cost more in
    // unpredictable branches than the planes it saved.
    if (p == 2 && planes.Count > 4 &&
      _mm256_movemask_pd(_mm256_and_pd(_mm256_cmp_pd(lo, hi, _CMP_LT_OQ), open)) == 0)
    {
      hi = minusInf; // an out lane may still be open here
      return;
    }
  }
  if (_mm256_movemask_pd(parallel) != 0)
  {
    out = _mm256_or_pd(out, ParallelOut(planes, rays, l));
  }
  hi = _mm256_blendv_pd(hi, minusInf, out);
}

// Lattice::First(lo) of four rays, as doubles, and t_k: the smallest k with t_k >= lo. The
// ceiling k0 of the quotient is Lattice::First's first guess (truncation, then up for a
// positive fraction), which rounding leaves at most one off; t_k = (k + offset) spacing with
// Lattice::At's operations does not decrease with k, so t_(k0-2) < lo <= t_(k0+1) puts the
// answer in k0-1 .. k0+1, and the compares of those four values, formed side by side instead
// of a step down, a step up and a check one after the other, say which. A lane the window
// does not settle (never seen) is marked in the returned mask and left to Lattice::First.
__attribute__((target("avx2"))) inline __m256d FirstFour(
  const Lattice& lattice, __m256d lo, __m256d offset, __m256d& tk, int& unsettled)
{
  const __m256d one = _mm256_set1_pd(1.0);
  const __m256d two = _mm256_set1_pd(2.0);
  const __m256d spacing = _mm256_set1_pd(lattice.Spacing);
  const __m256d x =
    _mm256_sub_pd(_mm256_mul_pd(lo, _mm256_set1_pd(lattice.InverseSpacing)), offset);
  const __m256d k0 = _mm256_round_pd(x, _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC);
  const __m256d k1 = _mm256_add_pd(k0, one);
  // t_(k0+j), j = -2 .. 1 (the integers k0 + j are exact).
  const __m256d tm2 = _mm256_mul_pd(_mm256_add_pd(_mm256_sub_pd(k0, two), offset), spacing);
  const __m256d tm1 = _mm256_mul_pd(_mm256_add_pd(_mm256_sub_pd(k0, one), offset), spacing);
  const __m256d t0 = _mm256_mul_pd(_mm256_add_pd(k0, offset), spacing);
  const __m256d t1 = _mm256_mul_pd(_mm256_add_pd(k1, offset), spacing);
  const __m256d cm2 = _mm256_cmp_pd(tm2, lo, _CMP_GE_OQ);
  const __m256d cm1 = _mm256_cmp_pd(tm1, lo, _CMP_GE_OQ);
  const __m256d c0 = _mm256_cmp_pd(t0, lo, _CMP_GE_OQ);
  const __m256d c1 = _mm256_cmp_pd(t1, lo, _CMP_GE_OQ);
  // Settled: not t_(k0-2) >= lo, and t_(k0+1) >= lo; then k = k0 + 1 - [c_-1] - [c_0].
  unsettled = _mm256_movemask_pd(_mm256_andnot_pd(cm2, c1)) ^ 0xF;
  tk = _mm256_blendv_pd(_mm256_blendv_pd(t1, t0, c0), tm1, cm1);
  return _mm256_sub_pd(_mm256_sub_pd(k1, _mm256_and_pd(cm1, one)), _mm256_and_pd(c0, one));
}

// The offsets in a packet of four rays of the lanes set in a 4-bit mask, in order, as four
// 16-bit numbers: the packet's kept rays are appended to ClippedRays::Hits with one store
// and a count instead of a loop per set lane, whose exits the processor could not predict.
struct LaneList
{
  uint64_t Lanes[16];
  constexpr LaneList()
    : Lanes()
  {
    for (int m = 0; m < 16; ++m)
    {
      int n = 0;
      for (int b = 0; b < 4; ++b)
      {
        if (m >> b & 1)
        {
          this->Lanes[m] |= static_cast<uint64_t>(b) << (16 * n++);
        }
      }
    }
  }
};
constexpr LaneList kLaneList;

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

namespace
{

// The eight lanes of two packets of four rays (l0 and l1 on, each as ClipFour reads it) as
// one vector: the low half packet l0's, the high half l1's.
__attribute__((target("avx512f,avx512vl"), always_inline)) inline __m512d Halves(
  const double* v, int l0, int l1)
{
  return _mm512_insertf64x4(
    _mm512_castpd256_pd512(_mm256_loadu_pd(v + l0)), _mm256_loadu_pd(v + l1), 1);
}

// ClipFour of two packets at once (valid: bits 0-3 packet l0's lanes, 4-7 packet l1's): the
// same operations lane by lane, so the same intervals where they are not empty; one division
// per plane for eight rays instead of two. The packets leave early together: where all
// their valid lanes are out, or none is open after three planes.
__attribute__((target("avx512f,avx512vl"))) inline void ClipEight(const CellPlanes& planes,
  const TileRays& rays, int l0, int l1, __mmask8 valid, const double* stop, double near,
  __m512d& lo, __m512d& hi)
{
  const __m512d zero = _mm512_setzero_pd();
  const __m512d inf = _mm512_set1_pd(std::numeric_limits<double>::infinity());
  const __m512d minusInf = _mm512_set1_pd(-std::numeric_limits<double>::infinity());
  const __m512d dx = Halves(rays.Dx, l0, l1);
  const __m512d dy = Halves(rays.Dy, l0, l1);
  const __m512d dz = Halves(rays.Dz, l0, l1);
  lo = zero;
  hi = Halves(rays.End, l0, l1);
  __mmask8 out = 0;
  if (stop)
  {
    // min(tout, stop) as std::min keeps tout on a tie. stop holds no padding.
    const __m512d s = _mm512_insertf64x4(
      _mm512_castpd256_pd512(_mm256_maskz_loadu_pd(static_cast<__mmask8>(valid & 0xF), stop + l0)),
      _mm256_maskz_loadu_pd(static_cast<__mmask8>(valid >> 4), stop + l1), 1);
    hi = _mm512_min_pd(s, hi);
    out = _mm512_cmp_pd_mask(_mm512_set1_pd(near), s, _CMP_GE_OQ);
    if ((valid & ~out & 0xFF) == 0)
    {
      hi = minusInf;
      return;
    }
  }
  const __mmask8 open = valid & ~out;
  __mmask8 parallel = 0;
  __m512d ox = zero;
  __m512d oy = zero;
  __m512d oz = zero;
  if (!planes.SharedOrigin)
  {
    ox = Halves(rays.Ox, l0, l1);
    oy = Halves(rays.Oy, l0, l1);
    oz = Halves(rays.Oz, l0, l1);
  }
  for (int p = 0; p < planes.Count; ++p)
  {
    // PlaneTerms' products and sums, no FMA.
    const __m512d nx = _mm512_set1_pd(planes.Nx[p]);
    const __m512d ny = _mm512_set1_pd(planes.Ny[p]);
    const __m512d nz = _mm512_set1_pd(planes.Nz[p]);
    const __m512d denom = _mm512_add_pd(
      _mm512_add_pd(_mm512_mul_pd(nx, dx), _mm512_mul_pd(ny, dy)), _mm512_mul_pd(nz, dz));
    __m512d num;
    if (planes.SharedOrigin)
    {
      num = _mm512_set1_pd(planes.Num[p]);
    }
    else
    {
      const __m512d dot = _mm512_add_pd(
        _mm512_add_pd(_mm512_mul_pd(nx, ox), _mm512_mul_pd(ny, oy)), _mm512_mul_pd(nz, oz));
      num = _mm512_sub_pd(_mm512_set1_pd(planes.Offset[p]), dot);
    }
    const __m512d q = _mm512_div_pd(num, denom);
    const __mmask8 entering = _mm512_cmp_pd_mask(denom, zero, _CMP_LT_OQ);
    const __mmask8 leaving = _mm512_cmp_pd_mask(denom, zero, _CMP_GT_OQ);
    lo = _mm512_max_pd(_mm512_mask_blend_pd(entering, minusInf, q), lo);
    hi = _mm512_min_pd(_mm512_mask_blend_pd(leaving, inf, q), hi);
    parallel |= _mm512_cmp_pd_mask(denom, zero, _CMP_EQ_OQ);
    if (p == 2 && planes.Count > 4 && (_mm512_cmp_pd_mask(lo, hi, _CMP_LT_OQ) & open) == 0)
    {
      hi = minusInf; // an out lane may still be open here
      return;
    }
  }
  if (parallel != 0)
  {
    // Rare: each half as ClipFour finds its lanes.
    if (parallel & 0xF)
    {
      out |= static_cast<__mmask8>(_mm256_movemask_pd(ParallelOut(planes, rays, l0)));
    }
    if (parallel >> 4)
    {
      out |= static_cast<__mmask8>(_mm256_movemask_pd(ParallelOut(planes, rays, l1)) << 4);
    }
  }
  hi = _mm512_mask_blend_pd(out, hi, minusInf);
}

// FirstFour of eight rays: the same operations lane by lane.
__attribute__((target("avx512f,avx512vl"))) inline __m512d FirstEight(
  const Lattice& lattice, __m512d lo, __m512d offset, __m512d& tk, int& unsettled)
{
  const __m512d one = _mm512_set1_pd(1.0);
  const __m512d two = _mm512_set1_pd(2.0);
  const __m512d spacing = _mm512_set1_pd(lattice.Spacing);
  const __m512d x =
    _mm512_sub_pd(_mm512_mul_pd(lo, _mm512_set1_pd(lattice.InverseSpacing)), offset);
  const __m512d k0 = _mm512_roundscale_pd(x, _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC);
  const __m512d k1 = _mm512_add_pd(k0, one);
  const __m512d tm2 = _mm512_mul_pd(_mm512_add_pd(_mm512_sub_pd(k0, two), offset), spacing);
  const __m512d tm1 = _mm512_mul_pd(_mm512_add_pd(_mm512_sub_pd(k0, one), offset), spacing);
  const __m512d t0 = _mm512_mul_pd(_mm512_add_pd(k0, offset), spacing);
  const __m512d t1 = _mm512_mul_pd(_mm512_add_pd(k1, offset), spacing);
  const __mmask8 cm2 = _mm512_cmp_pd_mask(tm2, lo, _CMP_GE_OQ);
  const __mmask8 cm1 = _mm512_cmp_pd_mask(tm1, lo, _CMP_GE_OQ);
  const __mmask8 c0 = _mm512_cmp_pd_mask(t0, lo, _CMP_GE_OQ);
  const __mmask8 c1 = _mm512_cmp_pd_mask(t1, lo, _CMP_GE_OQ);
  unsettled = (~cm2 & c1) ^ 0xFF;
  tk = _mm512_mask_blend_pd(cm1, _mm512_mask_blend_pd(c0, t1, t0), tm1);
  // k1 - [c_-1] - [c_0], as FirstFour's subtractions of 1 or 0.
  const __m512d m1 = _mm512_maskz_mov_pd(cm1, one);
  const __m512d m0 = _mm512_maskz_mov_pd(c0, one);
  return _mm512_sub_pd(_mm512_sub_pd(k1, m1), m0);
}

} // namespace

// ClipRaysAvx2 two packets at a time: the rectangle's packets of four rays (a row's from its
// first ray on, as ClipRaysAvx2 forms them) taken in pairs, across rows too, so that a
// rectangle a packet wide (most of them at 1024²) fills the eight lanes as well.
__attribute__((target("avx512f,avx512vl"))) int ClipRaysAvx512(const CellPlanes& planes,
  const TileRays& rays, const RayRect& rect, const double* stop, double near,
  const Lattice* lattice, ClippedRays& out)
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
    ClipEight(planes, rays, l0, l1, valid, stop, near, lo, hi);
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
      const __m512d offset = Halves(rays.Offset, l0, l1);
      int unsettled = 0;
      __m512d first;
      const __m512d k = FirstEight(*lattice, lo, offset, first, unsettled);
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
int ClipRaysAvx512(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
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
