// SPDX-License-Identifier: BSD-3-Clause
#include "apcFrameAgreement.h"

#include "apcCompositeFrame.h"
#include "apcFrameInputsFromVTK.h"

#include "vtkCommunicator.h"
#include "vtkMultiProcessController.h"

#include "vtkAPCVolumeMapper.h"
#include "vtkObject.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <type_traits>
#include <vector>

namespace apc
{
namespace
{
// One MAX allreduce settles everything: each value travels as its maximum and its negated
// minimum. Values are added and read back in the same order on every process.
class MaxMin
{
public:
  void Add(double max, double min)
  {
    this->Values.push_back(max);
    this->Values.push_back(-min);
  }
  void Add(double value) { this->Add(value, value); }

  void Reduce(const ProcessGroup& group)
  {
    std::vector<double> all(this->Values);
    if (group.Parallel)
    {
      group.Collective("agree",
        [&]
        {
          group.Controller->AllReduce(this->Values.data(), all.data(),
            static_cast<vtkIdType>(this->Values.size()), vtkCommunicator::MAX_OP);
        });
    }
    this->Values = std::move(all);
    this->Next = 0;
  }

  // The next value's maximum and minimum over all processes.
  std::pair<double, double> Take()
  {
    const double max = this->Values[this->Next];
    const double min = -this->Values[this->Next + 1];
    this->Next += 2;
    return { max, min };
  }

private:
  std::vector<double> Values;
  size_t Next = 0;
};

// A setting's value back from a double: integers saturate (VTK_ID_MAX travels as 2^63).
template <class T>
T FromDouble(double value)
{
  if constexpr (std::is_same_v<T, bool>)
  {
    return value != 0;
  }
  else if constexpr (std::is_integral_v<T>)
  {
    const double top = static_cast<double>(std::numeric_limits<T>::max());
    const double bottom = static_cast<double>(std::numeric_limits<T>::lowest());
    return value >= top ? std::numeric_limits<T>::max()
      : value <= bottom ? std::numeric_limits<T>::lowest()
                        : static_cast<T>(value);
  }
  else
  {
    return static_cast<T>(value);
  }
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
  MaxMin values;
  for (int d = 0; d < 3; ++d)
  {
    values.Add(local.Bounds[2 * d + 1], local.Bounds[2 * d]);
  }
  values.Add(local.Failed ? 1 : 0);
  // A process without volumes does not take part in the moments' minimum.
  values.Add(local.Volumes > 0 ? local.MaxMoments : 0, local.Volumes > 0 ? local.MinMoments : inf);
  values.Add(local.Volumes);
  values.Add(local.Width);
  values.Add(local.Height);
  values.Add(local.ReportPending ? 1 : 0);
  values.Add(local.Interactive ? 1 : 0);
  values.Add(local.StopsWhereOpaque ? 1 : 0);
  values.Add(local.NeedsSharedBoundary ? 1 : 0);
  values.Add(local.Opaque ? 1 : 0);
  ForEachAgreed(
    local.Settings, [&](const char*, const auto& setting, AgreementRule) { values.Add(setting); });
  // A process without volumes has no transfer function to compare: it adds neutral values.
  const bool some = local.Volumes > 0;
  const TransferSignature& t = local.Transfer;
  values.Add(some ? t.Colour : -inf, some ? t.Colour : inf);
  values.Add(some ? t.Opacity : -inf, some ? t.Opacity : inf);
  values.Add(some ? t.Range[0] : -inf, some ? t.Range[0] : inf);
  values.Add(some ? t.Range[1] : -inf, some ? t.Range[1] : inf);
  values.Reduce(group);

  FrameAgreement agreed;
  // The cells' total and their volume, sums (the MAX above cannot give them), both exact in
  // integers: the count, and the volume's fixed-point digits (apcExactSum.h), so every process
  // gets the same values whatever the partition and the order of the sum.
  agreed.Cells = local.Cells;
  ExactSum volume = local.Volume;
  if (group.Parallel)
  {
    std::array<unsigned long long, ExactSum::kLanes + 1> mine{};
    std::array<unsigned long long, ExactSum::kLanes + 1> all{};
    const auto lanes = volume.Lanes();
    std::copy(lanes.begin(), lanes.end(), mine.begin());
    mine.back() = static_cast<unsigned long long>(local.Cells);
    group.Collective("agree",
      [&]
      {
        group.Controller->AllReduce(
          mine.data(), all.data(), static_cast<vtkIdType>(mine.size()), vtkCommunicator::SUM_OP);
      });
    std::array<uint64_t, ExactSum::kLanes> summed;
    std::copy(all.begin(), all.end() - 1, summed.begin());
    volume = ExactSum::FromLanes(summed);
    agreed.Cells = static_cast<double>(all.back());
  }
  agreed.Volume = volume.Value();
  for (int d = 0; d < 3; ++d)
  {
    const auto extent = values.Take();
    agreed.Bounds[2 * d] = extent.second;
    agreed.Bounds[2 * d + 1] = extent.first;
  }
  agreed.AnyFailed = values.Take().first > 0;
  const auto moments = values.Take();
  agreed.MaxMoments = static_cast<int>(moments.first);
  agreed.MinMoments = static_cast<int>(moments.second);
  const auto volumes = values.Take();
  agreed.MaxVolumes = static_cast<int>(volumes.first);
  agreed.MinVolumes = static_cast<int>(volumes.second);
  const auto width = values.Take();
  const auto height = values.Take();
  agreed.SizesDiffer = width.first != width.second || height.first != height.second;
  agreed.AnyReportPending = values.Take().first > 0;
  agreed.Interactive = values.Take().first > 0;
  agreed.AnyStopsWhereOpaque = values.Take().first > 0;
  agreed.AnyNeedsSharedBoundary = values.Take().first > 0;
  agreed.AnyOpaque = values.Take().first > 0;
  ForEachAgreed(agreed.Settings,
    [&](const char* name, auto& setting, AgreementRule rule)
    {
      using T = std::decay_t<decltype(setting)>;
      const auto range = values.Take();
      if (rule == AgreementRule::Same && range.first != range.second &&
        agreed.SettingDiffers.empty())
      {
        agreed.SettingDiffers = name;
      }
      setting = FromDouble<T>(rule == AgreementRule::Smallest ? range.second : range.first);
    });
  const auto colour = values.Take();
  const auto opacity = values.Take();
  const auto low = values.Take();
  const auto high = values.Take();
  if (agreed.MaxVolumes > 0)
  {
    agreed.ColourDiffers = colour.first != colour.second;
    agreed.OpacityDiffers = opacity.first != opacity.second;
    agreed.RangeLow[0] = low.second;
    agreed.RangeLow[1] = low.first;
    agreed.RangeHigh[0] = high.second;
    agreed.RangeHigh[1] = high.first;
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
  if (!this->SettingDiffers.empty())
  {
    return "the processes' " + this->SettingDiffers + " settings differ";
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
