// Per-pixel resolve of APC's second pass. Each sample adds w = alpha_i T(z_i) with colour
// c_i to plain sums (C = sum w c, W = sum w), which are then reduced across ranks and turned
// into one premultiplied RGBA value (Huang, Usher et al., "Approximate Puzzlepiece
// Compositing", arXiv 2501.12581; MBOIT's resolve: Münstermann et al. 2018, I3D).
#ifndef apcResolve_h
#define apcResolve_h

#include <array>
#include <cstddef>

namespace apc
{

using RGB = std::array<double, 3>;
using RGBA = std::array<double, 4>; // premultiplied unless stated otherwise

// (C_r, C_g, C_b, W) as four doubles, a flat buffer that sums across threads and ranks.
struct ColourSums
{
  std::array<double, 4> Sums{};

  // weight = alpha_i * T(z_i). NaN or non-positive weights are skipped. Inline: pass 2 calls
  // it once per sample.
  void Add(double weight, const RGB& colour)
  {
    if (!(weight > 0.0))
    {
      return;
    }
    for (int k = 0; k < 3; ++k)
    {
      this->Sums[k] += weight * colour[k];
    }
    this->Sums[3] += weight;
  }
  ColourSums& operator+=(const ColourSums& other);

  double W() const { return this->Sums[3]; }
  double* Data() { return this->Sums.data(); }
  const double* Data() const { return this->Sums.data(); }
};

enum class ResolveMode
{
  // The APC paper's plain sum: rgb = C, alpha = W (clamped to [0,1]; if W > 1, rgb is
  // scaled by 1/W as well so that it stays a valid premultiplied colour).
  PaperSum,
  // MBOIT's resolve: alpha = 1 - exp(-b0) exactly, rgb = alpha C / W. The errors of the
  // reconstructed T then only redistribute colour between samples, never change opacity.
  // W <= 0 (or non-finite, or below kMinResolveWeight) gives rgb = 0 with that alpha.
  Renormalised,
  // Renormalised, on sums whose weights pass 2 took from each process's own samples exactly
  // and only from the other processes' moments (apcHybridTransmittance.h). The resolve itself
  // is Renormalised's; the mode tells the passes how to weight.
  Hybrid
};

// Below this W the ratio C/W is not trusted (it would be the quotient of two underflowed
// quantities).
constexpr double kMinResolveWeight = 1e-300;

// b0 is the pixel's total (global) absorbance; Renormalised and Hybrid use it.
RGBA Resolve(ResolveMode mode, const ColourSums& sums, double b0);

// Resolve for a whole image: pixel p's b0 is moments[p * momentStride], its colour sums
// colourSums[4p .. 4p + 3]; writes premultiplied RGBA floats to rgba[4p .. 4p + 3].
void ResolveImage(ResolveMode mode, size_t pixels, const double* moments, int momentStride,
  const double* colourSums, float* rgba);
// The same image written over the colour sums' own memory: afterwards its first 16 * pixels
// bytes hold the float RGBA (what a caller short of memory copies out), the rest is garbage.
void ResolveImageInPlace(
  ResolveMode mode, size_t pixels, const double* moments, int momentStride, double* colourSums);

// Premultiplied colour over an opaque background: rgb + (1 - alpha) background.
RGB BlendOverBackground(const RGBA& premultiplied, const RGB& background);

} // namespace apc

#endif
