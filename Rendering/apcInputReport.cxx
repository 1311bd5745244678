// SPDX-License-Identifier: BSD-3-Clause
#include "apcInputReport.h"

#include "apcCompositeFrame.h"

#include "vtkCellTypes.h"
#include "vtkCommunicator.h"
#include "vtkMultiProcessController.h"
#include "vtkObject.h"
#include "vtkSetGet.h"

#include <sstream>

namespace apc
{
namespace
{
// Counts are sums of integers below 2^53: exact in double.
std::string Number(double count)
{
  std::ostringstream text;
  text.precision(17);
  text << count;
  return text.str();
}
}

bool InputReport::Empty() const
{
  for (double c : this->Counts)
  {
    if (c != 0)
    {
      return false;
    }
  }
  return true;
}

void InputReport::Add(const InputReport& other)
{
  for (size_t i = 0; i < this->Counts.size(); ++i)
  {
    this->Counts[i] += other.Counts[i];
  }
}

std::string InputReport::Errors() const
{
  std::ostringstream text;
  for (int type = 0; type < VTK_NUMBER_OF_CELL_TYPES; ++type)
  {
    const double count = this->Counts[CountKinds + type];
    if (count > 0)
    {
      text << ' ' << Number(count) << " x " << vtkCellTypes::GetClassNameFromTypeId(type);
    }
  }
  if (text.str().empty())
  {
    return std::string();
  }
  return "Skipped cells the APC ray marcher cannot render (it renders 3D cells: linear ones "
         "directly, quadratic cells, pentagonal and hexagonal prisms and polyhedra through their "
         "tetrahedra; other cells hold no volume or are not supported):" +
    text.str();
}

std::string InputReport::Warnings() const
{
  std::ostringstream text;
  auto add = [&text](const std::string& part) { text << (text.str().empty() ? "" : "; ") << part; };
  const InputReport& r = *this;
  if (r[FlatCells] > 0)
  {
    add(Number(r[FlatCells]) +
      " cells with no volume (collapsed, or all corners in one plane) were skipped");
  }
  if (r[NonFiniteCorners] > 0)
  {
    add(Number(r[NonFiniteCorners]) + " cells with a NaN or infinite corner were skipped");
  }
  if (r[NonFiniteScalars] > 0)
  {
    add(Number(r[NonFiniteScalars]) +
      " cells with a NaN or infinite scalar are transparent (non-finite values are never "
      "coloured)");
  }
  if (r[RGBColoursMode] > 0)
  {
    add("the vector mode RGBCOLORS (direct colours) is not supported: the vectors' magnitude "
        "is rendered");
  }
  if (r[ComponentClamped] > 0)
  {
    add("the selected vector component does not exist: the nearest one is rendered");
  }
  return text.str();
}

void InputReport::Emit(vtkObject* reporter, int processes) const
{
  const std::string where =
    processes > 1 ? " (summed over " + std::to_string(processes) + " processes)" : "";
  const std::string errors = this->Errors();
  if (!errors.empty())
  {
    vtkErrorWithObjectMacro(reporter, << errors << where);
  }
  const std::string warnings = this->Warnings();
  if (!warnings.empty())
  {
    vtkWarningWithObjectMacro(reporter, << "APC input: " << warnings << where << '.');
  }
}

void ShareInputReports(const ProcessGroup& group, const InputReport& local, vtkObject* reporter)
{
  InputReport sum = local;
  if (group.Parallel)
  {
    group.Collective("agree",
      [&]
      {
        group.Controller->Reduce(local.Counts.data(), sum.Counts.data(),
          static_cast<vtkIdType>(sum.Counts.size()), vtkCommunicator::SUM_OP, group.Display);
      });
  }
  if (group.IsDisplay())
  {
    sum.Emit(reporter, group.Processes);
  }
}
}
