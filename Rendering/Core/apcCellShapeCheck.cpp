#include "apcCellShapeCheck.h"

#include <algorithm>
#include <cmath>

namespace apc
{
namespace
{
using Vec = std::array<double, 3>;

Vec Sub(const Vec& a, const Vec& b)
{
  return { a[0] - b[0], a[1] - b[1], a[2] - b[2] };
}

Vec Cross(const Vec& a, const Vec& b)
{
  return { a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0] };
}

double Dot(const Vec& a, const Vec& b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
}

//------------------------------------------------------------------------------
const CellFaces& FacesOf(CellShape shape)
{
  switch (shape)
  {
    case CellShape::Tetra:
      return *FacetsOfCellType(CellType::Tetra);
    case CellShape::Pyramid:
      return *FacetsOfCellType(CellType::Pyramid);
    case CellShape::Wedge:
      return *FacetsOfCellType(CellType::Wedge);
    default:
      return *FacetsOfCellType(CellType::Hexahedron);
  }
}

//------------------------------------------------------------------------------
CellMeasure MeasureCell(CellShape shape, const std::array<std::array<double, 3>, 8>& corners)
{
  const int n = NumberOfCorners(shape);
  Vec centroid = { 0, 0, 0 };
  Vec lo = corners[0];
  Vec hi = corners[0];
  for (int i = 0; i < n; ++i)
  {
    for (int d = 0; d < 3; ++d)
    {
      centroid[d] += corners[i][d] / n;
      lo[d] = std::min(lo[d], corners[i][d]);
      hi[d] = std::max(hi[d], corners[i][d]);
    }
  }
  return MeasureCell(shape, corners, centroid, { lo[0], hi[0], lo[1], hi[1], lo[2], hi[2] });
}

//------------------------------------------------------------------------------
CellMeasure MeasureCell(CellShape shape, const std::array<std::array<double, 3>, 8>& corners,
  const std::array<double, 3>& centroid, const std::array<double, 6>& bounds)
{
  const int n = NumberOfCorners(shape);
  // Everything relative to the centroid: far from the origin, absolute coordinates would
  // cancel the cell's own digits away.
  std::array<Vec, 8> x;
  for (int i = 0; i < n; ++i)
  {
    x[i] = Sub(corners[i], centroid);
  }
  const Vec extent = { bounds[1] - bounds[0], bounds[3] - bounds[2], bounds[5] - bounds[4] };
  const double diagonal = std::sqrt(Dot(extent, extent));

  double volume6 = 0;    // six times the signed volume
  double maxSquared = 0; // the largest face's (twice its area) squared
  const CellFaces& faces = FacesOf(shape);
  for (int f = 0; f < faces.Count; ++f)
  {
    const int* c = faces.Corner[f];
    Vec area2 = { 0, 0, 0 };
    for (int k = 1; k + 1 < faces.Size[f]; ++k)
    {
      const Vec& a = x[c[0]];
      const Vec& b = x[c[k]];
      const Vec& d = x[c[k + 1]];
      const Vec t = Cross(Sub(b, a), Sub(d, a));
      for (int i = 0; i < 3; ++i)
      {
        area2[i] += t[i];
      }
      volume6 += Dot(a, Cross(b, d));
    }
    // One square root for the largest face, not one per face: sqrt is correctly rounded and
    // never decreasing, so the root of the largest square is the largest root, bit for bit
    // (and a NaN square is passed over by max here as its root was).
    maxSquared = std::max(maxSquared, Dot(area2, area2));
  }
  const double maxArea2 = std::sqrt(maxSquared); // twice the largest face area
  CellMeasure measure;
  measure.Volume = std::abs(volume6) / 6.0;
  if (std::isnan(volume6) || std::isnan(maxArea2) || std::isnan(diagonal))
  {
    measure.RelativeThickness = volume6 + maxArea2 + diagonal; // NaN
    return measure;
  }
  const double denominator = 0.5 * maxArea2 * diagonal;
  measure.RelativeThickness =
    denominator > 0 && std::isfinite(denominator) ? measure.Volume / denominator : 0;
  return measure;
}

//------------------------------------------------------------------------------
double RelativeThickness(CellShape shape, const std::array<std::array<double, 3>, 8>& corners)
{
  return MeasureCell(shape, corners).RelativeThickness;
}

} // namespace apc
