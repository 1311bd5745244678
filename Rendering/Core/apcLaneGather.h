// The part of filling a LaneRays that the plain and the end-weighted lanes share (internal to
// apcLaneSamples.cpp and apcLaneMoments.cpp, whose gathers differ only in where a lane's
// first index and offset come from): each lane's ray index, its direction and its interval's
// end, with one vector store per field. Include only where AVX2 code is compiled.
#ifndef apcLaneGather_h
#define apcLaneGather_h

#include "apcLaneSamples.h"

#include <immintrin.h>

#include <cstdint>
#include <limits>

namespace apc
{
namespace walk
{
namespace gather
{

// The tile's rays list[0 .. n - 1] as lanes; lanes n .. 3 read ray list[0] (their values are
// not used).
struct LaneIndices
{
  int I[4];
};

__attribute__((always_inline)) inline LaneIndices Indices(const uint16_t* list, int n)
{
  const int i0 = list[0];
  return { { i0, n > 1 ? list[1] : i0, n > 2 ? list[2] : i0, n > 3 ? list[3] : i0 } };
}

// v at the four lanes' indices. Four loads put together in registers: AVX2's gathers took
// longer.
__attribute__((target("avx2"), always_inline)) inline __m256d Four(const double* v, LaneIndices l)
{
  return _mm256_setr_pd(v[l.I[0]], v[l.I[1]], v[l.I[2]], v[l.I[3]]);
}

// rays.D from packed.
__attribute__((target("avx2"), always_inline)) inline void Directions(
  const TileRays& packed, LaneIndices l, LaneRays& rays)
{
  _mm256_store_pd(rays.D[0], Four(packed.Dx, l));
  _mm256_store_pd(rays.D[1], Four(packed.Dy, l));
  _mm256_store_pd(rays.D[2], Four(packed.Dz, l));
}

// rays.Tout from clipped, -inf in lanes n .. 3. (Stored after the first indices and offsets,
// as the gathers did before they shared this: formed first it took more registers.)
__attribute__((target("avx2"), always_inline)) inline void Ends(
  const ClippedRays& clipped, LaneIndices l, int n, LaneRays& rays)
{
  const __m256d used =
    _mm256_castsi256_pd(_mm256_cmpgt_epi64(_mm256_set1_epi64x(n), _mm256_setr_epi64x(0, 1, 2, 3)));
  _mm256_store_pd(rays.Tout,
    _mm256_blendv_pd(
      _mm256_set1_pd(-std::numeric_limits<double>::infinity()), Four(clipped.Tout, l), used));
}

} // namespace gather
} // namespace walk
} // namespace apc

#endif
