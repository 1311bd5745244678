// SPDX-License-Identifier: BSD-3-Clause
#include "apcFrameInputsFromVTK.h"

#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkPiecewiseFunction.h"
#include "vtkRenderer.h"
#include "vtkVolumeProperty.h"

#include "apcRayCamera.h"
#include "apcTransferTable.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace
{
// Transfer functions are sampled this finely; finer than 8-bit colour and far finer than
// the opacity ramps of typical volume renderings.
constexpr int kTableSize = 1024;
}

namespace apc
{

namespace
{
// The first component's colour (or gray) and opacity functions sampled over the union of
// their ranges: what the table holds, before the opacity correction.
void SampleTransferFunctions(vtkVolumeProperty* property, double range[2], std::vector<double>& rgb,
  std::vector<double>& alphas)
{
  vtkPiecewiseFunction* opacity = property->GetScalarOpacity(0);
  opacity->GetRange(range);
  rgb.assign(3 * kTableSize, 0.0);
  if (property->GetColorChannels(0) == 1)
  {
    vtkPiecewiseFunction* gray = property->GetGrayTransferFunction(0);
    double grayRange[2];
    gray->GetRange(grayRange);
    range[0] = std::min(range[0], grayRange[0]);
    range[1] = std::max(range[1], grayRange[1]);
    std::vector<double> g(kTableSize);
    gray->GetTable(range[0], range[1], kTableSize, g.data());
    for (int i = 0; i < kTableSize; ++i)
    {
      rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = g[i];
    }
  }
  else
  {
    vtkColorTransferFunction* colour = property->GetRGBTransferFunction(0);
    const double* colourRange = colour->GetRange();
    range[0] = std::min(range[0], colourRange[0]);
    range[1] = std::max(range[1], colourRange[1]);
    colour->GetTable(range[0], range[1], kTableSize, rgb.data());
  }
  alphas.assign(kTableSize, 0.0);
  opacity->GetTable(range[0], range[1], kTableSize, alphas.data());
}

// A 48-bit checksum of values rounded to float (exact in a double, so it travels in the frame
// agreement's MAX allreduce unchanged).
double Checksum(const std::vector<double>& values, double extra)
{
  std::uint64_t hash = 1469598103934665603ull;
  auto mix = [&hash](float v)
  {
    std::uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    hash = (hash ^ bits) * 1099511628211ull;
  };
  for (double v : values)
  {
    mix(static_cast<float>(v));
  }
  mix(static_cast<float>(extra));
  return static_cast<double>(hash >> 16);
}
}

std::unique_ptr<TransferTable> TransferTableFromVTK(vtkVolumeProperty* property, double spacing)
{
  double range[2];
  std::vector<double> rgb, alphas;
  SampleTransferFunctions(property, range, rgb, alphas);
  std::vector<std::array<float, 3>> colours(kTableSize);
  for (int i = 0; i < kTableSize; ++i)
  {
    colours[i] = { static_cast<float>(rgb[3 * i]), static_cast<float>(rgb[3 * i + 1]),
      static_cast<float>(rgb[3 * i + 2]) };
  }
  return std::unique_ptr<TransferTable>(new TransferTable(
    range[0], range[1], colours, alphas, spacing, property->GetScalarOpacityUnitDistance(0)));
}

TransferSignature TransferSignatureFromVTK(vtkVolumeProperty* property)
{
  TransferSignature signature;
  std::vector<double> rgb, alphas;
  SampleTransferFunctions(property, signature.Range, rgb, alphas);
  signature.Colour = Checksum(rgb, 0.0);
  signature.Opacity = Checksum(alphas, property->GetScalarOpacityUnitDistance(0));
  return signature;
}

std::unique_ptr<RayCamera> RayCameraFromVTK(vtkRenderer* ren, int width, int height, double aspect)
{
  vtkCamera* cam = ren->GetActiveCamera();
  if (!(aspect > 0))
  {
    aspect = static_cast<double>(std::max(width, 1)) / std::max(height, 1);
  }
  double clip[2];
  cam->GetClippingRange(clip);
  double viewAngle = cam->GetViewAngle();
  if (cam->GetUseHorizontalViewAngle())
  {
    const double pi = 3.14159265358979323846;
    viewAngle = 2.0 * std::atan(std::tan(0.5 * viewAngle * pi / 180.0) / aspect) * 180.0 / pi;
  }
  const double* p = cam->GetPosition();
  const double* f = cam->GetFocalPoint();
  const double* u = cam->GetViewUp();
  const double* c = cam->GetWindowCenter();
  return std::unique_ptr<RayCamera>(new RayCamera({ p[0], p[1], p[2] }, { f[0], f[1], f[2] },
    { u[0], u[1], u[2] }, viewAngle, cam->GetParallelProjection() != 0, cam->GetParallelScale(),
    width, height, clip[0], clip[1], { c[0], c[1] }, aspect));
}

} // namespace apc
