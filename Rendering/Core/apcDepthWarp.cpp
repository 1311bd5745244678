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

} // namespace apc
