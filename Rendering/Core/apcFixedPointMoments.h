// SPDX-License-Identifier: BSD-3-Clause
// Moment sums on the wire as 32-bit integers with a per-pixel scale that every process agrees
// on before summing. Integer sums are exact, so the global moments do not depend on the order
// in which MPI adds the processes' contributions, and they carry 30 - ceil(log2 N) bits
// relative to the largest process's b0 (29 at 2 processes, 27 at 8, 22 at 256), where float
// sums carry 24 bits and lose more in each of the additions. Float rounding was
// measured to move the gear teeth's resolved image by 7e-5 (the moment solve amplifies a
// relative error of 1e-7 in nearly degenerate slabs ~700 times); these sums keep it below
// 1e-6 at 2 processes for the same 4 bytes per moment.
//
// Why one scale fits every moment of a pixel: the warped depths lie in [-1, 1], so
// |b_k| = |sum z^k a| <= sum a = b0 for every k, on every process.
#ifndef apcFixedPointMoments_h
#define apcFixedPointMoments_h

#include <cmath>
#include <cstdint>

namespace apc
{
namespace fixedpoint
{

// The exponent byte of one process's b0: 0 for an empty pixel (b0 <= 0), otherwise
// 128 + e with b0 < 2^e, e clamped to [-127, 127]. The processes' bytes are combined by
// MAX, which gives a bound on every process's b0, hence on every moment.
inline unsigned char ExponentByte(double b0)
{
  if (!(b0 > 0.0))
  {
    return 0;
  }
  int e = 0;
  std::frexp(b0, &e); // b0 = m 2^e, m in [0.5, 1): b0 < 2^e
  e = e < -127 ? -127 : (e > 127 ? 127 : e);
  return static_cast<unsigned char>(128 + e);
}

// Bits kept free so that the sum of `processes` values, each at most 2^30 / 2^headroom in
// magnitude, stays within int32.
inline int HeadroomBits(int processes)
{
  int bits = 0;
  while ((1LL << bits) < processes)
  {
    ++bits;
  }
  return bits;
}

// What a moment is multiplied by before rounding, for a pixel whose agreed exponent byte is
// exponentByte (non-zero).
inline double Scale(unsigned char exponentByte, int headroomBits)
{
  return std::ldexp(1.0, 30 - headroomBits - (static_cast<int>(exponentByte) - 128));
}

// The largest code's magnitude, 2^(30 - headroomBits).
inline double Limit(int headroomBits)
{
  return std::ldexp(1.0, 30 - headroomBits);
}

// One process's moment as an integer: rounded to nearest and saturated at limit (Limit's; only
// a moment above the agreed bound, which the bound excludes, could saturate).
inline int32_t EncodeWithin(double moment, double scale, double limit)
{
  double q = std::nearbyint(moment * scale);
  q = q > limit ? limit : (q < -limit ? -limit : q);
  return q == q ? static_cast<int32_t>(q) : 0;
}

inline int32_t Encode(double moment, double scale, int headroomBits)
{
  return EncodeWithin(moment, scale, Limit(headroomBits));
}

inline double Decode(int32_t sum, double scale)
{
  return static_cast<double>(sum) / scale;
}

} // namespace fixedpoint
} // namespace apc

#endif
