// The linear inverse of nearly affine cells (CellInterpolator::LinearRay) and the bound on
// its scalar error, set up with the cell; see docs/sampler.md.
#include "apcCellInterpolation.h"

#include "apcCellAlgebra.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace apc
{

using cellalgebra::Cross;
using cellalgebra::Dot;
using cellalgebra::IsSingular;

namespace
{
// How far outside the reference cell (parametric units) the error bound of LinearRay still
// holds. The marcher samples points inside the cell's face planes; where the cell is nearly
// affine its faces are nearly planar, so those points lie within about the bound's own
// parametric error of the reference cell, which the bound only accepts below this.
constexpr double kLinearMargin = 0.05;

bool IsFinite3(const double v[3])
{
  return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}
}

void CellInterpolator::SetLinear(const double centre[3], const double offset[3], const double cr[3],
  const double cs[3], const double ct[3], double det)
{
  // Rows of the inverse of [J0 J1 J2] are the cross products over the determinant.
  for (int d = 0; d < 3; ++d)
  {
    this->Inverse[0][d] = cr[d] / det;
    this->Inverse[1][d] = cs[d] / det;
    this->Inverse[2][d] = ct[d] / det;
  }
  if (this->Affine)
  {
    for (int d = 0; d < 3; ++d)
    {
      this->LinearP[d] = 0.0;
      this->LinearX[d] = this->C[0][d];
    }
    this->LinearScalarError = 0.0;
    return;
  }
  for (int d = 0; d < 3; ++d)
  {
    this->LinearP[d] = centre[d];
    this->LinearX[d] = this->C[0][d] + offset[d];
  }
  this->LinearScalarError = std::numeric_limits<double>::infinity();
  if (this->CellType == CellShape::Pyramid)
  {
    this->SetLinearPyramid();
    return;
  }
  // About the centre, x(p) = x(pc) + J (p - pc) + R(p - pc) exactly, with the remainder
  // R = dr ds (c4 + tc c7) + dr dt (c5 + sc c7) + ds dt (c6 + rc c7) + dr ds dt c7. So the
  // linear inverse p' = pc + J^-1 (x - x(pc)) of a point x = x(p) is p' = p + J^-1 R:
  // |p' - p| <= |J^-1| |R| componentwise, with |dr| <= h[0] etc. over the cell.
  const auto& c = this->C;
  const double rc = centre[0], sc = centre[1], tc = centre[2];
  double h[3];
  for (int d = 0; d < 3; ++d)
  {
    h[d] = std::max(centre[d], 1.0 - centre[d]) + kLinearMargin;
  }
  double remainder[3];
  for (int i = 0; i < 3; ++i)
  {
    remainder[i] = h[0] * h[1] * std::abs(c[4][i] + tc * c[7][i]) +
      h[0] * h[2] * std::abs(c[5][i] + sc * c[7][i]) +
      h[1] * h[2] * std::abs(c[6][i] + rc * c[7][i]) + h[0] * h[1] * h[2] * std::abs(c[7][i]);
  }
  double e[3];
  for (int d = 0; d < 3; ++d)
  {
    e[d] = std::abs(this->Inverse[d][0]) * remainder[0] +
      std::abs(this->Inverse[d][1]) * remainder[1] + std::abs(this->Inverse[d][2]) * remainder[2];
  }
  if (!(std::max(e[0], std::max(e[1], e[2])) <= kLinearMargin))
  {
    return;
  }
  // The scalar's parametric gradient, bounded over the box that holds p and p' (the same
  // expansion about the centre), times the parametric error: the mean value theorem.
  const double H[3] = { h[0] + e[0], h[1] + e[1], h[2] + e[2] };
  const auto& a = this->SC;
  const double gr = std::abs(a[1] + a[4] * sc + a[5] * tc + a[7] * sc * tc) +
    std::abs(a[4] + a[7] * tc) * H[1] + std::abs(a[5] + a[7] * sc) * H[2] +
    std::abs(a[7]) * H[1] * H[2];
  const double gs = std::abs(a[2] + a[4] * rc + a[6] * tc + a[7] * rc * tc) +
    std::abs(a[4] + a[7] * tc) * H[0] + std::abs(a[6] + a[7] * rc) * H[2] +
    std::abs(a[7]) * H[0] * H[2];
  const double gt = std::abs(a[3] + a[5] * rc + a[6] * sc + a[7] * rc * sc) +
    std::abs(a[5] + a[7] * sc) * H[0] + std::abs(a[6] + a[7] * rc) * H[1] +
    std::abs(a[7]) * H[0] * H[1];
  const double bound = gr * e[0] + gs * e[1] + gt * e[2];
  if (std::isfinite(bound))
  {
    this->LinearScalarError = bound;
  }
}

void CellInterpolator::SetLinearPyramid()
{
  // In (u, v, t) the map is C0 + M (u, v, t) + C4 w with M = [C1 C2 C3] and w = r s (1-t),
  // at most (1 + margin)^3 in the grown cell: the linear inverse q' = M^-1 (x - C0) is off by
  // |M^-1| |C4| w_max per axis. Its scalar (LinearScalarAt) is Lipschitz in u, v and t with
  // constants |SC1| + |SC4|, |SC2| + |SC4| and |SC3| + |SC4| (the clamped r s (1-t) changes by
  // at most 1 per unit of each).
  const auto& c = this->C;
  double cr[3], cs[3], ct[3];
  Cross(c[2], c[3], cr);
  Cross(c[3], c[1], cs);
  Cross(c[1], c[2], ct);
  const double det = Dot(c[1], cr);
  if (IsSingular(det, c[1], c[2], c[3]))
  {
    return;
  }
  for (int d = 0; d < 3; ++d)
  {
    this->Inverse[0][d] = cr[d] / det;
    this->Inverse[1][d] = cs[d] / det;
    this->Inverse[2][d] = ct[d] / det;
    this->LinearP[d] = 0.0;
    this->LinearX[d] = c[0][d];
  }
  for (int d = 0; d < 3; ++d)
  {
    this->PyramidG[d] = Dot(this->Inverse[d], c[4]);
  }
  this->PyramidInverse = IsFinite3(this->PyramidG);
  const double grown = 1.0 + kLinearMargin;
  const double wMax = grown * grown * grown;
  const auto& a = this->SC;
  const double lipschitz[3] = { std::abs(a[1]) + std::abs(a[4]), std::abs(a[2]) + std::abs(a[4]),
    std::abs(a[3]) + std::abs(a[4]) };
  double bound = 0;
  for (int d = 0; d < 3; ++d)
  {
    const double e = wMax *
      (std::abs(this->Inverse[d][0]) * std::abs(c[4][0]) +
        std::abs(this->Inverse[d][1]) * std::abs(c[4][1]) +
        std::abs(this->Inverse[d][2]) * std::abs(c[4][2]));
    bound += lipschitz[d] * e;
  }
  if (std::isfinite(bound))
  {
    this->LinearScalarError = bound;
  }
}

} // namespace apc
