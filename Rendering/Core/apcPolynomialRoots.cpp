#include "apcPolynomialRoots.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace apc
{
namespace
{

using detail::kDiscriminantTolerance;

void Polish(const double* c, int degree, double* roots, int count)
{
  for (int i = 0; i < count; ++i)
  {
    double x = roots[i];
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
      // Only accept strict improvements: near a double root Newton can wander off.
      if (!(std::abs(pNext) < std::abs(px)))
      {
        break;
      }
      x = next;
      px = pNext;
    }
    roots[i] = x;
  }
  std::sort(roots, roots + count);
}

} // namespace

int SolveCubic(const double c[4], double roots[3])
{
  if (c[3] == 0.0)
  {
    return SolveQuadratic(c, roots);
  }
  const double a = c[2] / c[3];
  const double b = c[1] / c[3];
  const double d = c[0] / c[3];
  // Depressed cubic t^3 + p t + q with x = t - a/3.
  const double shift = a / 3.0;
  const double p = b - a * shift;
  const double q = (2.0 / 27.0) * a * a * a - a * b / 3.0 + d;
  int count = 0;
  if (p == 0.0)
  {
    roots[0] = std::cbrt(-q) - shift;
    count = 1;
    if (q == 0.0)
    {
      roots[1] = roots[2] = roots[0];
      count = 3;
    }
  }
  else
  {
    // For p < 0, the trigonometric form is exact in the three-real-root case and free of
    // the complex intermediate values of Cardano's formula.
    double cosArg = 0.0;
    bool threeReal = false;
    if (p < 0.0)
    {
      cosArg = (1.5 * q / p) * std::sqrt(-3.0 / p);
      if (std::abs(cosArg) <= 1.0 + kDiscriminantTolerance)
      {
        threeReal = true;
        cosArg = std::clamp(cosArg, -1.0, 1.0);
      }
    }
    if (threeReal)
    {
      const double m = 2.0 * std::sqrt(-p / 3.0);
      const double theta = std::acos(cosArg) / 3.0;
      constexpr double kTwoPiThird = 2.0943951023931954923;
      for (int k = 0; k < 3; ++k)
      {
        roots[k] = m * std::cos(theta - k * kTwoPiThird) - shift;
      }
      count = 3;
    }
    else
    {
      // One real root; the sign choice avoids cancellation between the two cube roots.
      const double disc = 0.25 * q * q + p * p * p / 27.0;
      const double u =
        -std::copysign(std::cbrt(0.5 * std::abs(q) + std::sqrt(std::max(disc, 0.0))), q);
      const double t = (u == 0.0) ? 0.0 : u - p / (3.0 * u);
      roots[0] = t - shift;
      count = 1;
    }
  }
  Polish(c, 3, roots, count);
  return count;
}

int SolveQuartic(const double c[5], double roots[4])
{
  if (c[4] == 0.0)
  {
    return SolveCubic(c, roots);
  }
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
    double mRoots[3];
    const int mCount = SolveCubic(resolvent, mRoots);
    if (mCount > 0)
    {
      m = mRoots[mCount - 1];
    }
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
  Polish(c, 4, roots, count);
  return count;
}

} // namespace apc
