// SPDX-License-Identifier: BSD-3-Clause
#include "apcFrameTimings.h"

#include "vtkMultiProcessController.h"

#include <algorithm>
#include <cstring>
#include <sstream>
#include <utility>
#include <vector>

namespace apc
{
namespace
{
// A timing name's stage and part: "tiles_wait" is ("tiles", 1), "allreduce_transfer"
// ("allreduce", 2), any other name (name, 0).
std::pair<std::string, int> StagePart(const std::string& name)
{
  for (const auto& suffix : { std::make_pair("_wait", 1), std::make_pair("_transfer", 2) })
  {
    const size_t length = std::strlen(suffix.first);
    if (name.size() > length && name.compare(name.size() - length, length, suffix.first) == 0)
    {
      return { name.substr(0, name.size() - length), suffix.second };
    }
  }
  return { name, 0 };
}

// The slowest render against the mean, and the longest wait, over the processes.
void SetRankTimings(const FrameRecord& record, vtkAPCCompositePass::Timings& t)
{
  const std::vector<double>& render = record.RankRender;
  if (render.empty())
  {
    return;
  }
  const auto slowest = std::max_element(render.begin(), render.end());
  double sum = 0;
  for (const double seconds : render)
  {
    sum += seconds;
  }
  t.RenderMean = sum / static_cast<double>(render.size());
  t.RenderMax = *slowest;
  t.RenderImbalance = t.RenderMean > 0 ? t.RenderMax / t.RenderMean : 1.0;
  t.SlowestRank = static_cast<double>(slowest - render.begin());
  const std::vector<double>& wait = record.RankWait;
  t.WaitMax = wait.empty() ? 0.0 : *std::max_element(wait.begin(), wait.end());
}
}

double RenderSeconds(const StageClock& clock)
{
  return clock.Get("pass1") + clock.Get("cut") + clock.Get("pass2") + clock.Get("segments") +
    clock.Get("blend_segments") + clock.Get("exact");
}

void GatherRankTimes(const ProcessGroup& group, FrameRecord& record)
{
  const double mine[2] = { RenderSeconds(record.Clock), record.Collectives.Wait(nullptr) };
  std::vector<double> all(mine, mine + 2);
  if (group.Parallel)
  {
    all.resize(2 * static_cast<size_t>(group.Processes));
    group.Collective(
      "ranks", [&] { group.Controller->Gather(mine, all.data(), 2, group.Display); });
    if (!group.IsDisplay())
    {
      all.assign(mine, mine + 2); // the gather's result is the display process's alone
    }
  }
  record.RankRender.clear();
  record.RankWait.clear();
  for (size_t p = 0; p < all.size() / 2; ++p)
  {
    record.RankRender.push_back(all[2 * p]);
    record.RankWait.push_back(all[2 * p + 1]);
  }
  record.Clock.Lap("ranks");
}

vtkAPCCompositePass::Timings TimingsOf(const FrameRecord& record)
{
  const StageClock& clock = record.Clock;
  const CollectiveTimes& collectives = record.Collectives;
  vtkAPCCompositePass::Timings t;
  // The stages and their collectives' parts by their names (the other names are no stage:
  // zero, set below).
  vtkAPCCompositePass::ForEachTiming(t,
    [&](const char* name, double& field)
    {
      const std::pair<std::string, int> part = StagePart(name);
      const char* stage = part.first.c_str();
      field = part.second == 0 ? clock.Get(stage)
        : part.second == 1     ? collectives.Wait(stage)
                               : collectives.Transfer(stage);
    });
  t.Total = clock.Get(nullptr);
  t.BytesSent = record.BytesSent;
  t.MessagesSent = static_cast<double>(record.MessagesSent);
  t.CompositedPixels = static_cast<double>(record.Pixels);
  t.CoveredPixels = static_cast<double>(record.CoveredPixels);
  t.AverageSegmentsPerPixel = record.Segments.Average();
  t.MaxSegmentsPerPixel = static_cast<double>(record.Segments.MaxPerPixel);
  t.Pass1Samples = static_cast<double>(record.Pass1Samples);
  t.Pass2Samples = static_cast<double>(record.Pass2Samples);
  t.OpaqueStopSkipped = record.OpaqueStopSkipped;
  t.OpaqueStopRedone = record.OpaqueStopRedone;
  t.OpaqueUnstoppedTiles = static_cast<double>(record.OpaqueUnstoppedTiles);
  t.ProfileBytes = record.ProfileBytes;
  t.OpaquePredictedUnresolved = static_cast<double>(record.OpaquePredictedUnresolved);
  t.OpaquePredictedRedone = static_cast<double>(record.OpaquePredictedRedone);
  t.OpaquePrepassSamples = static_cast<double>(record.OpaquePrepassSamples);
  t.Bands = record.Bands;
  if (record.Pass2Samples > 0)
  {
    const double pass2 = static_cast<double>(record.Pass2Samples);
    t.Pass2CachedShare = static_cast<double>(record.Pass2Replayed) / pass2;
    t.Pass2HiddenShare = static_cast<double>(record.Pass2Hidden) / pass2;
  }
  t.Wait = collectives.Wait(nullptr);
  t.Transfer = collectives.Transfer(nullptr);
  t.Render = RenderSeconds(clock);
  SetRankTimings(record, t);
  return t;
}

std::string DescribeStages(const FrameRecord& record)
{
  std::ostringstream line;
  for (const auto& entry : record.Clock.Stages())
  {
    line << ' ' << entry.first << ' ' << entry.second << " s";
    for (const CollectiveTimes::Entry& part : record.Collectives.Entries())
    {
      if (part.Stage == entry.first)
      {
        line << " (wait " << part.Wait << ", transfer " << part.Transfer << ")";
      }
    }
    line << ',';
  }
  line << " render per rank";
  for (const double seconds : record.RankRender)
  {
    line << ' ' << seconds;
  }
  line << " s,";
  return line.str();
}

} // namespace apc
