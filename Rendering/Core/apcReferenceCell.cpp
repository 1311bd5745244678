// SPDX-License-Identifier: BSD-3-Clause
// The reference cells of the linear cell types: their corners, centres, shape functions and
// extents in parametric space (declared in apcCellInterpolation.h). Kept apart from the
// interpolator's search, which only uses them.
#include "apcCellInterpolation.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace apc
{

namespace
{
// VTK's parametric corners of each linear cell type.
const std::array<std::array<double, 3>, 8> kTetraCorners = { {
  { 0, 0, 0 },
  { 1, 0, 0 },
  { 0, 1, 0 },
  { 0, 0, 1 },
} };
const std::array<std::array<double, 3>, 8> kPyramidCorners = { {
  { 0, 0, 0 },
  { 1, 0, 0 },
  { 1, 1, 0 },
  { 0, 1, 0 },
  { 0, 0, 1 },
} };
const std::array<std::array<double, 3>, 8> kWedgeCorners = { {
  { 0, 0, 0 },
  { 1, 0, 0 },
  { 0, 1, 0 },
  { 0, 0, 1 },
  { 1, 0, 1 },
  { 0, 1, 1 },
} };
const std::array<std::array<double, 3>, 8> kHexahedronCorners = { {
  { 0, 0, 0 },
  { 1, 0, 0 },
  { 1, 1, 0 },
  { 0, 1, 0 },
  { 0, 0, 1 },
  { 1, 0, 1 },
  { 1, 1, 1 },
  { 0, 1, 1 },
} };
}

const std::array<std::array<double, 3>, 8>& ReferenceCorners(CellShape shape)
{
  switch (shape)
  {
    case CellShape::Tetra:
      return kTetraCorners;
    case CellShape::Pyramid:
      return kPyramidCorners;
    case CellShape::Wedge:
      return kWedgeCorners;
    case CellShape::Hexahedron:
      break;
  }
  return kHexahedronCorners;
}

void ParametricCenter(CellShape shape, double pcoords[3])
{
  switch (shape)
  {
    case CellShape::Tetra:
      pcoords[0] = pcoords[1] = pcoords[2] = 0.25;
      return;
    case CellShape::Pyramid:
      pcoords[0] = pcoords[1] = 0.4;
      pcoords[2] = 0.2;
      return;
    case CellShape::Wedge:
      // VTK uses 0.333333; the exact third keeps the point symmetric.
      pcoords[0] = pcoords[1] = 1.0 / 3.0;
      pcoords[2] = 0.5;
      return;
    case CellShape::Hexahedron:
      break;
  }
  pcoords[0] = pcoords[1] = pcoords[2] = 0.5;
}

void ShapeFunctions(CellShape shape, const double p[3], double w[8])
{
  const double r = p[0], s = p[1], t = p[2];
  const double rm = 1.0 - r, sm = 1.0 - s, tm = 1.0 - t;
  switch (shape)
  {
    case CellShape::Tetra:
      w[0] = 1.0 - r - s - t;
      w[1] = r;
      w[2] = s;
      w[3] = t;
      return;
    case CellShape::Pyramid:
      w[0] = rm * sm * tm;
      w[1] = r * sm * tm;
      w[2] = r * s * tm;
      w[3] = rm * s * tm;
      w[4] = t;
      return;
    case CellShape::Wedge:
    {
      const double u = 1.0 - r - s;
      w[0] = u * tm;
      w[1] = r * tm;
      w[2] = s * tm;
      w[3] = u * t;
      w[4] = r * t;
      w[5] = s * t;
      return;
    }
    case CellShape::Hexahedron:
      break;
  }
  w[0] = rm * sm * tm;
  w[1] = r * sm * tm;
  w[2] = r * s * tm;
  w[3] = rm * s * tm;
  w[4] = rm * sm * t;
  w[5] = r * sm * t;
  w[6] = r * s * t;
  w[7] = rm * s * t;
}

void ClampToReferenceCell(CellShape shape, double p[3])
{
  for (int i = 0; i < 3; ++i)
  {
    // Written so that NaN lands on 0.
    p[i] = p[i] > 0.0 ? std::min(p[i], 1.0) : 0.0;
  }
  double sum = 0.0;
  if (shape == CellShape::Tetra)
  {
    sum = p[0] + p[1] + p[2];
  }
  else if (shape == CellShape::Wedge)
  {
    sum = p[0] + p[1];
  }
  if (sum > 1.0)
  {
    p[0] /= sum;
    p[1] /= sum;
    if (shape == CellShape::Tetra)
    {
      p[2] /= sum;
    }
  }
}

bool InsideReferenceCell(CellShape shape, const double p[3], double tolerance)
{
  const double low = -tolerance;
  const double high = 1.0 + tolerance;
  // Written so that NaN is outside.
  if (!(p[0] >= low && p[1] >= low && p[2] >= low && p[2] <= high))
  {
    return false;
  }
  switch (shape)
  {
    case CellShape::Tetra:
      return p[0] + p[1] + p[2] <= high;
    case CellShape::Wedge:
      return p[0] + p[1] <= high;
    case CellShape::Pyramid:
    case CellShape::Hexahedron:
      break;
  }
  return p[0] <= high && p[1] <= high;
}

} // namespace apc
