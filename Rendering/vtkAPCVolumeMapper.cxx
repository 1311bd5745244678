// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAPCVolumeMapper.h"

#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkOpenGLQuadHelper.h"
#include "vtkOpenGLRenderUtilities.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkOpenGLShaderCache.h"
#include "vtkOpenGLState.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkShaderProgram.h"
#include "vtkTextureObject.h"
#include "vtkUnstructuredGridBase.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"
#include "vtk_glew.h"

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
apc::MomentSettings<N> Settings(double overestimation, double bias)
{
  apc::MomentSettings<N> settings;
  settings.Overestimation = overestimation;
  if (bias >= 0)
  {
    settings.Bias = bias;
  }
  return settings;
}

std::unique_ptr<apc::TransferTable> MakeTable(vtkVolumeProperty* property, double spacing)
{
  // Tables over the union of the colour and opacity ranges.
  vtkPiecewiseFunction* opacity = property->GetScalarOpacity(0);
  double range[2];
  opacity->GetRange(range);
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
  std::vector<std::array<float, 3>> colours(kTableSize);
  for (int i = 0; i < kTableSize; ++i)
  {
    colours[i] = { static_cast<float>(rgb[3 * i]), static_cast<float>(rgb[3 * i + 1]),
      static_cast<float>(rgb[3 * i + 2]) };
  }
  std::vector<double> alphas(kTableSize);
  opacity->GetTable(range[0], range[1], kTableSize, alphas.data());
  return std::unique_ptr<apc::TransferTable>(new apc::TransferTable(
    range[0], range[1], colours, alphas, spacing, property->GetScalarOpacityUnitDistance(0)));
}

std::unique_ptr<apc::RayCamera> MakeCamera(vtkRenderer* ren, int width, int height)
{
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
  const double* p = cam->GetPosition();
  const double* f = cam->GetFocalPoint();
  const double* u = cam->GetViewUp();
  return std::unique_ptr<apc::RayCamera>(
    new apc::RayCamera({ p[0], p[1], p[2] }, { f[0], f[1], f[2] }, { u[0], u[1], u[2] }, viewAngle,
      cam->GetParallelProjection() != 0, cam->GetParallelScale(), width, height, clip[0], clip[1]));
}
}

struct vtkAPCVolumeMapper::Internals
{
  apc::CellMesh Mesh;
  bool MeshValid = false;
  vtkMTimeType MeshInputTime = 0;
  std::string MeshScalarKey;
  apc::VolumeRayMarcher Marcher;

  // The prepared frame.
  bool FrameReady = false;
  int Width = 0;
  int Height = 0;
  int X0 = 0;
  int Y0 = 0;
  double Spacing = 0.0;
  double DepthRange[2] = { 0.0, 0.0 };
  std::unique_ptr<apc::TransferTable> Table;
  std::unique_ptr<apc::RayCamera> Camera;
  std::unique_ptr<apc::LogDepthWarp> Warp;
  int64_t Samples = 0;

  vtkNew<vtkImageData> Image;
  StageClock Clock;

  size_t Pixels() const { return static_cast<size_t>(this->Width) * this->Height; }
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
  return this->Internal->Spacing;
}

int vtkAPCVolumeMapper::GetFrameWidth() const
{
  return this->Internal->Width;
}

int vtkAPCVolumeMapper::GetFrameHeight() const
{
  return this->Internal->Height;
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
void vtkAPCVolumeMapper::ReleaseGraphicsResources(vtkWindow*) {}

//------------------------------------------------------------------------------
bool vtkAPCVolumeMapper::UpdateInput()
{
  Internals& internal = *this->Internal;
  vtkUnstructuredGridBase* input = this->GetInput();
  if (!input || input->GetNumberOfCells() == 0)
  {
    // An empty piece renders nothing, silently: in parallel that is a normal rank.
    internal.Mesh = apc::CellMesh();
    internal.Mesh.Finalize();
    internal.MeshValid = true;
    internal.MeshScalarKey.clear();
    return true;
  }
  int cellFlag = 0;
  vtkDataArray* scalars = vtkAbstractMapper::GetScalars(
    input, this->ScalarMode, this->ArrayAccessMode, this->ArrayId, this->ArrayName, cellFlag);
  if (!scalars)
  {
    vtkErrorMacro("The input has no scalars to render (ScalarMode "
      << this->GetScalarModeAsString() << ", array "
      << (this->ArrayName ? this->ArrayName : "<none>") << ").");
    internal.MeshValid = false;
    return false;
  }
  // Rebuild the ray marcher's mesh only when the data or the scalar selection changed.
  std::ostringstream key;
  key << scalars << ' ' << scalars->GetMTime() << ' ' << cellFlag;
  if (internal.MeshValid && internal.MeshInputTime >= input->GetMTime() &&
    internal.MeshScalarKey == key.str())
  {
    return true;
  }
  std::string message;
  internal.MeshValid = apc::CellMeshFromVTK(input, scalars, cellFlag == 1, internal.Mesh, message);
  if (!message.empty())
  {
    vtkErrorMacro(<< message);
  }
  internal.MeshInputTime = input->GetMTime();
  internal.MeshScalarKey = key.str();
  internal.Clock.Lap("mesh");
  return internal.MeshValid;
}

//------------------------------------------------------------------------------
bool vtkAPCVolumeMapper::GetLocalBounds(double bounds[6]) const
{
  if (!this->Internal->MeshValid || this->Internal->Mesh.GetNumberOfCells() == 0)
  {
    return false;
  }
  const auto& b = this->Internal->Mesh.GetBounds();
  std::copy(b.begin(), b.end(), bounds);
  return true;
}

//------------------------------------------------------------------------------
bool vtkAPCVolumeMapper::PrepareFrame(vtkRenderer* ren, vtkVolume* vol, const double* globalBounds,
  const float* depthBuffer, double globalSampleDistance)
{
  Internals& internal = *this->Internal;
  internal.Clock = StageClock();
  internal.FrameReady = false;
  internal.Image->Initialize();
  ren->GetTiledSizeAndOrigin(&internal.Width, &internal.Height, &internal.X0, &internal.Y0);
  if (internal.Width < 1 || internal.Height < 1 || !this->UpdateInput())
  {
    return false;
  }

  // Everything that must agree between processes comes from the global bounds: the sample
  // spacing (the lattice) and the depth range of the warp (the moments' axis).
  std::array<double, 6> bounds = internal.Mesh.GetBounds();
  if (globalBounds)
  {
    std::copy(globalBounds, globalBounds + 6, bounds.begin());
  }
  if (!(bounds[0] <= bounds[1] && bounds[2] <= bounds[3] && bounds[4] <= bounds[5]))
  {
    return false; // no cells anywhere
  }
  const double diagonal = std::sqrt((bounds[1] - bounds[0]) * (bounds[1] - bounds[0]) +
    (bounds[3] - bounds[2]) * (bounds[3] - bounds[2]) +
    (bounds[5] - bounds[4]) * (bounds[5] - bounds[4]));
  internal.Spacing = globalSampleDistance > 0
    ? globalSampleDistance
    : (this->SampleDistance > 0 ? this->SampleDistance : diagonal / 256.0);
  if (!(internal.Spacing > 0))
  {
    return false; // a mesh with no extent
  }
  internal.Table = MakeTable(vol->GetProperty(), internal.Spacing);
  internal.Camera = MakeCamera(ren, internal.Width, internal.Height);
  double clip[2];
  ren->GetActiveCamera()->GetClippingRange(clip);
  double tmin = 0;
  double tmax = 0;
  internal.Camera->DistanceRange(bounds, tmin, tmax);
  internal.DepthRange[0] = std::max(tmin, clip[0]);
  internal.DepthRange[1] = tmax;
  internal.Warp.reset(new apc::LogDepthWarp(internal.DepthRange[0], internal.DepthRange[1]));

  // Rays end at the opaque geometry: the given depth buffer, or this window's.
  const size_t pixels = internal.Pixels();
  std::vector<float> depth;
  if (!depthBuffer)
  {
    depth.assign(pixels, 1.0f);
    ren->GetRenderWindow()->GetZbufferData(internal.X0, internal.Y0,
      internal.X0 + internal.Width - 1, internal.Y0 + internal.Height - 1, depth.data());
    depthBuffer = depth.data();
  }
  std::vector<float> rayEnds(pixels);
  for (int j = 0; j < internal.Height; ++j)
  {
    for (int i = 0; i < internal.Width; ++i)
    {
      const size_t p = static_cast<size_t>(j) * internal.Width + i;
      rayEnds[p] = static_cast<float>(internal.Camera->DistanceFromDepth(i, j, depthBuffer[p]));
    }
  }
  internal.Marcher.SetNumberOfThreads(this->NumberOfThreads);
  internal.Marcher.SetMesh(&internal.Mesh);
  internal.Marcher.SetView(*internal.Camera, rayEnds.data());
  internal.Samples = 0;
  internal.FrameReady = true;
  internal.Clock.Lap("setup");
  return true;
}

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::RenderMoments(double* moments)
{
  Internals& internal = *this->Internal;
  if (!internal.FrameReady)
  {
    return;
  }
  switch (this->NumberOfMoments)
  {
    case 6:
      internal.Marcher.AccumulateMoments<6>(*internal.Table, *internal.Warp, moments);
      break;
    case 8:
      internal.Marcher.AccumulateMoments<8>(*internal.Table, *internal.Warp, moments);
      break;
    default:
      internal.Marcher.AccumulateMoments<4>(*internal.Table, *internal.Warp, moments);
  }
  internal.Samples = internal.Marcher.GetLastSampleCount();
  internal.Clock.Lap("moments");
}

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::RenderColour(const double* moments, double* colourSums)
{
  Internals& internal = *this->Internal;
  if (!internal.FrameReady)
  {
    return;
  }
  const double beta = this->Overestimation;
  const double bias = this->MomentBias;
  switch (this->NumberOfMoments)
  {
    case 6:
      internal.Marcher.AccumulateColour<6>(
        *internal.Table, *internal.Warp, moments, Settings<6>(beta, bias), colourSums);
      break;
    case 8:
      internal.Marcher.AccumulateColour<8>(
        *internal.Table, *internal.Warp, moments, Settings<8>(beta, bias), colourSums);
      break;
    default:
      internal.Marcher.AccumulateColour<4>(
        *internal.Table, *internal.Warp, moments, Settings<4>(beta, bias), colourSums);
  }
  internal.Clock.Lap("colour");
}

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::RenderExactImage(float* rgba)
{
  Internals& internal = *this->Internal;
  if (!internal.FrameReady)
  {
    return;
  }
  internal.Marcher.RenderExact(*internal.Table, rgba);
  internal.Samples = internal.Marcher.GetLastSampleCount();
  internal.Clock.Lap("exact");
}

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::CountSegments(int* counts)
{
  Internals& internal = *this->Internal;
  if (!internal.FrameReady)
  {
    return;
  }
  internal.Marcher.CountSegments(counts);
  internal.Clock.Lap("segments");
}

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::RenderSegments(apc::SegmentImage& segments)
{
  Internals& internal = *this->Internal;
  if (!internal.FrameReady)
  {
    segments.Reset(internal.Width, internal.Height);
    return;
  }
  internal.Marcher.RenderSegments(*internal.Table, segments);
  internal.Samples = internal.Marcher.GetLastSampleCount();
  internal.Clock.Lap("segments");
}

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::ResolveImage(
  const double* moments, const double* colourSums, float* rgba) const
{
  const size_t pixels = this->Internal->Pixels();
  const int stride = this->NumberOfMoments + 1;
  const apc::ResolveMode mode =
    this->ResolveMode == PAPER_SUM ? apc::ResolveMode::PaperSum : apc::ResolveMode::Renormalised;
  for (size_t p = 0; p < pixels; ++p)
  {
    apc::ColourSums sums;
    std::copy(colourSums + 4 * p, colourSums + 4 * p + 4, sums.Data());
    const apc::RGBA out = apc::Resolve(mode, sums, moments[p * stride]);
    for (int c = 0; c < 4; ++c)
    {
      rgba[4 * p + c] = static_cast<float>(out[c]);
    }
  }
  this->Internal->Clock.Lap("resolve");
}

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::BlendIntoWindow(vtkRenderer* ren, const float* rgba)
{
  // A float texture on a viewport quad, blended premultiplied-over into whatever framebuffer
  // is bound: the window's in plain VTK, the one IceT composited into in ParaView (its
  // result is captured from there, so drawing anywhere else would be lost). Float keeps
  // the 8-bit quantisation of glDrawPixels out of the volume's colours.
  Internals& internal = *this->Internal;
  auto* window = vtkOpenGLRenderWindow::SafeDownCast(ren->GetRenderWindow());
  if (!window || internal.Pixels() == 0)
  {
    return;
  }
  vtkNew<vtkTextureObject> texture;
  texture->SetContext(window);
  texture->Create2DFromRaw(internal.Width, internal.Height, 4, VTK_FLOAT,
    const_cast<float*>(rgba)); // only read, despite the signature
  texture->SetMinificationFilter(vtkTextureObject::Nearest);
  texture->SetMagnificationFilter(vtkTextureObject::Nearest);
  std::string fragment = vtkOpenGLRenderUtilities::GetFullScreenQuadFragmentShaderTemplate();
  vtkShaderProgram::Substitute(fragment, "//VTK::FSQ::Decl", "uniform sampler2D volumeImage;");
  vtkShaderProgram::Substitute(
    fragment, "//VTK::FSQ::Impl", "gl_FragData[0] = texture2D(volumeImage, texCoord);");
  {
    vtkOpenGLQuadHelper quad(window,
      vtkOpenGLRenderUtilities::GetFullScreenQuadVertexShader().c_str(), fragment.c_str(), "");
    window->GetShaderCache()->ReadyShaderProgram(quad.Program);
    texture->Activate();
    quad.Program->SetUniformi("volumeImage", texture->GetTextureUnit());
    vtkOpenGLState* state = window->GetState();
    vtkOpenGLState::ScopedglEnableDisable blend(state, GL_BLEND);
    vtkOpenGLState::ScopedglEnableDisable depthTest(state, GL_DEPTH_TEST);
    vtkOpenGLState::ScopedglBlendFuncSeparate blendFunction(state);
    vtkOpenGLState::ScopedglDepthMask depthMask(state);
    vtkOpenGLState::ScopedglViewport viewport(state);
    vtkOpenGLState::ScopedglEnableDisable scissor(state, GL_SCISSOR_TEST);
    state->vtkglEnable(GL_BLEND);
    state->vtkglBlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    state->vtkglDisable(GL_DEPTH_TEST);
    state->vtkglDisable(GL_SCISSOR_TEST);
    state->vtkglDepthMask(GL_FALSE);
    state->vtkglViewport(internal.X0, internal.Y0, internal.Width, internal.Height);
    quad.Render();
    texture->Deactivate();
    quad.ReleaseGraphicsResources(window);
  }
  texture->ReleaseGraphicsResources(window);
  internal.Clock.Lap("blend");
}

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::StoreImages(
  const float* rgba, const double* moments, const double* colourSums, const int* segments)
{
  Internals& internal = *this->Internal;
  vtkImageData* image = internal.Image;
  image->Initialize();
  image->SetDimensions(internal.Width, internal.Height, 1);
  const vtkIdType pixels = static_cast<vtkIdType>(internal.Pixels());
  auto add = [&](auto array, const char* name, int components, const auto* values)
  {
    if (!values)
    {
      return;
    }
    array->SetName(name);
    array->SetNumberOfComponents(components);
    array->SetNumberOfTuples(pixels);
    std::copy(values, values + components * pixels, array->GetPointer(0));
    image->GetPointData()->AddArray(array);
  };
  add(vtkNew<vtkFloatArray>().Get(), "RGBA", 4, rgba);
  add(vtkNew<vtkFloatArray>().Get(), "Moments", this->NumberOfMoments + 1, moments);
  add(vtkNew<vtkFloatArray>().Get(), "ColourSums", 4, colourSums);
  add(vtkNew<vtkIntArray>().Get(), "SegmentCount", 1, segments);
  vtkNew<vtkDoubleArray> sampleCount;
  sampleCount->SetName("SampleCount");
  sampleCount->InsertNextValue(static_cast<double>(internal.Samples));
  image->GetFieldData()->AddArray(sampleCount);
}

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::Render(vtkRenderer* ren, vtkVolume* vol)
{
  if (!this->PrepareFrame(ren, vol, nullptr, nullptr, 0.0) ||
    this->Internal->Mesh.GetNumberOfCells() == 0)
  {
    return;
  }
  const size_t pixels = this->Internal->Pixels();
  std::vector<float> rgba(4 * pixels, 0.0f);
  std::vector<double> moments;
  std::vector<double> colourSums;
  std::vector<int> segments;
  if (this->Mode == EXACT)
  {
    this->RenderExactImage(rgba.data());
  }
  else
  {
    moments.assign(pixels * (this->NumberOfMoments + 1), 0.0);
    colourSums.assign(pixels * 4, 0.0);
    this->RenderMoments(moments.data());
    this->RenderColour(moments.data(), colourSums.data());
    this->ResolveImage(moments.data(), colourSums.data(), rgba.data());
  }
  if (this->ComputeSegmentCount)
  {
    segments.assign(pixels, 0);
    this->CountSegments(segments.data());
  }
  this->StoreImages(rgba.data(), moments.empty() ? nullptr : moments.data(),
    colourSums.empty() ? nullptr : colourSums.data(), segments.empty() ? nullptr : segments.data());
  this->BlendIntoWindow(ren, rgba.data());
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
