#include "apcPolynomialRoots.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace apc
{
namespace
{

using detail::kDiscriminantTolerance;

// A residual above this multiple of the bound on Horner's rounding error (degree * eps *
// sum |c_k x^k|) is a closed form's cancellation, not rounding: only then is a root polished.
// Below it Newton would only move the root within the rounding noise of p, which is what the
// unconditional polishing used to end up doing at a few polynomial evaluations per root.
constexpr double kPolishSlack = 4.0;

// Newton steps from x, accepting only strict improvements of |p|: near a double root Newton
// can wander off.
double PolishRoot(const double* c, int degree, double x)
{
  double px = EvaluatePolynomial(c, degree, x);
  for (int iter = 0; iter < 4 && px != 0.0; ++iter)
  {
    double dp = 0.0;
    for (int k = degree; k >= 1; --k)
    {
      dp = dp * x + k * c[k];
    }
    if (dp == 0.0 || !std::isfinite(dp))
    {
      break;
    }
    const double next = x - px / dp;
    const double pNext = EvaluatePolynomial(c, degree, next);
    if (!(std::abs(pNext) < std::abs(px)))
    {
      break;
    }
    x = next;
    px = pNext;
  }
  return x;
}

bool AtRoundingFloor(const double* c, int degree, double x)
{
  double p = c[degree];
  double magnitude = std::abs(c[degree]);
  const double ax = std::abs(x);
  for (int k = degree - 1; k >= 0; --k)
  {
    p = p * x + c[k];
    magnitude = magnitude * ax + std::abs(c[k]);
  }
  // Written so that a NaN residual is polished, as it always was.
  return std::abs(p) <= kPolishSlack * degree * std::numeric_limits<double>::epsilon() * magnitude;
}

double PolishIfNeeded(const double* c, int degree, double x)
{
  return AtRoundingFloor(c, degree, x) ? x : PolishRoot(c, degree, x);
}

// Ascending order by compare-exchange networks: the roots come out of the closed forms
// (nearly) sorted or in two sorted pairs, and min/max do not mispredict.
void CompareExchange(double& a, double& b)
{
  const double lo = std::min(a, b);
  b = std::max(b, a);
  a = lo;
}

void SortRoots(double* roots, int count)
{
  if (count == 2)
  {
    CompareExchange(roots[0], roots[1]);
  }
  else if (count == 3)
  {
    CompareExchange(roots[0], roots[1]);
    CompareExchange(roots[1], roots[2]);
    CompareExchange(roots[0], roots[1]);
  }
  else if (count == 4)
  {
    CompareExchange(roots[0], roots[1]);
    CompareExchange(roots[2], roots[3]);
    CompareExchange(roots[0], roots[2]);
    CompareExchange(roots[1], roots[3]);
    CompareExchange(roots[1], roots[2]);
  }
}

// The cubic's closed form without polishing: the roots in ascending order, or only the
// largest (what Ferrari's resolvent needs, one cosine instead of three roots).
int CubicClosedForm(const double c[4], double roots[3], bool largestOnly)
{
  const double a = c[2] / c[3];
  const double b = c[1] / c[3];
  const double d = c[0] / c[3];
  // Depressed cubic t^3 + p t + q with x = t - a/3.
  const double shift = a / 3.0;
  const double p = b - a * shift;
  const double q = (2.0 / 27.0) * a * a * a - a * b / 3.0 + d;
  if (p == 0.0)
  {
    roots[0] = std::cbrt(-q) - shift;
    if (q == 0.0 && !largestOnly)
    {
      roots[1] = roots[2] = roots[0];
      return 3;
    }
    return 1;
  }
  // For p < 0, the trigonometric form is exact in the three-real-root case and free of
  // the complex intermediate values of Cardano's formula.
  if (p < 0.0)
  {
    double cosArg = (1.5 * q / p) * std::sqrt(-3.0 / p);
    if (std::abs(cosArg) <= 1.0 + kDiscriminantTolerance)
    {
      cosArg = std::clamp(cosArg, -1.0, 1.0);
      const double m = 2.0 * std::sqrt(-p / 3.0);
      const double theta = std::acos(cosArg) / 3.0;
      if (largestOnly)
      {
        roots[0] = m * std::cos(theta) - shift;
        return 1;
      }
      // cos(theta -+ 2 pi / 3) from the sine and cosine of theta (one sincos) instead of two
      // more cosines; with theta in [0, pi/3] these are the middle and the smallest root.
      constexpr double kSqrt3Half = 0.86602540378443864676;
      const double cosTheta = std::cos(theta);
      const double sinPart = kSqrt3Half * std::sin(theta);
      roots[0] = m * (-0.5 * cosTheta - sinPart) - shift;
      roots[1] = m * (-0.5 * cosTheta + sinPart) - shift;
      roots[2] = m * cosTheta - shift;
      return 3;
    }
  }
  // One real root; the sign choice avoids cancellation between the two cube roots.
  const double disc = 0.25 * q * q + p * p * p / 27.0;
  const double u = -std::copysign(std::cbrt(0.5 * std::abs(q) + std::sqrt(std::max(disc, 0.0))), q);
  const double t = (u == 0.0) ? 0.0 : u - p / (3.0 * u);
  roots[0] = t - shift;
  return 1;
}

} // namespace

namespace
{

int SolveCubicDirect(const double c[4], double roots[3])
{
  const int count = CubicClosedForm(c, roots, false);
  for (int i = 0; i < count; ++i)
  {
    roots[i] = PolishIfNeeded(c, 3, roots[i]);
  }
  SortRoots(roots, count);
  return count;
}

int SolveQuarticDirect(const double c[5], double roots[4])
{
  const double a = c[3] / c[4];
  const double b = c[2] / c[4];
  const double cc = c[1] / c[4];
  const double d = c[0] / c[4];
  // Depressed quartic y^4 + p y^2 + q y + r with x = y - a/4.
  const double shift = 0.25 * a;
  const double a2 = a * a;
  const double p = b - 0.375 * a2;
  const double q = cc - 0.5 * a * b + 0.125 * a2 * a;
  const double r = d - 0.25 * a * cc + a2 * b / 16.0 - 3.0 * a2 * a2 / 256.0;

  int count = 0;
  double quadRoots[2];
  // Ferrari: pick m so that y^4 + p y^2 + q y + r = (y^2 + p/2 + m)^2 - 2m (y - q/(4m))^2;
  // m is a root of the resolvent 8m^3 + 8p m^2 + (2p^2 - 8r) m - q^2. Its largest root is
  // positive whenever q != 0 (the resolvent is -q^2 < 0 at m = 0).
  double m = 0.0;
  if (q != 0.0)
  {
    const double resolvent[4] = { -q * q, 2.0 * p * p - 8.0 * r, 8.0 * p, 8.0 };
    double largest[3];
    CubicClosedForm(resolvent, largest, true);
    m = PolishIfNeeded(resolvent, 3, largest[0]);
  }
  if (m > 0.0 && std::isfinite(m))
  {
    const double s = std::sqrt(2.0 * m);
    const double half = 0.5 * p + m;
    const double t = q / (2.0 * s);
    const double f1[3] = { half + t, -s, 1.0 };
    const double f2[3] = { half - t, s, 1.0 };
    for (const double* f : { f1, f2 })
    {
      const int n = SolveQuadratic(f, quadRoots);
      for (int i = 0; i < n; ++i)
      {
        roots[count++] = quadRoots[i] - shift;
      }
    }
  }
  else
  {
    // Biquadratic (q = 0, or q lost in rounding): a quadratic in u = y^2.
    const double f[3] = { r, p, 1.0 };
    const int n = SolveQuadratic(f, quadRoots);
    for (int i = 0; i < n; ++i)
    {
      double u = quadRoots[i];
      if (u < 0.0)
      {
        // A double root at y = 0 may come out as a tiny negative u.
        if (u < -kDiscriminantTolerance * (std::abs(p) + std::sqrt(std::abs(r))))
        {
          continue;
        }
        u = 0.0;
      }
      const double y = std::sqrt(u);
      roots[count++] = -y - shift;
      roots[count++] = y - shift;
    }
  }
  for (int i = 0; i < count; ++i)
  {
    roots[i] = PolishIfNeeded(c, 4, roots[i]);
  }
  SortRoots(roots, count);
  return count;
}

// A root far larger than the others (a nearly vanishing leading coefficient, as the kernel
// polynomial has next to a degree drop) makes the closed forms' shift c[n-1] / (n c[n]) dwarf
// the other roots, which then drown in its cancellation beyond what the polishing repairs
// (roots 1e-4 apart instead of 0.4, or missing). Their reciprocals are the roots of the
// reversed polynomial, where that root becomes the smallest and the shift stays small.
constexpr double kReverseRatio = 64.0;

bool SolveReversed(const double* c, int degree)
{
  return c[0] != 0.0 && std::abs(c[degree - 1]) > kReverseRatio * std::abs(c[degree]) &&
    std::abs(c[degree - 1] * c[0]) > kReverseRatio * std::abs(c[degree] * c[1]);
}

template <int Degree, typename Direct>
int SolveOriented(const double* c, double* roots, Direct direct)
{
  if (!SolveReversed(c, Degree))
  {
    return direct(c, roots);
  }
  double reversed[Degree + 1];
  for (int k = 0; k <= Degree; ++k)
  {
    reversed[k] = c[Degree - k];
  }
  const int count = direct(reversed, roots);
  for (int i = 0; i < count; ++i)
  {
    roots[i] = PolishIfNeeded(c, Degree, 1.0 / roots[i]);
  }
  SortRoots(roots, count);
  return count;
}

} // namespace

int SolveCubic(const double c[4], double roots[3])
{
  if (c[3] == 0.0)
  {
    return SolveQuadratic(c, roots);
  }
  return SolveOriented<3>(c, roots, SolveCubicDirect);
}

int SolveQuartic(const double c[5], double roots[4])
{
  if (c[4] == 0.0)
  {
    return SolveCubic(c, roots);
  }
  return SolveOriented<4>(c, roots, SolveQuarticDirect);
}

} // namespace apc
