#include "apcMomentTransmittance.h"

#include "apcPolynomialRoots.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>

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

// value if keep, else +0, by masking its bits: compilers turn a plain ?: into a branch (and
// sink the division into it), and that branch mispredicts on about every other query.
double KeepIf(bool keep, double value)
{
  std::uint64_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  bits &= std::uint64_t{ 0 } - static_cast<std::uint64_t>(keep);
  std::memcpy(&value, &bits, sizeof bits);
  return value;
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

} // namespace

template <int N>
MomentTransmittance<N>::MomentTransmittance(const double* sums, const MomentSettings<N>& settings)
  : B0(sums[0])
{
  this->Beta = SanitiseUnit(settings.Overestimation, kDefaultOverestimation);
  const double eps = settings.Bias < 0.0 ? DefaultMomentBias<N>()
                                         : SanitiseUnit(settings.Bias, DefaultMomentBias<N>());
  this->Fallback = AllAtQueryDepth(this->Beta, this->B0);

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

template <int N>
TransmittanceQuery MomentTransmittance<N>::Query(double z) const
{
  if (this->State == PixelState::Empty)
  {
    return { 1.0, false };
  }
  const TransmittanceQuery fallback{ this->Fallback, true };
  if (this->State == PixelState::Degenerate || std::isnan(z))
  {
    return fallback;
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

  if constexpr (M == 2)
  {
    // The common case of 4 moments, written out: two real roots from the stable quadratic
    // formula (the same arithmetic as SolveQuadratic), and no data-dependent branch between
    // them and the result. Which roots lie in front of z is a coin flip per query, and a
    // mispredicted branch there costs more than forming both kernels. Everything unusual
    // (degree drop, discriminant <= 0, a zero or non-finite root) takes the general path.
    const double disc = c[1] * c[1] - 4.0 * c[0] * c[2];
    if (c[2] != 0.0 && disc > 0.0)
    {
      const double q = -0.5 * (c[1] + std::copysign(std::sqrt(disc), c[1]));
      const double r0 = q / c[2];
      const double r1 = c[0] / q;
      const double lo = std::min(r0, r1);
      const double hi = std::max(r1, r0);
      if (q != 0.0 && std::isfinite(lo) && std::isfinite(hi))
      {
        const double wLo = 1.0 / this->ChristoffelKernel(lo);
        const double wHi = 1.0 / this->ChristoffelKernel(hi);
        // Summed in the general path's order. The selects keep a (pathological) NaN weight
        // behind z out of the sum, as the general path never forms it.
        double absorbance = this->Beta / kernelAtZ;
        absorbance += KeepIf(lo < z, wLo);
        absorbance += KeepIf(hi < z, wHi);
        const double t = std::exp(-this->B0 * absorbance);
        if (std::isfinite(absorbance) && !std::isnan(t))
        {
          return { t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t), false };
        }
      }
    }
  }
  return this->GeneralQuery(z, kernelAtZ, c.data());
}

template <int N>
TransmittanceQuery MomentTransmittance<N>::GeneralQuery(
  double z, double kernelAtZ, const double* c) const
{
  const TransmittanceQuery fallback{ this->Fallback, true };
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
    return fallback;
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
      return fallback;
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
    return fallback;
  }
  return { t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t), false };
}

template <int N>
double MomentTransmittance<N>::ChristoffelKernel(double x) const
{
  // e(x)^T (L D L^T)^-1 e(x) = |L^-1 e(x)|^2 in the D^-1 norm: a sum of positive terms.
  double kernel = 0.0;
  for (int i = 0; i <= M; ++i)
  {
    const double yi = EvaluatePolynomial(&this->LInv[i * (M + 1)], i, x);
    kernel += yi * yi * this->InvD[i];
  }
  return kernel;
}

template class MomentTransmittance<4>;
template class MomentTransmittance<6>;
template class MomentTransmittance<8>;

} // namespace apc
