// Logarithmic depth warp of MBOIT (Münstermann et al. 2018, I3D, Sec. 3.3 "Warping Depth").
// The moments are only meaningful on [-1,1], and the log spreads the near range where
// perspective packs most of the visible detail.
#ifndef apcDepthWarp_h
#define apcDepthWarp_h

#include <cmath>

namespace apc
{

// Maps a positive view distance d to z in [-1,1]:
//   z = 2 (ln clamp(d, zmin, zmax) - ln zmin) / (ln zmax - ln zmin) - 1.
// In APC every rank must use the same zmin/zmax, otherwise the moment sums of different
// ranks describe different depth axes and cannot be added.
//
// Guards (the result is never NaN):
// - zmin <= 0 (e.g. a camera inside the data) is replaced by kMinNearFraction * zmax, since
//   ln 0 is -inf.
// - zmax <= zmin after that, or non-finite bounds: the range is degenerate and every
//   distance maps to 0, i.e. all samples sit at one depth; MBOIT then behaves as for a
//   single layer, which is the only honest answer without a depth range.
// - d <= zmin maps to -1, d >= zmax (including +inf) to +1, NaN maps to +1 (treated as
//   "infinitely far", so it occludes nothing in front of it).
class LogDepthWarp
{
public:
  static constexpr double kMinNearFraction = 1e-6;

  LogDepthWarp(double zmin, double zmax);

  // Inline: pass 1 warps every sample.
  double operator()(double d) const
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

  double Near() const { return this->ZMin; }
  double Far() const { return this->ZMax; }
  bool IsDegenerate() const { return this->Degenerate; }

private:
  double ZMin;
  double ZMax;
  double LogZMin = 0.0;
  double Scale = 0.0; // 2 / (ln zmax - ln zmin)
  bool Degenerate = false;
};

} // namespace apc

#endif
