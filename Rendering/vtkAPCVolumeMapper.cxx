// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAPCVolumeMapper.h"

#include "vtkCamera.h"
#include "vtkCellType.h"
#include "vtkCellTypes.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataArray.h"
#include "vtkDataSetAttributes.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkFloatArray.h"
#include "vtkIdList.h"
#include "vtkImageData.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGridBase.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include "apcCellMesh.h"
#include "apcCellMeshFromVTK.h"
#include "apcDepthWarp.h"
#include "apcMomentTransmittance.h"
#include "apcRayCamera.h"
#include "apcResolve.h"
#include "apcTransferTable.h"
#include "apcVolumeRayMarcher.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkAPCVolumeMapper);

namespace
{
// Transfer functions are sampled this finely; finer than 8-bit colour and far finer than
// the opacity ramps of typical volume renderings.
constexpr int kTableSize = 1024;

// Wall-clock seconds of the stages of one frame, in the order they ran.
class StageClock
{
public:
  void Lap(const std::string& stage)
  {
    const auto now = std::chrono::steady_clock::now();
    this->Seconds.emplace_back(stage, std::chrono::duration<double>(now - this->Last).count());
    this->Last = now;
  }
  std::vector<std::pair<std::string, double>> Seconds;

private:
  std::chrono::steady_clock::time_point Last = std::chrono::steady_clock::now();
};

template <int N>
void RenderMBOIT(apc::VolumeRayMarcher& marcher, const apc::TransferTable& table,
  const apc::LogDepthWarp& warp, double overestimation, double bias, int resolveMode,
  std::vector<double>& moments, std::vector<double>& colourSums, std::vector<float>& rgba,
  int64_t& samples, StageClock& clock)
{
  const size_t pixels = rgba.size() / 4;
  moments.assign(pixels * (N + 1), 0.0);
  colourSums.assign(pixels * 4, 0.0);
  marcher.AccumulateMoments<N>(table, warp, moments.data());
  samples = marcher.GetLastSampleCount();
  clock.Lap("moments");
  apc::MomentSettings<N> settings;
  settings.Overestimation = overestimation;
  if (bias >= 0)
  {
    settings.Bias = bias;
  }
  marcher.AccumulateColour<N>(table, warp, moments.data(), settings, colourSums.data());
  clock.Lap("colour");
  const apc::ResolveMode mode = resolveMode == vtkAPCVolumeMapper::PAPER_SUM
    ? apc::ResolveMode::PaperSum
    : apc::ResolveMode::Renormalised;
  for (size_t p = 0; p < pixels; ++p)
  {
    apc::ColourSums sums;
    std::copy(colourSums.begin() + 4 * p, colourSums.begin() + 4 * p + 4, sums.Data());
    const apc::RGBA out = apc::Resolve(mode, sums, moments[p * (N + 1)]);
    for (int c = 0; c < 4; ++c)
    {
      rgba[4 * p + c] = static_cast<float>(out[c]);
    }
  }
  clock.Lap("resolve");
}
}

struct vtkAPCVolumeMapper::Internals
{
  apc::CellMesh Mesh;
  bool MeshValid = false;
  vtkMTimeType MeshInputTime = 0;
  std::string MeshScalarKey;
  apc::VolumeRayMarcher Marcher;
  vtkNew<vtkImageData> Image;
  double LastSpacing = 0.0;
  StageClock Clock;
};

//------------------------------------------------------------------------------
vtkAPCVolumeMapper::vtkAPCVolumeMapper()
  : Internal(new Internals)
{
}

vtkAPCVolumeMapper::~vtkAPCVolumeMapper() = default;

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::SetNumberOfMoments(int n)
{
  const int valid = n <= 4 ? 4 : (n <= 6 ? 6 : 8);
  if (valid != n)
  {
    vtkWarningMacro("NumberOfMoments must be 4, 6 or 8; using " << valid << " for " << n << ".");
  }
  if (valid != this->NumberOfMoments)
  {
    this->NumberOfMoments = valid;
    this->Modified();
  }
}

//------------------------------------------------------------------------------
vtkImageData* vtkAPCVolumeMapper::GetLastImage()
{
  return this->Internal->Image;
}

double vtkAPCVolumeMapper::GetLastSampleDistance() const
{
  return this->Internal->LastSpacing;
}

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::ReleaseGraphicsResources(vtkWindow*) {}

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::Render(vtkRenderer* ren, vtkVolume* vol)
{
  Internals& internal = *this->Internal;
  int width = 0;
  int height = 0;
  int x0 = 0;
  int y0 = 0;
  ren->GetTiledSizeAndOrigin(&width, &height, &x0, &y0);
  internal.Image->Initialize();
  if (width < 1 || height < 1)
  {
    return;
  }

  vtkUnstructuredGridBase* input = this->GetInput();
  if (!input)
  {
    vtkErrorMacro("No vtkUnstructuredGrid input: nothing to render.");
    return;
  }
  if (input->GetNumberOfCells() == 0)
  {
    return; // an empty piece renders nothing, silently
  }

  // Rebuild the ray marcher's mesh only when the data or the scalar selection changed.
  int cellFlag = 0;
  vtkDataArray* scalars = vtkAbstractMapper::GetScalars(
    input, this->ScalarMode, this->ArrayAccessMode, this->ArrayId, this->ArrayName, cellFlag);
  if (!scalars)
  {
    vtkErrorMacro("The input has no scalars to render (ScalarMode "
      << this->GetScalarModeAsString() << ", array "
      << (this->ArrayName ? this->ArrayName : "<none>") << ").");
    return;
  }
  internal.Clock = StageClock();
  std::ostringstream key;
  key << scalars << ' ' << scalars->GetMTime() << ' ' << cellFlag;
  if (!internal.MeshValid || internal.MeshInputTime < input->GetMTime() ||
    internal.MeshScalarKey != key.str())
  {
    const bool built = this->BuildMesh(input, scalars, cellFlag == 1);
    internal.Clock.Lap("mesh");
    if (!built)
    {
      return;
    }
    internal.MeshInputTime = input->GetMTime();
    internal.MeshScalarKey = key.str();
  }
  if (internal.Mesh.GetNumberOfCells() == 0)
  {
    return;
  }
  this->RenderFrame(ren, vol, width, height, x0, y0);
}

//------------------------------------------------------------------------------
double vtkAPCVolumeMapper::GetLastStageSeconds(const char* stage) const
{
  double seconds = 0.0;
  for (const auto& entry : this->Internal->Clock.Seconds)
  {
    if (!stage || entry.first == stage)
    {
      seconds += entry.second;
    }
  }
  return seconds;
}

//------------------------------------------------------------------------------
bool vtkAPCVolumeMapper::BuildMesh(
  vtkUnstructuredGridBase* input, vtkDataArray* scalars, bool cellData)
{
  Internals& internal = *this->Internal;
  std::string message;
  internal.MeshValid = apc::CellMeshFromVTK(input, scalars, cellData, internal.Mesh, message);
  if (!message.empty())
  {
    vtkErrorMacro(<< message);
  }
  return internal.MeshValid;
}

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::RenderFrame(
  vtkRenderer* ren, vtkVolume* vol, int width, int height, int x0, int y0)
{
  Internals& internal = *this->Internal;
  const std::array<double, 6>& bounds = internal.Mesh.GetBounds();
  const double diagonal = std::sqrt((bounds[1] - bounds[0]) * (bounds[1] - bounds[0]) +
    (bounds[3] - bounds[2]) * (bounds[3] - bounds[2]) +
    (bounds[5] - bounds[4]) * (bounds[5] - bounds[4]));
  const double spacing = this->SampleDistance > 0 ? this->SampleDistance : diagonal / 256.0;
  internal.LastSpacing = spacing;
  if (!(spacing > 0))
  {
    return; // a mesh with no extent
  }

  // Transfer function tables over the union of the colour and opacity ranges.
  vtkVolumeProperty* property = vol->GetProperty();
  vtkPiecewiseFunction* opacity = property->GetScalarOpacity(0);
  double range[2];
  opacity->GetRange(range);
  std::vector<std::array<float, 3>> colours(kTableSize);
  std::vector<double> rgb(3 * kTableSize);
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
  for (int i = 0; i < kTableSize; ++i)
  {
    colours[i] = { static_cast<float>(rgb[3 * i]), static_cast<float>(rgb[3 * i + 1]),
      static_cast<float>(rgb[3 * i + 2]) };
  }
  std::vector<double> alphas(kTableSize);
  opacity->GetTable(range[0], range[1], kTableSize, alphas.data());
  const apc::TransferTable table(
    range[0], range[1], colours, alphas, spacing, property->GetScalarOpacityUnitDistance(0));

  // The camera as VTK sees it, and the opaque depth: rays end where geometry is.
  vtkCamera* cam = ren->GetActiveCamera();
  double clip[2];
  cam->GetClippingRange(clip);
  double viewAngle = cam->GetViewAngle();
  if (cam->GetUseHorizontalViewAngle())
  {
    const double pi = 3.14159265358979323846;
    viewAngle =
      2.0 * std::atan(std::tan(0.5 * viewAngle * pi / 180.0) * height / width) * 180.0 / pi;
  }
  const apc::RayCamera camera(
    { cam->GetPosition()[0], cam->GetPosition()[1], cam->GetPosition()[2] },
    { cam->GetFocalPoint()[0], cam->GetFocalPoint()[1], cam->GetFocalPoint()[2] },
    { cam->GetViewUp()[0], cam->GetViewUp()[1], cam->GetViewUp()[2] }, viewAngle,
    cam->GetParallelProjection() != 0, cam->GetParallelScale(), width, height, clip[0], clip[1]);
  const size_t pixels = static_cast<size_t>(width) * height;
  std::vector<float> depth(pixels, 1.0f);
  vtkRenderWindow* window = ren->GetRenderWindow();
  window->GetZbufferData(x0, y0, x0 + width - 1, y0 + height - 1, depth.data());
  std::vector<float> rayEnds(pixels);
  for (int j = 0; j < height; ++j)
  {
    for (int i = 0; i < width; ++i)
    {
      const size_t p = static_cast<size_t>(j) * width + i;
      rayEnds[p] = static_cast<float>(camera.DistanceFromDepth(i, j, depth[p]));
    }
  }

  apc::VolumeRayMarcher& marcher = internal.Marcher;
  marcher.SetNumberOfThreads(this->NumberOfThreads);
  marcher.SetMesh(&internal.Mesh);
  marcher.SetView(camera, rayEnds.data());
  StageClock& clock = internal.Clock;
  clock.Lap("setup");

  std::vector<float> rgba(4 * pixels, 0.0f);
  std::vector<double> moments;
  std::vector<double> colourSums;
  int64_t samples = 0;
  if (this->Mode == EXACT)
  {
    marcher.RenderExact(table, rgba.data());
    samples = marcher.GetLastSampleCount();
    clock.Lap("exact");
  }
  else
  {
    double tmin = 0;
    double tmax = 0;
    camera.DistanceRange(bounds, tmin, tmax);
    const apc::LogDepthWarp warp(std::max(tmin, clip[0]), tmax);
    switch (this->NumberOfMoments)
    {
      case 6:
        RenderMBOIT<6>(marcher, table, warp, this->Overestimation, this->MomentBias,
          this->ResolveMode, moments, colourSums, rgba, samples, clock);
        break;
      case 8:
        RenderMBOIT<8>(marcher, table, warp, this->Overestimation, this->MomentBias,
          this->ResolveMode, moments, colourSums, rgba, samples, clock);
        break;
      default:
        RenderMBOIT<4>(marcher, table, warp, this->Overestimation, this->MomentBias,
          this->ResolveMode, moments, colourSums, rgba, samples, clock);
    }
  }

  // Float images of this frame.
  vtkImageData* image = internal.Image;
  image->SetDimensions(width, height, 1);
  auto addArray = [&](const char* name, int components, auto begin, auto end)
  {
    vtkNew<vtkFloatArray> array;
    array->SetName(name);
    array->SetNumberOfComponents(components);
    array->SetNumberOfTuples(static_cast<vtkIdType>(pixels));
    std::copy(begin, end, array->GetPointer(0));
    image->GetPointData()->AddArray(array);
  };
  addArray("RGBA", 4, rgba.begin(), rgba.end());
  if (!moments.empty())
  {
    addArray("Moments", this->NumberOfMoments + 1, moments.begin(), moments.end());
    addArray("ColourSums", 4, colourSums.begin(), colourSums.end());
  }
  if (this->ComputeSegmentCount)
  {
    std::vector<int32_t> counts(pixels, 0);
    marcher.CountSegments(counts.data());
    vtkNew<vtkIntArray> array;
    array->SetName("SegmentCount");
    array->SetNumberOfTuples(static_cast<vtkIdType>(pixels));
    std::copy(counts.begin(), counts.end(), array->GetPointer(0));
    image->GetPointData()->AddArray(array);
  }
  if (this->ComputeSegmentCount)
  {
    clock.Lap("segments");
  }
  vtkNew<vtkDoubleArray> sampleCount;
  sampleCount->SetName("SampleCount");
  sampleCount->InsertNextValue(static_cast<double>(samples));
  image->GetFieldData()->AddArray(sampleCount);

  // Blend over the opaque image. VTK blends straight (non-premultiplied) colour.
  std::vector<float> straight(4 * pixels);
  for (size_t p = 0; p < pixels; ++p)
  {
    const float a = rgba[4 * p + 3];
    const float inv = a > 0 ? 1.0f / a : 0.0f;
    for (int c = 0; c < 3; ++c)
    {
      straight[4 * p + c] = std::min(1.0f, rgba[4 * p + c] * inv);
    }
    straight[4 * p + 3] = std::min(1.0f, std::max(0.0f, a));
  }
  window->SetRGBAPixelData(
    x0, y0, x0 + width - 1, y0 + height - 1, straight.data(), window->GetDoubleBuffer() ? 0 : 1, 1);
}

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Mode: " << (this->Mode == EXACT ? "EXACT" : "MBOIT") << "\n";
  os << indent << "NumberOfMoments: " << this->NumberOfMoments << "\n";
  os << indent << "Overestimation: " << this->Overestimation << "\n";
  os << indent << "MomentBias: " << this->MomentBias << "\n";
  os << indent << "ResolveMode: " << (this->ResolveMode == PAPER_SUM ? "PAPER_SUM" : "RENORMALISED")
     << "\n";
  os << indent << "SampleDistance: " << this->SampleDistance << "\n";
  os << indent << "NumberOfThreads: " << this->NumberOfThreads << "\n";
  os << indent << "ComputeSegmentCount: " << this->ComputeSegmentCount << "\n";
}
