// SPDX-License-Identifier: BSD-3-Clause
#include "apcFrameAgreement.h"

#include "apcCompositeFrame.h"

#include "vtkCommunicator.h"
#include "vtkMultiProcessController.h"

#include <algorithm>
#include <limits>

namespace apc
{
namespace
{
// One MAX allreduce settles everything: minima travel negated.
namespace slot
{
enum Slot
{
  XMinNegated,
  XMax,
  YMinNegated,
  YMax,
  ZMinNegated,
  ZMax,
  Failed,
  MaxMoments,
  MinMomentsNegated,
  MaxVolumes,
  MinVolumesNegated,
  MaxWidth,
  MinWidthNegated,
  MaxHeight,
  MinHeightNegated,
  ReportPending,
  Interactive,
  SampleFactor,
  Reduction,
  MaxMode,
  MinModeNegated,
  MinBandPixelsNegated,
  SlotCount
};
}
}

LocalFrame::LocalFrame()
{
  const double inf = std::numeric_limits<double>::infinity();
  for (int d = 0; d < 3; ++d)
  {
    this->Bounds[2 * d] = inf;
    this->Bounds[2 * d + 1] = -inf;
  }
}

void LocalFrame::AddVolume(int moments, const double* bounds)
{
  this->MinMoments = this->Volumes == 0 ? moments : std::min(this->MinMoments, moments);
  this->MaxMoments = this->Volumes == 0 ? moments : std::max(this->MaxMoments, moments);
  ++this->Volumes;
  for (int d = 0; bounds && d < 3; ++d)
  {
    this->Bounds[2 * d] = std::min(this->Bounds[2 * d], bounds[2 * d]);
    this->Bounds[2 * d + 1] = std::max(this->Bounds[2 * d + 1], bounds[2 * d + 1]);
  }
}

FrameAgreement FrameAgreement::Agree(const ProcessGroup& group, const LocalFrame& local)
{
  const double inf = std::numeric_limits<double>::infinity();
  double mine[slot::SlotCount];
  for (int d = 0; d < 3; ++d)
  {
    mine[slot::XMinNegated + 2 * d] = -local.Bounds[2 * d];
    mine[slot::XMax + 2 * d] = local.Bounds[2 * d + 1];
  }
  mine[slot::Failed] = local.Failed ? 1 : 0;
  mine[slot::MaxMoments] = local.Volumes > 0 ? local.MaxMoments : 0;
  mine[slot::MinMomentsNegated] = local.Volumes > 0 ? -local.MinMoments : -inf;
  mine[slot::MaxVolumes] = local.Volumes;
  mine[slot::MinVolumesNegated] = -local.Volumes;
  mine[slot::MaxWidth] = local.Width;
  mine[slot::MinWidthNegated] = -local.Width;
  mine[slot::MaxHeight] = local.Height;
  mine[slot::MinHeightNegated] = -local.Height;
  mine[slot::ReportPending] = local.ReportPending ? 1 : 0;
  mine[slot::Interactive] = local.Interactive ? 1 : 0;
  mine[slot::SampleFactor] = std::max(local.SampleFactor, 1.0);
  mine[slot::Reduction] = std::max(local.Reduction, 1);
  // Mode, precision and depth sharing in one number: minimum and maximum must agree.
  const double mode = 4.0 * local.Mode + (local.InDouble ? 2 : 0) + (local.DepthComposited ? 1 : 0);
  mine[slot::MaxMode] = mode;
  mine[slot::MinModeNegated] = -mode;
  mine[slot::MinBandPixelsNegated] = -std::max(local.BandPixels, 1.0);
  double all[slot::SlotCount];
  std::copy(mine, mine + slot::SlotCount, all);
  if (group.Parallel)
  {
    group.Controller->AllReduce(mine, all, slot::SlotCount, vtkCommunicator::MAX_OP);
  }

  FrameAgreement agreed;
  for (int d = 0; d < 3; ++d)
  {
    agreed.Bounds[2 * d] = -all[slot::XMinNegated + 2 * d];
    agreed.Bounds[2 * d + 1] = all[slot::XMax + 2 * d];
  }
  agreed.AnyFailed = all[slot::Failed] > 0;
  agreed.MaxMoments = static_cast<int>(all[slot::MaxMoments]);
  agreed.MinMoments = static_cast<int>(-all[slot::MinMomentsNegated]);
  agreed.MaxVolumes = static_cast<int>(all[slot::MaxVolumes]);
  agreed.MinVolumes = static_cast<int>(-all[slot::MinVolumesNegated]);
  agreed.SizesDiffer = all[slot::MaxWidth] != -all[slot::MinWidthNegated] ||
    all[slot::MaxHeight] != -all[slot::MinHeightNegated];
  agreed.ModesDiffer = all[slot::MaxMode] != -all[slot::MinModeNegated];
  agreed.AnyReportPending = all[slot::ReportPending] > 0;
  agreed.Interactive = all[slot::Interactive] > 0;
  if (agreed.Interactive)
  {
    agreed.SampleFactor = all[slot::SampleFactor];
    agreed.Reduction = static_cast<int>(all[slot::Reduction]);
  }
  agreed.BandPixels = -all[slot::MinBandPixelsNegated];
  agreed.Width = local.Width;
  agreed.Height = local.Height;
  return agreed;
}

bool FrameAgreement::HasCells() const
{
  return this->Bounds[0] <= this->Bounds[1] && this->Bounds[2] <= this->Bounds[3] &&
    this->Bounds[4] <= this->Bounds[5];
}

std::string FrameAgreement::Problem() const
{
  if (this->AnyFailed)
  {
    return "a process could not render its volume (its error says why)";
  }
  if (this->MinVolumes == 0)
  {
    return "a process has no visible APC volume while others have";
  }
  if (this->SizesDiffer)
  {
    return "the processes' viewports differ in size";
  }
  if (this->ModesDiffer)
  {
    return "the processes' compositing settings (CompositeMode, CompositeInDouble, "
           "DisplayDepthComposited) differ";
  }
  if (this->MinMoments != this->MaxMoments)
  {
    return "the APC volumes use different numbers of moments";
  }
  return std::string();
}

} // namespace apc
