// Everything the MBOIT passes need to know about the moments, as one value: how many, the
// overestimation beta, the bias and the resolve. It is built and checked once where the
// settings enter (the mapper alone, or the composite pass for all processes) and handed down
// unchanged; the compile-time number of moments is chosen in one place, DispatchMoments.
#ifndef apcMomentParameters_h
#define apcMomentParameters_h

#include "apcMomentTransmittance.h"
#include "apcResolve.h"

#include <type_traits>

namespace apc
{

struct MomentParameters
{
  int Moments = 4; // 4, 6 or 8 power moments
  double Overestimation = kDefaultOverestimation;
  double Bias = kUseDefaultMomentBias;
  ResolveMode Resolve = ResolveMode::Renormalised;

  // The per-N settings of the transmittance reconstruction.
  template <int N>
  MomentSettings<N> Settings() const
  {
    MomentSettings<N> settings;
    settings.Overestimation = this->Overestimation;
    settings.Bias = this->Bias;
    return settings;
  }
};

// Calls f(std::integral_constant<int, N>{}) for the supported N equal to moments (4 for any
// other value: the caller has checked it) and returns its result.
template <class F>
decltype(auto) DispatchMoments(int moments, F&& f)
{
  switch (moments)
  {
    case 6:
      return f(std::integral_constant<int, 6>{});
    case 8:
      return f(std::integral_constant<int, 8>{});
    default:
      return f(std::integral_constant<int, 4>{});
  }
}

} // namespace apc

#endif
