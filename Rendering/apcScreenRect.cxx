// SPDX-License-Identifier: BSD-3-Clause
#include "apcScreenRect.h"

#include "vtkCamera.h"
#include "vtkMatrix4x4.h"
#include "vtkRenderer.h"

#include <cmath>
#include <limits>

namespace apc
{

ScreenRect ScreenRectOf(
  vtkRenderer* ren, const double bounds[6], int width, int height, double aspect)
{
  ScreenRect full{ 0, 0, width, height };
  vtkCamera* camera = ren->GetActiveCamera();
  // The camera's projection includes its window centre: a tile's rectangle is the part of
  // the full image's that falls into the tile.
  vtkMatrix4x4* m = camera->GetCompositeProjectionTransformMatrix(
    aspect > 0 ? aspect : static_cast<double>(width) / height, -1, 1);
  double x0 = std::numeric_limits<double>::infinity();
  double y0 = x0;
  double x1 = -x0;
  double y1 = -x0;
  for (int c = 0; c < 8; ++c)
  {
    const double p[4] = { bounds[c & 1], bounds[2 + ((c >> 1) & 1)], bounds[4 + ((c >> 2) & 1)],
      1.0 };
    double q[4];
    m->MultiplyPoint(p, q);
    if (!(q[3] > 0))
    {
      return full; // a corner behind the eye: the projection is unbounded
    }
    const double px = (q[0] / q[3] + 1.0) * 0.5 * width;
    const double py = (q[1] / q[3] + 1.0) * 0.5 * height;
    x0 = std::min(x0, px);
    x1 = std::max(x1, px);
    y0 = std::min(y0, py);
    y1 = std::max(y1, py);
  }
  ScreenRect r;
  r.I0 = static_cast<int>(std::max(0.0, std::floor(x0) - 1));
  r.J0 = static_cast<int>(std::max(0.0, std::floor(y0) - 1));
  r.I1 = static_cast<int>(std::min(static_cast<double>(width), std::ceil(x1) + 1));
  r.J1 = static_cast<int>(std::min(static_cast<double>(height), std::ceil(y1) + 1));
  if (r.I1 <= r.I0 || r.J1 <= r.J0)
  {
    r.I1 = r.I0;
  }
  return r;
}

} // namespace apc
