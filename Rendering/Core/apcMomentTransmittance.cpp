#include "apcMomentTransmittance.h"

#include "apcPolynomialRoots.h"

#include <array>
#include <cmath>

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
  // so, which is exactly when the reconstruction cannot be trusted. D is kept while factorising
  // (the pivots' own rounding is the old one) and only inverted at the end.
  std::array<double, M + 1> d;
  for (int j = 0; j <= M; ++j)
  {
    double dj = moments[2 * j];
    for (int k = 0; k < j; ++k)
    {
      dj -= this->L[j * (M + 1) + k] * this->L[j * (M + 1) + k] * d[k];
    }
    if (!(dj > 0.0) || !std::isfinite(dj))
    {
      this->State = PixelState::Degenerate;
      return;
    }
    d[j] = dj;
    this->L[j * (M + 1) + j] = 1.0;
    for (int i = j + 1; i <= M; ++i)
    {
      double lij = moments[i + j];
      for (int k = 0; k < j; ++k)
      {
        lij -= this->L[i * (M + 1) + k] * this->L[j * (M + 1) + k] * d[k];
      }
      this->L[i * (M + 1) + j] = lij / dj;
    }
  }
  for (int j = 0; j <= M; ++j)
  {
    this->InvD[j] = 1.0 / d[j];
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
  // y = L^-1 e(z), u = D^-1 y, c = L^-T u. The Christoffel kernel at z, y^T D^-1 y, falls
  // out of the forward pass for free (the same sum of positive terms ChristoffelKernel forms).
  std::array<double, M + 1> c;
  double kernelAtZ = 0.0;
  double power = 1.0;
  for (int i = 0; i <= M; ++i)
  {
    double yi = power;
    for (int k = 0; k < i; ++k)
    {
      yi -= this->L[i * (M + 1) + k] * c[k];
    }
    c[i] = yi;
    power *= z;
  }
  for (int i = 0; i <= M; ++i)
  {
    const double ui = c[i] * this->InvD[i];
    kernelAtZ += c[i] * ui;
    c[i] = ui;
  }
  for (int i = M - 1; i >= 0; --i)
  {
    for (int k = i + 1; k <= M; ++k)
    {
      c[i] -= this->L[k * (M + 1) + i] * c[k];
    }
  }

  // Support points: z plus the real roots of the kernel polynomial. A vanishing leading
  // coefficient (exactly 0 e.g. at z = 0 for moments symmetric about 0) moves a support
  // point to infinity, where its weight is 0: such a root is missing, not an error.
  int degree = M;
  while (degree > 0 && c[degree] == 0.0)
  {
    --degree;
  }
  std::array<double, M> roots;
  const int count = KernelRoots<M>(c.data(), roots.data());
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
  // Support points behind z have f_i = 0, so their kernels are never formed; a non-finite
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
  // e(x)^T (L D L^T)^-1 e(x) = |L^-1 e(x)|^2 in the D^-1 norm.
  std::array<double, M + 1> y;
  double power = 1.0;
  double kernel = 0.0;
  for (int i = 0; i <= M; ++i)
  {
    double yi = power;
    for (int k = 0; k < i; ++k)
    {
      yi -= this->L[i * (M + 1) + k] * y[k];
    }
    y[i] = yi;
    kernel += yi * yi * this->InvD[i];
    power *= x;
  }
  return kernel;
}

template class MomentTransmittance<4>;
template class MomentTransmittance<6>;
template class MomentTransmittance<8>;

} // namespace apc
