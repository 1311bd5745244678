// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAPCVolumeMapper.h"

#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkRenderer.h"
#include "vtkVolume.h"

#include "apcFrameEngine.h"
#include "apcImageOutput.h"
#include "apcMomentParameters.h"
#include "apcResolve.h"

#include <vector>

vtkStandardNewMacro(vtkAPCVolumeMapper);

struct vtkAPCVolumeMapper::Internals
{
  apc::FrameEngine Engine;
  vtkNew<vtkImageData> Image;
  // Kept from frame to frame: fresh buffers of this size (~80 MB at 1024^2) cost more in
  // page faults than the gear teeth's whole second pass.
  std::vector<float> RGBA;
  std::vector<double> Moments;
  std::vector<double> ColourSums;
  std::vector<int> Segments;
};

//------------------------------------------------------------------------------
vtkAPCVolumeMapper::vtkAPCVolumeMapper()
  : Overestimation(apc::kDefaultOverestimation)
  , MomentBias(apc::kUseDefaultMomentBias)
  , Internal(new Internals)
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

apc::MomentParameters vtkAPCVolumeMapper::GetMomentParameters() const
{
  apc::MomentParameters parameters;
  parameters.Moments = this->NumberOfMoments;
  parameters.Overestimation = this->Overestimation;
  parameters.Bias = this->MomentBias;
  parameters.Resolve = this->ResolveMode == PAPER_SUM ? apc::ResolveMode::PaperSum
    : this->ResolveMode == HYBRID                     ? apc::ResolveMode::Hybrid
                                                      : apc::ResolveMode::Renormalised;
  return parameters;
}

apc::FrameEngine* vtkAPCVolumeMapper::GetFrameEngine()
{
  return &this->Internal->Engine;
}

//------------------------------------------------------------------------------
vtkImageData* vtkAPCVolumeMapper::GetLastImage()
{
  return this->Internal->Image;
}

double vtkAPCVolumeMapper::GetLastSampleDistance() const
{
  return this->Internal->Engine.GetSampleDistance();
}

double vtkAPCVolumeMapper::GetLastStageSeconds(const char* stage) const
{
  return this->Internal->Engine.GetClock().Get(stage);
}

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::Render(vtkRenderer* ren, vtkVolume* vol)
{
  apc::FrameEngine& engine = this->Internal->Engine;
  engine.BeginFrame();
  const bool usable = engine.UpdateInput(this);
  if (engine.TakeNewInputReport())
  {
    engine.GetInputReport().Emit(this);
  }
  // Only the pixels whose rays can meet the cells are rendered: the buffers follow the
  // data's footprint on screen.
  apc::ImageSetup image = apc::ImageSetup::FullQuality(ren);
  double bounds[6];
  if (usable && engine.GetLocalBounds(bounds))
  {
    image.Crop = apc::ScreenRectOf(ren, bounds, image.Width, image.Height);
  }
  if (!usable || !engine.Prepare(this, ren, vol, nullptr, nullptr, image) ||
    engine.GetNumberOfCells() == 0)
  {
    this->Internal->Image->Initialize();
    return;
  }
  const size_t pixels = engine.GetPixels();
  std::vector<float>& rgba = this->Internal->RGBA;
  std::vector<double>& moments = this->Internal->Moments;
  std::vector<double>& colourSums = this->Internal->ColourSums;
  std::vector<int>& segments = this->Internal->Segments;
  rgba.assign(4 * pixels, 0.0f);
  moments.clear();
  colourSums.clear();
  segments.clear();
  const apc::MomentParameters parameters = this->GetMomentParameters();
  if (this->Mode == EXACT)
  {
    engine.RenderExact(rgba.data());
  }
  else
  {
    moments.assign(pixels * (parameters.Moments + 1), 0.0);
    colourSums.assign(pixels * 4, 0.0);
    engine.RenderMoments(parameters, moments.data());
    engine.RenderColour(parameters, moments.data(), colourSums.data());
    apc::ResolveImage(parameters.Resolve, pixels, moments.data(), parameters.Moments + 1,
      colourSums.data(), rgba.data());
    engine.GetClock().Lap("resolve");
  }
  if (this->ComputeSegmentCount)
  {
    segments.assign(pixels, 0);
    engine.CountSegments(segments.data());
  }
  apc::FloatImages images;
  images.RGBA = rgba.data();
  images.Moments = moments.empty() ? nullptr : moments.data();
  images.MomentComponents = parameters.Moments + 1;
  images.ColourSums = colourSums.empty() ? nullptr : colourSums.data();
  images.SegmentCount = segments.empty() ? nullptr : segments.data();
  images.SampleCount = engine.GetSampleCount();
  const apc::ScreenRect& crop = engine.GetCrop();
  apc::StoreFloatImages(this->Internal->Image, image.Width, image.Height, crop, images);
  apc::BlendIntoWindow(ren, engine.GetX0() + crop.I0, engine.GetY0() + crop.J0, engine.GetWidth(),
    engine.GetHeight(), engine.GetWidth(), engine.GetHeight(), rgba.data());
  engine.GetClock().Lap("blend");
}

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Mode: " << (this->Mode == EXACT ? "EXACT" : "MBOIT") << "\n";
  os << indent << "NumberOfMoments: " << this->NumberOfMoments << "\n";
  os << indent << "Overestimation: " << this->Overestimation << "\n";
  os << indent << "MomentBias: " << this->MomentBias << "\n";
  os << indent << "ResolveMode: "
     << (this->ResolveMode == PAPER_SUM   ? "PAPER_SUM"
            : this->ResolveMode == HYBRID ? "HYBRID"
                                          : "RENORMALISED")
     << "\n";
  os << indent << "SampleDistance: " << this->SampleDistance << "\n";
  os << indent << "LatticeJitter: " << this->LatticeJitter << "\n";
  os << indent << "SampleCacheSize: " << this->SampleCacheSize << " MiB\n";
  os << indent << "NumberOfThreads: " << this->NumberOfThreads << "\n";
  os << indent << "ComputeSegmentCount: " << this->ComputeSegmentCount << "\n";
  os << indent << "VectorMode: " << this->VectorMode << "\n";
  os << indent << "VectorComponent: " << this->VectorComponent << "\n";
}
