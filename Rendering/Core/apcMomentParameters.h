// Everything the MBOIT passes need to know about the moments, as one value: how many, the
// overestimation beta, the bias and the resolve. It is built and checked once where the
// settings enter (the mapper alone, or the composite pass for all processes) and handed down
// unchanged; the compile-time number of moments is chosen in one place, DispatchMoments.
#ifndef apcMomentParameters_h
#define apcMomentParameters_h

#include "apcMomentTransmittance.h"
#include "apcResolve.h"

#include <stdexcept>
#include <string>
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

// Whether moments is a supported number of power moments: 4, 6 or 8.
constexpr bool IsSupportedMoments(int moments)
{
  return moments == 4 || moments == 6 || moments == 8;
}

// Calls f(std::integral_constant<int, N>{}) for the supported N equal to moments and returns
// its result. Where the number enters (vtkAPCVolumeMapper::SetNumberOfMoments) it is checked;
// any other value here is a bug, never silently replaced by another number.
template <class F>
decltype(auto) DispatchMoments(int moments, F&& f)
{
  switch (moments)
  {
    case 4:
      return f(std::integral_constant<int, 4>{});
    case 6:
      return f(std::integral_constant<int, 6>{});
    case 8:
      return f(std::integral_constant<int, 8>{});
    default:
      throw std::invalid_argument(
        "apc::DispatchMoments: unsupported number of moments " + std::to_string(moments));
  }
}

} // namespace apc

#endif
