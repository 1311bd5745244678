// A 4-moment pixel's constants (FourMomentPixel) in the four lanes of an AVX2 vector, as pass 2's
// replay (apcPixelReplay.cpp) and the hidden depth's decisions (apcHiddenDecisions.cpp) read them.
// Internal to the core; for x86-64 builds with GCC or Clang, whose AVX2 code includes it.
#ifndef apcFourMomentLanes_h
#define apcFourMomentLanes_h

#include "apcMomentTransmittance.h"

#include <immintrin.h>

#define APC_FOUR_MOMENT_LANES_INLINE inline __attribute__((always_inline, target("avx2")))

namespace apc
{

struct FourMomentLanes
{
  __m256d L3, L4, L6, L7, L8, D0, D1, D2, Beta, OneMinusBeta, B0;

  // Every lane from px. A user that reads a constant for every group of samples sets this
  // once a pixel: set in each group, the constants were loaded, broadcast and spilled again
  // in every group (the replay's loop has more live vectors than registers).
  APC_FOUR_MOMENT_LANES_INLINE explicit FourMomentLanes(const FourMomentPixel& px)
    : L3(_mm256_set1_pd(px.L3))
    , L4(_mm256_set1_pd(px.L4))
    , L6(_mm256_set1_pd(px.L6))
    , L7(_mm256_set1_pd(px.L7))
    , L8(_mm256_set1_pd(px.L8))
    , D0(_mm256_set1_pd(px.D0))
    , D1(_mm256_set1_pd(px.D1))
    , D2(_mm256_set1_pd(px.D2))
    , Beta(_mm256_set1_pd(px.Beta))
    , OneMinusBeta(_mm256_sub_pd(_mm256_set1_pd(1.0), this->Beta))
    , B0(_mm256_set1_pd(px.B0))
  {
  }

  // Lane i from *px[i], i < 4.
  APC_FOUR_MOMENT_LANES_INLINE explicit FourMomentLanes(const FourMomentPixel* const* px)
    : L3(Gather(px, &FourMomentPixel::L3))
    , L4(Gather(px, &FourMomentPixel::L4))
    , L6(Gather(px, &FourMomentPixel::L6))
    , L7(Gather(px, &FourMomentPixel::L7))
    , L8(Gather(px, &FourMomentPixel::L8))
    , D0(Gather(px, &FourMomentPixel::D0))
    , D1(Gather(px, &FourMomentPixel::D1))
    , D2(Gather(px, &FourMomentPixel::D2))
    , Beta(Gather(px, &FourMomentPixel::Beta))
    , OneMinusBeta(_mm256_sub_pd(_mm256_set1_pd(1.0), this->Beta))
    , B0(Gather(px, &FourMomentPixel::B0))
  {
  }

  static APC_FOUR_MOMENT_LANES_INLINE __m256d Gather(
    const FourMomentPixel* const* px, double FourMomentPixel::*field)
  {
    return _mm256_set_pd(px[3]->*field, px[2]->*field, px[1]->*field, px[0]->*field);
  }
};

} // namespace apc

#endif
