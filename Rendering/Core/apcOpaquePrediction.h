// Pass 1 on several processes bounded by a predicted cut (docs/sampler.md, "A bound from the
// previous frame's cut").
//
// A process stops a ray where its OWN absorbance reaches the threshold, which on several
// processes lies far behind where the summed one does: each process marches much more than
// its share. The previous frame's agreed cut (the same on every process) predicts this
// frame's closely after a small camera move, so every process also stops each ray at the end
// of a predicted last bin. The summed profile then still gives the exact cut wherever it
// reaches the threshold by that bin; elsewhere (an "unresolved" pixel, which every process
// recognises from the summed profile) the pixel's tile is marched again without the bound and
// its profile summed again, so the cut, and the samples kept, are those without a prediction.
#ifndef apcOpaquePrediction_h
#define apcOpaquePrediction_h

#include "apcOpaqueBins.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace apc
{

// The last agreed cut of every pixel of a rectangle of an image (one byte per pixel, row by
// row), and what identifies that image: a prediction is only made for the same image.
struct OpaqueCutMemory
{
  // Every value that must match for the cuts to predict: image size and origin, reduction.
  std::vector<long long> Image;
  int I0 = 0; // the rectangle's first column and row in the image, and its size
  int J0 = 0;
  int Width = 0;
  int Height = 0;
  std::vector<uint8_t> Cut; // Width * Height, kBins - 1 where nothing is opaque
  bool Valid = false;

  // Starts recording a frame's cuts over a rectangle (every pixel: nothing opaque).
  void Begin(const std::vector<long long>& image, int i0, int j0, int width, int height)
  {
    this->Image = image;
    this->I0 = i0;
    this->J0 = j0;
    this->Width = width;
    this->Height = height;
    this->Cut.assign(static_cast<size_t>(width) * static_cast<size_t>(height),
      static_cast<uint8_t>(OpaqueBins::kBins - 1));
    this->Valid = true;
  }
  // The cut of image pixel (i, j); kBins - 1 outside the rectangle (no samples were there).
  int At(int i, int j) const
  {
    const int x = i - this->I0;
    const int y = j - this->J0;
    if (x < 0 || y < 0 || x >= this->Width || y >= this->Height)
    {
      return OpaqueBins::kBins - 1;
    }
    return this->Cut[static_cast<size_t>(y) * this->Width + x];
  }
};

// The predicted last bin of each pixel of rows of a rectangle (image columns i0..i0+width,
// rows j0..j0+rows; bound: width * rows bytes): the largest previous cut within radius pixels
// (a square), plus margin bins, at most kBins - 1 (which bounds nothing). False (bound
// untouched) if previous is not for image.
inline bool PredictOpaqueBound(const OpaqueCutMemory& previous, const std::vector<long long>& image,
  int i0, int j0, int width, int rows, int radius, int margin, uint8_t* bound)
{
  if (!previous.Valid || previous.Image != image || width <= 0 || rows <= 0)
  {
    return false;
  }
  constexpr int none = OpaqueBins::kBins - 1;
  // A separable maximum: over the columns of each needed row, then over the rows.
  const int rowsIn = rows + 2 * radius;
  std::vector<uint8_t> across(static_cast<size_t>(width) * rowsIn);
  std::vector<uint8_t> line(static_cast<size_t>(width) + 2 * radius);
  for (int r = 0; r < rowsIn; ++r)
  {
    const int j = j0 - radius + r;
    for (int x = 0; x < width + 2 * radius; ++x)
    {
      line[x] = static_cast<uint8_t>(previous.At(i0 - radius + x, j));
    }
    for (int x = 0; x < width; ++x)
    {
      across[static_cast<size_t>(r) * width + x] =
        *std::max_element(line.begin() + x, line.begin() + x + 2 * radius + 1);
    }
  }
  for (int y = 0; y < rows; ++y)
  {
    for (int x = 0; x < width; ++x)
    {
      int most = 0;
      for (int r = y; r <= y + 2 * radius; ++r)
      {
        most = std::max<int>(most, across[static_cast<size_t>(r) * width + x]);
      }
      bound[static_cast<size_t>(y) * width + x] =
        static_cast<uint8_t>(most >= none ? none : std::min(none, most + margin));
    }
  }
  return true;
}

// A first frame has no previous cut. On several processes it probes instead: every process
// marches the rays of every step-th pixel in each direction (from offset) with its own stop,
// their profiles are summed and cut (the exact cut of those rays), and each pixel of the
// rectangle takes the largest probe cut around it as its "previous" cut, which
// PredictOpaqueBound then widens as for a later frame. A wrong prediction costs only time:
// the pixels it leaves unresolved are marched again.
//
// The probe's pixels along a side of pixels pixels (at least one).
inline int ProbeSize(int pixels, int step, int offset)
{
  return std::max(1, (pixels - offset + step - 1) / step);
}

// Fills memory's rectangle (after Begin) from the probe's agreed cuts (probeWidth x
// probeHeight, probe pixel (i, j) = the rectangle's pixel (i * step + offset, j * step +
// offset)): each pixel takes the largest cut of the (up to) two probe columns and two probe
// rows nearest it on either side, so that an opaque region's edge between two probe pixels
// is not taken as open.
inline void SpreadProbeCuts(const uint8_t* probe, int probeWidth, int probeHeight, int step,
  int offset, OpaqueCutMemory& memory)
{
  const auto below = [&](int x, int n)
  {
    const int d = x - offset;
    const int a = d >= 0 ? d / step : -1;
    return std::min(std::max(a, 0), n - 1);
  };
  const auto above = [&](int x, int n)
  {
    const int d = x - offset;
    const int a = d >= 0 ? d / step : -1;
    return std::min(std::max(a + 1, 0), n - 1);
  };
  for (int y = 0; y < memory.Height; ++y)
  {
    const int j0 = below(y, probeHeight);
    const int j1 = above(y, probeHeight);
    for (int x = 0; x < memory.Width; ++x)
    {
      const int i0 = below(x, probeWidth);
      const int i1 = above(x, probeWidth);
      const size_t r0 = static_cast<size_t>(j0) * probeWidth;
      const size_t r1 = static_cast<size_t>(j1) * probeWidth;
      memory.Cut[static_cast<size_t>(y) * memory.Width + x] = std::max(
        std::max(probe[r0 + i0], probe[r0 + i1]), std::max(probe[r1 + i0], probe[r1 + i1]));
    }
  }
}

// Marks the pixels whose summed profile (kBins per pixel) does not reach the threshold by
// their bound (only pixels with a bound below kBins - 1): their cut is unknown, since past
// the bound no process took a sample. Returns how many.
inline size_t MarkUnresolved(
  const uint8_t* bound, const uint16_t* profile, size_t pixels, uint8_t* unresolved)
{
  size_t count = 0;
  for (size_t p = 0; p < pixels; ++p)
  {
    const bool open = bound[p] < OpaqueBins::kBins - 1 &&
      CutBin(profile + p * OpaqueBins::kBins) > static_cast<int>(bound[p]);
    unresolved[p] = open ? 1 : 0;
    count += open ? 1 : 0;
  }
  return count;
}

// The profile values a pixel with predicted last bin bound can hold: bins 0..bound (no process
// takes a sample past it, so its later bins are zero on every process and in their sum).
inline int BoundedProfileBins(uint8_t bound)
{
  return std::min<int>(bound, OpaqueBins::kBins - 1) + 1;
}

} // namespace apc

#endif
