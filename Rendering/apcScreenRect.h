// SPDX-License-Identifier: BSD-3-Clause
// The part of the viewport the pass composites: the pixels whose rays can meet the data's
// global bounds, and moving images between the full viewport and that rectangle, packed.
#ifndef apcScreenRect_h
#define apcScreenRect_h

#include <algorithm>
#include <cstddef>

class vtkRenderer;

namespace apc
{

// Pixel rectangle [I0, I1) x [J0, J1) of the viewport.
struct ScreenRect
{
  int I0 = 0, J0 = 0, I1 = 0, J1 = 0;
  int Width() const { return this->I1 - this->I0; }
  int Height() const { return this->J1 - this->J0; }
  size_t Pixels() const
  {
    return this->I1 > this->I0 && this->J1 > this->J0
      ? static_cast<size_t>(this->Width()) * this->Height()
      : 0;
  }
};

// The pixels of a width x height image whose rays can meet the box bounds: its projected
// corners and one pixel of margin; the whole image if a corner lies behind the eye. The image
// covers a viewport of the given aspect (width / height; 0: the image's own). Every process
// computes the same rectangle from the same camera and global bounds.
ScreenRect ScreenRectOf(
  vtkRenderer* ren, const double bounds[6], int width, int height, double aspect = 0.0);

// Copies the rectangle's pixels (components each) from a full image to a packed buffer.
template <class Packed, class Full>
void Pack(const Full* full, int width, const ScreenRect& r, int components, Packed* packed)
{
  for (int j = r.J0; j < r.J1; ++j)
  {
    const Full* row = full + (static_cast<size_t>(j) * width + r.I0) * components;
    std::copy(row, row + static_cast<size_t>(r.Width()) * components,
      packed + static_cast<size_t>(j - r.J0) * r.Width() * components);
  }
}

// The reverse of Pack.
template <class Packed, class Full>
void Unpack(const Packed* packed, int width, const ScreenRect& r, int components, Full* full)
{
  for (int j = r.J0; j < r.J1; ++j)
  {
    const Packed* row = packed + static_cast<size_t>(j - r.J0) * r.Width() * components;
    std::copy(row, row + static_cast<size_t>(r.Width()) * components,
      full + (static_cast<size_t>(j) * width + r.I0) * components);
  }
}

} // namespace apc

#endif
