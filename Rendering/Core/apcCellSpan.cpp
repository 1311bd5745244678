#include "apcCellSpan.h"

#include "apcCellMesh.h"
#include "apcCellShapeCheck.h"

#include <algorithm>
#include <cmath>

namespace apc
{
namespace
{
using Vec = std::array<double, 3>;

double Dot(const Vec& a, const Vec& b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
Vec Cross(const Vec& a, const Vec& b)
{
  return { a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0] };
}
double Norm(const Vec& a)
{
  return std::sqrt(Dot(a, a));
}
Vec NormalOf(const FacePlane& plane)
{
  return { plane.Normal[0], plane.Normal[1], plane.Normal[2] };
}

// Three planes nearer than this to dependent (the determinant of their unit normals) get no
// bound: their point moves too far for the planes' rounding.
constexpr double kMinDeterminant = 1e-3;
// A vertex must lie this far (relative to the cell's size) inside the planes it is not on.
constexpr double kMinSlack = 1e-6;
// Rounding of the projection and of a ray's direction, in pixels, far above either.
constexpr double kPixelPad = 1e-4;
// Projected coordinates beyond this (pixels) are too close to the eye plane to bound.
constexpr double kMaxPixel = 1e6;
}

namespace
{
// Where planes on[0..2] meet (Cramer's rule), and a bound of the inverse of their normals'
// matrix (its columns are the cross products over the determinant, so its norm is at most
// their norms' sum over |det|); false if they are nearly dependent.
bool MeetingPoint(const FacePlane* planes, const int* on, Vec& v, double& inverse)
{
  const Vec na = NormalOf(planes[on[0]]);
  const Vec nb = NormalOf(planes[on[1]]);
  const Vec nc = NormalOf(planes[on[2]]);
  const Vec bc = Cross(nb, nc);
  const Vec ca = Cross(nc, na);
  const Vec ab = Cross(na, nb);
  const double det = Dot(na, bc);
  if (!(std::abs(det) >= kMinDeterminant * Norm(na) * Norm(nb) * Norm(nc)))
  {
    return false;
  }
  for (int d = 0; d < 3; ++d)
  {
    v[d] =
      (planes[on[0]].Offset * bc[d] + planes[on[1]].Offset * ca[d] + planes[on[2]].Offset * ab[d]) /
      det;
  }
  inverse = (Norm(bc) + Norm(ca) + Norm(ab)) / std::abs(det);
  return std::isfinite(inverse) && std::isfinite(v[0] + v[1] + v[2]);
}

// A pyramid's planes (base 0, sides 1-4 around it) hold no unbounded direction: every r with
// n_s . r <= 0 for the four sides has n_base . r > 0 unless r = 0. Those r form a cone whose
// edges lie where two sides' planes through the origin meet: where adjacent sides meet inside
// the other two (the lateral edges' directions), and nowhere else where opposite ones do. So
// the test is that each adjacent pair's line, oriented inside the other two, points through the
// base, and each opposite pair's line leaves the cone either way, all by a clear margin
// (directions only: the clip's rounding tilts a normal by about 1e-16).
bool SidesBoundThePyramid(const FacePlane* planes)
{
  constexpr double kMargin = 1e-6;
  Vec n[5];
  for (int p = 0; p < 5; ++p)
  {
    n[p] = NormalOf(planes[p]);
    const double length = Norm(n[p]);
    for (int d = 0; d < 3; ++d)
    {
      n[p][d] /= length;
    }
  }
  for (int a = 1; a <= 4; ++a)
  {
    for (int b = a + 1; b <= 4; ++b)
    {
      const bool adjacent = b == a + 1 || (a == 1 && b == 4);
      Vec e = Cross(n[a], n[b]);
      const double length = Norm(e);
      if (!(length > kMargin))
      {
        return false;
      }
      for (int d = 0; d < 3; ++d)
      {
        e[d] /= length;
      }
      // The other two sides' values along e.
      double other[2];
      for (int s = 1, k = 0; s <= 4; ++s)
      {
        if (s != a && s != b)
        {
          other[k++] = Dot(n[s], e);
        }
      }
      if (adjacent)
      {
        // Inside both others one way: that way is the edge, and it must leave through the base.
        const double sign = other[0] < 0 ? 1.0 : -1.0;
        if (!(sign * other[0] < -kMargin && sign * other[1] < -kMargin &&
              sign * Dot(n[0], e) > kMargin))
        {
          return false;
        }
      }
      else if (!(std::max(other[0], other[1]) > kMargin && std::min(other[0], other[1]) < -kMargin))
      {
        return false; // along e one way and the other, some side is left
      }
    }
  }
  return true;
}
}

//------------------------------------------------------------------------------
PlaneReach PlaneReachOf(CellShape shape, const std::array<std::array<double, 3>, 8>& x,
  const FacePlane* planes, int count)
{
  const PlaneReach none;
  const CellFaces& faces = FacesOf(shape);
  if (count != faces.Count)
  {
    return none;
  }
  const bool pyramid = shape == CellShape::Pyramid;
  if (pyramid && !SidesBoundThePyramid(planes))
  {
    return none;
  }
  const int corners = NumberOfCorners(shape);
  // The cell's size and the largest magnitude the arithmetic meets.
  Vec lo = x[0];
  Vec hi = x[0];
  double magnitude = 0;
  for (int c = 0; c < corners; ++c)
  {
    for (int d = 0; d < 3; ++d)
    {
      lo[d] = std::min(lo[d], x[c][d]);
      hi[d] = std::max(hi[d], x[c][d]);
      magnitude = std::max(magnitude, std::abs(x[c][d]));
    }
  }
  const double size = Norm({ hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2] });
  for (int p = 0; p < count; ++p)
  {
    magnitude = std::max(magnitude, std::abs(planes[p].Offset));
  }
  double reach = 0;
  double grow = 0;
  double slack = std::numeric_limits<double>::infinity();
  for (int c = 0; c < corners; ++c)
  {
    if (pyramid && c == 4)
    {
      // The apex: each three of the four sides meet near it, and P's vertices there are
      // among those points, which need not lie inside the fourth side.
      for (int skip = 1; skip <= 4; ++skip)
      {
        int on[3];
        for (int f = 1, k = 0; f <= 4; ++f)
        {
          if (f != skip)
          {
            on[k++] = f;
          }
        }
        Vec v;
        double inverse = 0;
        if (!MeetingPoint(planes, on, v, inverse))
        {
          return none;
        }
        grow = std::max(grow, std::sqrt(3.0) * inverse + 1.0);
        reach = std::max(reach, Norm({ v[0] - x[c][0], v[1] - x[c][1], v[2] - x[c][2] }));
      }
      continue;
    }
    int on[3];
    int found = 0;
    for (int f = 0; f < faces.Count; ++f)
    {
      for (int i = 0; i < faces.Size[f]; ++i)
      {
        if (faces.Corner[f][i] == c)
        {
          if (found == 3)
          {
            return none;
          }
          on[found++] = f;
        }
      }
    }
    if (found != 3)
    {
      return none;
    }
    Vec v;
    double inverse = 0;
    if (!MeetingPoint(planes, on, v, inverse))
    {
      return none;
    }
    // A unit move of each plane moves the vertex by at most sqrt(3) inverse; the planes it is
    // not on move by one more.
    grow = std::max(grow, std::sqrt(3.0) * inverse + 1.0);
    reach = std::max(reach, Norm({ v[0] - x[c][0], v[1] - x[c][1], v[2] - x[c][2] }));
    for (int p = 0; p < count; ++p)
    {
      if (p == on[0] || p == on[1] || p == on[2])
      {
        continue;
      }
      const Vec n = NormalOf(planes[p]);
      slack = std::min(slack, (planes[p].Offset - Dot(n, v)) / Norm(n));
    }
  }
  // This arithmetic's own rounding, as the frame's allowance for the clip's (far above both).
  const double own = kPlaneError * magnitude;
  slack -= own;
  reach += own * grow;
  if (!(slack > kMinSlack * size) || !std::isfinite(reach))
  {
    return none;
  }
  PlaneReach out;
  // Rounded to float outwards.
  out.Reach = std::nextafter(static_cast<float>(reach), std::numeric_limits<float>::infinity());
  out.Grow = std::nextafter(static_cast<float>(grow), std::numeric_limits<float>::infinity());
  out.Slack = std::nextafter(static_cast<float>(slack), 0.0f);
  return out;
}

//------------------------------------------------------------------------------
double PlaneErrorOf(const std::array<double, 3>& eye, const std::array<double, 6>& bounds)
{
  double largest = 0;
  for (double b : bounds)
  {
    largest = std::max(largest, std::abs(b));
  }
  return kPlaneError * (Norm(eye) + std::sqrt(3.0) * largest);
}

//------------------------------------------------------------------------------
CellDiagonals DiagonalsOf(const double* px, const double* py, const double* z, int n, double ax,
  double bx, double ay, double by, const PlaneReach& reach, double planeError)
{
  if (!(planeError * reach.Grow < reach.Slack))
  {
    return kNoDiagonals; // also no bound (Reach = inf, Slack = 0)
  }
  // How far from the corners' hull a ray the clip keeps can pass.
  const double m = reach.Reach + planeError * reach.Grow;
  double zmin = std::numeric_limits<double>::infinity();
  double sx = 0; // the largest |x / z|, |y / z|
  double sy = 0;
  double u0 = std::numeric_limits<double>::infinity();
  double u1 = -u0;
  double w0 = u0;
  double w1 = -u0;
  for (int c = 0; c < n; ++c)
  {
    if (!(std::abs(px[c]) <= kMaxPixel && std::abs(py[c]) <= kMaxPixel))
    {
      return kNoDiagonals;
    }
    zmin = std::min(zmin, z[c]);
    sx = std::max(sx, std::abs(px[c] - bx));
    sy = std::max(sy, std::abs(py[c] - by));
    u0 = std::min(u0, px[c] + py[c]);
    u1 = std::max(u1, px[c] + py[c]);
    w0 = std::min(w0, px[c] - py[c]);
    w1 = std::max(w1, px[c] - py[c]);
  }
  // A point within m of the corners' hull lies at depth >= zmin - m, and its projection lies
  // within a m (1 + |x / z|) / (z - m) of its nearest hull point's (per axis; the hull's x / z
  // within the corners').
  if (!(zmin > 2 * m) || !(zmin > 0))
  {
    return kNoDiagonals;
  }
  const double rx = ax * m * (1 + sx / ax) / (zmin - m) + kPixelPad;
  const double ry = ay * m * (1 + sy / ay) / (zmin - m) + kPixelPad;
  const double r = rx + ry;
  // The pixel centres within: i + j >= u0 - r is i + j >= ceil(u0 - r), and so on (clamped
  // first: r can be large where a cell nearly reaches the eye).
  const double limit = kNoBound;
  auto ceiling = [limit](double v) -> int32_t
  { return static_cast<int32_t>(std::ceil(std::min(std::max(v, -limit), limit))); };
  auto floor = [limit](double v) -> int32_t
  { return static_cast<int32_t>(std::floor(std::min(std::max(v, -limit), limit))); };
  return { ceiling(u0 - r), floor(u1 + r), ceiling(w0 - r), floor(w1 + r) };
}

} // namespace apc
