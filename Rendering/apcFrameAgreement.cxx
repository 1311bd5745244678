// SPDX-License-Identifier: BSD-3-Clause
#include "apcFrameAgreement.h"

#include "apcCompositeFrame.h"
#include "apcFrameInputsFromVTK.h"

#include "vtkCommunicator.h"
#include "vtkMultiProcessController.h"

#include "vtkAPCVolumeMapper.h"
#include "vtkObject.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

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
  MaxColour,
  MinColourNegated,
  MaxOpacity,
  MinOpacityNegated,
  MaxRangeLow,
  MinRangeLowNegated,
  MaxRangeHigh,
  MinRangeHighNegated,
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

void LocalFrame::AddVolume(int moments, const double* bounds, vtkVolumeProperty* property)
{
  const TransferSignature transfer =
    property ? TransferSignatureFromVTK(property) : TransferSignature();
  if (this->Volumes == 0)
  {
    this->Transfer = transfer;
  }
  else
  {
    // Several volumes: the checksums combined in order, the ranges' union.
    this->Transfer.Colour =
      std::fmod(this->Transfer.Colour * 31 + transfer.Colour, 281474976710656.0);
    this->Transfer.Opacity =
      std::fmod(this->Transfer.Opacity * 31 + transfer.Opacity, 281474976710656.0);
    this->Transfer.Range[0] = std::min(this->Transfer.Range[0], transfer.Range[0]);
    this->Transfer.Range[1] = std::max(this->Transfer.Range[1], transfer.Range[1]);
  }
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
  // A process without volumes has no transfer function to compare: it leaves these slots.
  const bool some = local.Volumes > 0;
  const TransferSignature& t = local.Transfer;
  mine[slot::MaxColour] = some ? t.Colour : -inf;
  mine[slot::MinColourNegated] = some ? -t.Colour : -inf;
  mine[slot::MaxOpacity] = some ? t.Opacity : -inf;
  mine[slot::MinOpacityNegated] = some ? -t.Opacity : -inf;
  mine[slot::MaxRangeLow] = some ? t.Range[0] : -inf;
  mine[slot::MinRangeLowNegated] = some ? -t.Range[0] : -inf;
  mine[slot::MaxRangeHigh] = some ? t.Range[1] : -inf;
  mine[slot::MinRangeHighNegated] = some ? -t.Range[1] : -inf;
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
  if (all[slot::MaxVolumes] > 0)
  {
    agreed.ColourDiffers = all[slot::MaxColour] != -all[slot::MinColourNegated];
    agreed.OpacityDiffers = all[slot::MaxOpacity] != -all[slot::MinOpacityNegated];
    agreed.RangeLow[0] = -all[slot::MinRangeLowNegated];
    agreed.RangeLow[1] = all[slot::MaxRangeLow];
    agreed.RangeHigh[0] = -all[slot::MinRangeHighNegated];
    agreed.RangeHigh[1] = all[slot::MaxRangeHigh];
  }
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

bool FrameAgreement::TransferFunctionsDiffer() const
{
  return this->ColourDiffers || this->OpacityDiffers || this->RangeLow[0] != this->RangeLow[1] ||
    this->RangeHigh[0] != this->RangeHigh[1];
}

std::string FrameAgreement::TransferMismatch(const std::string& array) const
{
  if (!this->TransferFunctionsDiffer())
  {
    return std::string();
  }
  std::ostringstream out;
  out << "APC: the processes map '" << array << "' with different transfer functions (";
  const char* sep = "";
  if (this->ColourDiffers)
  {
    out << "colour transfer function";
    sep = ", ";
  }
  if (this->OpacityDiffers)
  {
    out << sep << "opacity transfer function";
    sep = ", ";
  }
  if (this->RangeLow[0] != this->RangeLow[1] || this->RangeHigh[0] != this->RangeHigh[1])
  {
    out << sep << "scalar range from [" << this->RangeLow[0] << ", " << this->RangeHigh[0]
        << "] to [" << this->RangeLow[1] << ", " << this->RangeHigh[1] << "]";
  }
  out << "): each process's cells are drawn with its own, so the picture mixes them. A script "
         "every rank runs (Catalyst, pvbatch --symmetric) gets each rank's own data range: "
         "rescale to one range on all ranks (a fixed one, or the global range from an MPI "
         "allreduce of the ranks' minima and maxima).";
  return out.str();
}

void WarnOnceIfTransferFunctionsDiffer(vtkObject* self, const ProcessGroup& group,
  const FrameAgreement& agreed, const std::vector<vtkAPCVolumeMapper*>& mappers, bool& warned)
{
  if (!agreed.TransferFunctionsDiffer())
  {
    warned = false;
    return;
  }
  if (!warned && group.IsDisplay())
  {
    const char* array = mappers.empty() ? nullptr : mappers.front()->GetArrayName();
    vtkWarningWithObjectMacro(self, << agreed.TransferMismatch(array ? array : "the scalars"));
  }
  warned = true;
}

} // namespace apc
