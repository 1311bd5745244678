// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAPCCompositePass.h"

#include "vtkCommunicator.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkLogger.h"
#include "vtkMultiProcessController.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkRenderState.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"
#include "vtkVolume.h"

#include "apcAutoMode.h"
#include "apcBoundaryExchange.h"
#include "apcCompositeFrame.h"
#include "apcFrameEngine.h"
#include "apcFrameSettings.h"
#include "apcFrameStart.h"
#include "apcFrameTimings.h"
#include "apcImageOutput.h"
#include "apcNodeThreads.h"
#include "apcSettingChecks.h"
#include "apcStageAgreement.h"
#include "apcTestFailures.h"
#include "apcVolumeSettings.h"

#include <algorithm>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkAPCCompositePass);

struct vtkAPCCompositePass::Internals
{
  apc::FrameSettings Settings; // this process's; every frame agrees on them first
  std::vector<apc::VolumeEntry> Volumes;
  apc::FrameRecord Record;
  apc::MomentBuffers Buffers; // APC mode's, kept between frames
  apc::FrameResult Result;    // emptied every frame, its memory kept (see MomentBuffers)
  int LastMode = -1;
  int LastReduction = 0;
  bool LastInteractive = false;
  apc::AutoMode Auto; // the same on every process: fed only by collectives' results
  bool Opaque = true; // the last APC frame had a pixel at the opaque stop's threshold
  vtkNew<vtkImageData> Image;
  vtkSmartPointer<vtkFloatArray> DelegateDepth; // this frame's, if its delegate gave one
  bool TransferWarned = false; // the display process said that transfer functions differ
  bool SeveralWarned = false;  // ... that the exact modes cannot blend several volumes
  // The default thread count was set from the processes sharing the node (a collective, so
  // done in a frame, which every process renders, and once per controller).
  vtkMultiProcessController* ThreadsSharedFor = nullptr;
  bool ThreadsShared = false;
};

//------------------------------------------------------------------------------
vtkAPCCompositePass::vtkAPCCompositePass()
  : Internal(new Internals)
{
  this->SetController(vtkMultiProcessController::GetGlobalController());
}

vtkAPCCompositePass::~vtkAPCCompositePass()
{
  this->SetController(nullptr);
  this->SetImageFileName(nullptr);
}

//------------------------------------------------------------------------------
void vtkAPCCompositePass::SetController(vtkMultiProcessController* controller)
{
  vtkSetObjectBodyMacro(Controller, vtkMultiProcessController, controller);
}

void vtkAPCCompositePass::AddVolume(vtkVolume* volume)
{
  auto& v = this->Internal->Volumes;
  if (volume &&
    std::none_of(
      v.begin(), v.end(), [volume](const apc::VolumeEntry& e) { return e.Volume == volume; }))
  {
    v.push_back({ volume, std::make_unique<apc::FrameEngine>() });
    this->Modified();
  }
}

void vtkAPCCompositePass::RemoveVolume(vtkVolume* volume)
{
  auto& v = this->Internal->Volumes;
  const auto it = std::find_if(
    v.begin(), v.end(), [volume](const apc::VolumeEntry& e) { return e.Volume == volume; });
  if (it != v.end())
  {
    v.erase(it);
    this->Modified();
  }
}

void vtkAPCCompositePass::RemoveAllVolumes()
{
  this->Internal->Volumes.clear();
  this->Modified();
}

void vtkAPCCompositePass::SetDelegateDepth(vtkFloatArray* depth)
{
  this->Internal->DelegateDepth = depth;
}

int vtkAPCCompositePass::GetNumberOfVolumes() const
{
  return static_cast<int>(this->Internal->Volumes.size());
}

//------------------------------------------------------------------------------
// The settings every process agrees on live in Internal->Settings: their setters and getters,
// each setter checking its value where it enters.
#define APC_FRAME_SETTING(Name, Type, checked)                                                     \
  void vtkAPCCompositePass::Set##Name(Type value)                                                  \
  {                                                                                                \
    apc::Assign(this, this->Internal->Settings.Name, checked);                                     \
  }                                                                                                \
  Type vtkAPCCompositePass::Get##Name() const                                                      \
  {                                                                                                \
    return this->Internal->Settings.Name;                                                          \
  }

APC_FRAME_SETTING(DisplayDepthComposited, bool, value)
APC_FRAME_SETTING(CompositeInDouble, bool, value)
APC_FRAME_SETTING(OpaqueProbeStep, int,
  apc::CheckedSetting(this, "OpaqueProbeStep", value, 0, apc::FrameSettings::MaxOpaqueProbeStep))
APC_FRAME_SETTING(MaxBandPixels, vtkIdType,
  apc::CheckedSetting<vtkIdType>(this, "MaxBandPixels", value, 1, VTK_ID_MAX))
APC_FRAME_SETTING(MaxMessageBytes, vtkIdType,
  apc::CheckedSetting<vtkIdType>(this, "MaxMessageBytes", value, 64, VTK_ID_MAX))
APC_FRAME_SETTING(CompositeMode, int,
  apc::CheckedSetting(
    this, "CompositeMode", value, int(APC), int(AUTO), "0 APC, 1 SEGMENTS, 2 LOCAL_EXACT, 3 AUTO"))
APC_FRAME_SETTING(InteractiveSampleDistanceFactor, double,
  apc::CheckedSetting(this, "InteractiveSampleDistanceFactor", value, 1.0,
    apc::FrameSettings::MaxSampleDistanceFactor, "1 switches it off"))
APC_FRAME_SETTING(InteractiveImageReduction, int,
  apc::CheckedSetting(this, "InteractiveImageReduction", value, 1,
    apc::FrameSettings::MaxImageReduction, "1 switches it off"))
#undef APC_FRAME_SETTING

void vtkAPCCompositePass::SetDisplayProcess(int process)
{
  apc::Assign(this, this->DisplayProcess,
    apc::CheckedSetting(this, "DisplayProcess", process, 0, VTK_INT_MAX));
}

void vtkAPCCompositePass::SetVerbosity(int verbosity)
{
  apc::Assign(this, this->Verbosity, apc::CheckedSetting(this, "Verbosity", verbosity, 0, 1));
}

//------------------------------------------------------------------------------
double vtkAPCCompositePass::GetLastStageSeconds(const char* stage) const
{
  return this->Internal->Record.Clock.Get(stage);
}

double vtkAPCCompositePass::GetLastBytesSent() const
{
  return this->Internal->Record.BytesSent;
}

vtkIdType vtkAPCCompositePass::GetLastMessagesSent() const
{
  return this->Internal->Record.MessagesSent;
}

vtkIdType vtkAPCCompositePass::GetLastSegmentCount() const
{
  return static_cast<vtkIdType>(this->Internal->Record.Segments.Segments);
}

std::vector<double> vtkAPCCompositePass::GetLastRankRenderSeconds() const
{
  return this->Internal->Record.RankRender;
}

vtkAPCCompositePass::Timings vtkAPCCompositePass::GetLastTimings() const
{
  Timings t = apc::TimingsOf(this->Internal->Record);
  t.Mode = this->Internal->LastMode;
  t.ImageReduction = this->Internal->LastReduction;
  return t;
}

vtkIdType vtkAPCCompositePass::GetLastNonEmptyPixels() const
{
  return static_cast<vtkIdType>(this->Internal->Record.Segments.NonEmptyPixels);
}

double vtkAPCCompositePass::GetLastAverageSegmentsPerPixel() const
{
  return this->Internal->Record.Segments.Average();
}

vtkIdType vtkAPCCompositePass::GetLastMaxSegmentsPerPixel() const
{
  return static_cast<vtkIdType>(this->Internal->Record.Segments.MaxPerPixel);
}

bool vtkAPCCompositePass::SamplesPlainLattice(int compositeMode)
{
  return compositeMode == SEGMENTS || compositeMode == LOCAL_EXACT;
}

void vtkAPCCompositePass::GetScreenRectangle(
  vtkRenderer* ren, const double bounds[6], int width, int height, int rectangle[4])
{
  const apc::ScreenRect r = apc::ScreenRectOf(ren, bounds, width, height);
  rectangle[0] = r.I0;
  rectangle[1] = r.J0;
  rectangle[2] = r.I1;
  rectangle[3] = r.J1;
}

vtkIdType vtkAPCCompositePass::GetLastCompositedPixels() const
{
  return this->Internal->Record.Pixels;
}

int vtkAPCCompositePass::GetLastImageReduction() const
{
  return this->Internal->LastReduction;
}

bool vtkAPCCompositePass::GetLastFrameInteractive() const
{
  return this->Internal->LastInteractive;
}

int vtkAPCCompositePass::GetLastCompositeMode() const
{
  return this->Internal->LastMode;
}

vtkIdType vtkAPCCompositePass::GetLastCoveredPixels() const
{
  return this->Internal->Record.CoveredPixels;
}

bool vtkAPCCompositePass::GetLastFrameFailed() const
{
  return this->Internal->Record.Failed;
}

vtkImageData* vtkAPCCompositePass::GetLastImage()
{
  return this->Internal->Image;
}

//------------------------------------------------------------------------------
void vtkAPCCompositePass::Render(const vtkRenderState* s)
{
  this->NumberOfRenderedProps = 0;
  this->Internal->DelegateDepth = nullptr; // only an observer of this frame's event sets it
  if (this->DelegatePass)
  {
    this->DelegatePass->Render(s);
    this->NumberOfRenderedProps += this->DelegatePass->GetNumberOfRenderedProps();
  }
  this->InvokeEvent(DelegateRenderedEvent, s->GetRenderer());
  Internals& internal = *this->Internal;
  internal.Record = apc::FrameRecord();
  internal.LastMode = -1;
  internal.LastReduction = 0;
  internal.LastInteractive = false;
  internal.Record.Clock.Restart();
  internal.Image->Initialize();

  const apc::ProcessGroup group(
    this->Controller, this->DisplayProcess, &internal.Record.Collectives);
  if (!internal.ThreadsShared || internal.ThreadsSharedFor != this->Controller)
  {
    apc::ShareNode(this->Controller);
    internal.ThreadsShared = true;
    internal.ThreadsSharedFor = this->Controller;
  }
  apc::CompositeFrame frame;
  std::vector<vtkVolume*> volumes;
  if (!apc::AgreeOnFrame(this, group, internal.Volumes, internal.Settings, s->GetRenderer(), frame,
        volumes, internal.Record, internal.TransferWarned, internal.Opaque))
  {
    return;
  }
  internal.Record.Pixels = static_cast<vtkIdType>(frame.Rect.Pixels()); // APC: fewer
  frame.KeepFloatImages =
    this->KeepLastImage || (group.IsDisplay() && this->ImageFileName && *this->ImageFileName);
  internal.LastReduction = frame.Reduction();
  internal.LastInteractive = frame.Interactive;
  std::vector<float> depth = apc::ShareDepth(group, frame, internal.DelegateDepth, internal.Record);
  internal.DelegateDepth = nullptr;
  internal.Record.Clock.Lap("depth");
  std::string boundaryProblem;
  if (!apc::ShareBoundaryFaces(group, frame, boundaryProblem) && group.IsDisplay())
  {
    vtkWarningMacro(<< boundaryProblem);
  }
  if (frame.ShareBoundary)
  {
    internal.Record.Clock.Lap("boundary");
  }
  apc::FrameResult& result = internal.Result;
  result.RGBA.clear();
  result.Moments.clear();
  result.ColourSums.clear();
  const bool prepared = apc::PrepareEngines(group, frame, volumes, depth, internal.Record, result);
  depth = std::vector<float>(); // the engines hold their rays' ends
  if (!prepared)
  {
    // Agreed: every process skips the frame before its first compositing collective.
    vtkErrorMacro("APC frame skipped: " << internal.Record.Problem);
    result.RGBA.clear();
    result.Moments.clear();
    result.ColourSums.clear();
    apc::GatherRankTimes(group, internal.Record);
    this->FinishFrame(group, frame, result);
    return;
  }

  const int mode = this->ChooseMode(group, frame);
  internal.LastMode = mode;
  const double before = internal.Record.Clock.Get(nullptr);
  switch (mode)
  {
    case LOCAL_EXACT:
      // Each process's own image (reserved in the set-up); a process whose march throws makes
      // every one give the frame up before the frame's timings are gathered.
      apc::RunAgreedStage(group, "exact", "the local exact image", internal.Record,
        [&]
        {
          apc::ThrowIfFailingForTesting(apc::FailurePoint::LocalExact);
          result.RGBA.assign(4 * frame.RectPixels(), 0.0f);
          for (apc::FrameEngine* engine : frame.Engines)
          {
            engine->RenderExact(result.RGBA.data());
          }
        });
      internal.Record.Clock.Lap("exact");
      break;
    case SEGMENTS:
      apc::RunSegmentCompositing(group, frame, internal.Record, result);
      break;
    default:
      apc::RunMomentCompositing(group, frame, internal.Record, result, internal.Buffers);
      if (!internal.Record.Failed)
      {
        internal.Opaque = internal.Record.OpaquePixels > 0;
      }
  }
  if (internal.Record.Failed)
  {
    // Agreed: every process left the frame at the same point, with nothing to blend.
    vtkErrorMacro("APC frame skipped: " << internal.Record.Problem);
    result.RGBA.clear();
    result.Moments.clear();
    result.ColourSums.clear();
  }
  if (frame.Settings.CompositeMode == AUTO && !internal.Record.Failed)
  {
    // Interactive frames render another lattice and image: only still frames are timed.
    this->RecordForAuto(
      group, frame.Interactive ? -1.0 : internal.Record.Clock.Get(nullptr) - before);
  }
  apc::GatherRankTimes(group, internal.Record);
  this->FinishFrame(group, frame, result);
}

//------------------------------------------------------------------------------
int vtkAPCCompositePass::ChooseMode(
  const apc::ProcessGroup& group, const apc::CompositeFrame& frame)
{
  Internals& internal = *this->Internal;
  int mode = frame.Settings.CompositeMode;
  // The exact modes blend each volume's samples on their own: where two volumes overlap,
  // their segments (or images) cover the same depths, and no order of whole segments is the
  // interleaved blend. Several volumes are rendered by APC, whose moments sum over volumes.
  const bool several = frame.Volumes > 1;
  if (several && (mode == SEGMENTS || mode == LOCAL_EXACT))
  {
    if (group.IsDisplay() && !internal.SeveralWarned)
    {
      vtkWarningMacro("APC Mode " << (mode == SEGMENTS ? "Exact (segments)" : "Local exact")
                                  << " blends one APC volume at a time and cannot interleave "
                                  << frame.Volumes
                                  << " APC volumes where they overlap: this view renders them "
                                     "with APC. Show one APC volume for the exact picture.");
    }
    internal.SeveralWarned = true;
    return APC;
  }
  internal.SeveralWarned = false;
  if (mode == AUTO)
  {
    if (several)
    {
      return APC; // never the segments: see above
    }
    const double bytesPerPixel = frame.Settings.CompositeInDouble
      ? 8.0 * (frame.Moments.Moments + 5)
      : 1 + 4.0 * (frame.Moments.Moments + 5);
    mode = internal.Auto.Choose(group.Processes, bytesPerPixel) == apc::AutoMode::Moments
      ? APC
      : SEGMENTS;
  }
  return mode;
}

//------------------------------------------------------------------------------
void vtkAPCCompositePass::RecordForAuto(const apc::ProcessGroup& group, double seconds)
{
  Internals& internal = *this->Internal;
  const apc::FrameRecord& record = internal.Record;
  // Covered pixels and microseconds (< 0: untimed): integers, so every process sums the same.
  long long own[2] = { record.OwnCoveredPixels, static_cast<long long>(seconds * 1e6) };
  long long sum[2] = { own[0], own[1] };
  if (group.Parallel)
  {
    group.Collective(
      "auto", [&] { group.Controller->AllReduce(own, sum, 2, vtkCommunicator::SUM_OP); });
  }
  const bool segments = internal.LastMode == SEGMENTS;
  const double coveredUnion = segments ? static_cast<double>(record.Segments.NonEmptyPixels)
                                       : static_cast<double>(record.CoveredPixels);
  internal.Auto.Record(coveredUnion, static_cast<double>(sum[0]),
    segments ? static_cast<double>(record.Segments.Segments) : -1.0,
    seconds < 0 ? -1.0 : static_cast<double>(sum[1]) * 1e-6, segments);
  internal.Record.Clock.Lap("auto");
}

//------------------------------------------------------------------------------
void vtkAPCCompositePass::FinishFrame(
  const apc::ProcessGroup& group, const apc::CompositeFrame& frame, const apc::FrameResult& result)
{
  Internals& internal = *this->Internal;
  const apc::ScreenRect& rect = frame.Rect;
  if (!result.RGBA.empty() && rect.Pixels() > 0)
  {
    if (frame.KeepFloatImages)
    {
      apc::FloatImages images;
      images.RGBA = result.RGBA.data();
      images.Moments = result.Moments.empty() ? nullptr : result.Moments.data();
      images.MomentComponents = frame.Moments.Moments + 1;
      images.ColourSums = result.ColourSums.empty() ? nullptr : result.ColourSums.data();
      for (const apc::FrameEngine* engine : frame.Engines)
      {
        images.SampleCount += engine->GetSampleCount();
      }
      apc::StoreFloatImages(internal.Image, frame.Width, frame.Height, rect, images);
    }
    if (frame.Reduction() == 1)
    {
      apc::BlendIntoWindow(frame.Renderer, frame.X0 + rect.I0, frame.Y0 + rect.J0, rect.Width(),
        rect.Height(), rect.Width(), rect.Height(), result.RGBA.data());
    }
    else
    {
      // A reduced image is stretched over the viewport as a whole, so that its interpolation
      // at the rectangle's edges is the same as with the full image (it is small: 1/r^2).
      std::vector<float> full(4 * frame.Pixels(), 0.0f);
      apc::Unpack(result.RGBA.data(), frame.Width, rect, 4, full.data());
      apc::BlendIntoWindow(frame.Renderer, frame.X0, frame.Y0, frame.ViewWidth, frame.ViewHeight,
        frame.Width, frame.Height, full.data());
    }
    internal.Record.Clock.Lap("blend");
    if (group.IsDisplay())
    {
      this->WriteImage(); // if there is a file name
    }
    if (!this->KeepLastImage)
    {
      internal.Image->Initialize();
    }
  }
  if (this->Verbosity < 1 || !group.IsDisplay())
  {
    return;
  }
  const char* names[] = { "APC frame (", "APC segments frame (", "APC local exact frame (" };
  std::ostringstream line;
  line << (frame.Settings.CompositeMode == AUTO ? "Auto: " : "") << names[internal.LastMode]
       << group.Processes << " processes, " << frame.Rect.Pixels() << " pixels composited";
  if (frame.Interactive)
  {
    line << ", interactive: image reduction " << frame.Reduction() << ", sample distance x"
         << frame.SampleFactor();
  }
  line << "):";
  line << apc::DescribeStages(internal.Record);
  line << " bytes sent by the display process " << internal.Record.BytesSent << " in "
       << internal.Record.MessagesSent << " messages";
  if (internal.LastMode == SEGMENTS)
  {
    line << "; segments per non-empty pixel: average " << internal.Record.Segments.Average()
         << ", max " << internal.Record.Segments.MaxPerPixel;
  }
  vtkLog(INFO, << line.str());
}

//------------------------------------------------------------------------------
void vtkAPCCompositePass::WriteImage()
{
  if (this->ImageFileName && *this->ImageFileName)
  {
    apc::WriteFloatImages(this->Internal->Image, this->ImageFileName);
  }
}

//------------------------------------------------------------------------------
void vtkAPCCompositePass::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Controller: " << this->Controller << "\n";
  os << indent << "Volumes: " << this->Internal->Volumes.size() << "\n";
  os << indent << "DisplayProcess: " << this->DisplayProcess << "\n";
  const apc::FrameSettings& settings = this->Internal->Settings;
  os << indent << "DisplayDepthComposited: " << settings.DisplayDepthComposited << "\n";
  os << indent << "CompositeInDouble: " << settings.CompositeInDouble << "\n";
  os << indent << "MaxBandPixels: " << settings.MaxBandPixels << "\n";
  os << indent << "MaxMessageBytes: " << settings.MaxMessageBytes << "\n";
  os << indent << "OpaqueProbeStep: " << settings.OpaqueProbeStep << "\n";
  os << indent << "KeepLastImage: " << this->KeepLastImage << "\n";
  const char* modes[] = { "APC", "SEGMENTS", "LOCAL_EXACT", "AUTO" };
  os << indent << "CompositeMode: " << modes[settings.CompositeMode] << "\n";
  os << indent << "Verbosity: " << this->Verbosity << "\n";
  os << indent << "InteractiveSampleDistanceFactor: " << settings.InteractiveSampleDistanceFactor
     << "\n";
  os << indent << "InteractiveImageReduction: " << settings.InteractiveImageReduction << "\n";
  os << indent << "ImageFileName: " << (this->ImageFileName ? this->ImageFileName : "(none)")
     << "\n";
}
