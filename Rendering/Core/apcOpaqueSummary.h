// SPDX-License-Identifier: BSD-3-Clause
// A frame without a predicted bound (the first of a view on several processes) sums the
// processes' opaque profiles (apcOpaqueBins.h) only as far as the cut can lie, which every
// process learns from one small allreduce of a 16-bit summary per pixel first.
//
// Process r's own cumulative is at most the complete one at every bin, so the complete cut c*
// comes no later than r's own cut c_r = CutBin(r's profile); and r, if it stopped, stopped at
// the end of a bin s_r >= c_r (its own cumulative had reached the threshold there), so its
// profile is complete up to c_r (everywhere if it did not stop). With S = min_r c_r, every
// profile is complete up to S >= c*: the sums of bins 0..S alone give c* exactly. And where
// the processes' totals add up to less than the threshold, no bin reaches it: the cut is the
// whole ray (kBins - 1) whatever the profiles hold, and no bin need be sent.
//
// The summary packs both into 16 bits: c_r in the top 4 (combined by minimum) and the total
// in 12 bits of 16 quanta, rounded up (combined by saturating sum), so that a combined total
// below its saturation proves the true total below the threshold.
#ifndef apcOpaqueSummary_h
#define apcOpaqueSummary_h

#include "apcOpaqueBins.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>

namespace apc
{

struct OpaqueSummary
{
  static_assert(OpaqueBins::kBins == 16, "the cut's bin takes the summary's top 4 bits");
  static constexpr uint32_t kTotalBits = 12;
  static constexpr uint32_t kTotalMask = (1u << kTotalBits) - 1;
  // Quanta per unit of the summary's total, which saturates at kTotalMask units.
  static constexpr uint32_t kQuantaPerUnit = 16;
  static_assert((kTotalMask - 1) * kQuantaPerUnit < OpaqueBins::kOpaque,
    "a total below the summary's saturation must be below the threshold");

  // A pixel's summary from its profile (kBins values).
  static uint16_t Of(const uint16_t* profile)
  {
    // One pass for both: the cut is CutBin's (the first bin whose cumulative reaches the
    // threshold, kBins - 1 if none before it).
    uint32_t total = 0;
    uint32_t cut = OpaqueBins::kBins - 1;
    for (int b = 0; b < OpaqueBins::kBins; ++b)
    {
      total += profile[b];
      if (total >= OpaqueBins::kOpaque && static_cast<uint32_t>(b) < cut)
      {
        cut = static_cast<uint32_t>(b);
      }
    }
    const uint32_t units =
      std::min(kTotalMask, (total + kQuantaPerUnit - 1) / kQuantaPerUnit); // rounded up
    return static_cast<uint16_t>((cut << kTotalBits) | units);
  }

  // Two processes' summaries combined: the earlier cut, the totals summed (saturating).
  static uint16_t Combine(uint16_t a, uint16_t b)
  {
    const uint32_t cut = std::min(a >> kTotalBits, b >> kTotalBits);
    const uint32_t units = std::min(kTotalMask, (a & kTotalMask) + (b & kTotalMask));
    return static_cast<uint16_t>((cut << kTotalBits) | units);
  }

  // The bins of each process's profile that the sums need, given the summary combined over
  // every process: none if the totals stay below the threshold (the cut is then kBins - 1,
  // the sum of nothing), else bins 0..S.
  static int Bins(uint16_t combined)
  {
    if ((combined & kTotalMask) < kTotalMask)
    {
      // At most (kTotalMask - 1) * kQuantaPerUnit quanta in all: below the threshold.
      return 0;
    }
    return static_cast<int>(combined >> kTotalBits) + 1;
  }

  // A combined summary with a predicted last bin (apcOpaquePrediction.h) as well: every
  // profile is complete up to min(bound, S) and zero past the bound, so Bins then sends bins
  // 0..min(bound, S). A pixel whose totals stay below the threshold still sends none: its
  // zero sum leaves it unresolved if the bound bounds anything, as its whole sum would.
  static uint16_t Bounded(uint16_t combined, uint8_t bound)
  {
    const uint32_t cut = std::min<uint32_t>(combined >> kTotalBits, bound);
    return static_cast<uint16_t>((cut << kTotalBits) | (combined & kTotalMask));
  }
};

// Element-wise Combine: into[i] = Combine(into[i], from[i]) (the summaries' allreduce).
inline void CombineOpaqueSummaries(uint16_t* into, const uint16_t* from, size_t count)
{
  for (size_t i = 0; i < count; ++i)
  {
    into[i] = OpaqueSummary::Combine(into[i], from[i]);
  }
}

} // namespace apc

#endif
