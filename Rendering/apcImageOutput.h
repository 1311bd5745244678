// SPDX-License-Identifier: BSD-3-Clause
// Where a finished APC image goes: blended into the render window, and kept as float arrays
// of a vtkImageData for inspection, files and tests. Shared by the mapper and the pass, which
// hand in everything explicitly.
#ifndef apcImageOutput_h
#define apcImageOutput_h

#include "apcScreenRect.h"

#include <cstdint>

class vtkImageData;
class vtkRenderer;

namespace apc
{

/**
 * Blends premultiplied float RGBA (imageWidth x imageHeight, row 0 at the bottom) over
 * whatever framebuffer is bound, into the width x height viewport at (x0, y0) of ren's
 * window; an image smaller than the viewport (an interactive frame) is stretched over it,
 * interpolated linearly.
 */
void BlendIntoWindow(vtkRenderer* ren, int x0, int y0, int width, int height, int imageWidth,
  int imageHeight, const float* rgba);

// The float images of one frame; null ones are left out.
struct FloatImages
{
  const float* RGBA = nullptr;     // 4 per pixel, premultiplied
  const double* Moments = nullptr; // MomentComponents per pixel
  int MomentComponents = 0;
  const double* ColourSums = nullptr; // 4 per pixel
  const int* SegmentCount = nullptr;  // 1 per pixel
  int64_t SampleCount = 0;
};

/**
 * Replaces image's content by a width x height image whose point arrays are "RGBA",
 * "Moments", "ColourSums" and "SegmentCount" (those given, as float / int) and whose field
 * array "SampleCount" holds the lattice samples taken. The given buffers hold the pixels of
 * rect only; the others are zero.
 */
void StoreFloatImages(
  vtkImageData* image, int width, int height, const ScreenRect& rect, const FloatImages& images);

/**
 * Writes StoreFloatImages' image to a file: OpenEXR if its name ends in ".exr", else VTK XML
 * image data (binary, readable everywhere).
 */
void WriteFloatImages(vtkImageData* image, const char* fileName);

} // namespace apc

#endif
