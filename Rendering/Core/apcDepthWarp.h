// Logarithmic depth warp of MBOIT (Münstermann et al. 2018, I3D, Sec. 3.3 "Warping Depth").
// The moments are only meaningful on [-1,1], and the log spreads the near range where
// perspective packs most of the visible detail.
#ifndef apcDepthWarp_h
#define apcDepthWarp_h

#include <cmath>
#include <cstdint>
#include <vector>

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

// The warp of the sample lattice's depths t_k = (k + 0) * spacing, tabulated for the k
// between the warp's near and far: pass 1 warps every sample, and a table read costs a small
// fraction of the logarithm (a call per sample, with the sample loop's registers saved
// around it). The value is the warp's own, bit for bit: entry k holds warp(t_k) for t_k
// computed as the lattice computes it, and a depth that is not its index's t_k (a jittered
// ray, whose offset is not 0) or an index outside the table is warped directly.
class LatticeDepthWarp
{
public:
  // No table beyond this many indices (a lattice far finer than the depth range needs):
  // every depth is then warped directly.
  static constexpr int64_t kMaxEntries = int64_t(1) << 16;

  LatticeDepthWarp(const LogDepthWarp& warp, double spacing);

  // The warp of depth t, the lattice's sample k (t = Lattice::At(k, offset)).
  double operator()(int64_t k, double t) const
  {
    const uint64_t i = static_cast<uint64_t>(k) - static_cast<uint64_t>(this->Base);
    if (i < this->Z.size() && t == static_cast<double>(k) * this->Spacing)
    {
      return this->Z[i];
    }
    return this->Warp(t);
  }

  const LogDepthWarp& GetWarp() const { return this->Warp; }
  int64_t GetNumberOfEntries() const { return static_cast<int64_t>(this->Z.size()); }
  // The table itself (entry i: the warp of index GetBase() + i, of depth index times
  // GetSpacing()), for the walker's lanes, which read four entries at once.
  const double* GetEntries() const { return this->Z.data(); }
  int64_t GetBase() const { return this->Base; }
  double GetSpacing() const { return this->Spacing; }

private:
  LogDepthWarp Warp;
  double Spacing;
  int64_t Base = 0;
  std::vector<double> Z; // Z[i] = Warp(t_(Base + i))
};

} // namespace apc

#endif
