// Logarithmic depth warp of MBOIT (Münstermann et al. 2018, I3D, Sec. 3.3 "Warping Depth").
// The moments are only meaningful on [-1,1], and the log spreads the near range where
// perspective packs most of the visible detail.
#ifndef apcDepthWarp_h
#define apcDepthWarp_h

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

  double operator()(double d) const;

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
