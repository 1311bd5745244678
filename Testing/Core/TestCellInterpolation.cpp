#include "apcCellInterpolation.h"
#include "apcTestCells.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>

namespace
{

using apc::CellCorners;
using apc::CellInterpolator;
using apc::CellShape;

using apctest::kSolidShapes;
using apctest::ShapeName;

// Undistorted model cells with unit-size edges. The pyramid's apex sits over the middle of
// its base (the parametric apex (0,0,1) would give a skewed, though valid, cell).
std::array<std::array<double, 3>, 8> ModelCorners(CellShape shape)
{
  auto corners = apc::ReferenceCorners(shape);
  if (shape == CellShape::Pyramid)
  {
    corners[4] = { 0.5, 0.5, 0.8 };
  }
  return corners;
}

double Determinant(const double J[3][3])
{
  return J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) -
    J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0]) +
    J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
}

// Random point of the reference cell (the pyramid's parametric domain is the unit cube).
void RandomPCoords(CellShape shape, std::mt19937& rng, double p[3])
{
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (;;)
  {
    p[0] = u(rng);
    p[1] = u(rng);
    p[2] = u(rng);
    if ((shape == CellShape::Tetra && p[0] + p[1] + p[2] > 1.0) ||
      (shape == CellShape::Wedge && p[0] + p[1] > 1.0))
    {
      continue;
    }
    return;
  }
}

// Jacobian of the world map by central differences of WorldPosition: independent of the
// analytic one under test, accurate enough (1e-6) to check its sign.
double FiniteDifferenceJacobianDeterminant(const CellCorners& cell, const double p[3])
{
  const double h = 1e-6;
  double J[3][3];
  for (int k = 0; k < 3; ++k)
  {
    double a[3] = { p[0], p[1], p[2] }, b[3] = { p[0], p[1], p[2] };
    a[k] += h;
    b[k] -= h;
    double xa[3], xb[3];
    apc::WorldPosition(cell, a, xa);
    apc::WorldPosition(cell, b, xb);
    for (int d = 0; d < 3; ++d)
    {
      J[d][k] = (xa[d] - xb[d]) / (2 * h);
    }
  }
  return Determinant(J);
}

// A random non-degenerate cell: the model cell with every corner moved by up to 0.1 per
// axis (~17% of an edge), then rotated, scaled anisotropically by 0.5..3 and moved up to 100
// away from the origin (so that rounding of large coordinates is part of the test).
// Rejected and redrawn unless the Jacobian keeps its sign on a grid through the cell.
CellCorners RandomCell(CellShape shape, std::mt19937& rng, double distortion = 0.1)
{
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> scale(0.5, 3.0);
  for (;;)
  {
    CellCorners cell;
    cell.Shape = shape;
    const auto model = ModelCorners(shape);
    double q[4] = { u(rng), u(rng), u(rng), u(rng) };
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (double& c : q)
    {
      c /= norm;
    }
    const double R[3][3] = {
      { 1 - 2 * (q[2] * q[2] + q[3] * q[3]), 2 * (q[1] * q[2] - q[0] * q[3]),
        2 * (q[1] * q[3] + q[0] * q[2]) },
      { 2 * (q[1] * q[2] + q[0] * q[3]), 1 - 2 * (q[1] * q[1] + q[3] * q[3]),
        2 * (q[2] * q[3] - q[0] * q[1]) },
      { 2 * (q[1] * q[3] - q[0] * q[2]), 2 * (q[2] * q[3] + q[0] * q[1]),
        1 - 2 * (q[1] * q[1] + q[2] * q[2]) },
    };
    const double sc[3] = { scale(rng), scale(rng), scale(rng) };
    const double shift[3] = { 100 * u(rng), 100 * u(rng), 100 * u(rng) };
    for (int i = 0; i < apc::NumberOfCorners(shape); ++i)
    {
      double m[3];
      for (int d = 0; d < 3; ++d)
      {
        m[d] = (model[i][d] + distortion * u(rng)) * sc[d];
      }
      for (int d = 0; d < 3; ++d)
      {
        cell.X[i][d] = shift[d] + R[d][0] * m[0] + R[d][1] * m[1] + R[d][2] * m[2];
      }
    }
    bool valid = true;
    const int n = 6;
    for (int i = 0; i <= n && valid; ++i)
    {
      for (int j = 0; j <= n && valid; ++j)
      {
        for (int k = 0; k <= n && valid; ++k)
        {
          double p[3] = { double(i) / n, double(j) / n, double(k) / n };
          if ((shape == CellShape::Tetra && i + j + k > n) ||
            (shape == CellShape::Wedge && i + j > n) || (shape == CellShape::Pyramid && k == n))
          {
            continue;
          }
          valid = FiniteDifferenceJacobianDeterminant(cell, p) > 0.0;
        }
      }
    }
    if (valid)
    {
      return cell;
    }
  }
}

double Diameter(const CellCorners& cell)
{
  double diameter = 0.0;
  for (int i = 0; i < apc::NumberOfCorners(cell.Shape); ++i)
  {
    for (int j = 0; j < i; ++j)
    {
      double d2 = 0.0;
      for (int d = 0; d < 3; ++d)
      {
        d2 += (cell.X[i][d] - cell.X[j][d]) * (cell.X[i][d] - cell.X[j][d]);
      }
      diameter = std::max(diameter, std::sqrt(d2));
    }
  }
  return diameter;
}

double Distance(const double a[3], const double b[3])
{
  return std::sqrt(
    (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

bool AllFinite(const double p[3])
{
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

bool InReferenceCell(CellShape shape, const double p[3])
{
  for (int i = 0; i < 3; ++i)
  {
    if (!(p[i] >= 0.0 && p[i] <= 1.0))
    {
      return false;
    }
  }
  if (shape == CellShape::Tetra)
  {
    return p[0] + p[1] + p[2] <= 1.0 + 1e-15;
  }
  if (shape == CellShape::Wedge)
  {
    return p[0] + p[1] <= 1.0 + 1e-15;
  }
  return true;
}

TEST(CellInterpolation, ShapeFunctionsArePartitionOfUnityAndNodal)
{
  std::mt19937 rng(1);
  for (const CellShape shape : kSolidShapes)
  {
    const int n = apc::NumberOfCorners(shape);
    const auto& corners = apc::ReferenceCorners(shape);
    for (int i = 0; i < n; ++i)
    {
      double w[8];
      apc::ShapeFunctions(shape, corners[i].data(), w);
      for (int j = 0; j < n; ++j)
      {
        // Exact: the factors are 0 or 1 at a corner.
        EXPECT_EQ(w[j], i == j ? 1.0 : 0.0) << ShapeName(shape) << " corner " << i << " w" << j;
      }
    }
    for (int k = 0; k < 100; ++k)
    {
      double p[3], w[8];
      RandomPCoords(shape, rng, p);
      apc::ShapeFunctions(shape, p, w);
      double sum = 0.0;
      for (int j = 0; j < n; ++j)
      {
        EXPECT_GE(w[j], 0.0) << ShapeName(shape);
        sum += w[j];
      }
      // 1e-15: a few roundings of numbers in [0,1].
      EXPECT_NEAR(sum, 1.0, 1e-15) << ShapeName(shape);
    }
  }
}

TEST(CellInterpolation, CornersGiveCornerScalars)
{
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> value(-5.0, 5.0);
  for (const CellShape shape : kSolidShapes)
  {
    for (int trial = 0; trial < 20; ++trial)
    {
      CellCorners cell = RandomCell(shape, rng);
      const int n = apc::NumberOfCorners(shape);
      double lo = 1e300, hi = -1e300;
      for (int i = 0; i < n; ++i)
      {
        cell.S[i] = value(rng);
        lo = std::min(lo, cell.S[i]);
        hi = std::max(hi, cell.S[i]);
      }
      const CellInterpolator interpolator(cell);
      for (int i = 0; i < n; ++i)
      {
        const auto& pc = apc::ReferenceCorners(shape)[i];
        EXPECT_EQ(interpolator.InterpolateScalar(pc.data()), cell.S[i]);
        EXPECT_EQ(apc::InterpolateScalar(cell, pc.data()), cell.S[i]);
        // Through Newton from the center: the corner is the hardest point to reach from
        // there. 1e-12 of the scalar range: converged to 1e-10 in parametric units with a
        // quadratically small remainder, then rounding of coordinates ~100.
        double p[3];
        apc::ParametricCenter(shape, p);
        const double* x = cell.X[i].data();
        EXPECT_TRUE(interpolator.ParametricCoordinates(x, p))
          << ShapeName(shape) << " corner " << i;
        EXPECT_NEAR(interpolator.InterpolateScalar(p), cell.S[i], 1e-12 * (hi - lo))
          << ShapeName(shape) << " corner " << i;
      }
    }
  }
}

// s = a + g.x at the corners is reproduced exactly inside any cell (the weights sum to 1 and
// interpolate x itself), so the error measures only how well x -> pcoords was inverted.
TEST(CellInterpolation, AffineFieldReproducedInDistortedCells)
{
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const CellShape shape : kSolidShapes)
  {
    double worst = 0.0;
    int maxIterations = 0;
    for (int trial = 0; trial < 200; ++trial)
    {
      CellCorners cell = RandomCell(shape, rng);
      if (shape != CellShape::Tetra)
      {
        ASSERT_FALSE(apc::IsAffine(cell, 1e-6)) << ShapeName(shape);
      }
      const double a = 10 * u(rng);
      const double g[3] = { u(rng), u(rng), u(rng) };
      double lo = 1e300, hi = -1e300;
      for (int i = 0; i < apc::NumberOfCorners(shape); ++i)
      {
        cell.S[i] = a + g[0] * cell.X[i][0] + g[1] * cell.X[i][1] + g[2] * cell.X[i][2];
        lo = std::min(lo, cell.S[i]);
        hi = std::max(hi, cell.S[i]);
      }
      const CellInterpolator interpolator(cell);
      for (int k = 0; k < 50; ++k)
      {
        double p[3], x[3];
        RandomPCoords(shape, rng, p);
        interpolator.WorldPosition(p, x);
        double q[3];
        apc::ParametricCenter(shape, q);
        int iterations = -1;
        ASSERT_TRUE(interpolator.ParametricCoordinates(x, q, &iterations)) << ShapeName(shape);
        maxIterations = std::max(maxIterations, iterations);
        const double exact = a + g[0] * x[0] + g[1] * x[1] + g[2] * x[2];
        const double error = std::abs(interpolator.InterpolateScalar(q) - exact) / (hi - lo);
        worst = std::max(worst, error);
        // Relative to the scalar range over the cell; the field's offset (~100) costs
        // ~1e-14 of rounding, so 1e-12 leaves two orders of margin.
        ASSERT_LE(error, 1e-12) << ShapeName(shape) << " trial " << trial;
      }
    }
    // From the parametric center, not from the ray marcher's much closer guess.
    EXPECT_LE(maxIterations, 7) << ShapeName(shape);
    std::cout << ShapeName(shape) << ": affine field max rel. error " << worst
              << ", Newton iterations from the center <= " << maxIterations << "\n";
  }
}

TEST(CellInterpolation, RoundTrip)
{
  std::mt19937 rng(4);
  for (const CellShape shape : kSolidShapes)
  {
    double worstX = 0.0, worstP = 0.0;
    for (int trial = 0; trial < 200; ++trial)
    {
      const CellCorners cell = RandomCell(shape, rng);
      const CellInterpolator interpolator(cell);
      const double size = Diameter(cell);
      for (int k = 0; k < 50; ++k)
      {
        double p[3], x[3];
        RandomPCoords(shape, rng, p);
        interpolator.WorldPosition(p, x);
        double q[3];
        apc::ParametricCenter(shape, q);
        ASSERT_TRUE(interpolator.ParametricCoordinates(x, q)) << ShapeName(shape);
        double y[3];
        interpolator.WorldPosition(q, y);
        // World: 1e-10 of the cell size (rounding alone is ~1e-14 here).
        const double dx = Distance(x, y) / size;
        worstX = std::max(worstX, dx);
        ASSERT_LE(dx, 1e-10) << ShapeName(shape);
        // Parametric: 1e-10, except that a pyramid's r and s count times (1-t), the size of
        // the cross-section they parametrise (they are undetermined at the apex).
        const double section = shape == CellShape::Pyramid ? 1.0 - p[2] : 1.0;
        const double dp = std::max(
          std::abs(q[2] - p[2]), section * std::max(std::abs(q[0] - p[0]), std::abs(q[1] - p[1])));
        worstP = std::max(worstP, dp);
        ASSERT_LE(dp, 1e-10) << ShapeName(shape) << " p = " << p[0] << " " << p[1] << " " << p[2];
      }
    }
    std::cout << ShapeName(shape) << ": round trip max world error / size " << worstX
              << ", max parametric error " << worstP << "\n";
  }
}

TEST(CellInterpolation, TrilinearFieldOnUnitCube)
{
  CellCorners cell;
  cell.Shape = CellShape::Hexahedron;
  cell.X = apc::ReferenceCorners(CellShape::Hexahedron);
  const double c[8] = { 0.3, -1.2, 2.5, 0.7, 1.9, -0.4, 0.8, -2.2 };
  auto field = [&c](const double x[3])
  {
    return c[0] + c[1] * x[0] + c[2] * x[1] + c[3] * x[2] + c[4] * x[0] * x[1] +
      c[5] * x[0] * x[2] + c[6] * x[1] * x[2] + c[7] * x[0] * x[1] * x[2];
  };
  for (int i = 0; i < 8; ++i)
  {
    cell.S[i] = field(cell.X[i].data());
  }
  const CellInterpolator interpolator(cell);
  EXPECT_TRUE(interpolator.IsAffine());
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 1000; ++k)
  {
    const double x[3] = { u(rng), u(rng), u(rng) };
    double p[3] = { 0.5, 0.5, 0.5 };
    int iterations = -1;
    ASSERT_TRUE(interpolator.ParametricCoordinates(x, p, &iterations));
    EXPECT_EQ(iterations, 0);
    // 1e-14: the unit cube's parametric coordinates are x itself, exactly.
    for (int d = 0; d < 3; ++d)
    {
      EXPECT_NEAR(p[d], x[d], 1e-15);
    }
    EXPECT_NEAR(interpolator.InterpolateScalar(p), field(x), 1e-14);
  }
}

// Any tetra, a parallelepiped, a prism over a translated triangle: closed form, no Newton.
TEST(CellInterpolation, AffineCellsNeedNoIteration)
{
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const CellShape shape : { CellShape::Tetra, CellShape::Wedge, CellShape::Hexahedron })
  {
    for (int trial = 0; trial < 100; ++trial)
    {
      // An undistorted model cell under a random rotation/scale/shift is affine.
      CellCorners cell = RandomCell(shape, rng, 0.0);
      if (shape == CellShape::Hexahedron)
      {
        // Shear it into a general parallelepiped: x += M (pcoords), M random.
        double M[3][3];
        for (auto& row : M)
        {
          for (double& v : row)
          {
            v = 0.3 * u(rng);
          }
        }
        for (int i = 0; i < 8; ++i)
        {
          const auto& pc = apc::ReferenceCorners(shape)[i];
          for (int d = 0; d < 3; ++d)
          {
            cell.X[i][d] += M[d][0] * pc[0] + M[d][1] * pc[1] + M[d][2] * pc[2];
          }
        }
      }
      if (shape == CellShape::Wedge)
      {
        // Translate the top triangle sideways: still a prism over a translated triangle.
        const double shift[3] = { 0.4 * u(rng), 0.4 * u(rng), 0.4 * u(rng) };
        for (int i = 3; i < 6; ++i)
        {
          for (int d = 0; d < 3; ++d)
          {
            cell.X[i][d] += shift[d];
          }
        }
      }
      for (int i = 0; i < apc::NumberOfCorners(shape); ++i)
      {
        cell.S[i] = u(rng);
      }
      EXPECT_TRUE(apc::IsAffine(cell, 1e-12)) << ShapeName(shape);
      const CellInterpolator interpolator(cell);
      ASSERT_TRUE(interpolator.IsAffine()) << ShapeName(shape);
      for (int k = 0; k < 20; ++k)
      {
        double p[3], x[3], q[3] = { 0.1, 0.9, 0.1 };
        RandomPCoords(shape, rng, p);
        interpolator.WorldPosition(p, x);
        int iterations = -1;
        ASSERT_TRUE(interpolator.ParametricCoordinates(x, q, &iterations));
        EXPECT_LE(iterations, 1) << ShapeName(shape);
        for (int d = 0; d < 3; ++d)
        {
          // 1e-12: a 3x3 inverse of a well-conditioned cell at coordinates ~100.
          EXPECT_NEAR(q[d], p[d], 1e-12) << ShapeName(shape);
        }
      }
    }
  }
  // The top triangle rotated instead of translated: bilinear terms appear.
  CellCorners twisted;
  twisted.Shape = CellShape::Wedge;
  twisted.X = apc::ReferenceCorners(CellShape::Wedge);
  twisted.X[4] = { 0.9, 0.1, 1.0 };
  EXPECT_FALSE(apc::IsAffine(twisted, 1e-6));
  EXPECT_FALSE(CellInterpolator(twisted).IsAffine());
  // A pyramid never is: its rt coefficient is minus a base edge.
  CellCorners pyramid;
  pyramid.Shape = CellShape::Pyramid;
  pyramid.X = ModelCorners(CellShape::Pyramid);
  EXPECT_FALSE(apc::IsAffine(pyramid, 1e-3));
}

// Convergence is detected after a single Newton step when the guess is already right, so the
// ray marcher pays one Jacobian solve per sample in nearly affine cells.
TEST(CellInterpolation, ExactGuessStopsAfterOneStep)
{
  std::mt19937 rng(7);
  for (const CellShape shape : { CellShape::Pyramid, CellShape::Wedge, CellShape::Hexahedron })
  {
    for (int trial = 0; trial < 50; ++trial)
    {
      const CellCorners cell = RandomCell(shape, rng);
      const CellInterpolator interpolator(cell);
      ASSERT_FALSE(interpolator.IsAffine());
      for (int k = 0; k < 20; ++k)
      {
        double p[3], x[3];
        RandomPCoords(shape, rng, p);
        interpolator.WorldPosition(p, x);
        double q[3] = { p[0], p[1], p[2] };
        int iterations = -1;
        ASSERT_TRUE(interpolator.ParametricCoordinates(x, q, &iterations));
        EXPECT_EQ(iterations, 1) << ShapeName(shape);
      }
    }
  }
}

// The ray marcher's guess: the parametric coordinates of the entry and exit points (on two
// faces) interpolated along the segment. Exact for affine cells, close for distorted ones.
TEST(CellInterpolation, RayMarcherGuessConvergesFast)
{
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (const CellShape shape : { CellShape::Pyramid, CellShape::Wedge, CellShape::Hexahedron })
  {
    int histogram[apc::kMaxNewtonIterations + 1] = {};
    for (int trial = 0; trial < 200; ++trial)
    {
      CellCorners cell = RandomCell(shape, rng);
      for (int i = 0; i < apc::NumberOfCorners(shape); ++i)
      {
        cell.S[i] = u(rng);
      }
      const CellInterpolator interpolator(cell);
      // Entry on the face t = 0, exit on the face t = 1 (the pyramid's apex for t = 1).
      double entry[3], exit[3];
      RandomPCoords(shape, rng, entry);
      RandomPCoords(shape, rng, exit);
      entry[2] = 0.0;
      exit[2] = 1.0;
      double xEntry[3], xExit[3];
      interpolator.WorldPosition(entry, xEntry);
      interpolator.WorldPosition(exit, xExit);
      for (int k = 1; k < 10; ++k)
      {
        const double f = k / 10.0;
        double x[3], q[3];
        for (int d = 0; d < 3; ++d)
        {
          x[d] = (1 - f) * xEntry[d] + f * xExit[d];
          q[d] = (1 - f) * entry[d] + f * exit[d];
        }
        // A looser tolerance stops earlier, yet the applied last update leaves far less: the
        // square of a Newton step, or a chord step (below 1e-6) times the Newton step before
        // it (below 1e-2) times the cell's distortion; checked at 1e-8.
        double loose[3] = { q[0], q[1], q[2] };
        int looseIterations = -1;
        ASSERT_TRUE(interpolator.ParametricCoordinates(x, loose, &looseIterations, 1e-6));
        int iterations = -1;
        ASSERT_TRUE(interpolator.ParametricCoordinates(x, q, &iterations)) << ShapeName(shape);
        ++histogram[iterations];
        EXPECT_LE(looseIterations, iterations);
        EXPECT_NEAR(interpolator.InterpolateScalar(loose), interpolator.InterpolateScalar(q), 1e-8);
        double y[3];
        interpolator.WorldPosition(q, y);
        ASSERT_LE(Distance(x, y), 1e-10 * Diameter(cell));
      }
    }
    std::cout << ShapeName(shape) << ": Newton iterations from the ray guess:";
    for (int i = 0; i <= apc::kMaxNewtonIterations; ++i)
    {
      if (histogram[i])
      {
        std::cout << " " << i << ":" << histogram[i];
      }
    }
    std::cout << "\n";
    // Quadratic convergence from a guess within ~0.1: a handful of steps at most.
    for (int i = 6; i <= apc::kMaxNewtonIterations; ++i)
    {
      EXPECT_EQ(histogram[i], 0) << ShapeName(shape) << " needed " << i << " iterations";
    }
  }
}

TEST(CellInterpolation, PyramidApex)
{
  CellCorners cell;
  cell.Shape = CellShape::Pyramid;
  cell.X = ModelCorners(CellShape::Pyramid);
  cell.S = { 1, 2, 3, 4, 10 };
  const CellInterpolator interpolator(cell);
  // Exactly at the apex the Jacobian is singular (the plane t = 1 maps onto it).
  double p[3] = { 0.3, 0.3, 0.3 };
  EXPECT_TRUE(interpolator.ParametricCoordinates(cell.X[4].data(), p));
  EXPECT_NEAR(p[2], 1.0, 1e-12);
  EXPECT_NEAR(interpolator.InterpolateScalar(p), 10.0, 1e-11);
  // Just below it r and s are ill-conditioned but the scalar is not.
  for (const double depth : { 1e-3, 1e-6, 1e-9, 1e-12 })
  {
    const double pc[3] = { 0.3, 0.6, 1.0 - depth };
    double x[3];
    interpolator.WorldPosition(pc, x);
    double q[3] = { 0.4, 0.4, 0.2 };
    EXPECT_TRUE(interpolator.ParametricCoordinates(x, q)) << depth;
    EXPECT_NEAR(interpolator.InterpolateScalar(q), interpolator.InterpolateScalar(pc), 1e-11)
      << depth;
  }
}

TEST(CellInterpolation, VoxelThroughHexahedronOrder)
{
  // Voxel corners in VTK's voxel order (x fastest), an axis-aligned box.
  const double origin[3] = { 2.0, -1.0, 5.0 }, h[3] = { 0.5, 2.0, 1.5 };
  CellCorners cell;
  cell.Shape = CellShape::Hexahedron;
  for (int i = 0; i < 8; ++i)
  {
    const int v = apc::kVoxelToHexahedron[i];
    const int bits[3] = { v & 1, (v >> 1) & 1, (v >> 2) & 1 };
    for (int d = 0; d < 3; ++d)
    {
      cell.X[i][d] = origin[d] + bits[d] * h[d];
    }
    cell.S[i] = 1.0 + v; // the voxel's scalar for its corner v
  }
  // The reordered corners form a right-handed hexahedron with the voxel's parametrisation.
  const CellInterpolator interpolator(cell);
  ASSERT_TRUE(interpolator.IsAffine());
  const double x[3] = { 2.1, 0.5, 6.2 };
  double p[3] = { 0.5, 0.5, 0.5 };
  ASSERT_TRUE(interpolator.ParametricCoordinates(x, p));
  double trilinear = 0.0;
  for (int v = 0; v < 8; ++v)
  {
    double w = 1.0;
    for (int d = 0; d < 3; ++d)
    {
      const double pd = (x[d] - origin[d]) / h[d];
      EXPECT_NEAR(p[d], pd, 1e-14);
      w *= ((v >> d) & 1) ? pd : 1.0 - pd;
    }
    trilinear += w * (1.0 + v);
  }
  EXPECT_NEAR(interpolator.InterpolateScalar(p), trilinear, 1e-13);
}

TEST(CellInterpolation, DegenerateCellsGiveFiniteClampedResults)
{
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const CellShape shape : kSolidShapes)
  {
    CellCorners point;
    point.Shape = shape;
    for (int i = 0; i < 8; ++i)
    {
      point.X[i] = { 1.0, 2.0, 3.0 };
      point.S[i] = i;
    }
    const CellInterpolator collapsed(point);
    EXPECT_TRUE(collapsed.IsDegenerate()) << ShapeName(shape);
    EXPECT_FALSE(apc::IsAffine(point, 1e-12)) << ShapeName(shape);
    const double x[3] = { 1.0, 2.0, 3.0 };
    for (const double guess : { 0.3, -4.0, 7.0, nan })
    {
      double p[3] = { guess, guess, guess };
      int iterations = -1;
      EXPECT_FALSE(collapsed.ParametricCoordinates(x, p, &iterations)) << ShapeName(shape);
      EXPECT_TRUE(AllFinite(p)) << ShapeName(shape);
      EXPECT_TRUE(InReferenceCell(shape, p)) << ShapeName(shape) << " guess " << guess;
      EXPECT_TRUE(std::isfinite(collapsed.InterpolateScalar(p))) << ShapeName(shape);
      EXPECT_GE(iterations, 0);
    }
  }
  // A flat hexahedron (all corners at z = 0).
  CellCorners flat;
  flat.Shape = CellShape::Hexahedron;
  flat.X = apc::ReferenceCorners(CellShape::Hexahedron);
  for (auto& corner : flat.X)
  {
    corner[2] = 0.0;
  }
  const CellInterpolator squashed(flat);
  EXPECT_TRUE(squashed.IsDegenerate());
  const double x[3] = { 0.5, 0.5, 0.0 };
  double p[3] = { 0.2, 0.2, 0.2 };
  EXPECT_FALSE(squashed.ParametricCoordinates(x, p));
  EXPECT_TRUE(AllFinite(p));
  EXPECT_TRUE(InReferenceCell(CellShape::Hexahedron, p));
}

TEST(CellInterpolation, BadInputsNeverGiveNaN)
{
  std::mt19937 rng(9);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const CellShape shape : kSolidShapes)
  {
    CellCorners cell = RandomCell(shape, rng);
    for (int i = 0; i < 8; ++i)
    {
      cell.S[i] = i;
    }
    const CellInterpolator interpolator(cell);
    double center[3];
    interpolator.WorldPosition(apc::ReferenceCorners(shape)[1].data(), center);
    const double points[][3] = { { nan, 0.0, 0.0 }, { inf, 1.0, 1.0 }, { 1e30, -1e30, 0.0 },
      { center[0] + 1e3, center[1], center[2] } };
    for (const auto& x : points)
    {
      double p[3] = { nan, 0.5, 0.5 };
      const bool ok = interpolator.ParametricCoordinates(x, p);
      EXPECT_TRUE(AllFinite(p)) << ShapeName(shape);
      if (!ok)
      {
        EXPECT_TRUE(InReferenceCell(shape, p)) << ShapeName(shape);
      }
      EXPECT_TRUE(std::isfinite(interpolator.InterpolateScalar(p))) << ShapeName(shape);
    }
    // A NaN or infinite point can never converge.
    double p[3] = { 0.2, 0.2, 0.2 };
    EXPECT_FALSE(interpolator.ParametricCoordinates(points[0], p)) << ShapeName(shape);
  }
}

TEST(CellInterpolation, ClampToReferenceCell)
{
  const double nan = std::numeric_limits<double>::quiet_NaN();
  double p[3] = { -0.5, 1.5, nan };
  apc::ClampToReferenceCell(CellShape::Hexahedron, p);
  EXPECT_EQ(p[0], 0.0);
  EXPECT_EQ(p[1], 1.0);
  EXPECT_EQ(p[2], 0.0);
  double q[3] = { 0.8, 0.8, 0.8 };
  apc::ClampToReferenceCell(CellShape::Tetra, q);
  EXPECT_TRUE(InReferenceCell(CellShape::Tetra, q));
  EXPECT_NEAR(q[0], 1.0 / 3.0, 1e-15);
  double r[3] = { 0.8, 0.8, 0.8 };
  apc::ClampToReferenceCell(CellShape::Wedge, r);
  EXPECT_TRUE(InReferenceCell(CellShape::Wedge, r));
  EXPECT_EQ(r[2], 0.8);
}

} // namespace
