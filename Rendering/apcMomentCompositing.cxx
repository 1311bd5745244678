// SPDX-License-Identifier: BSD-3-Clause
// APC mode (the paper's Sec. 3): pass 1 and one moment allreduce, pass 2 and one colour
// reduce, resolve on the display process. Only the data's screen rectangle travels.
#include "apcCompositeFrame.h"
#include "apcFrameEngine.h"
#include "apcResolve.h"

#include "vtkCommunicator.h"
#include "vtkMultiProcessController.h"

#include <vector>

namespace apc
{
namespace
{
// Sums the rectangle of an image over all processes, in precision T: onto every process
// (allreduce) or onto the display process (reduce). Returns the bytes this process sent.
template <class T>
double SumRect(const ProcessGroup& group, std::vector<double>& image, int width,
  const ScreenRect& rect, int components, bool everywhere)
{
  const vtkIdType count = static_cast<vtkIdType>(rect.Pixels() * components);
  std::vector<T> send(count);
  std::vector<T> received(count);
  Pack(image.data(), width, rect, components, send.data());
  if (everywhere)
  {
    group.Controller->AllReduce(send.data(), received.data(), count, vtkCommunicator::SUM_OP);
  }
  else
  {
    group.Controller->Reduce(
      send.data(), received.data(), count, vtkCommunicator::SUM_OP, group.Display);
  }
  Unpack(received.data(), width, rect, components, image.data());
  return static_cast<double>(sizeof(T)) * count;
}
}

void RunMomentCompositing(const ProcessGroup& group, const CompositeFrame& frame, bool inDouble,
  FrameRecord& record, FrameResult& result)
{
  const MomentParameters& parameters = frame.Moments;
  auto sum = [&](std::vector<double>& image, int components, bool everywhere)
  {
    if (!group.Parallel || frame.Rect.Pixels() == 0)
    {
      return;
    }
    record.BytesSent += inDouble
      ? SumRect<double>(group, image, frame.Width, frame.Rect, components, everywhere)
      : SumRect<float>(group, image, frame.Width, frame.Rect, components, everywhere);
    ++record.MessagesSent;
  };

  const int stride = parameters.Moments + 1;
  std::vector<double> moments(frame.Pixels() * stride, 0.0);
  for (FrameEngine* engine : frame.Engines)
  {
    engine->RenderMoments(parameters, moments.data());
  }
  record.Clock.Lap("pass1");
  sum(moments, stride, true);
  record.Clock.Lap("allreduce");

  std::vector<double> colourSums(frame.Pixels() * 4, 0.0);
  for (FrameEngine* engine : frame.Engines)
  {
    engine->RenderColour(parameters, moments.data(), colourSums.data());
  }
  record.Clock.Lap("pass2");
  sum(colourSums, 4, false);
  record.Clock.Lap("reduce");

  if (group.IsDisplay())
  {
    result.RGBA.assign(4 * frame.Pixels(), 0.0f);
    ResolveImage(parameters.Resolve, frame.Pixels(), moments.data(), stride, colourSums.data(),
      result.RGBA.data());
    record.Clock.Lap("resolve");
    result.Moments.swap(moments);
    result.ColourSums.swap(colourSums);
  }
}

} // namespace apc
