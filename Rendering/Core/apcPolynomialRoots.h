// Real roots of polynomials of degree 1 to 4 in double precision. MBOIT needs the real
// roots of the kernel polynomial of degree N/2 (Münstermann et al. 2018, I3D, Sec. 3); for
// a positive definite Hankel matrix all of them are real and distinct, so these solvers
// treat a slightly negative discriminant (rounding) as zero rather than dropping roots.
#ifndef apcPolynomialRoots_h
#define apcPolynomialRoots_h

#include <algorithm>
#include <cmath>
#include <limits>

namespace apc
{
namespace detail
{
// A discriminant that is negative by no more than this fraction of the magnitude of its
// terms is rounding noise around a double root.
constexpr double kDiscriminantTolerance = 64.0 * std::numeric_limits<double>::epsilon();
} // namespace detail

// Each solver takes the coefficients c[0] + c[1] x + ... (lowest degree first), writes the
// real roots in ascending order (double roots repeated) and returns how many it found.
// A vanishing leading coefficient drops to the next lower degree. Roots from the closed
// forms of degree 3 and 4 are polished by Newton steps on the original polynomial where
// their residual shows that the closed form lost digits through cancellation (clustered or
// large roots); elsewhere they already sit at the rounding floor of the polynomial.
// (SolveQuadratic and EvaluatePolynomial are inline: they sit in the inner loops of the
// quartic and of every transmittance query.)
inline int SolveQuadratic(const double c[3], double roots[2]);
int SolveCubic(const double c[4], double roots[3]);
int SolveQuartic(const double c[5], double roots[4]);

// c[0] + c[1] x + ... + c[degree] x^degree by Horner's rule.
inline double EvaluatePolynomial(const double* c, int degree, double x)
{
  double p = c[degree];
  for (int k = degree - 1; k >= 0; --k)
  {
    p = p * x + c[k];
  }
  return p;
}

inline int SolveQuadratic(const double c[3], double roots[2])
{
  if (c[2] == 0.0)
  {
    if (c[1] == 0.0)
    {
      return 0;
    }
    roots[0] = -c[0] / c[1];
    return 1;
  }
  double disc = c[1] * c[1] - 4.0 * c[0] * c[2];
  if (disc < 0.0)
  {
    const double scale = c[1] * c[1] + 4.0 * std::abs(c[0] * c[2]);
    if (disc < -detail::kDiscriminantTolerance * scale)
    {
      return 0;
    }
    disc = 0.0;
  }
  // Citardauq form: never subtracts two numbers of similar size.
  const double q = -0.5 * (c[1] + std::copysign(std::sqrt(disc), c[1]));
  if (q == 0.0)
  {
    // Only when c1 = 0 and disc = 0, hence c0 = 0: a double root at 0.
    roots[0] = roots[1] = 0.0;
    return 2;
  }
  const double r0 = q / c[2];
  const double r1 = c[0] / q;
  // min/max rather than a compare-and-swap: which root is smaller is a coin flip that a
  // branch predictor cannot learn.
  roots[0] = std::min(r0, r1);
  roots[1] = std::max(r1, r0);
  return 2;
}

} // namespace apc

#endif
