// SPDX-License-Identifier: BSD-3-Clause
// The compact cache's expansion for pass 2's colour, eight samples a step on AVX2 (the scalar
// form in apcSampleCache.h is the reference and serves other processors): its own file so that
// only this function is compiled for AVX2, and called only where the CPU has it.
#include "apcSampleCache.h"

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#define APC_HAVE_AVX2_EXPAND 1
#endif

namespace apc
{

#ifdef APC_HAVE_AVX2_EXPAND
namespace
{

// Eight samples a step: their depth slots widened, the table's depths gathered for the slots
// that are not escapes, interleaved with the scalars and stored; each escape's depth (and
// weight) then stored over its lane, in sample order.
template <bool Weighted>
__attribute__((target("avx2"))) void ExpandEight(
  const CompactSpan& compact, const float* table, CachedSample* samples, float* weights)
{
  const size_t n = compact.Size;
  const EscapedSample* escape = compact.Escapes;
  const __m256i escaped = _mm256_set1_epi32(kEscapedDepth);
  size_t s = 0;
  for (; s + 8 <= n; s += 8)
  {
    const __m256i slots =
      _mm256_cvtepu16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(compact.Depths + s)));
    const __m256i isEscape = _mm256_cmpeq_epi32(slots, escaped);
    // The escapes' lanes are not gathered (their slot is past the table).
    const __m256 z = _mm256_mask_i32gather_ps(_mm256_setzero_ps(), table, slots,
      _mm256_castsi256_ps(_mm256_xor_si256(isEscape, _mm256_set1_epi32(-1))), 4);
    const __m256 scalar = _mm256_loadu_ps(compact.Scalars + s);
    // (z0 s0 z1 s1 | z4 s4 z5 s5) and (z2 s2 z3 s3 | z6 s6 z7 s7), then in sample order.
    const __m256 low = _mm256_unpacklo_ps(z, scalar);
    const __m256 high = _mm256_unpackhi_ps(z, scalar);
    float* out = reinterpret_cast<float*>(samples + s);
    _mm256_storeu_ps(out, _mm256_permute2f128_ps(low, high, 0x20));
    _mm256_storeu_ps(out + 8, _mm256_permute2f128_ps(low, high, 0x31));
    if (Weighted)
    {
      _mm256_storeu_ps(weights + s, _mm256_set1_ps(1.0f));
    }
    unsigned lanes = static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(isEscape)));
    while (lanes != 0)
    {
      const int k = __builtin_ctz(lanes);
      lanes &= lanes - 1;
      samples[s + k].Z = escape->Z;
      if (Weighted)
      {
        weights[s + k] = escape->Weight;
      }
      ++escape;
    }
  }
  for (; s < n; ++s)
  {
    const uint16_t slot = compact.Depths[s];
    if (slot != kEscapedDepth)
    {
      samples[s] = { table[slot], compact.Scalars[s] };
      if (Weighted)
      {
        weights[s] = 1.0f;
      }
    }
    else
    {
      samples[s] = { escape->Z, compact.Scalars[s] };
      if (Weighted)
      {
        weights[s] = escape->Weight;
      }
      ++escape;
    }
  }
}

} // namespace
#endif

bool ExpandSamplesAvx2(
  const CompactSpan& compact, const float* table, CachedSample* samples, float* weights)
{
#ifdef APC_HAVE_AVX2_EXPAND
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2)
  {
    if (compact.Weighted)
    {
      ExpandEight<true>(compact, table, samples, weights);
    }
    else
    {
      ExpandEight<false>(compact, table, samples, nullptr);
    }
    return true;
  }
#endif
  (void)compact;
  (void)table;
  (void)samples;
  (void)weights;
  return false;
}

} // namespace apc
