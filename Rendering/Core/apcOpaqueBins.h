// The opaque stop's bins along each ray, and the cut every process agrees on.
//
// A process stops a ray once its own absorbance along it reaches the threshold, but the
// moments carry every sample they include, so which samples are included must not depend on
// how the cells are split among processes. Each ray is cut into kBins ranges of the global
// lattice index k (the same on every process, without communication). A process stops at the
// END of the bin in which its own absorbance reached the threshold, so its per-bin absorbance
// is complete up to that edge; it reports that profile in fixed point (each sample's
// absorbance rounded down to whole quanta, summed as saturating integers: exact and
// order-independent), the profiles are summed over processes, and every process keeps only
// the samples up to the end of the first bin at which the summed profile reaches the
// threshold (CutBin). docs/sampler.md proves that this cut is the one complete data gives.
#ifndef apcOpaqueBins_h
#define apcOpaqueBins_h

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace apc
{

struct OpaqueBins
{
  static constexpr int kBins = 16;
  // The threshold in quanta; every per-bin value and every sum saturates at it (what lies
  // past it does not change where the cumulative first reaches it).
  static constexpr uint32_t kOpaque = 65535;
  // The lattice span the bins may cover: the cache keeps the low 16 bits of k, read back
  // as a signed offset from Base.
  static constexpr double kMaxSpan = 30000;

  int64_t Base = 0;                                    // bin 0 ends at Base + Width
  int64_t Width = std::numeric_limits<int64_t>::max(); // lattice steps per bin
  double QuantaPerAbsorbance = 0;                      // 0: no bins, nothing stops

  // Bins over the lattice indices between the frame's near and far distance (the depth
  // warp's, which every process shares) for a lattice of this spacing; threshold: the
  // absorbance at which a ray counts as opaque (+inf: none).
  static OpaqueBins Make(double threshold, double nearT, double farT, double spacing)
  {
    OpaqueBins bins;
    const double span = (farT - nearT) / spacing;
    if (!(threshold > 0) || !std::isfinite(threshold) || !(spacing > 0) ||
      !std::isfinite(nearT / spacing) || !(span >= 0) || !(span <= kMaxSpan) ||
      !(std::abs(nearT / spacing) < 1e15))
    {
      return bins; // inactive: every sample is taken
    }
    bins.Base = static_cast<int64_t>(std::floor(nearT / spacing));
    bins.Width = std::max<int64_t>(1, static_cast<int64_t>(std::ceil(span / kBins)));
    bins.QuantaPerAbsorbance = kOpaque / threshold;
    return bins;
  }
  bool Active() const { return this->QuantaPerAbsorbance > 0; }

  // The bin of lattice index k; the first and last bins reach to either end of the ray.
  int Of(int64_t k) const
  {
    const int64_t d = k - this->Base;
    if (d < this->Width)
    {
      return 0;
    }
    return static_cast<int>(std::min<int64_t>(d / this->Width, kBins - 1));
  }
  // The same from k's low 16 bits (SampleCache's K16), for k within kMaxSpan of the bins.
  int OfLow16(uint16_t k16) const
  {
    const int16_t d =
      static_cast<int16_t>(static_cast<uint16_t>(k16 - static_cast<uint16_t>(this->Base)));
    return this->Of(this->Base + d);
  }
  // The first lattice index past bin (none past the last bin).
  int64_t End(int bin) const
  {
    return bin >= kBins - 1 ? std::numeric_limits<int64_t>::max()
                            : this->Base + (static_cast<int64_t>(bin) + 1) * this->Width;
  }
  // A sample's absorbance in whole quanta, rounded down (the cut only ever comes later).
  uint32_t Quanta(double absorbance) const
  {
    const double q = absorbance * this->QuantaPerAbsorbance;
    return q >= kOpaque ? kOpaque : (q > 0 ? static_cast<uint32_t>(q) : 0u);
  }
  static uint16_t Add(uint32_t a, uint32_t b)
  {
    return static_cast<uint16_t>(std::min<uint32_t>(a + b, kOpaque));
  }
};

// The last bin a pixel keeps: the first at which its profile's cumulative reaches the
// threshold (kBins - 1, the whole ray, if none does).
inline int CutBin(const uint16_t* profile)
{
  uint32_t sum = 0;
  for (int b = 0; b < OpaqueBins::kBins - 1; ++b)
  {
    sum += profile[b];
    if (sum >= OpaqueBins::kOpaque)
    {
      return b;
    }
  }
  return OpaqueBins::kBins - 1;
}

// Saturating element-wise sum of profiles: into += from, count values.
inline void AddProfiles(uint16_t* into, const uint16_t* from, size_t count)
{
  for (size_t i = 0; i < count; ++i)
  {
    into[i] = OpaqueBins::Add(into[i], from[i]);
  }
}

} // namespace apc

#endif
