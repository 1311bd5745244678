// Pass 2's replay of one pixel (apcPixelReplay.h) with AVX-512: 8 samples a lane group, whose
// lanes 0-3 and 4-7 are the AVX2 replay's two groups of 4 of a step, and each lane's sums in
// that replay's order, so that both give the same sums to the bit. Internal to
// apcPixelReplay.cpp, which chooses the kernel at run time.
#ifndef apcPixelReplayAvx512_h
#define apcPixelReplayAvx512_h

#include "apcMomentTransmittance.h"
#include "apcSampleCache.h"
#include "apcTransferTable.h"

namespace apc
{

// True if this build has the AVX-512 replay and the CPU runs it (AVX-512 F, DQ and VL).
bool HasAvx512Replay();

// As the AVX2 replay: adds the weighted colour of samples[0, n) in front of hiddenFrom to
// sums and returns how many were hidden. Only where HasAvx512Replay().
int ReplayFourMomentAvx512(const MomentTransmittance<4>& t, const FourMomentPixel& px,
  double hiddenFrom, const TransferTable::Layout& table, const CachedSample* samples, int n,
  double sums[4], const float* weights);

} // namespace apc

#endif
