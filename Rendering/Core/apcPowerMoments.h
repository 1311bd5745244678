// Power-moment accumulation of MBOIT (Münstermann et al. 2018, I3D): b0 = sum a,
// b_k = sum z^k a. APC (Huang, Usher et al., "Approximate Puzzlepiece Compositing",
// arXiv 2501.12581) relies on these being plain sums: samples, threads and MPI ranks can
// add them in any order, so nothing is ever sorted or moved between ranks.
#ifndef apcPowerMoments_h
#define apcPowerMoments_h

#include "apcAbsorbance.h"

#include <array>
#include <cmath>
#include <cstddef>

namespace apc
{

// AccumulatePowerMoments for a sample whose caller knows a is positive and finite and z in
// [-1, 1] (pass 1: a transfer table's absorbance at a LogDepthWarp depth), where its checks
// change nothing: the same sums without a test and two compares per sample.
template <int N>
[[gnu::always_inline]] inline void AccumulateCheckedPowerMoments(double* b, double z, double a)
{
  double w = a;
  b[0] += w;
  for (int k = 1; k <= N; ++k)
  {
    w *= z;
    b[k] += w;
  }
}

// Adds one sample of absorbance a at warped depth z to a raw buffer of N+1 unnormalised
// sums (b0, b1, ..., bN). This is the form the MPI layer reduces.
// - a <= 0 or NaN: skipped (contributes nothing, like alpha = 0).
// - a = +inf: treated as kAbsorbanceMax, an opaque sample, rather than poisoning the sums.
// - z is clamped to [-1,1] (the warp's range, so |b_k| <= b0 always holds); NaN z skips
//   the sample because there is no depth at which to place it.
template <int N>
inline void AccumulatePowerMoments(double* b, double z, double a)
{
  static_assert(N == 4 || N == 6 || N == 8, "APC supports 4, 6 or 8 power moments");
  if (!(a > 0.0) || std::isnan(z))
  {
    return;
  }
  if (a > kAbsorbanceMax && std::isinf(a))
  {
    a = kAbsorbanceMax;
  }
  AccumulateCheckedPowerMoments<N>(b, z < -1.0 ? -1.0 : (z > 1.0 ? 1.0 : z), a);
}

// Elementwise dst += src over N+1 moment sums (what an MPI_SUM reduction does).
template <int N>
inline void AddPowerMoments(double* dst, const double* src)
{
  for (int k = 0; k <= N; ++k)
  {
    dst[k] += src[k];
  }
}

// One pixel's unnormalised moment sums. Standard layout and exactly N+1 doubles, so an
// image of them is a flat double buffer of (N+1) * pixels.
template <int N>
struct PowerMoments
{
  static_assert(N == 4 || N == 6 || N == 8, "APC supports 4, 6 or 8 power moments");
  static constexpr int kOrder = N;
  static constexpr int kSize = N + 1;

  std::array<double, N + 1> Sums{};

  void Add(double z, double absorbance)
  {
    AccumulatePowerMoments<N>(this->Sums.data(), z, absorbance);
  }
  void AddAlpha(double z, double alpha) { this->Add(z, AbsorbanceFromAlpha(alpha)); }

  PowerMoments& operator+=(const PowerMoments& other)
  {
    AddPowerMoments<N>(this->Sums.data(), other.Sums.data());
    return *this;
  }

  double B0() const { return this->Sums[0]; }
  double* Data() { return this->Sums.data(); }
  const double* Data() const { return this->Sums.data(); }

  static PowerMoments FromData(const double* b)
  {
    PowerMoments m;
    for (int k = 0; k <= N; ++k)
    {
      m.Sums[k] = b[k];
    }
    return m;
  }
};

template <int N>
inline PowerMoments<N> operator+(PowerMoments<N> lhs, const PowerMoments<N>& rhs)
{
  lhs += rhs;
  return lhs;
}

static_assert(sizeof(PowerMoments<4>) == 5 * sizeof(double), "moments must be a flat buffer");
static_assert(sizeof(PowerMoments<8>) == 9 * sizeof(double), "moments must be a flat buffer");

} // namespace apc

#endif
