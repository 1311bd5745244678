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
#include "apcSettingChecks.h"
#include "apcVolumeSettings.h"

#include <algorithm>
#include <exception>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkAPCVolumeMapper);

struct vtkAPCVolumeMapper::Internals
{
  apc::VolumeSettings Settings; // every property of the mapper, with its default
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
  : Internal(new Internals)
{
}

vtkAPCVolumeMapper::~vtkAPCVolumeMapper() = default;

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::SetMode(int mode)
{
  apc::Assign(this, this->Internal->Settings.Exact,
    apc::CheckedSetting(this, "Mode", mode, int(EXACT), int(MBOIT), "0 EXACT, 1 MBOIT") == EXACT);
}

int vtkAPCVolumeMapper::GetMode() const
{
  return this->Internal->Settings.Exact ? EXACT : MBOIT;
}

void vtkAPCVolumeMapper::SetNumberOfMoments(int n)
{
  const int valid = n <= 4 ? 4 : (n <= 6 ? 6 : 8);
  if (!apc::IsSupportedMoments(n))
  {
    vtkWarningMacro(
      "NumberOfMoments must be 4, 6 or 8; " << n << " was given, " << valid << " is used.");
  }
  apc::Assign(this, this->Internal->Settings.Moments.Moments, valid);
}

int vtkAPCVolumeMapper::GetNumberOfMoments() const
{
  return this->Internal->Settings.Moments.Moments;
}

void vtkAPCVolumeMapper::SetOverestimation(double beta)
{
  apc::Assign(this, this->Internal->Settings.Moments.Overestimation,
    apc::CheckedSetting(this, "Overestimation", beta, 0.0, 1.0));
}

double vtkAPCVolumeMapper::GetOverestimation() const
{
  return this->Internal->Settings.Moments.Overestimation;
}

void vtkAPCVolumeMapper::SetMomentBias(double bias)
{
  apc::Assign(this, this->Internal->Settings.Moments.Bias,
    apc::CheckedSetting(
      this, "MomentBias", bias, -1.0, 1.0, "negative: the published constant for the moments"));
}

double vtkAPCVolumeMapper::GetMomentBias() const
{
  return this->Internal->Settings.Moments.Bias;
}

void vtkAPCVolumeMapper::SetResolveMode(int mode)
{
  const int clamped = apc::CheckedSetting(this, "ResolveMode", mode, int(RENORMALISED), int(HYBRID),
    "0 RENORMALISED, 1 PAPER_SUM, 2 HYBRID");
  apc::Assign(this, this->Internal->Settings.Moments.Resolve,
    clamped == PAPER_SUM  ? apc::ResolveMode::PaperSum
      : clamped == HYBRID ? apc::ResolveMode::Hybrid
                          : apc::ResolveMode::Renormalised);
}

int vtkAPCVolumeMapper::GetResolveMode() const
{
  switch (this->Internal->Settings.Moments.Resolve)
  {
    case apc::ResolveMode::PaperSum:
      return PAPER_SUM;
    case apc::ResolveMode::Hybrid:
      return HYBRID;
    default:
      return RENORMALISED;
  }
}

void vtkAPCVolumeMapper::SetSampleDistance(double distance)
{
  apc::Assign(this, this->Internal->Settings.SampleDistance,
    apc::CheckedSetting(this, "SampleDistance", distance, 0.0, VTK_DOUBLE_MAX,
      "0 picks the mean cell size, at least diagonal / 192"));
}

double vtkAPCVolumeMapper::GetSampleDistance() const
{
  return this->Internal->Settings.SampleDistance;
}

void vtkAPCVolumeMapper::SetLatticeJitter(bool jitter)
{
  apc::Assign(this, this->Internal->Settings.LatticeJitter, jitter);
}

bool vtkAPCVolumeMapper::GetLatticeJitter() const
{
  return this->Internal->Settings.LatticeJitter;
}

void vtkAPCVolumeMapper::SetSampleEndWeights(int mode)
{
  // A boolean true is 1, all ends.
  apc::Assign(this, this->Internal->Settings.SampleEndWeights,
    apc::CheckedSetting(this, "SampleEndWeights", mode, int(END_WEIGHTS_OFF),
      int(END_WEIGHTS_BOUNDARY), "0 off, 1 all ends, 2 the ends on the mesh's boundary"));
}

int vtkAPCVolumeMapper::GetSampleEndWeights() const
{
  return this->Internal->Settings.SampleEndWeights;
}

void vtkAPCVolumeMapper::SetStopWhereOpaque(bool stop)
{
  apc::Assign(this, this->Internal->Settings.StopWhereOpaque, stop);
}

bool vtkAPCVolumeMapper::GetStopWhereOpaque() const
{
  return this->Internal->Settings.StopWhereOpaque;
}

void vtkAPCVolumeMapper::SetSampleCacheSize(int megabytes)
{
  apc::Assign(this, this->Internal->Settings.SampleCacheMiB,
    apc::CheckedSetting(this, "SampleCacheSize", megabytes, -1, VTK_INT_MAX,
      "MiB per process; 0 turns it off, -1 takes a quarter of the node's memory shared among its "
      "processes"));
}

int vtkAPCVolumeMapper::GetSampleCacheSize() const
{
  return this->Internal->Settings.SampleCacheMiB;
}

void vtkAPCVolumeMapper::SetNumberOfThreads(int threads)
{
  apc::Assign(this, this->Internal->Settings.NumberOfThreads,
    apc::CheckedSetting(
      this, "NumberOfThreads", threads, 0, 1024, "0 = this process's share of its node"));
}

int vtkAPCVolumeMapper::GetNumberOfThreads() const
{
  return this->Internal->Settings.NumberOfThreads;
}

void vtkAPCVolumeMapper::SetComputeSegmentCount(bool compute)
{
  apc::Assign(this, this->Internal->Settings.ComputeSegmentCount, compute);
}

bool vtkAPCVolumeMapper::GetComputeSegmentCount() const
{
  return this->Internal->Settings.ComputeSegmentCount;
}

void vtkAPCVolumeMapper::SetVectorMode(int mode)
{
  apc::Assign(this, this->Internal->Settings.Scalars.VectorMode,
    apc::CheckedSetting(this, "VectorMode", mode, int(vtkScalarsToColors::MAGNITUDE),
      int(vtkScalarsToColors::RGBCOLORS), "0 MAGNITUDE, 1 COMPONENT, 2 RGBCOLORS"));
}

int vtkAPCVolumeMapper::GetVectorMode() const
{
  return this->Internal->Settings.Scalars.VectorMode;
}

void vtkAPCVolumeMapper::SetVectorComponent(int component)
{
  apc::Assign(this, this->Internal->Settings.Scalars.VectorComponent, component);
}

int vtkAPCVolumeMapper::GetVectorComponent() const
{
  return this->Internal->Settings.Scalars.VectorComponent;
}

apc::VolumeSettings vtkAPCVolumeMapper::GetVolumeSettings() const
{
  apc::VolumeSettings settings = this->Internal->Settings;
  // vtkAbstractMapper's getters are not const.
  auto* self = const_cast<vtkAPCVolumeMapper*>(this);
  apc::ScalarChoice& scalars = settings.Scalars;
  scalars.ScalarMode = self->GetScalarMode();
  scalars.ArrayAccessMode = self->GetArrayAccessMode();
  scalars.ArrayId = self->GetArrayId();
  scalars.ArrayName = self->GetArrayName() ? self->GetArrayName() : "";
  return settings;
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

vtkIdType vtkAPCVolumeMapper::GetLastRenderedPixels() const
{
  return static_cast<vtkIdType>(this->Internal->Engine.GetPixels());
}

double vtkAPCVolumeMapper::GetLastStageSeconds(const char* stage) const
{
  return this->Internal->Engine.GetClock().Get(stage);
}

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::Render(vtkRenderer* ren, vtkVolume* vol)
{
  // One process alone has no collective to agree a failure in, but its memory can still run
  // out (the conversion, the sample cache, the images): the frame is skipped with an error
  // naming the step, as the composite pass skips it on every rank, never a crash.
  const char* step = "reading the input";
  try
  {
    this->RenderAlone(ren, vol, step);
  }
  catch (const std::exception& e)
  {
    this->Internal->Image->Initialize();
    vtkErrorMacro(<< "APC frame skipped: " << step << " failed: " << e.what());
  }
}

//------------------------------------------------------------------------------
void vtkAPCVolumeMapper::RenderAlone(vtkRenderer* ren, vtkVolume* vol, const char*& step)
{
  apc::FrameEngine& engine = this->Internal->Engine;
  const apc::VolumeSettings settings = this->GetVolumeSettings();
  engine.BeginFrame(settings);
  const bool usable = engine.UpdateInput(this->GetInput(), this);
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
  step = "the volume's set-up";
  if (!usable || !engine.Prepare(ren, vol->GetProperty(), nullptr, 0, 0, nullptr, image) ||
    engine.GetNumberOfCells() == 0)
  {
    this->Internal->Image->Initialize();
    return;
  }
  const std::string note = engine.TakeSpacingNote();
  if (!note.empty())
  {
    vtkWarningMacro(<< note);
  }
  const size_t pixels = engine.GetPixels();
  std::vector<float>& rgba = this->Internal->RGBA;
  std::vector<double>& moments = this->Internal->Moments;
  std::vector<double>& colourSums = this->Internal->ColourSums;
  std::vector<int>& segments = this->Internal->Segments;
  step = "the images";
  rgba.assign(4 * pixels, 0.0f);
  moments.clear();
  colourSums.clear();
  segments.clear();
  const apc::MomentParameters& parameters = settings.Moments;
  if (settings.Exact)
  {
    step = "the exact image";
    engine.RenderExact(rgba.data());
  }
  else
  {
    moments.assign(pixels * (parameters.Moments + 1), 0.0);
    colourSums.assign(pixels * 4, 0.0);
    step = "pass 1";
    // One process, one volume: tiles no ray of which nears the threshold skip the stop.
    engine.SetOpaqueStopAlone(true);
    engine.RenderMoments(parameters, moments.data());
    if (engine.StopsWhereOpaque(parameters))
    {
      // One process: its own profile is the whole ray's (the same cut the pass makes).
      step = "the opaque cut";
      engine.ApplyOpaqueCut(parameters, engine.GetOpaqueProfile().data(), moments.data(), {});
    }
    step = "pass 2";
    engine.RenderColour(parameters, moments.data(), colourSums.data());
    apc::ResolveImage(parameters.Resolve, pixels, moments.data(), parameters.Moments + 1,
      colourSums.data(), rgba.data());
    engine.GetClock().Lap("resolve");
  }
  if (settings.ComputeSegmentCount)
  {
    step = "the segment count";
    segments.assign(pixels, 0);
    engine.CountSegments(segments.data());
  }
  step = "the output images";
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
  const apc::VolumeSettings& settings = this->Internal->Settings;
  os << indent << "Mode: " << (settings.Exact ? "EXACT" : "MBOIT") << "\n";
  os << indent << "NumberOfMoments: " << settings.Moments.Moments << "\n";
  os << indent << "Overestimation: " << settings.Moments.Overestimation << "\n";
  os << indent << "MomentBias: " << settings.Moments.Bias << "\n";
  const int resolve = this->GetResolveMode();
  os << indent << "ResolveMode: "
     << (resolve == PAPER_SUM   ? "PAPER_SUM"
            : resolve == HYBRID ? "HYBRID"
                                : "RENORMALISED")
     << "\n";
  os << indent << "SampleDistance: " << settings.SampleDistance << "\n";
  os << indent << "LatticeJitter: " << settings.LatticeJitter << "\n";
  os << indent << "SampleEndWeights: " << settings.SampleEndWeights << "\n";
  os << indent << "StopWhereOpaque: " << settings.StopWhereOpaque << "\n";
  os << indent << "SampleCacheSize: " << settings.SampleCacheMiB << " MiB\n";
  os << indent << "NumberOfThreads: " << settings.NumberOfThreads << "\n";
  os << indent << "ComputeSegmentCount: " << settings.ComputeSegmentCount << "\n";
  os << indent << "VectorMode: " << settings.Scalars.VectorMode << "\n";
  os << indent << "VectorComponent: " << settings.Scalars.VectorComponent << "\n";
}
