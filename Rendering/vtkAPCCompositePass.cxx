// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAPCCompositePass.h"

#include "vtkAPCEXRWriter.h"
#include "vtkAPCVolumeMapper.h"
#include "vtkCamera.h"
#include "vtkCommunicator.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkLogger.h"
#include "vtkMatrix4x4.h"
#include "vtkMultiProcessController.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkRenderState.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"
#include "vtkVolume.h"
#include "vtkXMLImageDataWriter.h"

#include "apcVolumeRayMarcher.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkAPCCompositePass);

namespace
{
// Pixel rectangle [I0, I1) x [J0, J1) of the viewport.
struct Rect
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

// The pixels whose rays can meet the box: its projected corners, one pixel of margin. Every
// process computes the same rectangle from the same camera and global bounds.
Rect ScreenRect(vtkRenderer* ren, const double bounds[6], int width, int height)
{
  Rect full{ 0, 0, width, height };
  vtkCamera* camera = ren->GetActiveCamera();
  vtkMatrix4x4* m =
    camera->GetCompositeProjectionTransformMatrix(static_cast<double>(width) / height, -1, 1);
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
  Rect r;
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

// Copies the rectangle's pixels (components each) between a full image and a packed buffer.
template <class Packed, class Full>
void Pack(const Full* full, int width, const Rect& r, int components, Packed* packed)
{
  for (int j = r.J0; j < r.J1; ++j)
  {
    const Full* row = full + (static_cast<size_t>(j) * width + r.I0) * components;
    std::copy(row, row + static_cast<size_t>(r.Width()) * components,
      packed + static_cast<size_t>(j - r.J0) * r.Width() * components);
  }
}

template <class Packed, class Full>
void Unpack(const Packed* packed, int width, const Rect& r, int components, Full* full)
{
  for (int j = r.J0; j < r.J1; ++j)
  {
    const Packed* row = packed + static_cast<size_t>(j - r.J0) * r.Width() * components;
    std::copy(row, row + static_cast<size_t>(r.Width()) * components,
      full + (static_cast<size_t>(j) * width + r.I0) * components);
  }
}

// Sums the rectangle of an image over all processes, in precision T: onto every process
// (allreduce) or onto the display process (reduce). Returns the bytes this process sent.
template <class T>
double SumRect(vtkMultiProcessController* controller, std::vector<double>& image, int width,
  const Rect& rect, int components, bool everywhere, int display)
{
  const vtkIdType count = static_cast<vtkIdType>(rect.Pixels() * components);
  std::vector<T> send(count);
  std::vector<T> received(count);
  Pack(image.data(), width, rect, components, send.data());
  if (everywhere)
  {
    controller->AllReduce(send.data(), received.data(), count, vtkCommunicator::SUM_OP);
  }
  else
  {
    controller->Reduce(send.data(), received.data(), count, vtkCommunicator::SUM_OP, display);
  }
  Unpack(received.data(), width, rect, components, image.data());
  return static_cast<double>(sizeof(T)) * count;
}
}

namespace
{
// A segment as sent to its strip owner: the pixel within the owner's strip, the first lattice
// index relative to the frame's smallest (so that it fits 32 bits: a ray would need 2^31
// samples to overflow it), the premultiplied colour and the transmittance. KLast is not needed
// for blending.
struct WireSegment
{
  int32_t Pixel;
  int32_t KFirst;
  float Colour[3];
  float Transmittance;
};
static_assert(sizeof(WireSegment) == 24, "segments travel as 24 bytes");

constexpr int kSegmentTag = 470521;
}

struct vtkAPCCompositePass::Internals
{
  std::vector<vtkSmartPointer<vtkVolume>> Volumes;
  std::vector<vtkAPCVolumeMapper*> FrameMappers;
  vtkIdType MessagesSent = 0;
  apc::SegmentStatistics Segments;
  std::vector<std::pair<std::string, double>> Seconds;
  std::chrono::steady_clock::time_point Last;
  double BytesSent = 0;
  vtkIdType Pixels = 0;
  bool Failed = false;
  vtkNew<vtkImageData> Image;

  void StartClock()
  {
    this->Seconds.clear();
    this->Last = std::chrono::steady_clock::now();
  }
  void Lap(const char* stage)
  {
    const auto now = std::chrono::steady_clock::now();
    this->Seconds.emplace_back(stage, std::chrono::duration<double>(now - this->Last).count());
    this->Last = now;
  }
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

int vtkAPCCompositePass::GetNumberOfVolumes() const
{
  return static_cast<int>(this->Internal->Volumes.size());
}

double vtkAPCCompositePass::GetLastStageSeconds(const char* stage) const
{
  double seconds = 0;
  for (const auto& entry : this->Internal->Seconds)
  {
    if (!stage || entry.first == stage)
    {
      seconds += entry.second;
    }
  }
  return seconds;
}

double vtkAPCCompositePass::GetLastBytesSent() const
{
  return this->Internal->BytesSent;
}

vtkIdType vtkAPCCompositePass::GetLastMessagesSent() const
{
  return this->Internal->MessagesSent;
}

vtkIdType vtkAPCCompositePass::GetLastSegmentCount() const
{
  return static_cast<vtkIdType>(this->Internal->Segments.Segments);
}

vtkIdType vtkAPCCompositePass::GetLastNonEmptyPixels() const
{
  return static_cast<vtkIdType>(this->Internal->Segments.NonEmptyPixels);
}

double vtkAPCCompositePass::GetLastAverageSegmentsPerPixel() const
{
  return this->Internal->Segments.Average();
}

vtkIdType vtkAPCCompositePass::GetLastMaxSegmentsPerPixel() const
{
  return static_cast<vtkIdType>(this->Internal->Segments.MaxPerPixel);
}

void vtkAPCCompositePass::SetLocalExact(bool localExact)
{
  if (localExact)
  {
    this->SetCompositeMode(LOCAL_EXACT);
  }
  else if (this->CompositeMode == LOCAL_EXACT)
  {
    this->SetCompositeMode(APC);
  }
}

void vtkAPCCompositePass::GetScreenRectangle(
  vtkRenderer* ren, const double bounds[6], int width, int height, int rectangle[4])
{
  const Rect r = ScreenRect(ren, bounds, width, height);
  rectangle[0] = r.I0;
  rectangle[1] = r.J0;
  rectangle[2] = r.I1;
  rectangle[3] = r.J1;
}

vtkIdType vtkAPCCompositePass::GetLastCompositedPixels() const
{
  return this->Internal->Pixels;
}

bool vtkAPCCompositePass::GetLastFrameFailed() const
{
  return this->Internal->Failed;
}

vtkImageData* vtkAPCCompositePass::GetLastImage()
{
  return this->Internal->Image;
}

void vtkAPCCompositePass::ReleaseGraphicsResources(vtkWindow* w)
{
  this->Superclass::ReleaseGraphicsResources(w);
}

//------------------------------------------------------------------------------
void vtkAPCCompositePass::Render(const vtkRenderState* s)
{
  Internals& internal = *this->Internal;
  this->NumberOfRenderedProps = 0;
  if (this->DelegatePass)
  {
    this->DelegatePass->Render(s);
    this->NumberOfRenderedProps += this->DelegatePass->GetNumberOfRenderedProps();
  }
  internal.StartClock();
  internal.BytesSent = 0;
  internal.MessagesSent = 0;
  internal.Segments = apc::SegmentStatistics();
  internal.Pixels = 0;
  internal.Failed = false;
  internal.Image->Initialize();

  vtkRenderer* ren = s->GetRenderer();
  vtkMultiProcessController* controller = this->Controller;
  const bool parallel = controller && controller->GetNumberOfProcesses() > 1;
  const int rank = parallel ? controller->GetLocalProcessId() : 0;
  const int display =
    parallel ? std::min(this->DisplayProcess, controller->GetNumberOfProcesses() - 1) : 0;
  const bool isDisplay = rank == display;

  // 1. Agree on the data bounds, the number of moments and failures, in one allreduce (max):
  // a process that cannot render must not leave the others waiting in a later collective.
  std::vector<vtkAPCVolumeMapper*> mappers;
  const double inf = std::numeric_limits<double>::infinity();
  // -xmin, xmax, -ymin, ymax, -zmin, zmax, failed, moments, -moments, volumes, -volumes,
  // width, -width, height, -height
  double agree[15] = { -inf, -inf, -inf, -inf, -inf, -inf, 0, 0, -inf, 0, 0, 0, 0, 0, 0 };
  std::ostringstream problem;
  for (const auto& volume : internal.Volumes)
  {
    if (!volume->GetVisibility())
    {
      continue;
    }
    auto* mapper = vtkAPCVolumeMapper::SafeDownCast(volume->GetMapper());
    if (!mapper)
    {
      problem << "a volume without a vtkAPCVolumeMapper; ";
      agree[6] = 1;
      continue;
    }
    mappers.push_back(mapper);
    if (!mapper->UpdateInput())
    {
      problem << "unusable input (see the mapper's error); ";
      agree[6] = 1;
    }
    const double n = mapper->GetNumberOfMoments();
    agree[7] = std::max(agree[7], n);
    agree[8] = std::max(agree[8], -n);
    double b[6];
    if (mapper->GetLocalBounds(b))
    {
      for (int d = 0; d < 3; ++d)
      {
        agree[2 * d] = std::max(agree[2 * d], -b[2 * d]);
        agree[2 * d + 1] = std::max(agree[2 * d + 1], b[2 * d + 1]);
      }
    }
  }
  // Every process must take the same path below, so even "no visible APC volume here" is
  // agreed: a process without one while others have some would skip their collectives.
  agree[9] = static_cast<double>(mappers.size());
  agree[10] = -agree[9];
  // The screen rectangle and every image buffer derive from the viewport: sizes that differ
  // between processes would make their collectives disagree in length.
  int width = 0;
  int height = 0;
  int x0 = 0;
  int y0 = 0;
  ren->GetTiledSizeAndOrigin(&width, &height, &x0, &y0);
  agree[11] = width;
  agree[12] = -width;
  agree[13] = height;
  agree[14] = -height;
  double global[15];
  std::copy(agree, agree + 15, global);
  if (parallel)
  {
    controller->AllReduce(agree, global, 15, vtkCommunicator::MAX_OP);
  }
  internal.Lap("agree");
  if (global[9] == 0)
  {
    return; // no visible APC volume anywhere
  }
  const int moments = static_cast<int>(global[7]);
  const bool someWithout = -global[10] == 0;
  const bool sizesDiffer = global[11] != -global[12] || global[13] != -global[14];
  if (global[6] > 0 || someWithout || sizesDiffer || moments != static_cast<int>(-global[8]))
  {
    internal.Failed = true;
    if (!problem.str().empty())
    {
      vtkErrorMacro("APC on process " << rank << ": " << problem.str());
    }
    if (isDisplay)
    {
      vtkErrorMacro("APC frame skipped: " << (global[6] > 0
                        ? "a process could not render its volume (its error says why)"
                        : someWithout ? "a process has no visible APC volume while others have"
                                      : "the APC volumes use different numbers of moments"));
    }
    return;
  }
  const double bounds[6] = { -global[0], global[1], -global[2], global[3], -global[4], global[5] };
  if (!(bounds[0] <= bounds[1] && bounds[2] <= bounds[3] && bounds[4] <= bounds[5]))
  {
    return; // no cells anywhere: nothing to draw
  }

  if (width < 1 || height < 1)
  {
    return; // the same on every process (agreed above)
  }
  const Rect rect = ScreenRect(ren, bounds, width, height);
  const size_t pixels = static_cast<size_t>(width) * height;
  internal.Pixels = static_cast<vtkIdType>(rect.Pixels());

  // 2. The display process's (composited) depth, where every ray must stop.
  std::vector<float> depth(pixels, 1.0f);
  if (rect.Pixels() > 0)
  {
    std::vector<float> packed(rect.Pixels());
    if (isDisplay)
    {
      ren->GetRenderWindow()->GetZbufferData(
        x0 + rect.I0, y0 + rect.J0, x0 + rect.I1 - 1, y0 + rect.J1 - 1, packed.data());
    }
    if (parallel)
    {
      controller->Broadcast(packed.data(), static_cast<vtkIdType>(packed.size()), display);
      internal.BytesSent += isDisplay ? 4.0 * packed.size() : 0.0;
      internal.MessagesSent += isDisplay ? 1 : 0;
    }
    Unpack(packed.data(), width, rect, 1, depth.data());
  }
  internal.Lap("depth");

  std::vector<float> rgba(4 * pixels, 0.0f);
  for (size_t v = 0; v < internal.Volumes.size(); ++v)
  {
    auto* mapper = vtkAPCVolumeMapper::SafeDownCast(internal.Volumes[v]->GetMapper());
    if (mapper && internal.Volumes[v]->GetVisibility())
    {
      mapper->PrepareFrame(ren, internal.Volumes[v], bounds, depth.data(), 0.0);
    }
  }
  if (this->CompositeMode == LOCAL_EXACT)
  {
    for (vtkAPCVolumeMapper* mapper : mappers)
    {
      mapper->RenderExactImage(rgba.data());
    }
    internal.Lap("exact");
    mappers.front()->StoreImages(rgba.data(), nullptr, nullptr, nullptr);
    mappers.front()->BlendIntoWindow(ren, rgba.data());
    internal.Lap("blend");
    return;
  }
  if (this->CompositeMode == SEGMENTS)
  {
    internal.FrameMappers = mappers;
    const int r[4] = { rect.I0, rect.J0, rect.I1, rect.J1 };
    this->CompositeSegmentsFrame(ren, r, width, height);
    internal.FrameMappers.clear();
    this->ReportFrame(rect.Pixels());
    return;
  }

  // 3. Pass 1 and the moment allreduce.
  const int stride = moments + 1;
  std::vector<double> momentImage(pixels * stride, 0.0);
  for (vtkAPCVolumeMapper* mapper : mappers)
  {
    mapper->RenderMoments(momentImage.data());
  }
  internal.Lap("pass1");
  auto sum = [&](std::vector<double>& image, int components, bool everywhere)
  {
    if (!parallel || rect.Pixels() == 0)
    {
      return;
    }
    internal.BytesSent += this->CompositeInDouble
      ? SumRect<double>(controller, image, width, rect, components, everywhere, display)
      : SumRect<float>(controller, image, width, rect, components, everywhere, display);
    ++internal.MessagesSent;
  };
  sum(momentImage, stride, true);
  internal.Lap("allreduce");

  // 4. Pass 2 with the global moments, and the colour reduce onto the display process.
  std::vector<double> colourImage(pixels * 4, 0.0);
  for (vtkAPCVolumeMapper* mapper : mappers)
  {
    mapper->RenderColour(momentImage.data(), colourImage.data());
  }
  internal.Lap("pass2");
  sum(colourImage, 4, false);
  internal.Lap("reduce");

  // 5. Resolve and blend over the opaque image, on the display process only.
  if (isDisplay)
  {
    vtkAPCVolumeMapper* first = mappers.front();
    first->ResolveImage(momentImage.data(), colourImage.data(), rgba.data());
    internal.Lap("resolve");
    first->StoreImages(rgba.data(), momentImage.data(), colourImage.data(), nullptr);
    internal.Image->ShallowCopy(first->GetLastImage()); // the mapper makes new arrays each frame
    first->BlendIntoWindow(ren, rgba.data());
    internal.Lap("blend");
    this->WriteImage();
  }
  this->ReportFrame(rect.Pixels());
}

//------------------------------------------------------------------------------
void vtkAPCCompositePass::ReportFrame(size_t pixels)
{
  vtkMultiProcessController* controller = this->Controller;
  const bool parallel = controller && controller->GetNumberOfProcesses() > 1;
  const int rank = parallel ? controller->GetLocalProcessId() : 0;
  const int display =
    parallel ? std::min(this->DisplayProcess, controller->GetNumberOfProcesses() - 1) : 0;
  if (this->Verbosity < 1 || rank != display)
  {
    return;
  }
  const Internals& internal = *this->Internal;
  std::ostringstream line;
  line << (this->CompositeMode == SEGMENTS ? "APC segments frame (" : "APC frame (")
       << (parallel ? controller->GetNumberOfProcesses() : 1) << " processes, " << pixels
       << " pixels composited):";
  for (const auto& entry : internal.Seconds)
  {
    line << ' ' << entry.first << ' ' << entry.second << " s,";
  }
  line << " bytes sent by the display process " << internal.BytesSent << " in "
       << internal.MessagesSent << " messages";
  if (this->CompositeMode == SEGMENTS)
  {
    line << "; segments per non-empty pixel: average " << internal.Segments.Average() << ", max "
         << internal.Segments.MaxPerPixel;
  }
  vtkLog(INFO, << line.str());
}

//------------------------------------------------------------------------------
void vtkAPCCompositePass::CompositeSegmentsFrame(
  vtkRenderer* ren, const int rectArray[4], int width, int height)
{
  Internals& internal = *this->Internal;
  vtkMultiProcessController* controller = this->Controller;
  const bool parallel = controller && controller->GetNumberOfProcesses() > 1;
  const int processes = parallel ? controller->GetNumberOfProcesses() : 1;
  const int rank = parallel ? controller->GetLocalProcessId() : 0;
  const int display = parallel ? std::min(this->DisplayProcess, processes - 1) : 0;
  Rect rect;
  rect.I0 = rectArray[0];
  rect.J0 = rectArray[1];
  rect.I1 = rectArray[2];
  rect.J1 = rectArray[3];
  const int rectWidth = rect.Pixels() > 0 ? rect.Width() : 0;
  const int rectHeight = rect.Pixels() > 0 ? rect.Height() : 0;
  // Process o owns the rectangle's rows [stripStart(o), stripStart(o + 1)).
  auto stripStart = [&](int o)
  { return rect.J0 + static_cast<int>(static_cast<int64_t>(rectHeight) * o / processes); };

  // 1. This process's segments, per volume.
  std::vector<apc::SegmentImage> images(internal.FrameMappers.size());
  for (size_t v = 0; v < images.size(); ++v)
  {
    internal.FrameMappers[v]->RenderSegments(images[v]);
    if (images[v].Width != width || images[v].Height != height)
    {
      images[v].Reset(width, height); // a process that could not prepare renders nothing
    }
  }
  internal.Lap("segments");

  // 2. Counts per owner and the smallest lattice index, to every process; then the segments.
  std::vector<long long> mine(processes + 1, 0);
  long long kMin = std::numeric_limits<long long>::max();
  for (int o = 0; o < processes; ++o)
  {
    for (int j = stripStart(o); j < stripStart(o + 1); ++j)
    {
      for (const apc::SegmentImage& image : images)
      {
        const int64_t first = static_cast<int64_t>(j) * width + rect.I0;
        const int64_t begin = image.Offsets[first];
        const int64_t end = image.Offsets[first + rectWidth];
        mine[o] += end - begin;
        for (int64_t s = begin; s < end; ++s)
        {
          kMin = std::min<long long>(kMin, image.Segments[s].KFirst);
        }
      }
    }
  }
  mine[processes] = kMin;
  std::vector<long long> all(static_cast<size_t>(processes) * (processes + 1));
  if (parallel)
  {
    controller->AllGather(mine.data(), all.data(), processes + 1);
    internal.BytesSent += sizeof(long long) * mine.size();
    ++internal.MessagesSent;
  }
  else
  {
    all = mine;
  }
  long long kBase = std::numeric_limits<long long>::max();
  for (int p = 0; p < processes; ++p)
  {
    kBase = std::min(kBase, all[static_cast<size_t>(p) * (processes + 1) + processes]);
  }
  std::vector<std::vector<WireSegment>> outgoing(processes);
  for (int o = 0; o < processes; ++o)
  {
    outgoing[o].reserve(static_cast<size_t>(mine[o]));
    for (int j = stripStart(o); j < stripStart(o + 1); ++j)
    {
      for (int i = rect.I0; i < rect.I0 + rectWidth; ++i)
      {
        const int64_t pixel = static_cast<int64_t>(j) * width + i;
        const int32_t local = (j - stripStart(o)) * rectWidth + (i - rect.I0);
        for (const apc::SegmentImage& image : images)
        {
          for (int64_t s = image.Offsets[pixel]; s < image.Offsets[pixel + 1]; ++s)
          {
            const apc::RaySegment& seg = image.Segments[s];
            outgoing[o].push_back({ local, static_cast<int32_t>(seg.KFirst - kBase),
              { seg.Colour[0], seg.Colour[1], seg.Colour[2] }, seg.Transmittance });
          }
        }
      }
    }
  }
  std::vector<std::vector<WireSegment>> incoming(processes);
  incoming[rank].swap(outgoing[rank]);
  if (parallel)
  {
    // Direct send, one message per pair with segments. Pairs meet in rounds (partner = rank
    // XOR round), the lower rank sending first: blocking sends then never wait in a cycle.
    int rounds = 1;
    while (rounds < processes)
    {
      rounds *= 2;
    }
    for (int round = 1; round < rounds; ++round)
    {
      const int partner = rank ^ round;
      if (partner >= processes)
      {
        continue;
      }
      const std::vector<WireSegment>& send = outgoing[partner];
      std::vector<WireSegment>& receive = incoming[partner];
      receive.resize(
        static_cast<size_t>(all[static_cast<size_t>(partner) * (processes + 1) + rank]));
      auto sendPart = [&]
      {
        if (!send.empty())
        {
          controller->Send(reinterpret_cast<const char*>(send.data()),
            static_cast<vtkIdType>(send.size() * sizeof(WireSegment)), partner, kSegmentTag);
          internal.BytesSent += static_cast<double>(send.size() * sizeof(WireSegment));
          ++internal.MessagesSent;
        }
      };
      auto receivePart = [&]
      {
        if (!receive.empty())
        {
          controller->Receive(reinterpret_cast<char*>(receive.data()),
            static_cast<vtkIdType>(receive.size() * sizeof(WireSegment)), partner, kSegmentTag);
        }
      };
      if (rank < partner)
      {
        sendPart();
        receivePart();
      }
      else
      {
        receivePart();
        sendPart();
      }
    }
  }
  outgoing.clear();
  internal.Lap("exchange");

  // 3. The own strip: segments grouped by pixel (counting sort), then sorted and blended.
  const int stripRows = stripStart(rank + 1) - stripStart(rank);
  apc::SegmentImage strip;
  strip.Reset(rectWidth, stripRows);
  for (const auto& from : incoming)
  {
    for (const WireSegment& seg : from)
    {
      ++strip.Offsets[seg.Pixel + 1];
    }
  }
  for (size_t p = 1; p < strip.Offsets.size(); ++p)
  {
    strip.Offsets[p] += strip.Offsets[p - 1];
  }
  strip.Segments.resize(static_cast<size_t>(strip.Offsets.back()));
  {
    std::vector<int64_t> fill(strip.Offsets.begin(), strip.Offsets.end() - 1);
    for (const auto& from : incoming)
    {
      for (const WireSegment& seg : from)
      {
        strip.Segments[fill[seg.Pixel]++] = { seg.KFirst, seg.KFirst,
          { seg.Colour[0], seg.Colour[1], seg.Colour[2] }, seg.Transmittance };
      }
    }
  }
  incoming.clear();
  std::vector<float> stripImage(4 * static_cast<size_t>(rectWidth) * stripRows, 0.0f);
  apc::CompositeSegmentImage(strip, stripImage.data());
  const apc::SegmentStatistics own = apc::GetSegmentStatistics(strip);
  internal.Lap("blend_segments");

  // 4. The strips, in row order, are the rectangle's packed image on the display process.
  std::vector<float> packed;
  if (parallel)
  {
    std::vector<vtkIdType> lengths(processes);
    std::vector<vtkIdType> offsets(processes);
    for (int o = 0; o < processes; ++o)
    {
      lengths[o] = 4 * static_cast<vtkIdType>(rectWidth) * (stripStart(o + 1) - stripStart(o));
      offsets[o] = 4 * static_cast<vtkIdType>(rectWidth) * (stripStart(o) - rect.J0);
    }
    packed.resize(rank == display ? 4 * rect.Pixels() : 1);
    controller->GatherV(stripImage.data(), packed.data(), static_cast<vtkIdType>(stripImage.size()),
      lengths.data(), offsets.data(), display);
    if (rank != display && !stripImage.empty())
    {
      internal.BytesSent += sizeof(float) * static_cast<double>(stripImage.size());
      ++internal.MessagesSent;
    }
  }
  else
  {
    packed.swap(stripImage);
  }
  internal.Lap("gather");

  // The statistics of all strips, for the record on every process.
  long long stats[3] = { own.Segments, own.NonEmptyPixels, own.MaxPerPixel };
  if (parallel)
  {
    std::vector<long long> gathered(3 * static_cast<size_t>(processes));
    controller->AllGather(stats, gathered.data(), 3);
    stats[0] = stats[1] = stats[2] = 0;
    for (int p = 0; p < processes; ++p)
    {
      stats[0] += gathered[3 * p];
      stats[1] += gathered[3 * p + 1];
      stats[2] = std::max(stats[2], gathered[3 * p + 2]);
    }
  }
  internal.Segments.Segments = stats[0];
  internal.Segments.NonEmptyPixels = stats[1];
  internal.Segments.MaxPerPixel = stats[2];
  internal.Lap("statistics");

  // 5. On the display process, over the opaque image, as in APC.
  if (rank == display)
  {
    std::vector<float> rgba(4 * static_cast<size_t>(width) * height, 0.0f);
    if (rect.Pixels() > 0)
    {
      Unpack(packed.data(), width, rect, 4, rgba.data());
    }
    vtkAPCVolumeMapper* first = internal.FrameMappers.front();
    first->StoreImages(rgba.data(), nullptr, nullptr, nullptr);
    internal.Image->ShallowCopy(first->GetLastImage()); // the mapper makes new arrays each frame
    first->BlendIntoWindow(ren, rgba.data());
    internal.Lap("blend");
    this->WriteImage();
  }
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
  os << indent << "CompositeInDouble: " << this->CompositeInDouble << "\n";
  os << indent << "CompositeMode: "
     << (this->CompositeMode == SEGMENTS
            ? "SEGMENTS"
            : (this->CompositeMode == LOCAL_EXACT ? "LOCAL_EXACT" : "APC"))
     << "\n";
  os << indent << "Verbosity: " << this->Verbosity << "\n";
  os << indent << "ImageFileName: " << (this->ImageFileName ? this->ImageFileName : "(none)")
     << "\n";
}
