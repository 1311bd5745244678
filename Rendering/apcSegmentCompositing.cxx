// SPDX-License-Identifier: BSD-3-Clause
// The exact sort-last baseline (the APC paper's comparison): every process renders its ray
// segments and sends them directly to the process owning their strip of the screen
// rectangle; each owner sorts and blends its pixels' segments front to back, and a gather
// brings the strips to the display process.
#include "apcCompositeFrame.h"
#include "apcFrameEngine.h"
#include "apcStageAgreement.h"
#include "apcTestFailures.h"

#include "vtkMultiProcessController.h"

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

namespace apc
{
namespace
{
constexpr int kSegmentTag = 470521;

using Outgoing = std::vector<std::vector<WireSegment>>;

// Every process's segment count per owner and its smallest lattice index, on every process:
// counts[p * (processes + 1) + o] (o = processes: the index). Returns the frame's smallest
// lattice index, the base of the 32-bit indices on the wire.
long long ExchangeCounts(const ProcessGroup& group, const std::vector<SegmentImage>& images,
  const CompositeFrame& frame, const SegmentStrips& strips, FrameRecord& record,
  std::vector<long long>& counts)
{
  const int processes = group.Processes;
  const int rectWidth = frame.RectWidth();
  std::vector<long long> mine(processes + 1, 0);
  long long kMin = std::numeric_limits<long long>::max();
  for (int o = 0; o < processes; ++o)
  {
    for (int j = strips.Begin(o); j < strips.Begin(o + 1); ++j)
    {
      for (const SegmentImage& image : images)
      {
        const int64_t first = static_cast<int64_t>(j) * rectWidth;
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
  counts.assign(static_cast<size_t>(processes) * (processes + 1), 0);
  if (group.Parallel)
  {
    group.Collective(
      "exchange", [&] { group.Controller->AllGather(mine.data(), counts.data(), processes + 1); });
    record.BytesSent += sizeof(long long) * mine.size();
    ++record.MessagesSent;
  }
  else
  {
    counts = mine;
  }
  long long kBase = std::numeric_limits<long long>::max();
  for (int p = 0; p < processes; ++p)
  {
    kBase = std::min(kBase, counts[static_cast<size_t>(p) * (processes + 1) + processes]);
  }
  return kBase;
}

// This process's segments in wire format, per owner, in the owner's pixel order.
Outgoing PackForOwners(const std::vector<SegmentImage>& images, const CompositeFrame& frame,
  const SegmentStrips& strips, const std::vector<long long>& counts, int rank, long long kBase)
{
  const int processes = strips.Processes;
  const int rectWidth = frame.RectWidth();
  Outgoing outgoing(processes);
  for (int o = 0; o < processes; ++o)
  {
    outgoing[o].reserve(
      static_cast<size_t>(counts[static_cast<size_t>(rank) * (processes + 1) + o]));
    for (int j = strips.Begin(o); j < strips.Begin(o + 1); ++j)
    {
      for (int i = 0; i < rectWidth; ++i)
      {
        const int64_t pixel = static_cast<int64_t>(j) * rectWidth + i;
        const int32_t local = (j - strips.Begin(o)) * rectWidth + i;
        for (const SegmentImage& image : images)
        {
          for (int64_t s = image.Offsets[pixel]; s < image.Offsets[pixel + 1]; ++s)
          {
            outgoing[o].push_back(WireSegment::From(image.Segments[s], local, kBase));
          }
        }
      }
    }
  }
  return outgoing;
}

// Room for every process's segments to this one (counts: ExchangeCounts'), and its own moved
// in: all the exchange receives, allocated before it starts.
Outgoing SizeIncoming(
  const ProcessGroup& group, Outgoing& outgoing, const std::vector<long long>& counts)
{
  const int processes = group.Processes;
  const int rank = group.Rank;
  Outgoing incoming(processes);
  for (int partner = 0; partner < processes; ++partner)
  {
    if (partner != rank)
    {
      incoming[partner].resize(
        static_cast<size_t>(counts[static_cast<size_t>(partner) * (processes + 1) + rank]));
    }
  }
  incoming[rank].swap(outgoing[rank]);
  return incoming;
}

// Direct send into incoming (sized by SizeIncoming), one message per pair with segments. Pairs
// meet in rounds (partner = rank XOR round), the lower rank sending first: blocking sends then
// never wait in a cycle.
void DirectSend(
  const ProcessGroup& group, const Outgoing& outgoing, Outgoing& incoming, FrameRecord& record)
{
  const int processes = group.Processes;
  const int rank = group.Rank;
  if (!group.Parallel)
  {
    return;
  }
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
    auto sendPart = [&]
    {
      if (!send.empty())
      {
        group.Controller->Send(reinterpret_cast<const char*>(send.data()),
          static_cast<vtkIdType>(send.size() * sizeof(WireSegment)), partner, kSegmentTag);
        record.BytesSent += static_cast<double>(send.size() * sizeof(WireSegment));
        ++record.MessagesSent;
      }
    };
    auto receivePart = [&]
    {
      if (!receive.empty())
      {
        group.Controller->Receive(reinterpret_cast<char*>(receive.data()),
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

// Room for the gathered strips on the display process (its own strip alone).
std::vector<float> SizePacked(const ProcessGroup& group, const SegmentStrips& strips, int rectWidth)
{
  return std::vector<float>(
    group.Parallel && group.IsDisplay() ? 4 * static_cast<size_t>(rectWidth) * strips.Rows : 0);
}

// The strips, in row order, into packed (SizePacked): the rectangle's image on the display
// process.
void GatherStrips(const ProcessGroup& group, const SegmentStrips& strips, int rectWidth,
  std::vector<float>& stripImage, std::vector<float>& packed, FrameRecord& record)
{
  if (!group.Parallel)
  {
    packed.swap(stripImage);
    return;
  }
  const int processes = group.Processes;
  std::vector<vtkIdType> lengths(processes);
  std::vector<vtkIdType> offsets(processes);
  for (int o = 0; o < processes; ++o)
  {
    lengths[o] = 4 * static_cast<vtkIdType>(rectWidth) * strips.RowsOf(o);
    offsets[o] = 4 * static_cast<vtkIdType>(rectWidth) * (strips.Begin(o) - strips.RowBegin);
  }
  float unused = 0; // GatherV's receive buffer off the display process
  float* into = group.IsDisplay() ? packed.data() : &unused;
  group.Collective("gather",
    [&]
    {
      group.Controller->GatherV(stripImage.data(), into, static_cast<vtkIdType>(stripImage.size()),
        lengths.data(), offsets.data(), group.Display);
    });
  if (!group.IsDisplay() && !stripImage.empty())
  {
    record.BytesSent += sizeof(float) * static_cast<double>(stripImage.size());
    ++record.MessagesSent;
  }
}

// The statistics of all strips, the same on every process.
SegmentStatistics AllStatistics(const ProcessGroup& group, const SegmentStatistics& own)
{
  long long stats[3] = { own.Segments, own.NonEmptyPixels, own.MaxPerPixel };
  if (group.Parallel)
  {
    std::vector<long long> gathered(3 * static_cast<size_t>(group.Processes));
    group.Collective("statistics", [&] { group.Controller->AllGather(stats, gathered.data(), 3); });
    stats[0] = stats[1] = stats[2] = 0;
    for (int p = 0; p < group.Processes; ++p)
    {
      stats[0] += gathered[3 * p];
      stats[1] += gathered[3 * p + 1];
      stats[2] = std::max(stats[2], gathered[3 * p + 2]);
    }
  }
  SegmentStatistics all;
  all.Segments = stats[0];
  all.NonEmptyPixels = stats[1];
  all.MaxPerPixel = stats[2];
  return all;
}
}

// Each step of a process's own work (its segments, their packing, its strip's blend) runs
// inside the frame's failure agreement, with every buffer the next collective needs: a process
// whose memory runs out makes every process leave the frame there (record.Failed) instead of
// leaving them waiting in the exchange or the gather.
void RunSegmentCompositing(
  const ProcessGroup& group, const CompositeFrame& frame, FrameRecord& record, FrameResult& result)
{
  const int rectWidth = frame.RectWidth();
  const SegmentStrips strips{ 0, frame.RectHeight(), group.Processes };

  // 1. This process's segments, per volume.
  std::vector<SegmentImage> images(frame.Engines.size());
  std::string failure = CatchFailure(
    [&]
    {
      ThrowIfFailingForTesting(FailurePoint::Segments);
      for (size_t v = 0; v < images.size(); ++v)
      {
        frame.Engines[v]->RenderSegments(images[v]);
        if (images[v].Width != rectWidth || images[v].Height != frame.RectHeight())
        {
          images[v].Reset(rectWidth, frame.RectHeight()); // a process that could not prepare
        }
      }
    });
  record.Clock.Lap("segments");
  if (!AgreeOnStage(group, "exchange", "the exact segments", failure, record))
  {
    record.Clock.Lap("exchange");
    return;
  }
  for (size_t p = 0; p < frame.RectPixels(); ++p)
  {
    bool any = false;
    for (const SegmentImage& image : images)
    {
      any = any || image.Count(static_cast<int64_t>(p)) > 0;
    }
    record.OwnCoveredPixels += any ? 1 : 0;
  }

  // 2. Counts per owner, then the segments, to their owners.
  std::vector<long long> counts;
  const long long kBase = ExchangeCounts(group, images, frame, strips, record, counts);
  Outgoing outgoing;
  Outgoing incoming;
  if (!RunAgreedStage(group, "exchange", "packing the exact segments", record,
        [&]
        {
          ThrowIfFailingForTesting(FailurePoint::SegmentPacking);
          outgoing = PackForOwners(images, frame, strips, counts, group.Rank, kBase);
          images = std::vector<SegmentImage>();
          incoming = SizeIncoming(group, outgoing, counts);
        }))
  {
    record.Clock.Lap("exchange");
    return;
  }
  // The pairs' rounds are one collective: they start together, after the packing.
  group.Collective("exchange", [&] { DirectSend(group, outgoing, incoming, record); });
  outgoing = Outgoing();
  record.Clock.Lap("exchange");

  // 3. The own strip: segments grouped by pixel, then sorted and blended.
  std::vector<float> stripImage;
  std::vector<float> packed;
  SegmentStatistics own;
  failure = CatchFailure(
    [&]
    {
      ThrowIfFailingForTesting(FailurePoint::SegmentBlend);
      SegmentImage strip;
      GroupByPixel(incoming, rectWidth, strips.RowsOf(group.Rank), strip);
      incoming = Outgoing();
      stripImage.assign(4 * static_cast<size_t>(rectWidth) * strip.Height, 0.0f);
      CompositeSegmentImage(strip, stripImage.data());
      own = GetSegmentStatistics(strip);
      packed = SizePacked(group, strips, rectWidth);
    });
  record.Clock.Lap("blend_segments");
  if (!AgreeOnStage(group, "gather", "blending the exact segments", failure, record))
  {
    record.Clock.Lap("gather");
    return;
  }

  // 4. The strips to the display process.
  GatherStrips(group, strips, rectWidth, stripImage, packed, record);
  record.Clock.Lap("gather");
  record.Segments = AllStatistics(group, own);
  record.Clock.Lap("statistics");

  if (group.IsDisplay())
  {
    result.RGBA.swap(packed);
    result.RGBA.resize(4 * frame.RectPixels(), 0.0f);
  }
}

} // namespace apc
