#include "apcOrderedReference.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace apc
{
namespace
{

bool Usable(const Sample& s)
{
  return !std::isnan(s.Depth) && !std::isnan(s.Alpha);
}

double ClampedAlpha(double alpha)
{
  return alpha < 0.0 ? 0.0 : (alpha > 1.0 ? 1.0 : alpha);
}

} // namespace

RGBA CompositeOrdered(std::vector<Sample> samples)
{
  samples.erase(
    std::remove_if(samples.begin(), samples.end(), [](const Sample& s) { return !Usable(s); }),
    samples.end());
  std::sort(samples.begin(), samples.end(),
    [](const Sample& a, const Sample& b)
    { return std::tie(a.Depth, a.Alpha, a.Colour) < std::tie(b.Depth, b.Alpha, b.Colour); });
  RGBA out{ 0.0, 0.0, 0.0, 0.0 };
  double transmittance = 1.0;
  for (const Sample& s : samples)
  {
    const double w = transmittance * ClampedAlpha(s.Alpha);
    for (int k = 0; k < 3; ++k)
    {
      out[k] += w * s.Colour[k];
    }
    transmittance *= 1.0 - ClampedAlpha(s.Alpha);
  }
  out[3] = 1.0 - transmittance;
  return out;
}

double ExactTransmittance(const std::vector<Sample>& samples, double depth)
{
  // Multiplied in sorted order so that the rounding, too, is independent of input order.
  std::vector<double> factors;
  for (const Sample& s : samples)
  {
    if (Usable(s) && s.Depth < depth)
    {
      factors.push_back(1.0 - ClampedAlpha(s.Alpha));
    }
  }
  std::sort(factors.begin(), factors.end());
  double transmittance = 1.0;
  for (double f : factors)
  {
    transmittance *= f;
  }
  return transmittance;
}

} // namespace apc
