// SPDX-License-Identifier: BSD-3-Clause
// An exact sum of non-negative doubles, whatever the order of the terms: a fixed-point
// integer wide enough for every finite double (2^-1074 .. 2^1024, plus room for carries),
// kept as 32-bit digits in 64-bit lanes so that adding is plain integer addition.
//
// Why: the default sample distance comes from the cells' total volume, and every process
// must get the same double from it whatever the partition (the sample lattice is shared by
// all ranks, and N ranks must render what one process renders). A floating-point sum
// depends on its order; this one does not: the processes add their lanes with an integer
// MPI sum (Lanes, FromLanes) and every process rounds the same integer to the same double.
#ifndef apcExactSum_h
#define apcExactSum_h

#include <array>
#include <cmath>
#include <cstdint>

namespace apc
{

class ExactSum
{
public:
  // Bit 0 of the integer is 2^-1074 (the smallest subnormal); the largest double's top bit
  // is bit 2097. 68 digits of 32 bits leave 78 bits of room above it.
  static constexpr int kLanes = 68;
  static constexpr int kLowestExponent = -1074;

  // Adds x; negative, NaN and infinite terms are not added (a volume is never negative:
  // the caller takes the absolute value).
  void Add(double x)
  {
    if (!(x > 0) || !std::isfinite(x))
    {
      return;
    }
    int exponent = 0;
    const double m = std::frexp(x, &exponent); // x = m * 2^exponent, 0.5 <= m < 1
    // 53 significant bits as an integer: x = mantissa * 2^(exponent - 53), exactly (a
    // subnormal's low bits are zero, its bit position below the lowest is not reached).
    auto mantissa = static_cast<uint64_t>(std::ldexp(m, 53));
    int bit = exponent - 53 - kLowestExponent;
    if (bit < 0)
    {
      mantissa >>= -bit; // only zero bits of a subnormal
      bit = 0;
    }
    const int lane = bit / 32;
    const int shift = bit % 32;
    // Up to 53 + 31 bits spread over three digits.
    const unsigned __int128 wide = static_cast<unsigned __int128>(mantissa) << shift;
    this->Digits[lane] += static_cast<uint64_t>(wide) & 0xffffffffu;
    this->Digits[lane + 1] += static_cast<uint64_t>(wide >> 32) & 0xffffffffu;
    this->Digits[lane + 2] += static_cast<uint64_t>(wide >> 64);
    if (++this->Pending == kNormalizeEvery)
    {
      this->Normalize();
    }
  }

  void Add(const ExactSum& other)
  {
    for (int i = 0; i < kLanes; ++i)
    {
      this->Digits[i] += other.Digits[i];
    }
    this->Normalize();
  }

  // Each digit below 2^32 again: carries moved up. Called by Add, and before Lanes.
  void Normalize()
  {
    uint64_t carry = 0;
    for (int i = 0; i < kLanes; ++i)
    {
      const uint64_t v = this->Digits[i] + carry;
      this->Digits[i] = v & 0xffffffffu;
      carry = v >> 32;
    }
    this->Pending = 0;
  }

  // The normalised digits, for an integer sum over processes (each below 2^32, so up to 2^31
  // processes add without overflow); FromLanes takes such a sum back.
  std::array<uint64_t, kLanes> Lanes()
  {
    this->Normalize();
    return this->Digits;
  }
  static ExactSum FromLanes(const std::array<uint64_t, kLanes>& lanes)
  {
    ExactSum sum;
    sum.Digits = lanes;
    sum.Normalize();
    return sum;
  }

  // The sum rounded to a double (from its top three digits: 64 bits or more below the
  // leading one, far below a double's precision); the same value for the same integer.
  double Value() const
  {
    ExactSum copy = *this;
    copy.Normalize();
    int top = kLanes - 1;
    while (top > 0 && copy.Digits[top] == 0)
    {
      --top;
    }
    double value = 0;
    for (int i = top; i >= 0 && i > top - 3; --i)
    {
      value += std::ldexp(static_cast<double>(copy.Digits[i]), 32 * i + kLowestExponent);
    }
    return value;
  }

  bool operator==(const ExactSum& other) const
  {
    ExactSum a = *this;
    ExactSum b = other;
    a.Normalize();
    b.Normalize();
    return a.Digits == b.Digits;
  }

private:
  // A digit takes up to 2^32 per Add: 2^30 adds stay far below 2^64.
  static constexpr int64_t kNormalizeEvery = int64_t(1) << 30;
  std::array<uint64_t, kLanes> Digits{};
  int64_t Pending = 0;
};

} // namespace apc

#endif
