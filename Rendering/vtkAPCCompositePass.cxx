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

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
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

struct vtkAPCCompositePass::Internals
{
  std::vector<vtkSmartPointer<vtkVolume>> Volumes;
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
  // -xmin, xmax, -ymin, ymax, -zmin, zmax, failed, moments, -moments
  double agree[9] = { -inf, -inf, -inf, -inf, -inf, -inf, 0, 0, -inf };
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
  double global[9];
  std::copy(agree, agree + 9, global);
  if (parallel)
  {
    controller->AllReduce(agree, global, 9, vtkCommunicator::MAX_OP);
  }
  internal.Lap("agree");
  const int moments = static_cast<int>(global[7]);
  if (global[6] > 0 || (moments > 0 && moments != static_cast<int>(-global[8])))
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
                        : "the APC volumes use different numbers of moments"));
    }
    return;
  }
  const double bounds[6] = { -global[0], global[1], -global[2], global[3], -global[4], global[5] };
  if (mappers.empty() ||
    !(bounds[0] <= bounds[1] && bounds[2] <= bounds[3] && bounds[4] <= bounds[5]))
  {
    return; // no cells anywhere: nothing to draw
  }

  int width = 0;
  int height = 0;
  int x0 = 0;
  int y0 = 0;
  ren->GetTiledSizeAndOrigin(&width, &height, &x0, &y0);
  if (width < 1 || height < 1)
  {
    return;
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
  if (this->LocalExact)
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
    internal.Image->DeepCopy(first->GetLastImage());
    first->BlendIntoWindow(ren, rgba.data());
    internal.Lap("blend");
    this->WriteImage();
  }
  if (this->Verbosity > 0 && isDisplay)
  {
    std::ostringstream line;
    line << "APC frame (" << (parallel ? controller->GetNumberOfProcesses() : 1) << " processes, "
         << rect.Pixels() << " pixels composited):";
    for (const auto& entry : internal.Seconds)
    {
      line << ' ' << entry.first << ' ' << entry.second << " s,";
    }
    line << " bytes sent by the display process " << internal.BytesSent;
    vtkLog(INFO, << line.str());
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
  os << indent << "LocalExact: " << this->LocalExact << "\n";
  os << indent << "Verbosity: " << this->Verbosity << "\n";
  os << indent << "ImageFileName: " << (this->ImageFileName ? this->ImageFileName : "(none)")
     << "\n";
}
