// Point-scalar interpolation inside linear VTK cells (tetra, pyramid, wedge, hexahedron) for
// the ray marcher: world position -> parametric coordinates -> interpolated point scalar.
//
// Conventions are VTK's exactly (corner order, parametric coordinates, shape functions of
// vtkTetra, vtkPyramid, vtkWedge and vtkHexahedron::InterpolationFunctions), so a scalar
// sampled here is the one vtkCell::EvaluatePosition + InterpolateFunctions would give, only
// converged further (VTK stops Newton at steps of 1e-3 for wedges and pyramids, 1e-5 for
// hexahedra; here at 1e-10).
//
// Reference cells (corner i sits at ReferenceCorners(shape)[i]):
// - Tetra:      (0,0,0) (1,0,0) (0,1,0) (0,0,1); weights 1-r-s-t, r, s, t.
// - Pyramid:    the unit square base (0,0,0) (1,0,0) (1,1,0) (0,1,0) and the apex at
//               (0,0,1). Weights (1-t) x bilinear(r,s) for the base and t for the apex: the
//               whole plane t = 1 maps onto the apex, so r and s are arbitrary there and
//               ill-conditioned near it (see ParametricCoordinates).
// - Wedge:      triangle (0,0,0) (1,0,0) (0,1,0) at t = 0, the same triangle at t = 1;
//               weights linear triangle x linear in t.
// - Hexahedron: the unit cube, corners 0-3 counter-clockwise at t = 0, 4-7 above them;
//               trilinear weights.
// Voxels: VTK's voxel numbers its corners lexicographically (x fastest), so it becomes a
// hexahedron by reordering: hexahedron corner i = voxel corner kVoxelToHexahedron[i], i.e.
// voxel corners 0,1,3,2,4,5,7,6. The parametric coordinates are then the voxel's own.
//
// Every shape maps the reference cell to world space by a polynomial in the span of
// {1, r, s, t, rs, rt, st, rst} (the pyramid's (1-t) x bilinear expands into it too), which
// CellInterpolator stores as coefficients: the map and its Jacobian cost a few dozen
// multiply-adds per Newton step, and a cell whose non-linear coefficients vanish (any tetra,
// a parallelepiped hexahedron, a prism over a translated triangle) is inverted in closed
// form without iterating.
#ifndef apcCellInterpolation_h
#define apcCellInterpolation_h

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

namespace apc
{

// The value is the number of corners.
enum class CellShape : std::uint8_t
{
  Tetra = 4,
  Pyramid = 5,
  Wedge = 6,
  Hexahedron = 8
};

constexpr int NumberOfCorners(CellShape shape)
{
  return static_cast<int>(shape);
}

// Hexahedron corner i is voxel corner kVoxelToHexahedron[i] (the permutation is its own
// inverse).
constexpr std::array<int, 8> kVoxelToHexahedron = { 0, 1, 3, 2, 4, 5, 7, 6 };

// A cell as the ray marcher sees it: corner coordinates in VTK's point order and the corner
// (point) scalars. Entries beyond NumberOfCorners(Shape) are ignored.
struct CellCorners
{
  CellShape Shape = CellShape::Hexahedron;
  std::array<std::array<double, 3>, 8> X{};
  std::array<double, 8> S{};
};

// Newton stops when the update is below this, in parametric units. For pyramids the r and s
// updates are measured times (1-t), the size of the cross-section they move in: near the
// apex r and s are ill-conditioned but hardly matter for the position or the scalar.
constexpr double kNewtonTolerance = 1e-10;
constexpr int kMaxNewtonIterations = 10;

// Parametric coordinates of the corners of the reference cell (rows beyond the corner count
// are zero). The pyramid's apex is VTK's (0,0,1).
const std::array<std::array<double, 3>, 8>& ReferenceCorners(CellShape shape);

// VTK's GetParametricCenter: a point well inside the reference cell, the fallback guess.
void ParametricCenter(CellShape shape, double pcoords[3]);

// VTK's interpolation weights (shape functions) at pcoords; NumberOfCorners(shape) entries.
void ShapeFunctions(CellShape shape, const double pcoords[3], double weights[8]);

// Pulls pcoords into the reference cell: each coordinate into [0,1] (NaN -> 0), then for
// the triangle (wedge: r+s) or simplex (tetra: r+s+t) constraint a uniform shrink towards
// the vertex at the origin. Cheap, not the closest point.
void ClampToReferenceCell(CellShape shape, double pcoords[3]);

// True if pcoords lies in the reference cell grown by tolerance on every side.
bool InsideReferenceCell(CellShape shape, const double pcoords[3], double tolerance);

// What CellInterpolator::Follow carries from one point to the next: the last solution and
// the inverse Jacobian near it.
struct NewtonMemory
{
  bool Valid = false;
  double P[3] = { 0, 0, 0 };
  double X[3] = { 0, 0, 0 };
  double InverseJacobian[3][3] = {};
};

// The inverse map and the interpolation of one cell, set up once per cell and then queried
// per sample. Allocation-free; about 550 bytes, so it lives on the stack or in a
// per-thread cache.
class CellInterpolator
{
public:
  CellInterpolator() = default;
  explicit CellInterpolator(const CellCorners& cell) { this->Set(cell); }

  void Set(const CellCorners& cell);

  // World point x -> parametric coordinates. pcoords holds the initial guess on input (the
  // ray marcher interpolates the entry and exit parametric coordinates; a NaN guess is
  // replaced by the parametric center) and the result on output. Affine cells are solved in
  // closed form and report 0 iterations; others run Newton with the analytic Jacobian from
  // the guess, at most kMaxNewtonIterations steps, so an exact guess costs one step.
  // Returns false if the cell is degenerate (singular Jacobian at its center) or Newton did
  // not converge; pcoords is then the iterate with the smallest residual, clamped into the
  // reference cell, never NaN. A converged result is not clamped: points just outside the
  // cell (rounding on a face) extrapolate linearly, as in VTK.
  // Newton stops once the last update applied (a Newton step, or near the root a chord
  // step that reuses the Jacobian) is below tolerance, in parametric units; the error left
  // is then far smaller still. tolerance replaces kNewtonTolerance: an image needs far less
  // than 1e-10.
  bool ParametricCoordinates(const double x[3], double pcoords[3], int* iterations = nullptr,
    double tolerance = kNewtonTolerance) const;

  // ParametricCoordinates for a point x known to lie in the cell, near the one memory holds
  // (the next sample along a ray, the first sample of the neighbouring ray): the linear
  // prediction from memory, then chord steps with memory's Jacobian, which cost one
  // evaluation of the map each; a full Newton search (from the prediction, or from pcoords
  // if memory is not Valid) only when they do not converge. An answer clearly outside the
  // reference cell is a wrong root of a non-affine map and is searched again from the
  // centre. Stops at the same test as ParametricCoordinates and updates memory (not Valid
  // after a failure).
  bool Follow(const double x[3], NewtonMemory& memory, double pcoords[3], double tolerance) const;

  // An affine cell's parametric coordinates along the ray x(t) = o + t d: p(t) = p0 + t dp,
  // the closed form ParametricCoordinates evaluates, set up once per ray. Only for cells
  // that are IsAffine().
  void AffineRay(const double o[3], const double d[3], double p0[3], double dp[3]) const
  {
    const double y[3] = { o[0] - this->C[0][0], o[1] - this->C[0][1], o[2] - this->C[0][2] };
    for (int i = 0; i < 3; ++i)
    {
      p0[i] = this->Inverse[i][0] * y[0] + this->Inverse[i][1] * y[1] + this->Inverse[i][2] * y[2];
      dp[i] = this->Inverse[i][0] * d[0] + this->Inverse[i][1] * d[1] + this->Inverse[i][2] * d[2];
    }
  }

  // Nearly affine cells: the parametric coordinates along the ray x(t) = o + t d by the
  // affine part of the map about the cell's parametric centre (its centre Jacobian),
  // p(t) = p0 + t dp, with a scalar error of at most GetLinearScalarError(). Exactly affine
  // cells get AffineRay's closed form bit for bit (LinearP is 0 and LinearX is C[0]).
  // Inlined (as are its two halves): the marcher sets up a ray per (cell, ray) pair, which
  // holds one or two samples.
  [[gnu::always_inline]] void LinearRay(
    const double o[3], const double d[3], double p0[3], double dp[3]) const
  {
    this->LinearRayOrigin(o, p0);
    this->LinearRayDirection(d, dp);
  }
  // LinearRay's p0 alone: one per cell where every ray starts at the same point (a
  // perspective camera's eye), with the same arithmetic, hence the same bits.
  [[gnu::always_inline]] void LinearRayOrigin(const double o[3], double p0[3]) const
  {
    const double y[3] = { o[0] - this->LinearX[0], o[1] - this->LinearX[1],
      o[2] - this->LinearX[2] };
    for (int i = 0; i < 3; ++i)
    {
      p0[i] = this->LinearP[i] +
        (this->Inverse[i][0] * y[0] + this->Inverse[i][1] * y[1] + this->Inverse[i][2] * y[2]);
    }
  }
  // LinearRay's dp alone.
  [[gnu::always_inline]] void LinearRayDirection(const double d[3], double dp[3]) const
  {
    for (int i = 0; i < 3; ++i)
    {
      dp[i] = this->Inverse[i][0] * d[0] + this->Inverse[i][1] * d[1] + this->Inverse[i][2] * d[2];
    }
  }

  // A bound on how far LinearScalarAt (LinearRay's coordinates) can lie from the scalar at
  // the exact inverse (Newton's), for any point of the cell: 0 for affine cells, +inf for
  // degenerate ones. Derived from the map's non-linear coefficients, the inverse of its
  // linear part and the scalar's gradient; see docs/sampler.md.
  double GetLinearScalarError() const { return this->LinearScalarError; }

  // The scalar at LinearRay's coordinates q. For pyramids these are not (r, s, t) but
  // (u, v, t) = ((1-t) r, (1-t) s, t), in which the map is affine but for the base's twist
  // (rs term): x = C0 + C1 u + C2 v + C3 t + C4 uv / (1-t). The scalar is
  // S0 + SC3 t + SC1 u + SC2 v + SC4 r s (1-t), with r and s clamped to [0,1] so that it
  // stays bounded (and Lipschitz) near the apex.
  // Always inlined, as ScalarAt and PyramidScalarAt: the marcher calls them per sample.
  [[gnu::always_inline]] double LinearScalarAt(const double q[3]) const
  {
    if (this->CellType != CellShape::Pyramid)
    {
      return this->ScalarAt(q);
    }
    const auto& a = this->SC;
    double twist = 0;
    const double below = 1.0 - q[2];
    if (below > 0)
    {
      const double r = std::min(std::max(q[0] / below, 0.0), 1.0);
      const double s = std::min(std::max(q[1] / below, 0.0), 1.0);
      twist = r * s * below;
    }
    return a[0] + q[2] * a[3] + q[0] * a[1] + q[1] * a[2] + twist * a[4];
  }

  // Pyramids whose twist keeps them off the linear inverse: the exact inverse in closed form.
  // With a = M^-1 (x - C0) (LinearRay's coordinates of a pyramid) and g = M^-1 C4, the point's
  // (u, v, t) is a - g w, where w = u v / (1-t) = r s (1-t) solves the quadratic
  // (g2 - g0 g1) w^2 + (1 - a2 + a0 g1 + a1 g0) w - a0 a1 = 0: no Newton search. False for
  // other shapes and for a pyramid whose M is singular.
  bool HasPyramidInverse() const { return this->PyramidInverse; }

  // The exact (u, v, t) and w of a pyramid's point from its coordinates a (above): of the
  // quadratic's roots, the one whose point lies in the pyramid (or nearest to it). Only for
  // HasPyramidInverse() cells.
  void PyramidCoordinates(const double a[3], double q[3], double& w) const
  {
    const double* g = this->PyramidG;
    const double A = g[2] - g[0] * g[1];
    const double B = 1.0 - a[2] + a[0] * g[1] + a[1] * g[0];
    const double C = a[0] * a[1];
    const double root = std::sqrt(std::max(B * B + 4.0 * A * C, 0.0));
    // The root that tends to C / B as the twist vanishes, in the form without cancellation.
    const double denom = B >= 0 ? B + root : B - root;
    w = denom != 0 ? 2.0 * C / denom : 0.0;
    PyramidPoint(a, g, w, q);
    const double outside = PyramidOutside(q);
    if (outside > kPyramidInside && A != 0)
    {
      // A strongly twisted pyramid: the other root may be the one inside.
      const double other = -denom / (2.0 * A);
      double q2[3];
      PyramidPoint(a, g, other, q2);
      if (PyramidOutside(q2) < outside)
      {
        w = other;
        std::copy(q2, q2 + 3, q);
      }
    }
  }

  // The scalar at a pyramid's point with coordinates a (above): S0 + SC1 u + SC2 v + SC3 t +
  // SC4 w, VTK's interpolant at the exact inverse.
  [[gnu::always_inline]] double PyramidScalarAt(const double a[3]) const
  {
    double q[3];
    double w = 0;
    this->PyramidCoordinates(a, q, w);
    const auto& c = this->SC;
    return c[0] + q[0] * c[1] + q[1] * c[2] + q[2] * c[3] + w * c[4];
  }

  // Sum of VTK's weights times the corner scalars: exact at the corners.
  double InterpolateScalar(const double pcoords[3]) const;

  // The same interpolant in monomial form, cheaper per sample (the marcher's form); it
  // differs from InterpolateScalar by rounding only.
  [[gnu::always_inline]] double ScalarAt(const double p[3]) const
  {
    const double r = p[0], s = p[1], t = p[2];
    const double rs = r * s;
    const auto& a = this->SC;
    return a[0] + r * a[1] + s * a[2] + t * a[3] + rs * a[4] + r * t * a[5] + s * t * a[6] +
      rs * t * a[7];
  }

  // LinearRayDirection's matrix and ScalarAt's coefficients, for a vectorised sample loop
  // that repeats their arithmetic (apcLaneSamples.h).
  const double (&GetLinearInverse() const)[3][3] { return this->Inverse; }
  const double (&GetScalarCoefficients() const)[8] { return this->SC; }
  // PyramidCoordinates' g = M^-1 C4, for the same vectorised loop's closed form.
  const double (&GetPyramidG() const)[3] { return this->PyramidG; }

  // Below this distance outside the pyramid (in (u, v, t)) a root is taken as the one inside.
  static constexpr double kPyramidInside = 1e-9;

  // Reference -> world.
  void WorldPosition(const double pcoords[3], double x[3]) const;

  CellShape Shape() const { return this->CellType; }
  bool IsAffine() const { return this->Affine; }
  bool IsDegenerate() const { return this->Degenerate; }

private:
  // Newton's Jacobian columns and the offset of the map from x(0,0,0) at p.
  void Evaluate(const double p[3], double offset[3], double jacobian[3][3]) const;
  // The offset alone.
  void Map(const double p[3], double offset[3]) const;
  // Follow without the check for a wrong root.
  bool FollowFromMemory(
    const double x[3], NewtonMemory& memory, double pcoords[3], double tolerance) const;
  // ParametricCoordinates, also leaving the solution and its inverse Jacobian in memory.
  bool Search(const double x[3], double pcoords[3], int* iterations, double tolerance,
    NewtonMemory* memory) const;
  // Search's iteration for a cell that is not affine: y = x - C[0], p the first guess.
  bool Newton(const double x[3], const double y[3], double p[3], double pcoords[3], int* iterations,
    double tolerance, NewtonMemory* memory) const;
  // One chord step from p with the last Newton step's Jacobian (cofactors cr, cs, ct over
  // its determinant): true if it lands within tolerance.
  bool ChordStep(const double y[3], double p[3], const double cr[3], const double cs[3],
    const double ct[3], double invDet, double tolerance) const;

  CellShape CellType = CellShape::Hexahedron;
  bool Affine = false;
  bool Degenerate = true;
  // x(r,s,t) = C[0] + C[1] r + C[2] s + C[3] t + C[4] rs + C[5] rt + C[6] st + C[7] rst.
  double C[8][3] = {};
  double S[8] = {};
  // Affine cells: p = Inverse (x - C[0]).
  double Inverse[3][3] = {};
  // Largest linear coefficient: the cell's size, the scale of every tolerance on x.
  double Size = 0.0;
  // The scalar in the monomial basis of the map: s(r,s,t) = SC[0] + SC[1] r + ... + SC[7] rst.
  double SC[8] = {};
  // LinearRay's expansion point: p = LinearP + Inverse (x - LinearX); for affine cells
  // Inverse is exact, else it is the inverse Jacobian at the centre LinearP.
  double LinearP[3] = {};
  double LinearX[3] = {};
  double LinearScalarError = 0.0;
  // Pyramids: M^-1 C4, and whether the closed-form inverse applies (HasPyramidInverse).
  double PyramidG[3] = {};
  bool PyramidInverse = false;

  static void PyramidPoint(const double a[3], const double g[3], double w, double q[3])
  {
    q[0] = a[0] - g[0] * w;
    q[1] = a[1] - g[1] * w;
    q[2] = a[2] - g[2] * w;
  }
  // How far (u, v, t) lies outside the pyramid u, v >= 0, u, v <= 1 - t, t >= 0.
  static double PyramidOutside(const double q[3])
  {
    const double below = 1.0 - q[2];
    return std::max(
      std::max(std::max(-q[0], q[0] - below), std::max(-q[1], q[1] - below)), std::max(-q[2], 0.0));
  }

  void SetLinear(const double centre[3], const double offset[3], const double cr[3],
    const double cs[3], const double ct[3], double det);
  void SetLinearPyramid();
};

// Convenience forms that set up a CellInterpolator per call (tests, one-off queries).
bool ParametricCoordinates(
  const CellCorners& cell, const double x[3], double pcoords[3], int* iterations = nullptr);
double InterpolateScalar(const CellCorners& cell, const double pcoords[3]);
void WorldPosition(const CellCorners& cell, const double pcoords[3], double x[3]);

// True if the cell is an affine image of the reference cell, i.e. the non-linear
// coefficients of its map are at most relTol times its largest edge-like (linear)
// coefficient: any tetra, a parallelepiped hexahedron, a prism whose top triangle is a
// translate of the bottom one. Never true for a non-degenerate pyramid, whose map has an rt
// term equal to minus its base edge. Parametric coordinates are then linear in x.
bool IsAffine(const CellCorners& cell, double relTol);

} // namespace apc

#endif
