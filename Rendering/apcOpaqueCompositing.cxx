// SPDX-License-Identifier: BSD-3-Clause
// APC mode's Stop Where Opaque between pass 1 and the moments' allreduce: the processes'
// opaque profiles summed (each pixel's bins only as far as the cut can lie, agreed from a
// summary first: apcOpaqueSummary.h), the cut every process then applies, and on several
// processes pass 1's bound predicted from the last frame's cut, with the pixels it leaves
// unresolved marched again (apcOpaquePrediction.h; docs/sampler.md proves the cut is the one
// complete data gives).
#include "apcCompositeFrame.h"
#include "apcCoveredTiles.h"
#include "apcFrameEngine.h"
#include "apcOpaqueBins.h"
#include "apcOpaquePrediction.h"
#include "apcOpaqueSummary.h"
#include "apcStageAgreement.h"
#include "apcTestFailures.h"
#include "apcWireMessages.h"

#include "vtkCommunicator.h"
#include "vtkMultiProcessController.h"

#include <algorithm>
#include <cstdint>
#include <exception>
#include <string>
#include <vector>

namespace apc
{
using wire::Hold;
using wire::InMessages;

namespace
{
// Pass 1 on several processes stops each ray where the largest cut of the last frame within
// this many pixels ended, plus this many bins (docs/sampler.md: measured on the wind data).
constexpr int kPredictionRadius = 2;
constexpr int kPredictionMargin = 1;

// Saturating sums of opaque profiles (apcOpaqueBins.h): exact and order-independent.
class SaturatingProfileSum : public vtkCommunicator::Operation
{
public:
  void Function(const void* a, void* b, vtkIdType length, int) override
  {
    AddProfiles(static_cast<uint16_t*>(b), static_cast<const uint16_t*>(a), length);
  }
  int Commutative() override { return 1; }
};

// Combined opaque summaries (apcOpaqueSummary.h): the earliest own cut, the totals summed.
class OpaqueSummaryCombine : public vtkCommunicator::Operation
{
public:
  void Function(const void* a, void* b, vtkIdType length, int) override
  {
    CombineOpaqueSummaries(static_cast<uint16_t*>(b), static_cast<const uint16_t*>(a), length);
  }
  int Commutative() override { return 1; }
};

// This process's opaque profile of a band (values: pixels * OpaqueBins::kBins): one volume's
// own (no copy), several summed; zeros without volumes.
const uint16_t* LocalProfile(const CompositeFrame& frame, size_t values, MomentBuffers& buffers)
{
  if (frame.Engines.size() == 1 && frame.Engines.front()->GetOpaqueProfile().size() == values)
  {
    return frame.Engines.front()->GetOpaqueProfile().data();
  }
  uint16_t* profile = Hold(buffers.ProfileLocal, values);
  std::fill_n(profile, values, uint16_t(0));
  for (const FrameEngine* engine : frame.Engines)
  {
    const VolumeRayMarcher::OpaqueProfile volume = engine->GetOpaqueProfile();
    AddProfiles(profile, volume.data(), std::min(volume.size(), values));
  }
  return profile;
}

// An allreduce of count 16-bit values of send into received with operation,
// in messages of at most the settings' size.
void AllReduceInMessages(const ProcessGroup& group, const CompositeFrame& frame, const char* stage,
  const uint16_t* send, uint16_t* received, size_t count, vtkCommunicator::Operation* operation,
  FrameRecord& record)
{
  group.Collective(stage,
    [&]
    {
      InMessages<uint16_t>(count, static_cast<size_t>(frame.Settings.MaxMessageBytes),
        [&](size_t offset, vtkIdType length)
        {
          group.Controller->AllReduce(send + offset, received + offset, length, operation);
          ++record.MessagesSent;
        });
    });
  record.BytesSent += static_cast<double>(sizeof(uint16_t) * count);
  record.ProfileBytes += static_cast<double>(sizeof(uint16_t) * count);
}

// The profiles of the marked tiles summed over every process into summed (band pixels; the
// other tiles are left as they are): every process's summary of each pixel combined first (2
// bytes a pixel), then each pixel's bins up to the earliest own cut alone, none where the
// totals stay below the threshold (apcOpaqueSummary.h), and with a predicted bound (bound:
// band pixels, the same on every process) none past it, where every process's profile is
// zero. The marked tiles of summed get their sums, zero past the bins sent (summed may be
// mine: each is read before it is written). Every process makes the same calls: a process
// without volumes sends zeros.
void SumProfiles(const ProcessGroup& group, const CompositeFrame& frame, const TileGrid& tiles,
  const std::vector<unsigned char>& mask, const uint16_t* mine, const uint8_t* bound,
  uint16_t* summed, MomentBuffers& buffers, FrameRecord& record, const char* stage = "profile")
{
  constexpr int bins = OpaqueBins::kBins;
  const size_t pixels = tiles.PixelsIn(mask);
  if (pixels == 0)
  {
    return;
  }
  uint16_t* summaries = Hold(buffers.SummarySend, pixels);
  uint16_t* combined = Hold(buffers.SummarySum, pixels);
  size_t i = 0;
  tiles.ForEachPacked(mask, [&](size_t p) { summaries[i++] = OpaqueSummary::Of(mine + p * bins); });
  OpaqueSummaryCombine combine;
  AllReduceInMessages(group, frame, stage, summaries, combined, pixels, &combine, record);
  if (bound)
  {
    i = 0;
    tiles.ForEachPacked(mask,
      [&](size_t p)
      {
        combined[i] = OpaqueSummary::Bounded(combined[i], bound[p]);
        ++i;
      });
  }
  size_t count = 0;
  for (size_t q = 0; q < pixels; ++q)
  {
    count += static_cast<size_t>(OpaqueSummary::Bins(combined[q]));
  }
  if (count == 0)
  {
    tiles.ForEachPacked(mask, [&](size_t p) { std::fill_n(summed + p * bins, bins, uint16_t(0)); });
    return;
  }
  // The wire's buffers are free until the moments' sum (which held them at its size first).
  // One message at a time, in buffers of one message's size: the same messages as packing
  // every pixel's bins first.
  const size_t step = std::min(
    count, wire::MessageValues<uint16_t>(static_cast<size_t>(frame.Settings.MaxMessageBytes)));
  uint16_t* send = wire::HoldAs<uint16_t>(buffers.WireSend, step);
  uint16_t* received = wire::HoldAs<uint16_t>(buffers.WireReceived, step);
  const auto kept = [&](size_t i) { return static_cast<size_t>(OpaqueSummary::Bins(combined[i])); };
  PackedWalk packing(tiles, mask);
  PackedWalk unpacking(tiles, mask);
  // Every pixel's bins past those kept are zero in the sum; summed may be mine, whose kept
  // bins are read before they are written.
  const auto pack = [&](size_t length)
  {
    packing.Next(length, kept,
      [&](size_t p, size_t, size_t k0, size_t k1, size_t at)
      { std::copy(mine + p * bins + k0, mine + p * bins + k1, send + at); });
  };
  pack(step);
  SaturatingProfileSum sum;
  group.Collective(stage,
    [&]
    {
      InMessages<uint16_t>(count, static_cast<size_t>(frame.Settings.MaxMessageBytes),
        [&](size_t offset, vtkIdType length)
        {
          if (offset > 0)
          {
            pack(static_cast<size_t>(length));
          }
          group.Controller->AllReduce(send, received, length, &sum);
          ++record.MessagesSent;
          unpacking.Next(static_cast<size_t>(length), kept,
            [&](size_t p, size_t, size_t k0, size_t k1, size_t at)
            { std::copy(received + at, received + at + (k1 - k0), summed + p * bins + k0); });
        });
    });
  record.BytesSent += static_cast<double>(sizeof(uint16_t) * count);
  record.ProfileBytes += static_cast<double>(sizeof(uint16_t) * count);
  i = 0;
  tiles.ForEachPacked(mask,
    [&](size_t p)
    {
      const int keep = OpaqueSummary::Bins(combined[i++]);
      std::fill(summed + p * bins + keep, summed + (p + 1) * bins, uint16_t(0));
    });
}

// Calls work(engine, its moments) for each volume of the frame that stops where opaque: its own
// moments (own[e]) where the volumes keep them apart, else the band's (one volume).
template <class F>
void ForEachStoppingVolume(
  const CompositeFrame& frame, std::vector<std::vector<double>>& own, double* moments, F&& work)
{
  for (size_t e = 0; e < frame.Engines.size(); ++e)
  {
    if (frame.Engines[e]->StopsWhereOpaque(frame.Moments))
    {
      work(frame.Engines[e], own.empty() ? moments : own[e].data());
    }
  }
}

// With a predicted bound: the pixels whose summed profile does not reach the threshold by it
// have an unknown cut. Every process finds the same ones (the profile is summed), marches
// their marcher tiles again without the bound and sums those tiles' profiles again, so the
// cut is the one without a prediction. The tiles join covered (they may hold samples now).
// False if some process's march failed (agreed, record.Failed set): every process leaves the
// band before the profiles' second sum.
bool ResolvePredictedCut(const ProcessGroup& group, const CompositeFrame& frame,
  const RowBand& band, const TileGrid& tiles, std::vector<unsigned char>& covered,
  std::vector<std::vector<double>>& own, double* moments, size_t pixels, uint16_t* summed,
  MomentBuffers& buffers, FrameRecord& record)
{
  uint8_t* unresolved = Hold(buffers.Unresolved, pixels); // held before pass 1: no allocation
  const size_t open = MarkUnresolved(buffers.Bound.data(), summed, pixels, unresolved);
  record.OpaquePredictedUnresolved += static_cast<vtkIdType>(open);
  if (open == 0)
  {
    return true; // the same on every process: the profile is summed
  }
  // The tiles marched again (memory for their samples) and the local sum of their profiles run
  // inside the frame's failure agreement, before the profiles' second sum.
  std::vector<unsigned char> mask;
  const uint16_t* local = nullptr;
  auto redo = [&]
  {
    ThrowIfFailingForTesting(FailurePoint::OpaqueRedo);
    ForEachStoppingVolume(frame, own, moments,
      [&](FrameEngine* engine, double* volume)
      { engine->RedoOpaqueTiles(frame.Moments, unresolved, volume, band); });
    // The marcher's tiles marched again, then the wire's tiles inside them (they divide them).
    constexpr int size = VolumeRayMarcher::kTileSize;
    const int width = frame.RectWidth();
    const size_t across = static_cast<size_t>((width + size - 1) / size);
    std::vector<uint8_t> redone(across * ((pixels / width + size - 1) / size), 0);
    for (size_t p = 0; p < pixels; ++p)
    {
      if (unresolved[p])
      {
        redone[(p / width / size) * across + (p % width) / size] = 1;
      }
    }
    record.OpaquePredictedRedone +=
      static_cast<vtkIdType>(std::count(redone.begin(), redone.end(), uint8_t(1)));
    mask = tiles.Mark([&](size_t pixel)
      { return redone[(pixel / width / size) * across + (pixel % width) / size]; });
    local = LocalProfile(frame, pixels * OpaqueBins::kBins, buffers);
  };
  if (!RunAgreedStage(group, "profile", "marching the unresolved tiles again", record, redo))
  {
    return false;
  }
  // Marched again without the bound: every bin.
  SumProfiles(group, frame, tiles, mask, local, nullptr, summed, buffers, record);
  for (size_t t = 0; t < covered.size() && t < mask.size(); ++t)
  {
    covered[t] = covered[t] || mask[t];
  }
  return true;
}

} // namespace

// With Stop Where Opaque: every volume's opaque profile summed over the covered tiles of
// every process, then each volume's own moments (own[e], or moments with one volume) cut
// where the sum is opaque and summed into moments (pixels * stride values). With a predicted
// bound (buffers.Bound, several processes), unresolved pixels are resolved first. The agreed
// cut is remembered for the next frame's prediction.
bool CutWhereOpaque(const ProcessGroup& group, const CompositeFrame& frame, const RowBand& band,
  const TileGrid& tiles, std::vector<unsigned char>& covered, std::vector<std::vector<double>>& own,
  double* moments, size_t pixels, bool bounded, MomentBuffers& buffers, FrameRecord& record)
{
  constexpr int bins = OpaqueBins::kBins;
  const size_t values = pixels * bins;
  // One volume's profile is summed in place (at 1024^2 32 MB a process that a first frame
  // would page in afresh, and a later one write and read); several volumes' local sum is
  // read again for the tiles ResolvePredictedCut marches again, so theirs is summed apart.
  uint16_t* inPlace = group.Parallel && frame.Engines.size() == 1
    ? frame.Engines.front()->GetOpaqueProfileToSum(values)
    : nullptr;
  const uint16_t* mine = inPlace ? inPlace : LocalProfile(frame, values, buffers);
  uint16_t* summed = nullptr;
  if (inPlace)
  {
    summed = inPlace;
    std::vector<unsigned char> uncovered(covered.size());
    std::transform(
      covered.begin(), covered.end(), uncovered.begin(), [](unsigned char c) { return c ? 0 : 1; });
    // the uncovered tiles have no samples anywhere
    tiles.ForEachPacked(
      uncovered, [&](size_t p) { std::fill_n(summed + p * bins, bins, uint16_t(0)); });
  }
  else if (group.Parallel)
  {
    summed = Hold(buffers.Profile, values);
    std::fill_n(summed, values, uint16_t(0)); // the uncovered tiles have no samples anywhere
  }
  if (summed)
  {
    SumProfiles(group, frame, tiles, covered, mine, bounded ? buffers.Bound.data() : nullptr,
      summed, buffers, record);
    mine = summed;
  }
  record.Clock.Lap("profile");
  if (bounded && summed &&
    !ResolvePredictedCut(
      group, frame, band, tiles, covered, own, moments, pixels, summed, buffers, record))
  {
    return false;
  }
  // Applying the cut may sum a volume's moments again from its cached samples (memory): inside
  // the frame's failure agreement, before the moments' sum.
  const std::string failure = CatchFailure(
    [&]
    {
      ThrowIfFailingForTesting(FailurePoint::OpaqueCut);
      ForEachStoppingVolume(frame, own, moments,
        [&](FrameEngine* engine, double* volume)
        { engine->ApplyOpaqueCut(frame.Moments, mine, volume, band); });
    });
  record.Clock.Lap("cut");
  if (!AgreeOnStage(group, "allreduce", "the opaque cut", failure, record))
  {
    return false;
  }
  if (summed && buffers.Cuts.Valid)
  {
    const int width = frame.RectWidth();
    uint8_t* cuts = buffers.Cuts.Cut.data() + static_cast<size_t>(band.J0) * width;
    for (size_t p = 0; p < pixels; ++p)
    {
      cuts[p] = static_cast<uint8_t>(CutBin(summed + p * bins));
    }
  }
  if (!own.empty())
  {
    const size_t length = pixels * (frame.Moments.Moments + 1);
    std::fill_n(moments, length, 0.0);
    for (const std::vector<double>& volume : own)
    {
      std::transform(volume.begin(), volume.begin() + length, moments, moments,
        [](double a, double b) { return a + b; });
    }
  }
  return true;
}

bool PredictOpaqueBand(
  const CompositeFrame& frame, const RowBand& band, size_t pixels, MomentBuffers& buffers)
{
  const OpaqueCutMemory& previous = buffers.PreviousCuts;
  return buffers.Cuts.Valid &&
    PredictOpaqueBound(previous, buffers.Cuts.Image, frame.Rect.I0, frame.Rect.J0 + band.J0,
      frame.RectWidth(), band.J1 - band.J0, kPredictionRadius, kPredictionMargin,
      Hold(buffers.Bound, pixels));
}

ProbeResult ProbeOpaqueCuts(const ProcessGroup& group, const CompositeFrame& frame,
  MomentBuffers& buffers, FrameRecord& record)
{
  constexpr int bins = OpaqueBins::kBins;
  const int step = frame.Settings.OpaqueProbeStep;
  const int offset = step / 2; // the middle of each step x step block
  const int width = ProbeSize(frame.RectWidth(), step, offset);
  const int height = ProbeSize(frame.RectHeight(), step, offset);
  const size_t pixels = static_cast<size_t>(width) * height;
  std::vector<uint16_t> profile;
  // A process whose probe throws (memory for the probe's marcher or profile) must not leave
  // the others waiting in the profiles' allreduce: the frame's failure agreement.
  if (!RunAgreedStage(group, "opaque_prepass", "Stop Where Opaque's probe", record,
        [&]
        {
          profile.assign(pixels * bins, uint16_t(0));
          for (FrameEngine* engine : frame.Engines)
          {
            if (engine->GetWidth() == frame.RectWidth() &&
              engine->GetHeight() == frame.RectHeight())
            {
              record.OpaquePrepassSamples +=
                engine->ProbeOpaqueProfile(frame.Moments, step, offset, profile.data());
            }
          }
        }))
  {
    record.Clock.Lap("opaque_prepass");
    return ProbeResult::Failed;
  }
  // The probe's rays are a complete set of rays: their own stops and the summaries give
  // their exact cut, as in a first frame without a bound. Every process joins, with zeros if
  // it has nothing to probe.
  const TileGrid tiles(width, 0, 0, width, height);
  const std::vector<unsigned char> all(tiles.Tiles(), 1);
  SumProfiles(group, frame, tiles, all, profile.data(), nullptr, profile.data(), buffers, record,
    "opaque_prepass");
  std::vector<uint8_t> cuts(pixels);
  for (size_t p = 0; p < pixels; ++p)
  {
    cuts[p] = static_cast<uint8_t>(CutBin(profile.data() + p * bins));
  }
  // No probe ray turned opaque: a bound of "none" everywhere would bound nothing, so the frame
  // goes on without a bound, and its caller may march it without the stop.
  if (std::all_of(
        cuts.begin(), cuts.end(), [](uint8_t cut) { return cut == OpaqueBins::kBins - 1; }))
  {
    record.Clock.Lap("opaque_prepass");
    return ProbeResult::NoneOpaque;
  }
  buffers.PreviousCuts.Begin(
    buffers.Cuts.Image, frame.Rect.I0, frame.Rect.J0, frame.RectWidth(), frame.RectHeight());
  SpreadProbeCuts(cuts.data(), width, height, step, offset, buffers.PreviousCuts);
  record.Clock.Lap("opaque_prepass");
  return ProbeResult::Bounded;
}

} // namespace apc
