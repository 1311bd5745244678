// The Hybrid resolve's transmittance: a process's own samples composited exactly, only the
// other processes' absorbance by moments. This goes beyond the APC paper (Huang, Usher et al.,
// "Approximate Puzzlepiece Compositing", arXiv 2501.12581), whose pass 2 weights every sample
// by the transmittance reconstructed from the global moments (MBOIT, Münstermann et al. 2018).
//
// Why it works: transmittance is a product over the absorbing samples in front of a depth,
// so it factors over any split of the samples, T(z) = T_own(z) T_others(z). A process knows
// its own samples of a pixel exactly; sorted by depth they give T_own(z_i) as an ordered
// product, with no approximation. Power moments are plain sums, so global - own are exactly
// the moments of the others' absorbance, a valid moment sequence from which T_others is
// reconstructed as before (same bias, same guards). On one process the others are empty and
// the result is the exact render to float rounding; on N processes only what crosses a
// process boundary is approximated. The price: the image depends on how the data is split
// (APC's N-process image equals its 1-process image), and pass 2 sorts each pixel's samples.
// "Own" is one volume's samples on one process (one ray marcher): with several volumes in a
// view, the other volumes count among the others, whichever process holds them.
#ifndef apcHybridTransmittance_h
#define apcHybridTransmittance_h

#include "apcMomentTransmittance.h"
#include "apcPowerMoments.h"

#include <cmath>

namespace apc
{

// others = global - own, the moments of every other process's absorbance (the in-place
// subtraction others == global is allowed).
template <int N>
inline void OthersMoments(const double* global, const double* own, double* others)
{
  for (int k = 0; k <= N; ++k)
  {
    others[k] = global[k] - own[k];
  }
}

// T_others(z) of one pixel, built from its global and this process's own moment sums.
//
// Guards, beyond MomentTransmittance's own:
// - The others' b0 below kEmptyPixelAbsorbance (the same empty threshold as a pixel's): no
//   other process absorbs anything worth reconstructing, T_others = 1. This also catches
//   the cancellation where own ~ global: the difference of two nearly equal sums (rounded
//   differently, e.g. by the wire's fixed point) is noise, possibly negative, whose higher
//   moments need not even satisfy |b_k| <= b0; it must not be normalised.
// - T_others is clamped to [exp(-b0_others), 1]: the others cannot absorb more than all of
//   their absorbance, nor less than none, whatever rounding did to their higher moments.
template <int N>
class OthersTransmittance
{
public:
  OthersTransmittance(const double* global, const double* own, const MomentSettings<N>& settings)
    : Moments(Difference(global, own), settings)
  {
    const double b0 = this->Moments.TotalAbsorbance();
    this->Empty = !(b0 >= kEmptyPixelAbsorbance);
    this->Floor = this->Empty ? 1.0 : std::exp(-b0);
  }

  bool IsEmpty() const { return this->Empty; }
  double TotalAbsorbance() const { return this->Empty ? 0.0 : this->Moments.TotalAbsorbance(); }

  double operator()(double z) const
  {
    if (this->Empty)
    {
      return 1.0;
    }
    const double t = this->Moments(z);
    return t < this->Floor ? this->Floor : (t > 1.0 ? 1.0 : t);
  }

private:
  static PowerMoments<N> Difference(const double* global, const double* own)
  {
    PowerMoments<N> m;
    OthersMoments<N>(global, own, m.Data());
    return m;
  }

  MomentTransmittance<N> Moments;
  bool Empty = true;
  double Floor = 1.0;
};

// T_own along one pixel's own samples, fed front to back: Weight(a) returns the sample's
// alpha times the transmittance of the own samples in front of it, then lets the sample
// absorb. The arithmetic is that of the exact mode's front-to-back blend, so that on one
// process the Hybrid weights are the exact render's.
struct OwnTransmittance
{
  double Transmittance = 1.0;

  double Weight(double absorbance)
  {
    const double alpha = -std::expm1(-absorbance);
    const double weight = alpha * this->Transmittance;
    this->Transmittance *= 1.0 - alpha;
    return weight;
  }
};

} // namespace apc

#endif
