// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAPCGraphPartition.h"

#include "apcPartitionDistributed.h"
#include "apcPartitionGraph.h"
#include "apcPartitionInput.h"
#include "apcPartitionMove.h"

#include "vtkDataObject.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMultiProcessController.h"
#include "vtkObjectFactory.h"

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkAPCGraphPartition);
vtkCxxSetObjectMacro(vtkAPCGraphPartition, Controller, vtkMultiProcessController);

namespace
{
using namespace apc::partition;

double SecondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// A local error, or one on another rank, and the number of units, agreed in one reduction
// ([failure, units, -units]) so that a failing rank never leaves the others in a collective.
std::string AgreeOnUnits(
  vtkMultiProcessController* controller, const std::string& error, std::size_t units)
{
  int header[3] = { error.empty() ? 0 : 1, static_cast<int>(units), -static_cast<int>(units) };
  int agreed[3] = { header[0], header[1], header[2] };
  if (controller && controller->GetNumberOfProcesses() > 1)
  {
    controller->AllReduce(header, agreed, 3, vtkCommunicator::MAX_OP);
  }
  if (agreed[0])
  {
    return error.empty() ? std::string("failed on another rank (see its error)") : error;
  }
  if (agreed[1] != -agreed[2])
  {
    return "the composite input has " + std::to_string(units) +
      " meshes on this rank but not on every rank: its structure must be the same on all ranks";
  }
  return {};
}

// Each unit's cells summed over the ranks.
std::vector<vtkIdType> TotalCounts(
  vtkMultiProcessController* controller, const std::vector<LocalCells>& cells)
{
  std::vector<vtkIdType> local;
  for (const LocalCells& unit : cells)
  {
    local.push_back(unit.Count);
  }
  std::vector<vtkIdType> total = local;
  if (controller && controller->GetNumberOfProcesses() > 1 && !local.empty())
  {
    controller->AllReduce(
      local.data(), total.data(), static_cast<vtkIdType>(local.size()), vtkCommunicator::SUM_OP);
  }
  return total;
}
} // namespace

//------------------------------------------------------------------------------
vtkAPCGraphPartition::vtkAPCGraphPartition()
{
  this->SetController(vtkMultiProcessController::GetGlobalController());
}

//------------------------------------------------------------------------------
vtkAPCGraphPartition::~vtkAPCGraphPartition()
{
  this->SetController(nullptr);
}

//------------------------------------------------------------------------------
int vtkAPCGraphPartition::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkDataObject* input = vtkDataObject::GetData(inputVector[0], 0);
  vtkDataObject* output = vtkDataObject::GetData(outputVector, 0);
  vtkMultiProcessController* controller = this->Controller;
  this->LastEdgeCut = 0;
  this->LastImbalance = 0;
  this->LastGraphSeconds = this->LastPartitionSeconds = this->LastExchangeSeconds = 0;
  // Every failure is agreed on by all ranks before the next collective (the stages make sure
  // of it), so each rank says it and returns here.
  auto fail = [&](const std::string& message)
  {
    vtkErrorMacro(<< message);
    output->Initialize();
    return 0;
  };

  std::vector<Unit> units;
  std::string error = CollectUnits(input, output, units);
  if (error.empty() && this->NumberOfPartitions < 0)
  {
    error = "NumberOfPartitions is " + std::to_string(this->NumberOfPartitions) +
      ": it must be 0 (one piece per rank) or more";
  }
  error = AgreeOnUnits(controller, error, units.size());
  if (!error.empty())
  {
    return fail(error);
  }
  std::vector<LocalCells> cells;
  for (const Unit& unit : units)
  {
    cells.push_back(KeptCells(unit));
  }
  const std::vector<vtkIdType> totals = TotalCounts(controller, cells);
  if (std::all_of(totals.begin(), totals.end(), [](vtkIdType n) { return n == 0; }))
  {
    return fail("no cells to partition (the input has no cells on any rank)");
  }
  const int ranks = controller ? controller->GetNumberOfProcesses() : 1;
  const int pieces = this->NumberOfPartitions > 0 ? this->NumberOfPartitions : ranks;
  const bool distributed =
    this->Partitioner == PTSCOTCH || (this->Partitioner == AUTO && ranks > 1);

  for (std::size_t u = 0; u < units.size(); ++u)
  {
    if (totals[u] == 0)
    {
      InstallEmpty(units[u], cells[u]);
      continue;
    }
    const PartitionOutcome outcome = distributed
      ? PartitionCellsDistributed(units[u], cells[u], pieces, this->Seed, controller)
      : PartitionCells(units[u], cells[u], pieces, this->Seed, controller);
    if (!outcome.Error.empty())
    {
      return fail(outcome.Error);
    }
    this->LastGraphSeconds += outcome.GraphSeconds;
    this->LastPartitionSeconds += outcome.PartitionSeconds;
    this->LastEdgeCut += outcome.EdgeCut;
    this->LastImbalance = std::max(this->LastImbalance, outcome.Imbalance);

    const auto start = std::chrono::steady_clock::now();
    if (this->LabelOnly)
    {
      InstallLabelled(units[u], cells[u], outcome.Piece.data());
    }
    else
    {
      error = MovePieces(units[u], cells[u], outcome.Piece, pieces, controller);
      if (!error.empty())
      {
        return fail(error);
      }
    }
    this->LastExchangeSeconds += SecondsSince(start);
  }
  return 1;
}

//------------------------------------------------------------------------------
void vtkAPCGraphPartition::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "NumberOfPartitions: " << this->NumberOfPartitions << "\n";
  os << indent << "Partitioner: " << this->Partitioner << "\n";
  os << indent << "Seed: " << this->Seed << "\n";
  os << indent << "LabelOnly: " << this->LabelOnly << "\n";
  os << indent << "Controller: " << this->Controller << "\n";
  os << indent << "LastEdgeCut: " << this->LastEdgeCut << "\n";
  os << indent << "LastImbalance: " << this->LastImbalance << "\n";
}
