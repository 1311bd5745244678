#include "apcRayCamera.h"

#include <algorithm>
#include <cmath>
#include <limits>

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

Vec Normalized(const Vec& a)
{
  const double n = std::sqrt(Dot(a, a));
  return n > 0 ? Vec{ a[0] / n, a[1] / n, a[2] / n } : Vec{ 0, 0, 0 };
}
}

//------------------------------------------------------------------------------
RayCamera::RayCamera(const Vec& position, const Vec& focalPoint, const Vec& viewUp,
  double viewAngle, bool parallel, double parallelScale, int width, int height, double nearClip,
  double farClip, const std::array<double, 2>& windowCenter, double aspect)
  : Position(position)
  , Parallel(parallel)
  , Center(windowCenter)
  , Width(std::max(width, 1))
  , Height(std::max(height, 1))
  , FullWidth(std::max(width, 1))
  , FullHeight(std::max(height, 1))
  , Near(nearClip)
  , Far(farClip)
{
  this->Forward = Normalized(
    { focalPoint[0] - position[0], focalPoint[1] - position[1], focalPoint[2] - position[2] });
  this->Right = Normalized(Cross(this->Forward, viewUp));
  this->Up = Cross(this->Right, this->Forward);
  const double pi = 3.14159265358979323846;
  this->HalfHeight = parallel ? parallelScale : std::tan(0.5 * viewAngle * pi / 180.0);
  this->Aspect = aspect > 0 ? aspect : static_cast<double>(this->FullWidth) / this->FullHeight;
}

//------------------------------------------------------------------------------
RayCamera RayCamera::Cropped(int i0, int j0, int width, int height) const
{
  RayCamera crop(*this);
  crop.CropI0 = this->CropI0 + i0;
  crop.CropJ0 = this->CropJ0 + j0;
  crop.Width = std::max(width, 1);
  crop.Height = std::max(height, 1);
  return crop;
}

//------------------------------------------------------------------------------
RayCamera RayCamera::Decimated(int step, int offset) const
{
  RayCamera coarse(*this);
  step = std::max(step, 1);
  offset = std::min(std::max(offset, 0), step - 1);
  // Composes with an earlier decimation: pixel i is this camera's i * step + offset.
  coarse.Offset = this->Offset + this->Step * offset;
  coarse.Step = this->Step * step;
  coarse.Width = std::max(1, (this->Width - offset + step - 1) / step);
  coarse.Height = std::max(1, (this->Height - offset + step - 1) / step);
  return coarse;
}

//------------------------------------------------------------------------------
Ray RayCamera::PixelRay(int i, int j) const
{
  const double gi = i * this->Step + this->Offset + this->CropI0 + 0.5;
  const double gj = j * this->Step + this->Offset + this->CropJ0 + 0.5;
  const double x =
    (2.0 * gi / this->FullWidth - 1.0 + this->Center[0]) * this->HalfHeight * this->Aspect;
  const double y = (2.0 * gj / this->FullHeight - 1.0 + this->Center[1]) * this->HalfHeight;
  Ray ray;
  if (this->Parallel)
  {
    for (int d = 0; d < 3; ++d)
    {
      ray.Origin[d] = this->Position[d] + x * this->Right[d] + y * this->Up[d];
    }
    ray.Direction = this->Forward;
  }
  else
  {
    ray.Origin = this->Position;
    ray.Direction = Normalized({ this->Forward[0] + x * this->Right[0] + y * this->Up[0],
      this->Forward[1] + x * this->Right[1] + y * this->Up[1],
      this->Forward[2] + x * this->Right[2] + y * this->Up[2] });
  }
  return ray;
}

//------------------------------------------------------------------------------
bool RayCamera::Project(const Vec& x, double& px, double& py) const
{
  const Vec v = { x[0] - this->Position[0], x[1] - this->Position[1], x[2] - this->Position[2] };
  double scale = this->HalfHeight;
  if (!this->Parallel)
  {
    const double depth = Dot(v, this->Forward);
    // Closer than a millionth of the near plane counts as "at or behind the eye".
    if (!(depth > 1e-6 * std::max(this->Near, 1e-12)))
    {
      return false;
    }
    scale *= depth;
  }
  px =
    (Dot(v, this->Right) / (scale * this->Aspect) - this->Center[0] + 1.0) * 0.5 * this->FullWidth -
    0.5 - this->CropI0;
  py = (Dot(v, this->Up) / scale - this->Center[1] + 1.0) * 0.5 * this->FullHeight - 0.5 -
    this->CropJ0;
  if (this->Step != 1)
  {
    px = (px - this->Offset) / this->Step;
    py = (py - this->Offset) / this->Step;
  }
  return std::isfinite(px) && std::isfinite(py);
}

//------------------------------------------------------------------------------
double RayCamera::DistanceFromDepth(int i, int j, double depth) const
{
  if (!(depth < 1.0))
  {
    return std::numeric_limits<double>::infinity();
  }
  const double ndc = 2.0 * depth - 1.0;
  const double n = this->Near;
  const double f = this->Far;
  if (this->Parallel)
  {
    return 0.5 * (ndc * (f - n) + (f + n));
  }
  const double eyeDepth = 2.0 * f * n / ((f + n) - ndc * (f - n));
  return eyeDepth / Dot(this->PixelRay(i, j).Direction, this->Forward);
}

//------------------------------------------------------------------------------
void RayCamera::DistanceRange(const std::array<double, 6>& bounds, double& tmin, double& tmax) const
{
  tmin = std::numeric_limits<double>::infinity();
  tmax = -tmin;
  if (!(bounds[0] <= bounds[1] && bounds[2] <= bounds[3] && bounds[4] <= bounds[5]))
  {
    return;
  }
  for (int c = 0; c < 8; ++c)
  {
    const Vec corner = { bounds[c & 1], bounds[2 + ((c >> 1) & 1)], bounds[4 + ((c >> 2) & 1)] };
    const Vec v = { corner[0] - this->Position[0], corner[1] - this->Position[1],
      corner[2] - this->Position[2] };
    const double t = this->Parallel ? Dot(v, this->Forward) : std::sqrt(Dot(v, v));
    tmin = std::min(tmin, t);
    tmax = std::max(tmax, t);
  }
  if (!this->Parallel)
  {
    // The nearest point of the box, not its nearest corner, bounds t from below.
    Vec nearest;
    for (int d = 0; d < 3; ++d)
    {
      nearest[d] =
        std::min(std::max(this->Position[d], bounds[2 * d]), bounds[2 * d + 1]) - this->Position[d];
    }
    tmin = std::sqrt(Dot(nearest, nearest));
  }
}

} // namespace apc
