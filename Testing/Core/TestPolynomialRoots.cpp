#include "apcPolynomialRoots.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>
#include <vector>

namespace
{

// Coefficients (lowest degree first) of lead * prod (x - r_i).
std::vector<double> FromRoots(const std::vector<double>& roots, double lead)
{
  std::vector<double> c{ lead };
  for (double r : roots)
  {
    std::vector<double> next(c.size() + 1, 0.0);
    for (std::size_t k = 0; k < c.size(); ++k)
    {
      next[k + 1] += c[k];
      next[k] -= r * c[k];
    }
    c = next;
  }
  return c;
}

int Solve(const std::vector<double>& c, double* roots)
{
  switch (c.size())
  {
    case 3:
      return apc::SolveQuadratic(c.data(), roots);
    case 4:
      return apc::SolveCubic(c.data(), roots);
    default:
      return apc::SolveQuartic(c.data(), roots);
  }
}

TEST(PolynomialRoots, HandPicked)
{
  double r[4];
  const double quadratic[3] = { 6.0, -5.0, 1.0 }; // (x-2)(x-3)
  ASSERT_EQ(apc::SolveQuadratic(quadratic, r), 2);
  EXPECT_DOUBLE_EQ(r[0], 2.0);
  EXPECT_DOUBLE_EQ(r[1], 3.0);
  const double noReal[3] = { 1.0, 0.0, 1.0 }; // x^2 + 1
  EXPECT_EQ(apc::SolveQuadratic(noReal, r), 0);
  const double linear[3] = { 3.0, 2.0, 0.0 };
  ASSERT_EQ(apc::SolveQuadratic(linear, r), 1);
  EXPECT_DOUBLE_EQ(r[0], -1.5);
  const double oneRealCubic[4] = { -1.0, 0.0, 0.0, 1.0 }; // x^3 - 1
  ASSERT_EQ(apc::SolveCubic(oneRealCubic, r), 1);
  EXPECT_DOUBLE_EQ(r[0], 1.0);
  const double tripleRoot[4] = { 0.0, 0.0, 0.0, 2.0 };
  ASSERT_EQ(apc::SolveCubic(tripleRoot, r), 3);
  EXPECT_EQ(r[0], 0.0);
  EXPECT_EQ(r[2], 0.0);
  const double biquadratic[5] = { 4.0, 0.0, -5.0, 0.0, 1.0 }; // (x^2-1)(x^2-4)
  ASSERT_EQ(apc::SolveQuartic(biquadratic, r), 4);
  const double expected[4] = { -2.0, -1.0, 1.0, 2.0 };
  for (int i = 0; i < 4; ++i)
  {
    EXPECT_NEAR(r[i], expected[i], 1e-14);
  }
  const double noRealQuartic[5] = { 1.0, 0.0, 0.0, 0.0, 1.0 }; // x^4 + 1
  EXPECT_EQ(apc::SolveQuartic(noRealQuartic, r), 0);
}

// Random real roots in the range the MBOIT kernel polynomial produces (around [-1,1], some
// far outside) with random scale: every root found to 1e-9 relative to max(1, |root|).
// The bound is loose on purpose for the nearly coincident roots the generator sometimes
// draws (a double root is only determined to ~sqrt(eps) ~ 1e-8 by its coefficients), so
// the roots are kept at least 1e-3 apart; measured worst is 3.3e-11.
TEST(PolynomialRoots, RandomRealRoots)
{
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> near(-1.5, 1.5);
  std::uniform_real_distribution<double> far(-50.0, 50.0);
  std::uniform_real_distribution<double> lead(-1e3, 1e3);
  double worst = 0.0;
  for (int degree = 2; degree <= 4; ++degree)
  {
    for (int trial = 0; trial < 20000; ++trial)
    {
      std::vector<double> roots;
      for (int i = 0; i < degree; ++i)
      {
        roots.push_back(trial % 7 == 0 && i == 0 ? far(rng) : near(rng));
      }
      std::sort(roots.begin(), roots.end());
      bool separated = true;
      for (int i = 1; i < degree; ++i)
      {
        separated = separated && roots[i] - roots[i - 1] > 1e-3;
      }
      double scale = lead(rng);
      if (!separated || std::abs(scale) < 1e-3)
      {
        continue;
      }
      const std::vector<double> c = FromRoots(roots, scale);
      double found[4];
      ASSERT_EQ(Solve(c, found), degree) << "degree " << degree << " trial " << trial;
      for (int i = 0; i < degree; ++i)
      {
        const double error = std::abs(found[i] - roots[i]) / std::max(1.0, std::abs(roots[i]));
        worst = std::max(worst, error);
        ASSERT_LE(error, 1e-9) << "degree " << degree << " trial " << trial << " root " << i;
      }
    }
  }
  std::cout << "worst relative root error: " << worst << "\n";
}

// |p(x)| / (eps sum |c_k x^k|), in long double: below ~1 the root is exact for coefficients
// perturbed by rounding, the best any solver can do in double.
double ScaledResidual(const std::vector<double>& c, double x)
{
  long double p = 0.0L;
  long double magnitude = 0.0L;
  for (std::size_t k = c.size(); k-- > 0;)
  {
    p = p * x + c[k];
    magnitude = magnitude * std::abs(x) + std::abs(c[k]);
  }
  return static_cast<double>(std::abs(p) / (magnitude * std::numeric_limits<double>::epsilon()));
}

// Clustered roots far from 0 are where the closed forms cancel (the shift dwarfs the spread)
// and polishing is needed; well-separated roots near 0 are where it is skipped. Clustered
// roots are ill-conditioned (the quartic's move by ~1e-5 under rounding of its coefficients),
// so they are held to a residual at the rounding floor: measured <= 0.19 (0.14 before
// polishing became conditional); bound 1.
TEST(PolynomialRoots, PolishedWhereTheClosedFormCancels)
{
  double r[4];
  const std::vector<double> cubic = FromRoots({ 20.0, 20.01, 20.03 }, 0.7);
  ASSERT_EQ(apc::SolveCubic(cubic.data(), r), 3);
  for (int i = 0; i < 3; ++i)
  {
    EXPECT_LE(ScaledResidual(cubic, r[i]), 1.0) << "cubic root " << i;
    EXPECT_NEAR(r[i], (std::vector<double>{ 20.0, 20.01, 20.03 })[i], 1e-7);
  }
  const std::vector<double> quartic = FromRoots({ -30.0, -29.98, -29.95, -29.9 }, -3.0);
  ASSERT_EQ(apc::SolveQuartic(quartic.data(), r), 4);
  for (int i = 0; i < 4; ++i)
  {
    EXPECT_LE(ScaledResidual(quartic, r[i]), 1.0) << "quartic root " << i;
    EXPECT_NEAR(r[i], (std::vector<double>{ -30.0, -29.98, -29.95, -29.9 })[i], 1e-4);
  }
  const std::vector<double> separated = FromRoots({ -0.75, -0.25, 0.5, 0.875 }, 1.0);
  ASSERT_EQ(apc::SolveQuartic(separated.data(), r), 4);
  EXPECT_NEAR(r[0], -0.75, 1e-14);
  EXPECT_NEAR(r[1], -0.25, 1e-14);
  EXPECT_NEAR(r[2], 0.5, 1e-14);
  EXPECT_NEAR(r[3], 0.875, 1e-14);
}

// A nearly vanishing leading coefficient puts one root far out (the kernel polynomial next to
// a degree drop); the closed forms' shift then swamps the others (here a 3.8e-9 error in the
// quartic's; on a ray's kernel polynomial two roots 1e-4 apart instead of 0.45), so such
// polynomials are solved reversed. Measured errors of the small roots: <= 1e-16.
TEST(PolynomialRoots, LargeRootDoesNotSwampTheOthers)
{
  const std::vector<double> quarticRoots = { -0.68786, -0.24195, 0.18462, 165694.83 };
  const std::vector<double> quartic = FromRoots(quarticRoots, -1.4e-4);
  double r[4];
  ASSERT_EQ(apc::SolveQuartic(quartic.data(), r), 4);
  for (int i = 0; i < 3; ++i)
  {
    EXPECT_NEAR(r[i], quarticRoots[i], 1e-13) << "quartic root " << i;
  }
  EXPECT_NEAR(r[3], quarticRoots[3], 1e-9 * quarticRoots[3]);
  const std::vector<double> cubicRoots = { -276446.26, -0.09817, 0.29609 };
  const std::vector<double> cubic = FromRoots(cubicRoots, 3e-5);
  ASSERT_EQ(apc::SolveCubic(cubic.data(), r), 3);
  EXPECT_NEAR(r[0], cubicRoots[0], 1e-9 * std::abs(cubicRoots[0]));
  for (int i = 1; i < 3; ++i)
  {
    EXPECT_NEAR(r[i], cubicRoots[i], 1e-13) << "cubic root " << i;
  }
}

TEST(PolynomialRoots, NearlyDoubleRootIsNotLost)
{
  // (x - 0.3)^2 (x + 0.5)(x - 0.9), perturbed by rounding only: all four roots must come
  // back (the discriminant clamp), to ~sqrt(eps).
  const std::vector<double> c = FromRoots({ -0.5, 0.3, 0.3, 0.9 }, 1.0);
  double r[4];
  ASSERT_EQ(apc::SolveQuartic(c.data(), r), 4);
  EXPECT_NEAR(r[1], 0.3, 1e-7);
  EXPECT_NEAR(r[2], 0.3, 1e-7);
  const std::vector<double> c3 = FromRoots({ 0.3, 0.3, -0.2 }, 2.0);
  ASSERT_EQ(apc::SolveCubic(c3.data(), r), 3);
  EXPECT_NEAR(r[0], -0.2, 1e-12);
  EXPECT_NEAR(r[1], 0.3, 1e-7);
  EXPECT_NEAR(r[2], 0.3, 1e-7);
}

} // namespace
