#include "apcResolve.h"

#include <cstring>

#include <algorithm>
#include <cmath>

namespace apc
{

ColourSums& ColourSums::operator+=(const ColourSums& other)
{
  for (int k = 0; k < 4; ++k)
  {
    this->Sums[k] += other.Sums[k];
  }
  return *this;
}

RGBA Resolve(ResolveMode mode, const ColourSums& sums, double b0)
{
  const double w = sums.Sums[3];
  RGBA out{ 0.0, 0.0, 0.0, 0.0 };
  if (mode == ResolveMode::PaperSum)
  {
    if (!(w > 0.0) || !std::isfinite(w))
    {
      return out;
    }
    const double scale = w > 1.0 ? 1.0 / w : 1.0;
    for (int k = 0; k < 3; ++k)
    {
      out[k] = sums.Sums[k] * scale;
    }
    out[3] = w > 1.0 ? 1.0 : w;
    return out;
  }

  // -expm1 keeps the relative precision of faint pixels; NaN b0 means no opacity at all.
  const double alpha = std::isnan(b0) || !(b0 > 0.0) ? 0.0 : -std::expm1(-b0);
  out[3] = alpha;
  if (!(w > kMinResolveWeight) || !std::isfinite(w))
  {
    return out;
  }
  const double scale = alpha / w;
  for (int k = 0; k < 3; ++k)
  {
    out[k] = sums.Sums[k] * scale;
  }
  return out;
}

namespace
{
// Pixel p of an image: its four float RGBA values from its colour sums and b0.
void ResolvePixel(ResolveMode mode, size_t p, const double* moments, int momentStride,
  const double* colourSums, float rgba[4])
{
  ColourSums sums;
  std::copy(colourSums + 4 * p, colourSums + 4 * p + 4, sums.Data());
  const RGBA out = Resolve(mode, sums, moments[p * momentStride]);
  for (int c = 0; c < 4; ++c)
  {
    rgba[c] = static_cast<float>(out[c]);
  }
}
}

void ResolveImage(ResolveMode mode, size_t pixels, const double* moments, int momentStride,
  const double* colourSums, float* rgba)
{
  for (size_t p = 0; p < pixels; ++p)
  {
    ResolvePixel(mode, p, moments, momentStride, colourSums, rgba + 4 * p);
  }
}

void ResolveImageInPlace(
  ResolveMode mode, size_t pixels, const double* moments, int momentStride, double* colourSums)
{
  // Pixel p's floats go to bytes [16p, 16p + 16), which hold nothing pixel p or a later one
  // still needs (pixel p's sums, bytes [32p, 32p + 32), are read first). Bytes are written,
  // not float objects: the doubles there are dead.
  auto* out = reinterpret_cast<unsigned char*>(colourSums);
  for (size_t p = 0; p < pixels; ++p)
  {
    float rgba[4];
    ResolvePixel(mode, p, moments, momentStride, colourSums, rgba);
    std::memcpy(out + sizeof(rgba) * p, rgba, sizeof(rgba));
  }
}

RGB BlendOverBackground(const RGBA& premultiplied, const RGB& background)
{
  const double behind = 1.0 - premultiplied[3];
  return { premultiplied[0] + behind * background[0], premultiplied[1] + behind * background[1],
    premultiplied[2] + behind * background[2] };
}

} // namespace apc
