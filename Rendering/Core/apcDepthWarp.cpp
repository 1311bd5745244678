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

LatticeDepthWarp::LatticeDepthWarp(const LogDepthWarp& warp, double spacing)
  : Warp(warp)
  , Spacing(spacing)
{
  // Beyond near and far the warp is a constant, cheap to reach: the table covers the
  // indices between, one more on each side for the rounding of the quotients.
  const double first = std::floor(warp.Near() / spacing) - 1;
  const double last = std::ceil(warp.Far() / spacing) + 1;
  if (warp.IsDegenerate() || !(spacing > 0) || !std::isfinite(first) || !std::isfinite(last) ||
    !(last - first < static_cast<double>(kMaxEntries)) || !(std::abs(first) < 1e15))
  {
    return; // every depth warped directly
  }
  this->Base = static_cast<int64_t>(first);
  this->Z.resize(static_cast<size_t>(last - first) + 1);
  for (size_t i = 0; i < this->Z.size(); ++i)
  {
    const int64_t k = this->Base + static_cast<int64_t>(i);
    // Lattice::At(k, 0): (k + 0.0) * spacing, and k + 0.0 is k exactly.
    this->Z[i] = warp(static_cast<double>(k) * spacing);
  }
}

} // namespace apc
