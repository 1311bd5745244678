// Pass 2 of one pixel from the sample cache, with 4 moments, in one vectorised loop: each
// cached sample looked up in the transfer table, weighted by alpha T(z) (T reconstructed from
// the pixel's global moments) and summed into the pixel's colour, 4 samples per step with no
// scalar tail (the last step masks the lanes past the pixel's run). It does what
// visitors::Colour's generic replay does (MomentTransmittance::Weights after
// TransferTable::Lookup) with the same arithmetic, up to the order of the sums and FMA
// rounding. Internal to the core's marcher.
#ifndef apcPixelReplay_h
#define apcPixelReplay_h

#include "apcMomentTransmittance.h"
#include "apcSampleCache.h"
#include "apcTransferTable.h"

#include <cstdint>

namespace apc
{

// Which vector replay serves a pixel: the widest the CPU runs (Best: AVX-512, else AVX2), or
// one named, so that tests can hold the kernels against each other. Every kernel gives the
// same sums to the bit.
enum class ReplayKernel
{
  Best,
  Avx2,
  Avx512,
  Avx2Full // the AVX2 kernel without its shortcuts (every group's full arithmetic), for tests
};

// True if this build has the kernel and the CPU runs it (Best: any vector kernel).
bool HasReplayKernel(ReplayKernel kernel);

// Adds the weighted colour of samples[0, n) (one pixel's run) to sums (r, g, b, weight), as
// ColourSums::Add would, skipping the samples at depths >= hiddenFrom (added to hidden). t:
// the pixel's reconstruction; a sample its vector arithmetic cannot answer is weighted by t's
// query. weights, if not null: each sample's end weight (apcEndWeights.h), by which its
// looked-up absorbance is multiplied (a float product, as pass 1 took it). False, and nothing
// done, if the CPU lacks AVX2 with FMA (or the kernel asked for) or t is not a valid pixel:
// the generic replay then does it.
bool ReplayFourMomentPixel(const MomentTransmittance<4>& t, double hiddenFrom,
  const TransferTable::Layout& table, const CachedSample* samples, int n, double sums[4],
  int64_t& hidden, const float* weights = nullptr, ReplayKernel kernel = ReplayKernel::Best);

// The AVX2 replay's look-up of 4 scalars, for tests: out[4 c + k] is lane k's channel c (r, g,
// b, absorbance) widened to double; weights, if not null, as the replay takes them (lanes
// of them read). False, and nothing done, if the CPU lacks AVX2 with FMA.
bool ReplayLookupFour(const TransferTable::Layout& table, const double scalars[4],
  const float* weights, int lanes, double out[16]);

} // namespace apc

#endif
