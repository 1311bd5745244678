// Small vector algebra shared by the cell interpolator's search and its linear inverse
// (internal to Rendering/Core).
#ifndef apcCellAlgebra_h
#define apcCellAlgebra_h

namespace apc
{
namespace cellalgebra
{

// |det J| below this fraction of the product of the column lengths (the Hadamard bound) is
// treated as singular: the columns are then coplanar to ~1e-12 rad and the Newton update
// would be dominated by rounding.
constexpr double kSingularRatio = 1e-12;

inline double Dot(const double a[3], const double b[3])
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

inline void Cross(const double a[3], const double b[3], double c[3])
{
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

// NaN-safe: !(det^2 > ...) is true for NaN as well.
inline bool IsSingular(double det, const double c0[3], const double c1[3], const double c2[3])
{
  const double bound = Dot(c0, c0) * Dot(c1, c1) * Dot(c2, c2);
  return !(det * det > kSingularRatio * kSingularRatio * bound);
}

} // namespace cellalgebra
} // namespace apc

#endif
