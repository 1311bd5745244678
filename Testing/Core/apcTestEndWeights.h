// What the end-weight tests (TestEndWeights, TestBoundaryWeights) check a pair's weights
// against: their sum, the pair's sampled length in spacings.
#ifndef apcTestEndWeights_h
#define apcTestEndWeights_h

#include "apcEndWeights.h"

#include <cstdint>

namespace apctest
{

// The sum of the pair's sample weights: its middle sample's alone, or each lattice sample's
// and its end sample's.
inline double Sum(const apc::walk::EndWeights& w)
{
  if (w.Mid)
  {
    return w.MidWeight;
  }
  double sum = w.End ? w.EndWeight : 0.0;
  for (int64_t k = w.First; k <= w.Last; ++k)
  {
    sum += w.Of(k);
  }
  return sum;
}

} // namespace apctest

#endif
