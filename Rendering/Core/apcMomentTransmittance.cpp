#include "apcMomentTransmittance.h"

#include "apcPolynomialRoots.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

// The batched weights' helpers must be inlined into their AVX2 copy to be compiled for it.
#if defined(__GNUC__)
#define APC_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define APC_ALWAYS_INLINE inline
#endif

namespace apc
{
namespace
{

double SanitiseUnit(double value, double fallback)
{
  if (std::isnan(value))
  {
    return fallback;
  }
  return value < 0.0 ? 0.0 : (value > 1.0 ? 1.0 : value);
}

// exp(-beta b0) without the NaN of 0 * inf.
double AllAtQueryDepth(double beta, double b0)
{
  if (std::isnan(b0) || beta == 0.0 || !(b0 > 0.0))
  {
    return 1.0;
  }
  return std::exp(-beta * b0);
}

template <int M>
int KernelRoots(const double* c, double* roots)
{
  if constexpr (M == 2)
  {
    return SolveQuadratic(c, roots);
  }
  else if constexpr (M == 3)
  {
    return SolveCubic(c, roots);
  }
  else
  {
    static_assert(M == 4, "kernel polynomial degree must be 2, 3 or 4");
    return SolveQuartic(c, roots);
  }
}

// exp(x) for x <= 0 in vectorisable arithmetic: x = k ln 2 + r, |r| <= ln 2 / 2, e^r by its
// Taylor series to degree 13 (truncation below 2e-16 relative), 2^k added to the exponent.
// Below -708 (where 2^k would leave the normal range) the result is 0, whose difference from
// exp(x) is below 1e-307.
APC_ALWAYS_INLINE double ExpNonPositive(double x)
{
  constexpr double kLog2e = 1.4426950408889634;
  constexpr double kLn2Hi = 6.93147180369123816490e-01;
  constexpr double kLn2Lo = 1.90821492927058770002e-10;
  constexpr double kShifter = 6755399441055744.0; // 1.5 * 2^52: adding it rounds to an integer
  const double xc = x < -708.0 ? -708.0 : x;
  const double shifted = xc * kLog2e + kShifter;
  const double k = shifted - kShifter;
  const double r = (xc - k * kLn2Hi) - k * kLn2Lo;
  double p = 1.0 / 6227020800.0;
  p = p * r + 1.0 / 479001600.0;
  p = p * r + 1.0 / 39916800.0;
  p = p * r + 1.0 / 3628800.0;
  p = p * r + 1.0 / 362880.0;
  p = p * r + 1.0 / 40320.0;
  p = p * r + 1.0 / 5040.0;
  p = p * r + 1.0 / 720.0;
  p = p * r + 1.0 / 120.0;
  p = p * r + 1.0 / 24.0;
  p = p * r + 1.0 / 6.0;
  p = p * r + 0.5;
  p = p * r + 1.0;
  p = p * r + 1.0;
  // k sits in the low bits of shifted; unsigned arithmetic wraps as two's complement.
  uint64_t kBits;
  std::memcpy(&kBits, &shifted, sizeof kBits);
  uint64_t bits;
  std::memcpy(&bits, &p, sizeof bits);
  bits += (kBits - uint64_t{ 0x4338000000000000 }) << 52;
  double result;
  std::memcpy(&result, &bits, sizeof result);
  return x < -708.0 ? 0.0 : result;
}

// 1 - exp(-a) for a >= 0 without the cancellation of small a: its alternating series below
// 1/2 (16 terms, truncation below 1e-19 relative), 1 - exp(-a) above.
APC_ALWAYS_INLINE double OpacityOfAbsorbance(double a)
{
  // Written out: a loop here would stop the vectoriser.
  double series = 1.0 - a * (1.0 / 17.0);
  series = 1.0 - a * (1.0 / 16.0) * series;
  series = 1.0 - a * (1.0 / 15.0) * series;
  series = 1.0 - a * (1.0 / 14.0) * series;
  series = 1.0 - a * (1.0 / 13.0) * series;
  series = 1.0 - a * (1.0 / 12.0) * series;
  series = 1.0 - a * (1.0 / 11.0) * series;
  series = 1.0 - a * (1.0 / 10.0) * series;
  series = 1.0 - a * (1.0 / 9.0) * series;
  series = 1.0 - a * (1.0 / 8.0) * series;
  series = 1.0 - a * (1.0 / 7.0) * series;
  series = 1.0 - a * (1.0 / 6.0) * series;
  series = 1.0 - a * (1.0 / 5.0) * series;
  series = 1.0 - a * (1.0 / 4.0) * series;
  series = 1.0 - a * (1.0 / 3.0) * series;
  series = 1.0 - a * (1.0 / 2.0) * series;
  // Blended, not selected: with a select the compiler moves the exponential into a branch,
  // which stops the vectoriser. Both terms are finite for a in [0, kAbsorbanceMax].
  const double small = a < 0.5 ? 1.0 : 0.0;
  return small * (a * series) + (1.0 - small) * (1.0 - ExpNonPositive(-a));
}

// Query's 4-moment arithmetic for n samples, every branch turned into a select so that the loop
// vectorises; full[i] is set where Query's fast path would not answer (it then gives the
// sample's transmittance). Compiled twice, for the build's baseline and for AVX2 with FMA, and
// chosen by what the CPU has.
APC_ALWAYS_INLINE void FourMomentWeightsBody(const FourMomentPixel& px, const double* depths,
  const double* absorbances, double* weights, uint8_t* full, int n)
{
  // Locals: the stores to weights might otherwise alias px, and reloading it each sample
  // stops the vectoriser.
  const double l3 = px.L3, l4 = px.L4, l6 = px.L6, l7 = px.L7, l8 = px.L8;
  const double d0 = px.D0, d1 = px.D1, d2 = px.D2, b0 = px.B0, beta = px.Beta;
  for (int i = 0; i < n; ++i)
  {
    const double raw = depths[i];
    const double z = raw < -1.0 ? -1.0 : (raw > 1.0 ? 1.0 : raw);
    const double y1 = l4 * z + l3;
    const double y2 = (l8 * z + l7) * z + l6;
    const double u0 = d0;
    const double u1 = y1 * d1;
    const double u2 = y2 * d2;
    const double kernelAtZ = u0 + y1 * u1 + y2 * u2;
    const double c2 = u2;
    const double c1 = u1 + u2 * l7;
    const double c0 = u2 * l6 + u1 * l3 + u0;
    const double disc = c1 * c1 - 4.0 * c0 * c2;
    const double wz = 1.0 / kernelAtZ;
    const double outside = 2.0 * c2 * z > -c1 ? 1.0 - (1.0 - beta) * wz : beta * wz;
    const double root = std::sqrt(disc > 0.0 ? disc : 0.0);
    const double q = -0.5 * (c1 + (c1 < 0.0 ? -root : root));
    const double r0 = q / c2;
    const double r1 = c0 / q;
    const double lo = r0 < r1 ? r0 : r1;
    const double ylo1 = l4 * lo + l3;
    const double ylo2 = (l8 * lo + l7) * lo + l6;
    const double kernelAtLo = d0 + ylo1 * ylo1 * d1 + ylo2 * ylo2 * d2;
    const double between = beta * wz + 1.0 / kernelAtLo;
    const double absorbance = c2 > 0.0 ? outside : between;
    // Bitwise, not short-circuit: a branch would stop the vectoriser.
    const bool usual = (c2 != 0.0) & (disc > 0.0) &
      ((c2 > 0.0) | ((q != 0.0) & (std::abs(lo) <= 1.7976931348623157e308))) &
      (std::abs(absorbance) <= 1.7976931348623157e308);
    const double t = ExpNonPositive(-b0 * (usual ? absorbance : 0.0));
    const double clamped = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    weights[i] = OpacityOfAbsorbance(absorbances[i]) * clamped;
    full[i] = usual ? 0 : 1;
  }
}

#if defined(__GNUC__) && defined(__x86_64__)
#define APC_HAVE_AVX2_WEIGHTS 1
__attribute__((target("avx2,fma"))) void FourMomentWeightsAvx2(const FourMomentPixel& px,
  const double* depths, const double* absorbances, double* weights, uint8_t* full, int n)
{
  FourMomentWeightsBody(px, depths, absorbances, weights, full, n);
}
#endif

void FourMomentWeights(const FourMomentPixel& px, const double* depths, const double* absorbances,
  double* weights, uint8_t* full, int n)
{
#ifdef APC_HAVE_AVX2_WEIGHTS
  static const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  if (avx2)
  {
    FourMomentWeightsAvx2(px, depths, absorbances, weights, full, n);
    return;
  }
#endif
  FourMomentWeightsBody(px, depths, absorbances, weights, full, n);
}

} // namespace

template <int N>
void MomentTransmittance<N>::Weights(
  const double* depths, const double* absorbances, double* weights, int n) const
{
  if constexpr (M == 2)
  {
    if (this->State == PixelState::Valid)
    {
      constexpr int kChunk = 256;
      FourMomentPixel px;
      this->GetFourMomentPixel(px);
      uint8_t full[kChunk];
      for (int begin = 0; begin < n; begin += kChunk)
      {
        const int count = std::min(kChunk, n - begin);
        FourMomentWeights(px, depths + begin, absorbances + begin, weights + begin, full, count);
        for (int i = 0; i < count; ++i)
        {
          if (full[i])
          {
            weights[begin + i] = OpacityOfAbsorbance(absorbances[begin + i]) *
              this->FullQuery(depths[begin + i]).Transmittance;
          }
        }
      }
      return;
    }
  }
  for (int i = 0; i < n; ++i)
  {
    weights[i] = -std::expm1(-absorbances[i]) * this->Query(depths[i]).Transmittance;
  }
}

template <int N>
MomentTransmittance<N>::MomentTransmittance(const double* sums, const MomentSettings<N>& settings)
  : B0(sums[0])
{
  this->Beta = SanitiseUnit(settings.Overestimation, kDefaultOverestimation);
  const double eps = settings.Bias < 0.0 ? DefaultMomentBias<N>()
                                         : SanitiseUnit(settings.Bias, DefaultMomentBias<N>());
  // Written so that NaN lands in the degenerate branch, not in the empty one.
  if (this->B0 < kEmptyPixelAbsorbance)
  {
    this->State = PixelState::Empty;
    return;
  }
  if (!std::isfinite(this->B0))
  {
    this->State = PixelState::Degenerate;
    return;
  }

  std::array<double, N + 1> moments; // normalised and biased, moments[0] = 1
  moments[0] = 1.0;
  if constexpr (M == 2)
  {
    if (!this->SetUpFourMoments(sums, eps, settings.BiasVector.data(), moments.data()))
    {
      this->State = PixelState::Degenerate;
    }
    return;
  }
  for (int k = 1; k <= N; ++k)
  {
    const double normalised = sums[k] / this->B0;
    if (!std::isfinite(normalised))
    {
      this->State = PixelState::Degenerate;
      return;
    }
    moments[k] = (1.0 - eps) * normalised + eps * settings.BiasVector[k - 1];
  }

  // LDL^T of the Hankel matrix H_ij = b_{i+j}. Without pivoting: a positive definite
  // matrix needs none, and a pivot that is not positive means the bias failed to make it
  // so, which is exactly when the reconstruction cannot be trusted. D is inverted only after
  // factorising, so that the pivots and their guard see the rounding of a plain LDL^T.
  std::array<double, M + 1> d;
  std::array<double, (M + 1) * (M + 1)> l{}; // unit lower triangular, row major
  for (int j = 0; j <= M; ++j)
  {
    double dj = moments[2 * j];
    for (int k = 0; k < j; ++k)
    {
      dj -= l[j * (M + 1) + k] * l[j * (M + 1) + k] * d[k];
    }
    if (!(dj > 0.0) || !std::isfinite(dj))
    {
      this->State = PixelState::Degenerate;
      return;
    }
    d[j] = dj;
    l[j * (M + 1) + j] = 1.0;
    for (int i = j + 1; i <= M; ++i)
    {
      double lij = moments[i + j];
      for (int k = 0; k < j; ++k)
      {
        lij -= l[i * (M + 1) + k] * l[j * (M + 1) + k] * d[k];
      }
      l[i * (M + 1) + j] = lij / dj;
    }
  }
  for (int j = 0; j <= M; ++j)
  {
    this->InvD[j] = 1.0 / d[j];
  }
  // L^-1 row by row (forward substitution on the identity).
  for (int i = 0; i <= M; ++i)
  {
    this->LInv[i * (M + 1) + i] = 1.0;
    for (int j = 0; j < i; ++j)
    {
      double sum = 0.0;
      for (int k = j; k < i; ++k)
      {
        sum -= l[i * (M + 1) + k] * this->LInv[k * (M + 1) + j];
      }
      this->LInv[i * (M + 1) + j] = sum;
    }
  }
}

// The constructor's normalisation and factorisation for 4 moments, written out: the same
// operations on the same values as the general loops (a product by d0 = 1 and a quotient by it
// are exact, so leaving them out changes no bit), but its seven divisions in three vector ones
// and a scalar one. The divisions were a chain on the divider that pass 2 waits on once a
// pixel; a vector division rounds each lane as the scalar one does. False where the general
// code finds the pixel degenerate. Called for 4 moments only (instantiated for all N).
template <int N>
bool MomentTransmittance<N>::SetUpFourMoments(
  const double* sums, double eps, const double* biasVector, double* moments)
{
  const double b0 = this->B0;
  double normalised[4];
#if defined(__GNUC__)
  typedef double Pair __attribute__((vector_size(16)));
  const Pair b0s = { b0, b0 };
  const Pair n12 = Pair{ sums[1], sums[2] } / b0s;
  const Pair n34 = Pair{ sums[3], sums[4] } / b0s;
  normalised[0] = n12[0];
  normalised[1] = n12[1];
  normalised[2] = n34[0];
  normalised[3] = n34[1];
#else
  for (int k = 0; k < 4; ++k)
  {
    normalised[k] = sums[k + 1] / b0;
  }
#endif
  for (int k = 0; k < 4; ++k)
  {
    if (!std::isfinite(normalised[k]))
    {
      return false;
    }
    moments[k + 1] = (1.0 - eps) * normalised[k] + eps * biasVector[k];
  }
  // LDL^T as the general loop forms it, with d0 = moments[0] = 1.
  const double l10 = moments[1];
  const double l20 = moments[2];
  const double d1 = moments[2] - l10 * l10;
  if (!(d1 > 0.0) || !std::isfinite(d1))
  {
    return false;
  }
  const double l21Numerator = moments[3] - l20 * l10;
  double l21, invD1;
#if defined(__GNUC__)
  const Pair q = Pair{ l21Numerator, 1.0 } / Pair{ d1, d1 };
  l21 = q[0];
  invD1 = q[1];
#else
  l21 = l21Numerator / d1;
  invD1 = 1.0 / d1;
#endif
  double d2 = moments[4];
  d2 -= l20 * l20;
  d2 -= l21 * l21 * d1;
  if (!(d2 > 0.0) || !std::isfinite(d2))
  {
    return false;
  }
  this->InvD[0] = 1.0;
  this->InvD[1] = invD1;
  this->InvD[2] = 1.0 / d2;
  // L^-1 by the general loop's forward substitution: row 1 is 0 - l10 1, row 2's entries
  // 0 - l20 1 - l21 (0 - l10 1) and 0 - l21 1.
  double* inv = this->LInv.data();
  inv[0] = 1.0;
  inv[3] = 0.0 - l10 * 1.0;
  inv[4] = 1.0;
  double sum = 0.0;
  sum -= l20 * 1.0;
  sum -= l21 * inv[3];
  inv[6] = sum;
  inv[7] = 0.0 - l21 * 1.0;
  inv[8] = 1.0;
  return true;
}

// exp(-beta b0) computed where a query falls back, not kept per pixel: pass 2 sets up a
// pixel for every few dozen samples and falls back rarely, and a libm exp per set-up was a few
// per cent of it.
template <int N>
double MomentTransmittance<N>::FallbackTransmittance() const
{
  return AllAtQueryDepth(this->Beta, this->B0);
}

template <int N>
TransmittanceQuery MomentTransmittance<N>::FullQuery(double z) const
{
  if (this->State == PixelState::Empty)
  {
    return { 1.0, false };
  }
  if (this->State == PixelState::Degenerate || std::isnan(z))
  {
    return { this->FallbackTransmittance(), true };
  }
  z = z < -1.0 ? -1.0 : (z > 1.0 ? 1.0 : z);

  // The kernel polynomial's coefficients c = B^-1 e(z), e(z) = (1, z, ..., z^M), as
  // L^-T D^-1 y with y = L^-1 e(z), whose entries are polynomials in z with precomputed
  // coefficients: the solves without their serial dependency chains. (c straight from a
  // precomputed B^-1 is shorter still but loses about a digit, 3e-13 against 2e-14 in T.)
  // The Christoffel kernel at z, |y|^2 in the D^-1 norm, comes on the way.
  std::array<double, M + 1> u;
  double kernelAtZ = 0.0;
  for (int i = 0; i <= M; ++i)
  {
    const double yi = EvaluatePolynomial(&this->LInv[i * (M + 1)], i, z);
    u[i] = yi * this->InvD[i];
    kernelAtZ += yi * u[i];
  }
  std::array<double, M + 1> c;
  for (int k = 0; k <= M; ++k)
  {
    double ck = u[M] * this->LInv[M * (M + 1) + k];
    for (int i = M - 1; i >= k; --i)
    {
      ck += u[i] * this->LInv[i * (M + 1) + k];
    }
    c[k] = ck;
  }

  return this->GeneralQuery(z, kernelAtZ, c.data());
}

template <int N>
TransmittanceQuery MomentTransmittance<N>::GeneralQuery(
  double z, double kernelAtZ, const double* c) const
{
  const auto fallback = [this] {
    return TransmittanceQuery{ this->FallbackTransmittance(), true };
  };
  // Support points: z plus the real roots of the kernel polynomial. A vanishing leading
  // coefficient (exactly 0 e.g. at z = 0 for moments symmetric about 0) moves a support
  // point to infinity, where its weight is 0: such a root is missing, not an error.
  int degree = M;
  while (degree > 0 && c[degree] == 0.0)
  {
    --degree;
  }
  std::array<double, M> roots;
  const int count = KernelRoots<M>(c, roots.data());
  if (count != degree)
  {
    return fallback();
  }

  // The interpolant of the step function (beta at z, 1 at support points in front of z, 0
  // behind) integrates to sum_i f_i w_i, where w_i are the weights of the canonical
  // distribution. They equal the Christoffel function 1 / K(x_i, x_i) with
  // K(x, x) = e(x)^T B^-1 e(x), the classical result for quadratures whose nodes are the
  // zeros of a quasi-orthogonal polynomial. This is algebraically what the reference's
  // Newton divided differences compute, but as a sum of positive terms: no cancellation,
  // A stays in [0,1] up to rounding, and a root near infinity (leading coefficient ~ 0, e.g. z = 0
  // for symmetric moments) simply gets weight ~ 0 instead of wrecking a monomial expansion.
  // Support points behind z have f_i = 0, so their kernels are not formed; a non-finite
  // root still fails the query wherever it lies.
  double absorbance = this->Beta == 0.0 ? 0.0 : this->Beta / kernelAtZ;
  for (int i = 0; i < count; ++i)
  {
    if (!std::isfinite(roots[i]))
    {
      return fallback();
    }
    if (roots[i] < z)
    {
      absorbance += 1.0 / this->ChristoffelKernel(roots[i]);
    }
  }
  if (absorbance == 0.0)
  {
    return { 1.0, false }; // exp(-b0 * 0), b0 being finite here
  }
  const double t = std::exp(-this->B0 * absorbance);
  if (!std::isfinite(absorbance) || std::isnan(t))
  {
    return fallback();
  }
  return { t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t), false };
}

template <int N>
double MomentTransmittance<N>::HiddenDepth(double maxWeight) const
{
  // No samples known: every step is taken.
  return this->HiddenDepth(maxWeight,
    []
    {
      constexpr double kAll = std::numeric_limits<double>::infinity();
      return std::make_pair(-kAll, kAll);
    });
}

template class MomentTransmittance<4>;
template class MomentTransmittance<6>;
template class MomentTransmittance<8>;

} // namespace apc
