// SPDX-License-Identifier: BSD-3-Clause
#include "apcPartitionMove.h"

#include "vtkAPCGraphPartition.h"

#include "vtkAppendFilter.h"
#include "vtkCellData.h"
#include "vtkDIYDataExchanger.h"
#include "vtkDataSetAttributes.h"
#include "vtkExtractCells.h"
#include "vtkIdList.h"
#include "vtkIdTypeArray.h"
#include "vtkIntArray.h"
#include "vtkMultiProcessController.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkUnstructuredGrid.h"

#include <algorithm>

namespace apc
{
namespace partition
{
namespace
{
// A shallow copy of a part with its piece ids (-1 on ghost cells; piece may be null: all -1)
// and, if asked, without ghost arrays.
vtkSmartPointer<vtkUnstructuredGrid> Labelled(
  vtkUnstructuredGrid* part, const std::vector<vtkIdType>& kept, const int* piece, bool dropGhosts)
{
  auto copy = vtkSmartPointer<vtkUnstructuredGrid>::New();
  copy->ShallowCopy(part);
  vtkIdTypeArray* locations = part->GetFaceLocations();
  if (locations && locations->GetNumberOfValues() != part->GetNumberOfCells())
  {
    // Empty face arrays on a grid without polyhedra (ParaView's parallel XML reader leaves
    // them on some ranks) make vtkExtractCells read past their end.
    copy->SetCells(part->GetCellTypesArray(), part->GetCells(), nullptr, nullptr);
  }
  vtkNew<vtkIntArray> ids;
  ids->SetName(vtkAPCGraphPartition::GetPartitionIdArrayName());
  ids->SetNumberOfValues(part->GetNumberOfCells());
  ids->FillValue(-1);
  for (std::size_t i = 0; i < kept.size(); ++i)
  {
    ids->SetValue(kept[i], piece[i]);
  }
  copy->GetCellData()->AddArray(ids);
  if (dropGhosts)
  {
    copy->GetCellData()->RemoveArray(vtkDataSetAttributes::GhostArrayName());
    copy->GetPointData()->RemoveArray(vtkDataSetAttributes::GhostArrayName());
  }
  return copy;
}

// Every part of the unit labelled; piece runs over the parts' kept cells one after the other.
UGrids LabelParts(const Unit& unit, const LocalCells& cells, const int* piece, bool dropGhosts)
{
  UGrids labelled;
  vtkIdType at = 0;
  for (std::size_t p = 0; p < unit.Parts.size(); ++p)
  {
    labelled.push_back(
      Labelled(unit.Parts[p], cells.Kept[p], piece ? piece + at : nullptr, dropGhosts));
    at += static_cast<vtkIdType>(cells.Kept[p].size());
  }
  return labelled;
}

vtkSmartPointer<vtkUnstructuredGrid> Extract(
  vtkUnstructuredGrid* grid, const std::vector<vtkIdType>& ids)
{
  if (static_cast<vtkIdType>(ids.size()) == grid->GetNumberOfCells())
  {
    bool identity = true;
    for (std::size_t i = 0; i < ids.size() && identity; ++i)
    {
      identity = ids[i] == static_cast<vtkIdType>(i);
    }
    if (identity)
    {
      return grid;
    }
  }
  vtkNew<vtkIdList> list;
  list->SetNumberOfIds(static_cast<vtkIdType>(ids.size()));
  std::copy(ids.begin(), ids.end(), list->GetPointer(0));
  vtkNew<vtkExtractCells> extract;
  extract->SetInputData(grid);
  extract->SetCellList(list);
  extract->AssumeSortedAndUniqueIdsOn();
  extract->PassThroughCellIdsOff();
  extract->Update();
  return vtkUnstructuredGrid::SafeDownCast(extract->GetOutput());
}

vtkSmartPointer<vtkUnstructuredGrid> Append(const UGrids& grids)
{
  if (grids.size() == 1)
  {
    return grids[0];
  }
  vtkNew<vtkAppendFilter> append;
  append->MergePointsOff();
  for (const auto& g : grids)
  {
    append->AddInputData(g);
  }
  append->Update();
  return vtkUnstructuredGrid::SafeDownCast(append->GetOutput());
}

// Rank r of R owns pieces [r*K/R, (r+1)*K/R).
int RankOfPiece(int piece, int pieces, int ranks)
{
  int r = static_cast<int>((static_cast<long long>(piece) * ranks) / pieces);
  while (r > 0 && static_cast<long long>(r) * pieces / ranks > piece)
  {
    --r;
  }
  while (r + 1 < ranks && static_cast<long long>(r + 1) * pieces / ranks <= piece)
  {
    ++r;
  }
  return r;
}

// Every rank agrees on a failure before going on, so no rank waits for a failed one.
bool AnyRankFailed(vtkMultiProcessController* controller, int localFailure)
{
  int any = localFailure;
  if (controller && controller->GetNumberOfProcesses() > 1)
  {
    controller->AllReduce(&localFailure, &any, 1, vtkCommunicator::MAX_OP);
  }
  return any != 0;
}

// The labelled parts' cells grouped by destination rank. Chunks for rank r must be contiguous
// in the send buffer (vtkDIYDataExchanger's contract), so they are collected per rank first.
std::vector<UGrids> SortByRank(const UGrids& labelled, const LocalCells& cells,
  const std::vector<int>& piece, int pieces, int ranks)
{
  std::vector<UGrids> toRank(static_cast<std::size_t>(ranks));
  std::vector<std::vector<vtkIdType>> byRank(static_cast<std::size_t>(ranks));
  std::size_t at = 0;
  for (std::size_t p = 0; p < labelled.size(); ++p)
  {
    for (auto& list : byRank)
    {
      list.clear();
    }
    for (const vtkIdType c : cells.Kept[p])
    {
      byRank[RankOfPiece(piece[at++], pieces, ranks)].push_back(c);
    }
    for (int r = 0; r < ranks; ++r)
    {
      if (!byRank[r].empty())
      {
        toRank[r].push_back(Extract(labelled[p], byRank[r]));
      }
    }
  }
  return toRank;
}

// The all-to-all: what this rank keeps, then what came from the others in rank order (empty
// grids left out). Returns false if the exchange failed on any rank (failedHere: on this one).
bool Exchange(std::vector<UGrids>& toRank, vtkMultiProcessController* controller, int rank,
  UGrids& mine, bool& failedHere)
{
  const int ranks = static_cast<int>(toRank.size());
  std::vector<vtkSmartPointer<vtkDataSet>> send;
  std::vector<int> sendCounts(static_cast<std::size_t>(ranks), 0);
  for (int r = 0; r < ranks; ++r)
  {
    if (r != rank)
    {
      send.insert(send.end(), toRank[r].begin(), toRank[r].end());
      sendCounts[r] = static_cast<int>(toRank[r].size());
    }
  }
  int failed = 0;
  std::vector<vtkSmartPointer<vtkDataSet>> received;
  std::vector<int> receivedCounts;
  if (ranks > 1)
  {
    vtkNew<vtkDIYDataExchanger> exchanger;
    exchanger->SetController(controller);
    failed = exchanger->AllToAll(send, sendCounts, received, receivedCounts) ? 0 : 1;
  }
  failedHere = failed != 0;
  if (AnyRankFailed(controller, failed))
  {
    return false;
  }
  mine = toRank[rank];
  for (const auto& ds : received)
  {
    auto* ug = vtkUnstructuredGrid::SafeDownCast(ds);
    if (ug && ug->GetNumberOfCells() > 0)
    {
      mine.emplace_back(ug);
    }
  }
  return true;
}

// A partitioned unit gets one partition per piece this rank owns.
UGrids SplitByPiece(vtkUnstructuredGrid* result, int pieces)
{
  UGrids owned;
  auto* ids = vtkIntArray::SafeDownCast(
    result->GetCellData()->GetArray(vtkAPCGraphPartition::GetPartitionIdArrayName()));
  std::vector<std::vector<vtkIdType>> byPiece(static_cast<std::size_t>(pieces));
  for (vtkIdType c = 0; ids && c < result->GetNumberOfCells(); ++c)
  {
    byPiece[ids->GetValue(c)].push_back(c);
  }
  for (int p = 0; p < pieces; ++p)
  {
    if (!byPiece[p].empty())
    {
      owned.push_back(Extract(result, byPiece[p]));
    }
  }
  return owned;
}
} // namespace

//------------------------------------------------------------------------------
void InstallEmpty(const Unit& unit, const LocalCells& cells)
{
  UGrids empty = LabelParts(unit, cells, nullptr, true);
  if (!unit.Partitioned && empty.empty())
  {
    empty.push_back(vtkSmartPointer<vtkUnstructuredGrid>::New());
  }
  unit.Install(unit.Partitioned ? empty : UGrids{ empty[0] });
}

//------------------------------------------------------------------------------
void InstallLabelled(const Unit& unit, const LocalCells& cells, const int* piece)
{
  UGrids labelled = LabelParts(unit, cells, piece, false);
  if (!unit.Partitioned && labelled.empty())
  {
    labelled.push_back(vtkSmartPointer<vtkUnstructuredGrid>::New());
  }
  unit.Install(labelled);
}

//------------------------------------------------------------------------------
std::string MovePieces(const Unit& unit, const LocalCells& cells, const std::vector<int>& piece,
  int pieces, vtkMultiProcessController* controller)
{
  const int ranks = controller ? controller->GetNumberOfProcesses() : 1;
  const int rank = controller ? controller->GetLocalProcessId() : 0;
  const UGrids labelled = LabelParts(unit, cells, piece.data(), true);
  std::vector<UGrids> toRank = SortByRank(labelled, cells, piece, pieces, ranks);
  UGrids mine;
  bool failedHere = false;
  if (!Exchange(toRank, controller, rank, mine, failedHere))
  {
    return std::string("moving the pieces between ranks failed") +
      (failedHere ? " on this rank" : " on another rank");
  }
  vtkSmartPointer<vtkUnstructuredGrid> result;
  if (mine.empty())
  {
    // No piece here: an empty grid that still has the input's arrays.
    result =
      labelled.empty() ? vtkSmartPointer<vtkUnstructuredGrid>::New() : Extract(labelled[0], {});
  }
  else
  {
    result = Append(mine);
  }
  unit.Install(unit.Partitioned ? SplitByPiece(result, pieces) : UGrids{ result });
  return {};
}

} // namespace partition
} // namespace apc
