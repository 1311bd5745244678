// Absorbance of one sample, the quantity the power moments are built from
// (Münstermann et al. 2018, "Moment-Based Order-Independent Transparency", I3D).
#ifndef apcAbsorbance_h
#define apcAbsorbance_h

#include <cmath>

namespace apc
{

// Cap on the absorbance of a single sample. Without it an opaque sample (alpha = 1) would
// add +inf to b0 and turn every moment into inf or NaN. exp(-10) ~ 4.5e-5, so a capped
// sample still hides all but 0.005% of what lies behind it.
constexpr double kAbsorbanceMax = 10.0;

// -ln(1 - alpha), capped at kAbsorbanceMax. alpha <= 0 and NaN give 0 so that invalid
// samples contribute nothing instead of poisoning the sums; alpha >= 1 gives the cap.
inline double AbsorbanceFromAlpha(double alpha)
{
  if (!(alpha > 0.0))
  {
    return 0.0;
  }
  if (alpha >= 1.0)
  {
    return kAbsorbanceMax;
  }
  // log1p keeps full precision for the small per-sample opacities of volume rendering.
  const double a = -std::log1p(-alpha);
  return a < kAbsorbanceMax ? a : kAbsorbanceMax;
}

} // namespace apc

#endif
