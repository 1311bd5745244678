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

// Relative size of the non-linear coefficients below which the closed-form inverse is used.
// Rounding in the corner differences alone reaches ~1e-15 of the coordinates' magnitude,
// so an exactly affine cell far from the origin still qualifies; the closed form then errs
// by at most this much in parametric units, well inside kNewtonTolerance.
constexpr double kAffineTolerance = 1e-12;

// A residual this small, relative to the cell size, is accepted even where the Jacobian is
// singular (a pyramid's apex maps from the whole plane t = 1).
constexpr double kResidualTolerance = 1e-12;

// Newton steps below this (parametric units) are taken to be in the quadratic regime,
// where a chord step (the same Jacobian, a new residual) is a cheap and sure correction.
constexpr double kChordRegime = 1e-2;

// Newton iterates are kept in this box around the reference cell so that a wild step (bad
// guess, badly distorted cell) cannot overflow; a genuine solution lies in [0,1]^3.
constexpr double kBoxLow = -1.0;
constexpr double kBoxHigh = 2.0;

inline double MaxAbs(const double a[3])
{
  return std::max(std::abs(a[0]), std::max(std::abs(a[1]), std::abs(a[2])));
}

inline bool IsFinite(const double p[3])
{
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

// Monomial coefficients c[0..7] of sum_i w_i(r,s,t) v(i), by expanding VTK's shape
// functions; see the header. v(i) is corner i's value (a coordinate or the scalar).
template <class Value>
void Monomials(CellShape shape, Value v, double c[8])
{
  for (int k = 0; k < 8; ++k)
  {
    c[k] = 0.0;
  }
  c[0] = v(0);
  switch (shape)
  {
    case CellShape::Tetra:
      c[1] = v(1) - v(0);
      c[2] = v(2) - v(0);
      c[3] = v(3) - v(0);
      break;
    case CellShape::Pyramid:
    {
      // x = (1-t) B(r,s) + t X4 with B bilinear over the base.
      const double br = v(1) - v(0);
      const double bs = v(3) - v(0);
      const double brs = v(2) - v(1) - v(3) + v(0);
      c[1] = br;
      c[2] = bs;
      c[3] = v(4) - v(0);
      c[4] = brs;
      c[5] = -br;
      c[6] = -bs;
      c[7] = -brs;
      break;
    }
    case CellShape::Wedge:
      c[1] = v(1) - v(0);
      c[2] = v(2) - v(0);
      c[3] = v(3) - v(0);
      c[5] = v(4) - v(1) - v(3) + v(0);
      c[6] = v(5) - v(2) - v(3) + v(0);
      break;
    case CellShape::Hexahedron:
      c[1] = v(1) - v(0);
      c[2] = v(3) - v(0);
      c[3] = v(4) - v(0);
      c[4] = v(2) - v(1) - v(3) + v(0);
      c[5] = v(5) - v(1) - v(4) + v(0);
      c[6] = v(7) - v(3) - v(4) + v(0);
      c[7] = v(6) - v(2) - v(5) - v(7) + v(1) + v(3) + v(4) - v(0);
      break;
  }
}

// The map's coefficients, c[k][d] for coordinate d.
void MapCoefficients(const CellCorners& cell, double c[8][3])
{
  for (int d = 0; d < 3; ++d)
  {
    double column[8];
    Monomials(
      cell.Shape, [&cell, d](int i) { return cell.X[i][d]; }, column);
    for (int k = 0; k < 8; ++k)
    {
      c[k][d] = column[k];
    }
  }
}

// Largest linear coefficient and largest non-linear one (max norm).
void CoefficientSizes(const double c[8][3], double& linear, double& nonlinear)
{
  linear = std::max(MaxAbs(c[1]), std::max(MaxAbs(c[2]), MaxAbs(c[3])));
  nonlinear = 0.0;
  for (int k = 4; k < 8; ++k)
  {
    nonlinear = std::max(nonlinear, MaxAbs(c[k]));
  }
}

} // namespace

void CellInterpolator::Set(const CellCorners& cell)
{
  this->CellType = cell.Shape;
  this->PyramidInverse = false; // set by SetLinearPyramid
  const int n = NumberOfCorners(cell.Shape);
  for (int i = 0; i < 8; ++i)
  {
    this->S[i] = i < n ? cell.S[i] : 0.0;
  }
  MapCoefficients(cell, this->C);

  double nonlinear = 0.0;
  CoefficientSizes(this->C, this->Size, nonlinear);
  this->Affine = nonlinear <= kAffineTolerance * this->Size;

  double center[3];
  ParametricCenter(cell.Shape, center);
  double offset[3], J[3][3];
  this->Evaluate(center, offset, J);
  double cr[3], cs[3], ct[3];
  Cross(J[1], J[2], cr);
  Cross(J[2], J[0], cs);
  Cross(J[0], J[1], ct);
  const double det = Dot(J[0], cr);
  this->Degenerate = !(this->Size > 0.0) || !std::isfinite(this->Size) ||
    !std::isfinite(nonlinear) || IsSingular(det, J[0], J[1], J[2]);
  Monomials(
    cell.Shape, [this](int i) { return this->S[i]; }, this->SC);
  if (this->Degenerate)
  {
    this->Affine = false;
    this->LinearScalarError = std::numeric_limits<double>::infinity();
    return;
  }
  this->SetLinear(center, offset, cr, cs, ct, det);
}

// Inlined into every Newton and chord step (the marcher's innermost work).
[[gnu::always_inline]] inline void CellInterpolator::Map(const double p[3], double offset[3]) const
{
  const double r = p[0], s = p[1], t = p[2];
  const double rs = r * s, rt = r * t, st = s * t;
  const auto& c = this->C;
  for (int d = 0; d < 3; ++d)
  {
    offset[d] = r * c[1][d] + s * c[2][d] + t * c[3][d] + rs * c[4][d] + rt * c[5][d] +
      st * c[6][d] + rs * t * c[7][d];
  }
}

void CellInterpolator::Evaluate(const double p[3], double offset[3], double J[3][3]) const
{
  this->Map(p, offset);
  const double r = p[0], s = p[1], t = p[2];
  const double rs = r * s, rt = r * t, st = s * t;
  const auto& c = this->C;
  for (int d = 0; d < 3; ++d)
  {
    J[0][d] = c[1][d] + s * c[4][d] + t * c[5][d] + st * c[7][d];
    J[1][d] = c[2][d] + r * c[4][d] + t * c[6][d] + rt * c[7][d];
    J[2][d] = c[3][d] + r * c[5][d] + s * c[6][d] + rs * c[7][d];
  }
}

namespace
{
// The parametric size of a Newton step d that ended at p: in a pyramid the r and s steps are
// scaled by the cross-section at t, which shrinks to the apex.
double NewtonStepSize(const double d[3], const double p[3], bool pyramid)
{
  const double section = pyramid ? std::abs(1.0 - p[2]) : 1.0;
  const double rs = std::max(std::abs(d[0]), std::abs(d[1]));
  return std::max(std::abs(d[2]), pyramid ? section * rs : rs);
}

bool Converged(const double p[3], int steps, double pcoords[3], int* iterations)
{
  pcoords[0] = p[0];
  pcoords[1] = p[1];
  pcoords[2] = p[2];
  if (iterations)
  {
    *iterations = steps;
  }
  return true;
}
}

bool CellInterpolator::ParametricCoordinates(
  const double x[3], double pcoords[3], int* iterations, double tolerance) const
{
  return this->Search(x, pcoords, iterations, tolerance, nullptr);
}

namespace
{
inline void Multiply(const double m[3][3], const double v[3], double out[3])
{
  out[0] = Dot(m[0], v);
  out[1] = Dot(m[1], v);
  out[2] = Dot(m[2], v);
}

void Remember(NewtonMemory* memory, const double x[3], const double p[3], const double cr[3],
  const double cs[3], const double ct[3], double invDet)
{
  if (!memory)
  {
    return;
  }
  memory->Valid = true;
  for (int d = 0; d < 3; ++d)
  {
    memory->P[d] = p[d];
    memory->X[d] = x[d];
    memory->InverseJacobian[0][d] = cr[d] * invDet;
    memory->InverseJacobian[1][d] = cs[d] * invDet;
    memory->InverseJacobian[2][d] = ct[d] * invDet;
  }
}

// How far (parametric units) outside the reference cell Follow's answer for a point inside
// the cell may lie before it is taken for a wrong root: rounding on faces, and non-planar
// faces replaced by planes in the ray clipping, move it far less.
constexpr double kOutsideTolerance = 1e-3;

// Chord steps tried from a prediction before a full Newton search: from a neighbour's
// solution one or two reach an image's tolerance.
constexpr int kMaxChordSteps = 3;
}

bool CellInterpolator::Follow(
  const double x[3], NewtonMemory& memory, double pcoords[3], double tolerance) const
{
  if (this->FollowFromMemory(x, memory, pcoords, tolerance) &&
    InsideReferenceCell(this->CellType, pcoords, kOutsideTolerance))
  {
    return true;
  }
  // x is inside the cell, yet Newton converged outside it: another root of a non-affine map
  // (pyramids, from a neighbour's guess). The root inside is found from the cell's centre.
  ParametricCenter(this->CellType, pcoords);
  return this->Search(x, pcoords, nullptr, tolerance, &memory);
}

bool CellInterpolator::FollowFromMemory(
  const double x[3], NewtonMemory& memory, double pcoords[3], double tolerance) const
{
  if (!memory.Valid || this->Affine || this->Degenerate)
  {
    return this->Search(x, pcoords, nullptr, tolerance, &memory);
  }
  const bool pyramid = this->CellType == CellShape::Pyramid;
  const double y[3] = { x[0] - this->C[0][0], x[1] - this->C[0][1], x[2] - this->C[0][2] };
  const double dx[3] = { x[0] - memory.X[0], x[1] - memory.X[1], x[2] - memory.X[2] };
  double p[3];
  Multiply(memory.InverseJacobian, dx, p);
  for (int d = 0; d < 3; ++d)
  {
    p[d] += memory.P[d];
  }
  for (int step = 0; step < kMaxChordSteps && IsFinite(p); ++step)
  {
    double moved[3];
    this->Map(p, moved);
    const double G[3] = { moved[0] - y[0], moved[1] - y[1], moved[2] - y[2] };
    double e[3];
    Multiply(memory.InverseJacobian, G, e);
    p[0] -= e[0];
    p[1] -= e[1];
    p[2] -= e[2];
    if (IsFinite(p) && NewtonStepSize(e, p, pyramid) < tolerance)
    {
      std::copy(p, p + 3, pcoords);
      std::copy(p, p + 3, memory.P);
      std::copy(x, x + 3, memory.X);
      return true;
    }
  }
  if (IsFinite(p))
  {
    std::copy(p, p + 3, pcoords);
  }
  return this->Search(x, pcoords, nullptr, tolerance, &memory);
}

bool CellInterpolator::Search(const double x[3], double pcoords[3], int* iterations,
  double tolerance, NewtonMemory* memory) const
{
  if (memory)
  {
    memory->Valid = false;
  }
  if (iterations)
  {
    *iterations = 0;
  }
  if (!IsFinite(pcoords))
  {
    ParametricCenter(this->CellType, pcoords);
  }
  if (this->Degenerate)
  {
    ClampToReferenceCell(this->CellType, pcoords);
    return false;
  }

  const double y[3] = { x[0] - this->C[0][0], x[1] - this->C[0][1], x[2] - this->C[0][2] };
  if (this->Affine)
  {
    const double p[3] = { Dot(this->Inverse[0], y), Dot(this->Inverse[1], y),
      Dot(this->Inverse[2], y) };
    if (IsFinite(p))
    {
      pcoords[0] = p[0];
      pcoords[1] = p[1];
      pcoords[2] = p[2];
      return true;
    }
    ClampToReferenceCell(this->CellType, pcoords);
    return false;
  }

  double p[3] = { pcoords[0], pcoords[1], pcoords[2] };
  return this->Newton(x, y, p, pcoords, iterations, tolerance, memory);
}

bool CellInterpolator::Newton(const double x[3], const double y[3], double p[3], double pcoords[3],
  int* iterations, double tolerance, NewtonMemory* memory) const
{
  const bool pyramid = this->CellType == CellShape::Pyramid;
  double best[3] = { p[0], p[1], p[2] };
  double bestResidual = std::numeric_limits<double>::infinity();
  bool restarted = false;
  int steps = 0;
  while (steps < kMaxNewtonIterations)
  {
    double offset[3], J[3][3];
    this->Evaluate(p, offset, J);
    const double F[3] = { offset[0] - y[0], offset[1] - y[1], offset[2] - y[2] };
    const double residual = MaxAbs(F);
    if (residual < bestResidual)
    {
      bestResidual = residual;
      best[0] = p[0];
      best[1] = p[1];
      best[2] = p[2];
    }

    double cr[3], cs[3], ct[3];
    Cross(J[1], J[2], cr);
    Cross(J[2], J[0], cs);
    Cross(J[0], J[1], ct);
    const double det = Dot(J[0], cr);
    if (IsSingular(det, J[0], J[1], J[2]))
    {
      if (residual <= kResidualTolerance * this->Size)
      {
        // On the solution already (e.g. a pyramid's apex, t = 1).
        return Converged(p, steps, pcoords, iterations);
      }
      if (restarted)
      {
        break;
      }
      // A bad guess or an iterate on a singular spot of a valid cell: retry from the center.
      restarted = true;
      ParametricCenter(this->CellType, p);
      continue;
    }

    const double invDet = 1.0 / det;
    const double d[3] = { Dot(F, cr) * invDet, Dot(F, cs) * invDet, Dot(F, ct) * invDet };
    p[0] -= d[0];
    p[1] -= d[1];
    p[2] -= d[2];
    ++steps;
    if (!IsFinite(p))
    {
      break;
    }
    // Near the root a chord step, which reuses this Jacobian and only evaluates the map,
    // costs a third of a Newton step and, once the step is small, usually ends the search:
    // an image's tolerance is reached after one Newton and one chord step from a neighbour's
    // guess instead of three Newton steps.
    const double step = NewtonStepSize(d, p, pyramid);
    if (step < tolerance ||
      (step < kChordRegime && this->ChordStep(y, p, cr, cs, ct, invDet, tolerance)))
    {
      Remember(memory, x, p, cr, cs, ct, invDet);
      return Converged(p, steps, pcoords, iterations);
    }
    for (int i = 0; i < 3; ++i)
    {
      p[i] = std::min(std::max(p[i], kBoxLow), kBoxHigh);
    }
  }

  if (iterations)
  {
    *iterations = steps;
  }
  pcoords[0] = best[0];
  pcoords[1] = best[1];
  pcoords[2] = best[2];
  ClampToReferenceCell(this->CellType, pcoords);
  return false;
}

bool CellInterpolator::ChordStep(const double y[3], double p[3], const double cr[3],
  const double cs[3], const double ct[3], double invDet, double tolerance) const
{
  double moved[3];
  this->Map(p, moved);
  const double G[3] = { moved[0] - y[0], moved[1] - y[1], moved[2] - y[2] };
  const double e[3] = { Dot(G, cr) * invDet, Dot(G, cs) * invDet, Dot(G, ct) * invDet };
  p[0] -= e[0];
  p[1] -= e[1];
  p[2] -= e[2];
  return IsFinite(p) && NewtonStepSize(e, p, this->CellType == CellShape::Pyramid) < tolerance;
}

double CellInterpolator::InterpolateScalar(const double pcoords[3]) const
{
  double w[8];
  ShapeFunctions(this->CellType, pcoords, w);
  const int n = NumberOfCorners(this->CellType);
  double value = 0.0;
  for (int i = 0; i < n; ++i)
  {
    value += w[i] * this->S[i];
  }
  return value;
}

void CellInterpolator::WorldPosition(const double pcoords[3], double x[3]) const
{
  double offset[3], J[3][3];
  this->Evaluate(pcoords, offset, J);
  for (int d = 0; d < 3; ++d)
  {
    x[d] = this->C[0][d] + offset[d];
  }
}

bool ParametricCoordinates(
  const CellCorners& cell, const double x[3], double pcoords[3], int* iterations)
{
  return CellInterpolator(cell).ParametricCoordinates(x, pcoords, iterations);
}

double InterpolateScalar(const CellCorners& cell, const double pcoords[3])
{
  double w[8];
  ShapeFunctions(cell.Shape, pcoords, w);
  double value = 0.0;
  for (int i = 0; i < NumberOfCorners(cell.Shape); ++i)
  {
    value += w[i] * cell.S[i];
  }
  return value;
}

void WorldPosition(const CellCorners& cell, const double pcoords[3], double x[3])
{
  CellInterpolator(cell).WorldPosition(pcoords, x);
}

bool IsAffine(const CellCorners& cell, double relTol)
{
  double c[8][3];
  MapCoefficients(cell, c);
  double linear = 0.0, nonlinear = 0.0;
  CoefficientSizes(c, linear, nonlinear);
  return linear > 0.0 && nonlinear <= relTol * linear;
}

} // namespace apc
