#include "apcDepthWarp.h"

#include <cmath>

namespace apc
{

LogDepthWarp::LogDepthWarp(double zmin, double zmax)
  : ZMin(zmin)
  , ZMax(zmax)
{
  if (!std::isfinite(zmax) || !(zmax > 0.0) || std::isnan(zmin))
  {
    this->Degenerate = true;
    return;
  }
  if (!(zmin > 0.0))
  {
    this->ZMin = kMinNearFraction * zmax;
  }
  const double logRange = std::log(this->ZMax) - std::log(this->ZMin);
  // A range that rounds to zero in log space would make Scale overflow.
  if (!(logRange > 0.0) || !std::isfinite(2.0 / logRange))
  {
    this->Degenerate = true;
    return;
  }
  this->LogZMin = std::log(this->ZMin);
  this->Scale = 2.0 / logRange;
}

double LogDepthWarp::operator()(double d) const
{
  if (this->Degenerate)
  {
    return 0.0;
  }
  if (std::isnan(d) || d >= this->ZMax)
  {
    return 1.0;
  }
  if (d <= this->ZMin)
  {
    return -1.0;
  }
  const double z = this->Scale * (std::log(d) - this->LogZMin) - 1.0;
  // Rounding can push the endpoints a few ulps outside; the moments assume |z| <= 1.
  return z < -1.0 ? -1.0 : (z > 1.0 ? 1.0 : z);
}

} // namespace apc
