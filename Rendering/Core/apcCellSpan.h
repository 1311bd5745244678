// Which rays of each row of a cell's screen rectangle can meet its face planes (internal to the
// ray marcher): the rest of the row need not be clipped.
//
// The rectangle is the bounding box of the projected corners, and many of its rays miss the
// cell. The clip uses the face planes, whose polytope P is not the corners' hull where a face
// is warped, so a ray outside the corners' projected hull may still take a sample. P's
// vertices are found from its planes once per data change (PlaneReachOf): each corner of a
// tetrahedron, wedge or hexahedron lies on three faces, and a 3-polytope with F facets has at
// most 2F - 4 vertices (an unbounded one at most 2F - 5), which is the number of corners. So
// when each corner's three planes meet in a point strictly inside every other plane, those
// points are all of P's vertices and P is bounded: P is their hull, within Reach of the
// corners' hull. Pyramids (the apex on four planes), cells with a face left out, nearly
// dependent planes and vertices nearly on a fourth plane get no bound.
//
// The clip rounds: each of its quotients is the exact crossing of the ray with its plane moved
// by at most about 10 eps (|eye| + |x|) (the products and sums of the denominator and
// numerator, the division), so a ray it keeps meets a polytope P' whose planes lie within
// delta of P's. Where delta Grow < Slack, P' has the same vertices moved by at most
// delta Grow, so the ray passes within Reach + delta Grow of the corners' hull. The frame takes
// delta = kPlaneError (|eye| + the mesh's largest coordinate), far above that rounding.
//
// Per cell and frame (DiagonalsOf, when the cells are binned) the corners' projections,
// widened by what that distance projects to (and a margin for the projection's own rounding),
// are bounded by an octagon: their bounding box, the cell's rectangle, and the diagonal
// bounds of x + y and x - y, which every row of the rectangle is cut to.
#ifndef apcCellSpan_h
#define apcCellSpan_h

#include "apcCellInterpolation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace apc
{

struct FacePlane;

// What the frame needs of a cell's planes' polytope (see above); Reach = inf: no bound.
struct PlaneReach
{
  float Reach = std::numeric_limits<float>::infinity(); // vertices' distance from the corners
  float Grow = 0;  // how far the vertices move per unit the planes move
  float Slack = 0; // how far every vertex lies inside the planes it is not on
};

// Relative rounding the frame allows the clip's planes (see above).
constexpr double kPlaneError = 1e-12;

// P's reach beyond the corners x of a cell of shape with count planes (CellMesh's: the faces
// of FacesOf(shape) in order, none left out).
PlaneReach PlaneReachOf(CellShape shape, const std::array<std::array<double, 3>, 8>& x,
  const FacePlane* planes, int count);

// What the clip's rounding may move a plane by for a camera at eye over a mesh of bounds
// (delta above: kPlaneError (|eye| + the mesh's largest absolute coordinate)).
double PlaneErrorOf(const std::array<double, 3>& eye, const std::array<double, 6>& bounds);

// A cell's rows as an octagon of pixel centres: every ray the clip can keep is that of a pixel
// (i, j) with U0 <= i + j <= U1 and W0 <= i - j <= W1 (and inside the corners' bounding box,
// the cell's rectangle). Integers, so that each row's span is exact integer arithmetic.
struct CellDiagonals
{
  int32_t U0, U1, W0, W1;
};
// No bound: every ray of each row.
constexpr int32_t kNoBound = 1 << 30;
constexpr CellDiagonals kNoDiagonals = { -kNoBound, kNoBound, -kNoBound, kNoBound };

// The octagon of a cell whose n corners a perspective camera projects to (px, py) (pixel
// centres at integers) at depths z along the view direction: ax and ay are the camera's
// pixels per unit of x / z and y / z (RayCamera::GetPixelScale), bx and by where z's axis
// lands. kNoDiagonals where there is no bound (the reach, a corner near or behind the eye).
CellDiagonals DiagonalsOf(const double* px, const double* py, const double* z, int n, double ax,
  double bx, double ay, double by, const PlaneReach& reach, double planeError);

// The pixel centres i of row j with lo <= i <= hi inside the octagon (lo > hi: none); the
// caller clamps to the rectangle.
inline void RowOf(const CellDiagonals& d, int j, int& lo, int& hi)
{
  lo = std::max(d.U0 - j, d.W0 + j);
  hi = std::min(d.U1 - j, d.W1 + j);
}

} // namespace apc

#endif
