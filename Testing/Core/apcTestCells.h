// Cells shared by the interpolation tests (TestLinearInverse, TestLaneSamples,
// TestCellInterpolation, TestCellShapeCheck): the solid shapes, their names, random cells.
#ifndef apcTestCells_h
#define apcTestCells_h

#include "apcCellInterpolation.h"

#include <random>

namespace apctest
{

// The four solid shapes, each test's loop over every shape.
constexpr apc::CellShape kSolidShapes[] = { apc::CellShape::Tetra, apc::CellShape::Pyramid,
  apc::CellShape::Wedge, apc::CellShape::Hexahedron };

// The shape's name for a failing check's message.
inline const char* ShapeName(apc::CellShape shape)
{
  switch (shape)
  {
    case apc::CellShape::Tetra:
      return "tetra";
    case apc::CellShape::Pyramid:
      return "pyramid";
    case apc::CellShape::Wedge:
      return "wedge";
    default:
      return "hexahedron";
  }
}

// The reference cell with every corner moved by up to distortion per axis, then sheared,
// scaled by about 2 and shifted away from the origin (a fixed shear, so that the affine part
// is not diagonal); corner scalars in [0, 10].
inline apc::CellCorners DistortedCell(apc::CellShape shape, double distortion, std::mt19937& rng)
{
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> value(0.0, 10.0);
  apc::CellCorners cell;
  cell.Shape = shape;
  const auto& reference = apc::ReferenceCorners(shape);
  const double A[3][3] = { { 2.0, 0.4, 0.1 }, { -0.3, 1.5, 0.2 }, { 0.2, -0.1, 2.5 } };
  for (int i = 0; i < apc::NumberOfCorners(shape); ++i)
  {
    double m[3];
    for (int d = 0; d < 3; ++d)
    {
      m[d] = reference[i][d] + distortion * u(rng);
    }
    for (int d = 0; d < 3; ++d)
    {
      cell.X[i][d] = 50.0 + A[d][0] * m[0] + A[d][1] * m[1] + A[d][2] * m[2];
    }
    cell.S[i] = value(rng);
  }
  return cell;
}

} // namespace apctest

#endif
