// SPDX-License-Identifier: BSD-3-Clause
#include "apcCompositeFrame.h"

#include "apcFrameEngine.h"
#include "apcHugePages.h"
#include "apcStageAgreement.h"

#include "vtkAPCCompositePass.h"
#include "vtkAbstractVolumeMapper.h"
#include "vtkCommunicator.h"
#include "vtkFloatArray.h"
#include "vtkMultiProcessController.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkVolume.h"

#include <algorithm>
#include <string>
#include <vector>

namespace apc
{

ProcessGroup::ProcessGroup(
  vtkMultiProcessController* controller, int displayProcess, CollectiveTimes* times)
  : Controller(controller)
  , Parallel(controller && controller->GetNumberOfProcesses() > 1)
  , Times(times)
{
  if (this->Parallel)
  {
    this->Processes = controller->GetNumberOfProcesses();
    this->Rank = controller->GetLocalProcessId();
    this->Display = std::min(displayProcess, this->Processes - 1);
  }
}

std::vector<float> ShareDepth(const ProcessGroup& group, const CompositeFrame& frame,
  vtkFloatArray* delegateDepth, FrameRecord& record)
{
  const bool composited = frame.Settings.DisplayDepthComposited;
  std::vector<float> depth(frame.RectPixels(), 1.0f);
  const ScreenRect& rect = frame.Rect;
  if (rect.Pixels() == 0)
  {
    return depth;
  }
  if (group.IsDisplay() || !composited)
  {
    // The viewport pixels under the rectangle; an image pixel of a reduced frame takes the
    // nearest of those it covers (its ray stops at the nearest opaque surface in its
    // footprint). At full resolution that is the window's depth, unchanged.
    const int r = frame.Reduction();
    const int i0 = rect.I0 * r;
    const int j0 = rect.J0 * r;
    const int i1 = std::min(frame.ViewWidth, rect.I1 * r);
    const int j1 = std::min(frame.ViewHeight, rect.J1 * r);
    // At full resolution over a rectangle inside the window, the window's pixels are the
    // rectangle's row for row: read them straight into depth instead of into a second
    // rectangle-sized buffer (4 MB at 1024², fresh memory in a first frame), then take
    // min(1, z) in place, the same values bit for bit as the reduced path's min.
    const bool direct = r == 1 && i1 == rect.I1 && j1 == rect.J1;
    std::vector<float> packed(direct ? 0 : static_cast<size_t>(i1 - i0) * (j1 - j0));
    float* window = direct ? depth.data() : packed.data();
    if (delegateDepth && group.IsDisplay() && composited &&
      delegateDepth->GetNumberOfTuples() ==
        static_cast<vtkIdType>(frame.ViewWidth) * frame.ViewHeight)
    {
      const float* z = delegateDepth->GetPointer(0);
      for (int j = j0; j < j1; ++j)
      {
        std::copy_n(z + static_cast<size_t>(j) * frame.ViewWidth + i0, i1 - i0,
          window + static_cast<size_t>(j - j0) * (i1 - i0));
      }
    }
    else
    {
      frame.Renderer->GetRenderWindow()->GetZbufferData(
        frame.X0 + i0, frame.Y0 + j0, frame.X0 + i1 - 1, frame.Y0 + j1 - 1, window);
    }
    if (direct)
    {
      for (float& d : depth)
      {
        d = std::min(1.0f, d);
      }
    }
    else
    {
      for (int j = j0; j < j1; ++j)
      {
        for (int i = i0; i < i1; ++i)
        {
          float& d = depth[static_cast<size_t>(j / r - rect.J0) * rect.Width() + (i / r - rect.I0)];
          d = std::min(d, packed[static_cast<size_t>(j - j0) * (i1 - i0) + (i - i0)]);
        }
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
    group.Collective("depth",
      [&]
      {
        group.Controller->AllReduce(depth.data(), nearest.data(),
          static_cast<vtkIdType>(depth.size()), vtkCommunicator::MIN_OP);
      });
    record.BytesSent += 4.0 * static_cast<double>(depth.size());
    record.MessagesSent += 1;
    return nearest;
  }
  std::vector<unsigned char> opaque = group.IsDisplay()
    ? frame.Tiles.Mark([&](size_t pixel) { return depth[pixel] < 1.0f; })
    : std::vector<unsigned char>(frame.Tiles.Tiles());
  group.Collective("depth",
    [&]
    {
      group.Controller->Broadcast(
        opaque.data(), static_cast<vtkIdType>(opaque.size()), group.Display);
    });
  std::vector<float> packed(frame.Tiles.PixelsIn(opaque));
  frame.Tiles.Pack(opaque, depth.data(), 1, packed.data());
  if (!packed.empty())
  {
    group.Collective("depth",
      [&]
      {
        group.Controller->Broadcast(
          packed.data(), static_cast<vtkIdType>(packed.size()), group.Display);
      });
  }
  frame.Tiles.Unpack(opaque, packed.data(), 1, depth.data());
  if (group.IsDisplay())
  {
    record.BytesSent += static_cast<double>(opaque.size() + 4 * packed.size());
    record.MessagesSent += packed.empty() ? 1 : 2;
  }
  return depth;
}

bool PrepareEngines(const ProcessGroup& group, const CompositeFrame& frame,
  const std::vector<vtkVolume*>& volumes, const std::vector<float>& depth, FrameRecord& record,
  FrameResult& result)
{
  ImageSetup image;
  image.Width = frame.Width;
  image.Height = frame.Height;
  image.X0 = frame.X0;
  image.Y0 = frame.Y0;
  image.Aspect = frame.Aspect();
  image.SampleFactor = frame.SampleFactor();
  image.PlainLattice = vtkAPCCompositePass::SamplesPlainLattice(frame.Settings.CompositeMode);
  image.Crop = frame.Rect;
  // The set-up (the transfer table, the rays' ends, the boundary's planes) runs inside the
  // frame's failure agreement: the next collective is the first of the compositing. The
  // frame's timings count the set-up in pass 1, a stage without collectives of its own: the
  // agreement's wait for the slowest set-up stays in pass 1's time, not in a named wait.
  ProcessGroup untimed = group;
  untimed.Times = nullptr;
  return RunAgreedStage(untimed, "setup", "the volumes' set-up", record,
    [&]
    {
      const size_t pixels = frame.RectPixels();
      ReserveInHugePages(result.RGBA, 4 * pixels);
      if (frame.KeepFloatImages && group.IsDisplay())
      {
        result.Moments.reserve(pixels * (frame.Moments.Moments + 1));
        result.ColourSums.reserve(pixels * 4);
      }
      for (size_t v = 0; v < volumes.size(); ++v)
      {
        frame.Engines[v]->Prepare(frame.Renderer, volumes[v]->GetProperty(), frame.Bounds,
          frame.Cells, frame.CellVolume, depth.data(), image);
        // The same on every process (global bounds): said once, by the display process.
        const std::string note = frame.Engines[v]->TakeSpacingNote();
        if (!note.empty() && group.IsDisplay())
        {
          vtkWarningWithObjectMacro(volumes[v]->GetMapper(), << note);
        }
      }
    });
}

} // namespace apc
