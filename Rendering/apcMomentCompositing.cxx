// SPDX-License-Identifier: BSD-3-Clause
// APC mode (the paper's Sec. 3): pass 1, then the processes agree on the tiles any of them
// covers and sum only those tiles' moments onto every process (allreduce); pass 2, and the
// same tiles' colour sums are summed onto the display process (reduce), which resolves.
// Each process sums its own samples in double. On the wire, unless asked for double: the
// moments as 32-bit fixed point with a per-pixel scale agreed first (exact, order-independent
// sums; see apcFixedPointMoments.h for why not float), the colour sums in float (the paper's
// format; their rounding is not amplified). 4 moments: 1 + 20 + 16 bytes per covered pixel.
#include "apcCompositeFrame.h"
#include "apcFixedPointMoments.h"
#include "apcFrameEngine.h"
#include "apcResolve.h"

#include "vtkCommunicator.h"
#include "vtkMultiProcessController.h"

#include <cstdint>
#include <vector>

namespace apc
{
namespace
{
// Sums the marked tiles of an image over all processes, in precision T: onto every process
// (allreduce) or onto the display process (reduce). Returns the bytes this process sent.
template <class T>
double SumTiles(const ProcessGroup& group, const TileGrid& tiles,
  const std::vector<unsigned char>& mask, std::vector<double>& image, int components,
  bool everywhere)
{
  const vtkIdType count = static_cast<vtkIdType>(tiles.PixelsIn(mask) * components);
  std::vector<T> send(count);
  std::vector<T> received(count);
  tiles.Pack(mask, image.data(), components, send.data());
  if (everywhere)
  {
    group.Controller->AllReduce(send.data(), received.data(), count, vtkCommunicator::SUM_OP);
  }
  else
  {
    group.Controller->Reduce(
      send.data(), received.data(), count, vtkCommunicator::SUM_OP, group.Display);
  }
  if (everywhere || group.IsDisplay())
  {
    tiles.Unpack(mask, received.data(), components, image.data());
  }
  return static_cast<double>(sizeof(T)) * count;
}

// The global moments of the marked tiles onto every process, through fixed point: a MAX
// allreduce of each pixel's exponent byte, then a SUM allreduce of the int32 codes.
double SumMomentsInFixedPoint(const ProcessGroup& group, const TileGrid& tiles,
  const std::vector<unsigned char>& mask, std::vector<double>& moments, int stride,
  FrameRecord& record)
{
  const size_t pixels = tiles.PixelsIn(mask);
  std::vector<double> packed(pixels * stride);
  tiles.Pack(mask, moments.data(), stride, packed.data());
  std::vector<unsigned char> exponents(pixels);
  for (size_t p = 0; p < pixels; ++p)
  {
    exponents[p] = fixedpoint::ExponentByte(packed[p * stride]);
  }
  std::vector<unsigned char> agreed(pixels);
  group.Controller->AllReduce(
    exponents.data(), agreed.data(), static_cast<vtkIdType>(pixels), vtkCommunicator::MAX_OP);
  ++record.MessagesSent;

  const int headroom = fixedpoint::HeadroomBits(group.Processes);
  std::vector<int32_t> codes(packed.size(), 0);
  for (size_t p = 0; p < pixels; ++p)
  {
    if (agreed[p])
    {
      const double scale = fixedpoint::Scale(agreed[p], headroom);
      for (int k = 0; k < stride; ++k)
      {
        codes[p * stride + k] = fixedpoint::Encode(packed[p * stride + k], scale, headroom);
      }
    }
  }
  std::vector<int32_t> sums(codes.size());
  group.Controller->AllReduce(
    codes.data(), sums.data(), static_cast<vtkIdType>(codes.size()), vtkCommunicator::SUM_OP);
  for (size_t p = 0; p < pixels; ++p)
  {
    const double scale = agreed[p] ? fixedpoint::Scale(agreed[p], headroom) : 1.0;
    for (int k = 0; k < stride; ++k)
    {
      packed[p * stride + k] = fixedpoint::Decode(sums[p * stride + k], scale);
    }
  }
  tiles.Unpack(mask, packed.data(), stride, moments.data());
  return static_cast<double>(pixels + sizeof(int32_t) * codes.size());
}

// The union of every process's covered tiles, on every process.
std::vector<unsigned char> AgreeOnTiles(const ProcessGroup& group, const TileGrid& tiles,
  const std::vector<double>& moments, int stride, FrameRecord& record)
{
  std::vector<unsigned char> mine =
    tiles.Mark([&](size_t pixel) { return moments[pixel * stride] > 0.0; });
  if (!group.Parallel || mine.empty())
  {
    return mine;
  }
  std::vector<unsigned char> all(mine.size());
  group.Controller->AllReduce(
    mine.data(), all.data(), static_cast<vtkIdType>(mine.size()), vtkCommunicator::MAX_OP);
  record.BytesSent += static_cast<double>(mine.size());
  ++record.MessagesSent;
  return all;
}
}

void RunMomentCompositing(const ProcessGroup& group, const CompositeFrame& frame, bool inDouble,
  FrameRecord& record, FrameResult& result)
{
  const MomentParameters& parameters = frame.Moments;
  const int stride = parameters.Moments + 1;
  const bool exchange = group.Parallel && frame.Tiles.Tiles() > 0;

  std::vector<double> moments(frame.RectPixels() * stride, 0.0);
  for (FrameEngine* engine : frame.Engines)
  {
    engine->RenderMoments(parameters, moments.data());
  }
  record.Clock.Lap("pass1");
  for (size_t p = 0; p < frame.RectPixels(); ++p)
  {
    record.OwnCoveredPixels += moments[p * stride] > 0.0 ? 1 : 0;
  }

  // The mask's allreduce is where a process waits for the slowest one's pass 1; the moments'
  // allreduce after it is the transfer alone.
  const std::vector<unsigned char> covered =
    AgreeOnTiles(group, frame.Tiles, moments, stride, record);
  record.Clock.Lap("tiles");
  auto sum = [&](std::vector<double>& image, int components, bool everywhere)
  {
    if (exchange)
    {
      record.BytesSent += inDouble
        ? SumTiles<double>(group, frame.Tiles, covered, image, components, everywhere)
        : SumTiles<float>(group, frame.Tiles, covered, image, components, everywhere);
      ++record.MessagesSent;
    }
  };
  if (exchange && !inDouble)
  {
    record.BytesSent +=
      SumMomentsInFixedPoint(group, frame.Tiles, covered, moments, stride, record);
    ++record.MessagesSent;
  }
  else
  {
    sum(moments, stride, true);
  }
  record.Clock.Lap("allreduce");
  record.Pixels = static_cast<vtkIdType>(frame.Tiles.PixelsIn(covered));
  for (size_t p = 0; p < frame.RectPixels(); ++p)
  {
    record.CoveredPixels += moments[p * stride] > 0.0 ? 1 : 0;
  }

  std::vector<double> colourSums(frame.RectPixels() * 4, 0.0);
  for (FrameEngine* engine : frame.Engines)
  {
    engine->RenderColour(parameters, moments.data(), colourSums.data());
  }
  record.Clock.Lap("pass2");
  sum(colourSums, 4, false);
  record.Clock.Lap("reduce");

  if (group.IsDisplay())
  {
    result.RGBA.assign(4 * frame.RectPixels(), 0.0f);
    ResolveImage(parameters.Resolve, frame.RectPixels(), moments.data(), stride, colourSums.data(),
      result.RGBA.data());
    record.Clock.Lap("resolve");
    result.Moments.swap(moments);
    result.ColourSums.swap(colourSums);
  }
}

} // namespace apc
