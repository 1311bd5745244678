// The linear inverse of nearly affine cells (CellInterpolator::LinearRay) against the exact
// interpolant and Newton's inverse: the stated scalar error bound must hold at every point of
// the cell, and be tight enough to be useful.
#include "apcCellInterpolation.h"
#include "apcTestCells.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace
{

using apc::CellCorners;
using apc::CellInterpolator;
using apc::CellShape;

void RandomPCoords(CellShape shape, std::mt19937& rng, double p[3])
{
  std::uniform_real_distribution<double> u(0.0, 1.0);
  do
  {
    p[0] = u(rng);
    p[1] = u(rng);
    p[2] = u(rng);
  } while ((shape == CellShape::Tetra && p[0] + p[1] + p[2] > 1.0) ||
    (shape == CellShape::Wedge && p[0] + p[1] > 1.0));
}

// The coordinates the linear inverse gives at x, reached along a random ray through x (as the
// walker reaches them: linearly from the ray's origin).
void LinearCoordinates(
  const CellInterpolator& cell, const double x[3], std::mt19937& rng, double p[3])
{
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double d[3] = { u(rng), u(rng), u(rng) };
  const double t = 3.0 + u(rng);
  const double o[3] = { x[0] - t * d[0], x[1] - t * d[1], x[2] - t * d[2] };
  double p0[3], dp[3];
  cell.LinearRay(o, d, p0, dp);
  for (int i = 0; i < 3; ++i)
  {
    p[i] = p0[i] + t * dp[i];
  }
}

// The scalar the linear inverse gives at x, reached along a ray through x.
double LinearScalar(const CellInterpolator& cell, const double x[3], std::mt19937& rng)
{
  double p[3];
  LinearCoordinates(cell, x, rng, p);
  return cell.LinearScalarAt(p);
}

} // namespace

TEST(LinearInverse, ErrorBoundHoldsAndIsTight)
{
  std::mt19937 rng(7);
  for (CellShape shape : { CellShape::Pyramid, CellShape::Wedge, CellShape::Hexahedron })
  {
    for (double distortion : { 1e-5, 1e-4, 1e-3, 1e-2 })
    {
      double tightest = 0.0; // largest error seen over its bound, over the cells
      for (int c = 0; c < 40; ++c)
      {
        const CellCorners corners = apctest::DistortedCell(shape, distortion, rng);
        const CellInterpolator cell(corners);
        ASSERT_FALSE(cell.IsAffine());
        const double bound = cell.GetLinearScalarError();
        ASSERT_TRUE(std::isfinite(bound)) << "distortion " << distortion;
        ASSERT_GT(bound, 0.0);
        double worst = 0.0;
        for (int k = 0; k < 200; ++k)
        {
          double p[3];
          RandomPCoords(shape, rng, p);
          double x[3];
          cell.WorldPosition(p, x);
          const double linear = LinearScalar(cell, x, rng);
          // The exact scalar at x, and Newton's (what the marcher uses otherwise).
          const double exact = cell.InterpolateScalar(p);
          double newton[3] = { 0.5, 0.5, 0.5 };
          const double rounding = 1e-11;
          EXPECT_LE(std::abs(linear - exact), bound + rounding) << "distortion " << distortion;
          if (cell.ParametricCoordinates(x, newton))
          {
            EXPECT_LE(std::abs(linear - cell.InterpolateScalar(newton)), bound + 1e-8);
          }
          worst = std::max(worst, std::abs(linear - exact));
        }
        tightest = std::max(tightest, worst / bound);
      }
      // A bound far above every error would send cells to Newton for nothing.
      EXPECT_GT(tightest, 0.15) << "shape " << static_cast<int>(shape) << " distortion "
                                << distortion;
    }
  }
}

TEST(LinearInverse, BoundGrowsWithDistortion)
{
  std::mt19937 rng(11);
  double mean[2] = { 0.0, 0.0 };
  for (int i = 0; i < 2; ++i)
  {
    for (int c = 0; c < 50; ++c)
    {
      std::mt19937 same(static_cast<unsigned>(c));
      mean[i] +=
        CellInterpolator(apctest::DistortedCell(CellShape::Hexahedron, i == 0 ? 1e-4 : 1e-3, same))
          .GetLinearScalarError();
    }
  }
  // The error is first order in the non-linear coefficients.
  EXPECT_NEAR(mean[1] / mean[0], 10.0, 1.0);
}

TEST(LinearInverse, AffineCellsAreExact)
{
  std::mt19937 rng(3);
  for (CellShape shape : { CellShape::Tetra, CellShape::Wedge, CellShape::Hexahedron })
  {
    const CellInterpolator cell(apctest::DistortedCell(shape, 0.0, rng));
    ASSERT_TRUE(cell.IsAffine());
    EXPECT_EQ(cell.GetLinearScalarError(), 0.0);
    const double o[3] = { 1.0, -2.0, 3.0 };
    const double d[3] = { 0.3, 0.5, -0.7 };
    double p0[3], dp[3], q0[3], dq[3];
    cell.LinearRay(o, d, p0, dp);
    cell.AffineRay(o, d, q0, dq);
    for (int i = 0; i < 3; ++i)
    {
      EXPECT_EQ(p0[i], q0[i]);
      EXPECT_EQ(dp[i], dq[i]);
    }
  }
  // A pyramid over a parallelogram: affine in (u, v, t) = ((1-t) r, (1-t) s, t).
  const CellInterpolator pyramid(apctest::DistortedCell(CellShape::Pyramid, 0.0, rng));
  EXPECT_LT(pyramid.GetLinearScalarError(), 1e-12);
  CellCorners flat = apctest::DistortedCell(CellShape::Hexahedron, 0.0, rng);
  for (auto& x : flat.X)
  {
    x[2] = 0.0;
  }
  EXPECT_EQ(CellInterpolator(flat).GetLinearScalarError(), std::numeric_limits<double>::infinity());
}

TEST(LinearInverse, MonomialScalarMatchesShapeFunctions)
{
  std::mt19937 rng(5);
  for (CellShape shape :
    { CellShape::Tetra, CellShape::Pyramid, CellShape::Wedge, CellShape::Hexahedron })
  {
    const CellInterpolator cell(apctest::DistortedCell(shape, 0.1, rng));
    for (int k = 0; k < 100; ++k)
    {
      double p[3];
      RandomPCoords(shape, rng, p);
      EXPECT_NEAR(cell.ScalarAt(p), cell.InterpolateScalar(p), 1e-12) << static_cast<int>(shape);
    }
  }
}

// Twisted pyramids (too far from affine for the linear inverse) take the closed-form inverse:
// it must give the exact interpolant and (u, v, t) = ((1-t) r, (1-t) s, t), up to rounding,
// at every point of the cell, the apex region included.
TEST(LinearInverse, PyramidClosedFormIsExact)
{
  std::mt19937 rng(13);
  int checked = 0;
  for (double distortion : { 1e-3, 0.05, 0.15, 0.3 })
  {
    for (int c = 0; c < 40; ++c)
    {
      const CellInterpolator cell(apctest::DistortedCell(CellShape::Pyramid, distortion, rng));
      if (cell.IsDegenerate())
      {
        continue;
      }
      ASSERT_TRUE(cell.HasPyramidInverse());
      for (int k = 0; k < 200; ++k)
      {
        double p[3];
        RandomPCoords(CellShape::Pyramid, rng, p);
        if (k % 10 == 0)
        {
          p[2] = 1.0 - 1e-6 * (k + 1); // near the apex
        }
        double x[3];
        cell.WorldPosition(p, x);
        // The walker's coordinates a, reached along a ray through x.
        double a[3];
        LinearCoordinates(cell, x, rng, a);
        double q[3];
        double w = 0;
        cell.PyramidCoordinates(a, q, w);
        const double below = 1.0 - p[2];
        EXPECT_NEAR(q[0], below * p[0], 1e-9) << "distortion " << distortion;
        EXPECT_NEAR(q[1], below * p[1], 1e-9) << "distortion " << distortion;
        EXPECT_NEAR(q[2], p[2], 1e-9) << "distortion " << distortion;
        EXPECT_NEAR(w, p[0] * p[1] * below, 1e-9) << "distortion " << distortion;
        EXPECT_NEAR(cell.PyramidScalarAt(a), cell.InterpolateScalar(p), 1e-8)
          << "distortion " << distortion;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 20000);
  // Other shapes never take it.
  EXPECT_FALSE(
    CellInterpolator(apctest::DistortedCell(CellShape::Hexahedron, 0.1, rng)).HasPyramidInverse());
}
