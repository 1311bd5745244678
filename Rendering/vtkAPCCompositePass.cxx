// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAPCCompositePass.h"

#include "vtkAPCEXRWriter.h"
#include "vtkAPCVolumeMapper.h"
#include "vtkCommunicator.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkLogger.h"
#include "vtkMultiProcessController.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkRenderState.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"
#include "vtkVolume.h"
#include "vtkXMLImageDataWriter.h"

#include "apcAutoMode.h"
#include "apcCompositeFrame.h"
#include "apcFrameAgreement.h"
#include "apcFrameEngine.h"
#include "apcImageOutput.h"
#include "apcInputReport.h"

#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkAPCCompositePass);

struct vtkAPCCompositePass::Internals
{
  std::vector<vtkSmartPointer<vtkVolume>> Volumes;
  apc::FrameRecord Record;
  int LastMode = -1;
  int LastReduction = 0;
  bool LastInteractive = false;
  apc::AutoMode Auto; // the same on every process: fed only by collectives' results
  vtkNew<vtkImageData> Image;
  vtkSmartPointer<vtkFloatArray> DelegateDepth; // this frame's, if its delegate gave one
  bool TransferWarned = false; // the display process said that transfer functions differ
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
  if (volume && std::find(v.begin(), v.end(), volume) == v.end())
  {
    v.emplace_back(volume);
    this->Modified();
  }
}

void vtkAPCCompositePass::RemoveVolume(vtkVolume* volume)
{
  auto& v = this->Internal->Volumes;
  const auto it = std::find(v.begin(), v.end(), volume);
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
namespace
{
// Step 1 of a frame: this process's visible APC volumes and its side of the agreement, then
// the agreement itself. False if the frame is skipped on every process (failures reported).
bool AgreeOnFrame(vtkAPCCompositePass* self, const apc::ProcessGroup& group,
  const std::vector<vtkSmartPointer<vtkVolume>>& volumes, vtkRenderer* ren,
  apc::CompositeFrame& frame, std::vector<vtkVolume*>& visible, apc::FrameRecord& record,
  bool& transferWarned)
{
  apc::LocalFrame local;
  std::ostringstream problem;
  std::vector<vtkAPCVolumeMapper*> mappers;
  apc::InputReport reports; // said once for all processes when any has news
  for (const auto& volume : volumes)
  {
    if (!volume->GetVisibility())
    {
      continue;
    }
    auto* mapper = vtkAPCVolumeMapper::SafeDownCast(volume->GetMapper());
    if (!mapper)
    {
      problem << "a volume without a vtkAPCVolumeMapper; ";
      local.Failed = true;
      continue;
    }
    apc::FrameEngine* engine = mapper->GetFrameEngine();
    engine->BeginFrame();
    if (!engine->UpdateInput(mapper))
    {
      problem << "unusable input (see the mapper's error); ";
      local.Failed = true;
    }
    local.ReportPending = engine->TakeNewInputReport() || local.ReportPending;
    reports.Add(engine->GetInputReport());
    double bounds[6];
    local.AddVolume(mapper->GetNumberOfMoments(), engine->GetLocalBounds(bounds) ? bounds : nullptr,
      volume->GetProperty());
    mappers.push_back(mapper);
    visible.push_back(volume);
  }
  // The screen rectangle and every image buffer derive from the viewport: sizes that differ
  // between processes would make their collectives disagree in length.
  ren->GetTiledSizeAndOrigin(&local.Width, &local.Height, &frame.X0, &frame.Y0);
  // Whether this frame may be cheap is the window's word (ParaView's and VTK's interactive
  // renders raise its desired update rate); how cheap is this pass's setting. Both are
  // agreed, so no process renders a different lattice or image size than the others.
  vtkRenderWindow* window = ren->GetRenderWindow();
  local.Interactive = window && window->GetDesiredUpdateRate() >= 1.0;
  local.SampleFactor = self->GetInteractiveSampleDistanceFactor();
  local.Reduction = self->GetInteractiveImageReduction();
  local.Mode = self->GetCompositeMode();
  local.InDouble = self->GetCompositeInDouble();
  local.DepthComposited = self->GetDisplayDepthComposited();
  local.BandPixels = static_cast<double>(self->GetMaxBandPixels());
  const apc::FrameAgreement agreed = apc::FrameAgreement::Agree(group, local);
  if (agreed.AnyReportPending)
  {
    apc::ShareInputReports(group, reports,
      mappers.empty() ? static_cast<vtkObject*>(self) : static_cast<vtkObject*>(mappers.front()));
  }
  apc::WarnOnceIfTransferFunctionsDiffer(self, group, agreed, mappers, transferWarned);
  record.Clock.Lap("agree");
  if (agreed.NoVolumes())
  {
    return false;
  }
  const std::string why = agreed.Problem();
  if (!why.empty())
  {
    record.Failed = true;
    if (!problem.str().empty())
    {
      vtkErrorWithObjectMacro(self, "APC on process " << group.Rank << ": " << problem.str());
    }
    if (group.IsDisplay())
    {
      vtkErrorWithObjectMacro(self, "APC frame skipped: " << why);
    }
    return false;
  }
  if (!agreed.HasCells() || agreed.Width < 1 || agreed.Height < 1)
  {
    return false; // nothing to draw anywhere (the same on every process)
  }
  frame.Renderer = ren;
  frame.ViewWidth = agreed.Width;
  frame.ViewHeight = agreed.Height;
  frame.Interactive = agreed.Interactive;
  frame.Reduction = agreed.Reduction;
  frame.SampleFactor = agreed.SampleFactor;
  frame.BandPixels = static_cast<size_t>(agreed.BandPixels);
  frame.Width = (agreed.Width + frame.Reduction - 1) / frame.Reduction;
  frame.Height = (agreed.Height + frame.Reduction - 1) / frame.Reduction;
  frame.Rect = apc::ScreenRectOf(ren, agreed.Bounds, frame.Width, frame.Height, frame.Aspect());
  const apc::ScreenRect& r = frame.Rect;
  frame.Tiles =
    r.Pixels() > 0 ? apc::TileGrid(r.Width(), 0, 0, r.Width(), r.Height()) : apc::TileGrid();
  // The frame's moment settings: the agreed number, the first volume's beta, bias and resolve.
  frame.Moments = mappers.front()->GetMomentParameters();
  frame.Moments.Moments = agreed.MaxMoments;
  std::copy(agreed.Bounds, agreed.Bounds + 6, frame.Bounds);
  for (vtkAPCVolumeMapper* mapper : mappers)
  {
    frame.Engines.push_back(mapper->GetFrameEngine());
  }
  return true;
}

// Step 2: the display process's (composited) depth over the screen rectangle, where every
// ray must stop, on every process: only the tiles where it has opaque geometry travel. If no
// delegate composited depth (composited false), the nearest of every process's own depth.
std::vector<float> ShareDepth(const apc::ProcessGroup& group, const apc::CompositeFrame& frame,
  bool composited, vtkFloatArray* delegateDepth, apc::FrameRecord& record)
{
  std::vector<float> depth(frame.RectPixels(), 1.0f);
  const apc::ScreenRect& rect = frame.Rect;
  if (rect.Pixels() == 0)
  {
    return depth;
  }
  if (group.IsDisplay() || !composited)
  {
    // The viewport pixels under the rectangle; an image pixel of a reduced frame takes the
    // nearest of those it covers (its ray stops at the nearest opaque surface in its
    // footprint). At full resolution that is the window's depth, unchanged.
    const int r = frame.Reduction;
    const int i0 = rect.I0 * r;
    const int j0 = rect.J0 * r;
    const int i1 = std::min(frame.ViewWidth, rect.I1 * r);
    const int j1 = std::min(frame.ViewHeight, rect.J1 * r);
    std::vector<float> packed(static_cast<size_t>(i1 - i0) * (j1 - j0));
    if (delegateDepth && group.IsDisplay() && composited &&
      delegateDepth->GetNumberOfTuples() ==
        static_cast<vtkIdType>(frame.ViewWidth) * frame.ViewHeight)
    {
      const float* z = delegateDepth->GetPointer(0);
      for (int j = j0; j < j1; ++j)
      {
        std::copy_n(z + static_cast<size_t>(j) * frame.ViewWidth + i0, i1 - i0,
          &packed[static_cast<size_t>(j - j0) * (i1 - i0)]);
      }
    }
    else
    {
      frame.Renderer->GetRenderWindow()->GetZbufferData(
        frame.X0 + i0, frame.Y0 + j0, frame.X0 + i1 - 1, frame.Y0 + j1 - 1, packed.data());
    }
    for (int j = j0; j < j1; ++j)
    {
      for (int i = i0; i < i1; ++i)
      {
        float& d = depth[static_cast<size_t>(j / r - rect.J0) * rect.Width() + (i / r - rect.I0)];
        d = std::min(d, packed[static_cast<size_t>(j - j0) * (i1 - i0) + (i - i0)]);
      }
    }
  }
  if (!group.Parallel)
  {
    return depth;
  }
  if (!composited)
  {
    // Each process's framebuffer holds its own opaque geometry only: the composited depth
    // is the nearest over processes, on every process at once.
    std::vector<float> nearest(depth.size());
    group.Controller->AllReduce(
      depth.data(), nearest.data(), static_cast<vtkIdType>(depth.size()), vtkCommunicator::MIN_OP);
    record.BytesSent += 4.0 * static_cast<double>(depth.size());
    record.MessagesSent += 1;
    return nearest;
  }
  std::vector<unsigned char> opaque = group.IsDisplay()
    ? frame.Tiles.Mark([&](size_t pixel) { return depth[pixel] < 1.0f; })
    : std::vector<unsigned char>(frame.Tiles.Tiles());
  group.Controller->Broadcast(opaque.data(), static_cast<vtkIdType>(opaque.size()), group.Display);
  std::vector<float> packed(frame.Tiles.PixelsIn(opaque));
  frame.Tiles.Pack(opaque, depth.data(), 1, packed.data());
  if (!packed.empty())
  {
    group.Controller->Broadcast(
      packed.data(), static_cast<vtkIdType>(packed.size()), group.Display);
  }
  frame.Tiles.Unpack(opaque, packed.data(), 1, depth.data());
  if (group.IsDisplay())
  {
    record.BytesSent += static_cast<double>(opaque.size() + 4 * packed.size());
    record.MessagesSent += packed.empty() ? 1 : 2;
  }
  return depth;
}
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

  const apc::ProcessGroup group(this->Controller, this->DisplayProcess);
  apc::CompositeFrame frame;
  std::vector<vtkVolume*> volumes;
  if (!AgreeOnFrame(this, group, internal.Volumes, s->GetRenderer(), frame, volumes,
        internal.Record, internal.TransferWarned))
  {
    return;
  }
  internal.Record.Pixels = static_cast<vtkIdType>(frame.Rect.Pixels()); // APC: fewer
  frame.KeepFloatImages =
    this->KeepLastImage || (group.IsDisplay() && this->ImageFileName && *this->ImageFileName);
  internal.LastReduction = frame.Reduction;
  internal.LastInteractive = frame.Interactive;
  std::vector<float> depth =
    ShareDepth(group, frame, this->DisplayDepthComposited, internal.DelegateDepth, internal.Record);
  internal.DelegateDepth = nullptr;
  internal.Record.Clock.Lap("depth");
  apc::ImageSetup image;
  image.Width = frame.Width;
  image.Height = frame.Height;
  image.X0 = frame.X0;
  image.Y0 = frame.Y0;
  image.Aspect = frame.Aspect();
  image.SampleFactor = frame.SampleFactor;
  image.Crop = frame.Rect;
  for (size_t v = 0; v < volumes.size(); ++v)
  {
    auto* mapper = static_cast<vtkAPCVolumeMapper*>(volumes[v]->GetMapper());
    frame.Engines[v]->Prepare(
      mapper, frame.Renderer, volumes[v], frame.Bounds, depth.data(), image);
  }
  depth = std::vector<float>(); // the engines hold their rays' ends

  int mode = this->CompositeMode;
  if (mode == AUTO)
  {
    const double bytesPerPixel = this->CompositeInDouble ? 8.0 * (frame.Moments.Moments + 5)
                                                         : 1 + 4.0 * (frame.Moments.Moments + 5);
    mode = internal.Auto.Choose(group.Processes, bytesPerPixel) == apc::AutoMode::Moments
      ? APC
      : SEGMENTS;
  }
  internal.LastMode = mode;
  apc::FrameResult result;
  switch (mode)
  {
    case LOCAL_EXACT:
      result.RGBA.assign(4 * frame.RectPixels(), 0.0f);
      for (apc::FrameEngine* engine : frame.Engines)
      {
        engine->RenderExact(result.RGBA.data());
      }
      internal.Record.Clock.Lap("exact");
      break;
    case SEGMENTS:
      apc::RunSegmentCompositing(group, frame, internal.Record, result);
      break;
    default:
      apc::RunMomentCompositing(group, frame, this->CompositeInDouble, internal.Record, result);
  }
  if (this->CompositeMode == AUTO)
  {
    this->RecordForAuto(group);
  }
  this->FinishFrame(group, frame, result);
}

//------------------------------------------------------------------------------
void vtkAPCCompositePass::RecordForAuto(const apc::ProcessGroup& group)
{
  Internals& internal = *this->Internal;
  const apc::FrameRecord& record = internal.Record;
  long long covered = record.OwnCoveredPixels;
  long long coveredSum = covered;
  if (group.Parallel)
  {
    group.Controller->AllReduce(&covered, &coveredSum, 1, vtkCommunicator::SUM_OP);
  }
  const bool segments = internal.LastMode == SEGMENTS;
  const double coveredUnion = segments ? static_cast<double>(record.Segments.NonEmptyPixels)
                                       : static_cast<double>(record.CoveredPixels);
  internal.Auto.Record(coveredUnion, static_cast<double>(coveredSum),
    segments ? static_cast<double>(record.Segments.Segments) : -1.0);
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
    if (frame.Reduction == 1)
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
  line << (this->CompositeMode == AUTO ? "Auto: " : "") << names[internal.LastMode]
       << group.Processes << " processes, " << frame.Rect.Pixels() << " pixels composited";
  if (frame.Interactive)
  {
    line << ", interactive: image reduction " << frame.Reduction << ", sample distance x"
         << frame.SampleFactor;
  }
  line << "):";
  for (const auto& entry : internal.Record.Clock.Stages())
  {
    line << ' ' << entry.first << ' ' << entry.second << " s,";
  }
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
  if (!this->ImageFileName || !*this->ImageFileName)
  {
    return;
  }
  const std::string name = this->ImageFileName;
  const bool exr = name.size() > 4 && name.compare(name.size() - 4, 4, ".exr") == 0;
  if (exr)
  {
    vtkNew<vtkAPCEXRWriter> writer;
    writer->SetFileName(name.c_str());
    writer->SetInputData(this->Internal->Image);
    writer->Write();
  }
  else
  {
    vtkNew<vtkXMLImageDataWriter> writer;
    writer->SetFileName(name.c_str());
    writer->SetInputData(this->Internal->Image);
    writer->SetDataModeToBinary(); // Debian's ParaView rejects appended-mode XML
    writer->Write();
  }
}

//------------------------------------------------------------------------------
void vtkAPCCompositePass::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Controller: " << this->Controller << "\n";
  os << indent << "Volumes: " << this->Internal->Volumes.size() << "\n";
  os << indent << "DisplayProcess: " << this->DisplayProcess << "\n";
  os << indent << "DisplayDepthComposited: " << this->DisplayDepthComposited << "\n";
  os << indent << "CompositeInDouble: " << this->CompositeInDouble << "\n";
  os << indent << "MaxBandPixels: " << this->MaxBandPixels << "\n";
  os << indent << "KeepLastImage: " << this->KeepLastImage << "\n";
  const char* modes[] = { "APC", "SEGMENTS", "LOCAL_EXACT", "AUTO" };
  os << indent << "CompositeMode: " << modes[this->CompositeMode] << "\n";
  os << indent << "Verbosity: " << this->Verbosity << "\n";
  os << indent << "InteractiveSampleDistanceFactor: " << this->InteractiveSampleDistanceFactor
     << "\n";
  os << indent << "InteractiveImageReduction: " << this->InteractiveImageReduction << "\n";
  os << indent << "ImageFileName: " << (this->ImageFileName ? this->ImageFileName : "(none)")
     << "\n";
}
