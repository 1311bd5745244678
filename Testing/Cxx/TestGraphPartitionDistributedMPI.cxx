// SPDX-License-Identifier: BSD-3-Clause
// Run under mpirun -np N: vtkAPCGraphPartition with the distributed partitioner (PT-Scotch)
// on the real wind data, read as the .pvtu's pieces distributed over the ranks, against the
// METIS partitioner on the same input:
// - every cell gets a piece in [0, K), every piece has cells, and the pieces are balanced
//   within PT-Scotch's 3 % (largest <= 1.03 mean + 1);
// - the same input, K and seed give the same labels again (determinism);
// - the edge cut is of METIS's order (within 1.5x) and the same on every rank;
// - moving the pieces keeps every cell exactly once, each on the rank owning its piece;
// - a rank without cells takes part (its neighbours' edges are still found);
// - AUTO is METIS on one rank and PT-Scotch on more.

#include "apcMPITest.h"
#include "vtkAPCGraphPartition.h"

#include "vtkCellData.h"
#include "vtkIdTypeArray.h"
#include "vtkIntArray.h"
#include "vtkMPIController.h"
#include "vtkNew.h"
#include "vtkUnstructuredGrid.h"
#include "vtkXMLPUnstructuredGridReader.h"

#include <algorithm>
#include <numeric>
#include <string>
#include <vector>

namespace
{
using apctest::Check;

// The wind's pieces spread over the ranks; with emptyRank >= 0 that rank gets none, its share
// going to the next rank.
vtkSmartPointer<vtkUnstructuredGrid> ReadWind(vtkMPIController* controller, int emptyRank = -1)
{
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  if (rank != emptyRank)
  {
    const bool skip = emptyRank >= 0 && ranks > 1;
    const int readers = skip ? ranks - 1 : ranks;
    const int piece = skip && rank > emptyRank ? rank - 1 : rank;
    vtkNew<vtkXMLPUnstructuredGridReader> reader;
    reader->SetFileName(APC_DATA_DIR "/windAroundBuildings/wind.pvtu");
    reader->UpdatePiece(piece, readers, 0);
    grid->ShallowCopy(reader->GetOutput());
  }
  vtkNew<vtkIdTypeArray> id; // the cell's place in the global input, for the move check
  id->SetName("OriginalCell");
  const vtkIdType n = grid->GetNumberOfCells();
  std::vector<vtkIdType> counts(static_cast<std::size_t>(ranks));
  controller->AllGather(&n, counts.data(), 1);
  const vtkIdType offset = std::accumulate(counts.begin(), counts.begin() + rank, vtkIdType(0));
  for (vtkIdType c = 0; c < n; ++c)
  {
    id->InsertNextValue(offset + c);
  }
  grid->GetCellData()->AddArray(id);
  return grid;
}

struct Run
{
  std::vector<int> Labels; // this rank's cells' pieces, in input order
  vtkIdType EdgeCut = 0;
  double Imbalance = 0;
  vtkSmartPointer<vtkUnstructuredGrid> Output;
};

Run Partition(vtkUnstructuredGrid* input, int partitioner, int pieces, bool labelOnly)
{
  vtkNew<vtkAPCGraphPartition> filter;
  filter->SetInputData(input);
  filter->SetPartitioner(partitioner);
  filter->SetNumberOfPartitions(pieces);
  filter->SetLabelOnly(labelOnly);
  filter->Update();
  Run run;
  run.Output = vtkUnstructuredGrid::SafeDownCast(filter->GetOutput());
  run.EdgeCut = filter->GetLastEdgeCut();
  run.Imbalance = filter->GetLastImbalance();
  auto* ids = vtkIntArray::SafeDownCast(
    run.Output->GetCellData()->GetArray(vtkAPCGraphPartition::GetPartitionIdArrayName()));
  for (vtkIdType c = 0; ids && c < ids->GetNumberOfValues(); ++c)
  {
    run.Labels.push_back(ids->GetValue(c));
  }
  return run;
}

// Global cell counts per piece, and whether every label is in [0, pieces).
std::vector<long long> PieceSizes(
  vtkMPIController* controller, const std::vector<int>& labels, int pieces, bool& inRange)
{
  std::vector<long long> local(static_cast<std::size_t>(pieces), 0), total(local.size(), 0);
  inRange = true;
  for (const int p : labels)
  {
    inRange = inRange && p >= 0 && p < pieces;
    if (p >= 0 && p < pieces)
    {
      ++local[p];
    }
  }
  controller->AllReduce(local.data(), total.data(), pieces, vtkCommunicator::SUM_OP);
  return total;
}

void LabelCase(
  vtkMPIController* controller, vtkUnstructuredGrid* wind, int pieces, const std::string& what)
{
  const int rank = controller->GetLocalProcessId();
  const Run first = Partition(wind, vtkAPCGraphPartition::PTSCOTCH, pieces, true);
  Check(static_cast<vtkIdType>(first.Labels.size()) == wind->GetNumberOfCells(), rank,
    what + ": every input cell labelled");
  bool inRange = false;
  const std::vector<long long> sizes = PieceSizes(controller, first.Labels, pieces, inRange);
  const long long total = std::accumulate(sizes.begin(), sizes.end(), 0LL);
  const long long largest = *std::max_element(sizes.begin(), sizes.end());
  const long long smallest = *std::min_element(sizes.begin(), sizes.end());
  Check(inRange && smallest > 0, rank, what + ": labels in [0, K), no empty piece");
  Check(largest <= 1.03 * total / pieces + 1, rank,
    what + ": balanced within 3 % (largest " + std::to_string(largest) + " of mean " +
      std::to_string(total / pieces) + ")");
  Check(std::abs(first.Imbalance - largest / (double(total) / pieces)) < 1e-9, rank,
    what + ": LastImbalance is the largest piece over the mean");
  const Run again = Partition(wind, vtkAPCGraphPartition::PTSCOTCH, pieces, true);
  Check(again.Labels == first.Labels, rank, what + ": the same labels on a second run");
  const Run metis = Partition(wind, vtkAPCGraphPartition::METIS, pieces, true);
  vtkIdType cuts[2] = { first.EdgeCut, -first.EdgeCut };
  vtkIdType agreed[2] = { 0, 0 };
  controller->AllReduce(cuts, agreed, 2, vtkCommunicator::MAX_OP);
  Check(agreed[0] == -agreed[1], rank, what + ": the same edge cut on every rank");
  Check(first.EdgeCut > 0 && first.EdgeCut <= 1.5 * metis.EdgeCut, rank,
    what + ": edge cut " + std::to_string(first.EdgeCut) + " within 1.5x METIS's " +
      std::to_string(metis.EdgeCut));
  if (rank == 0)
  {
    std::printf("%s: K %d, PT-Scotch edge cut %lld (METIS %lld), imbalance %.4f (METIS %.4f)\n",
      what.c_str(), pieces, static_cast<long long>(first.EdgeCut),
      static_cast<long long>(metis.EdgeCut), first.Imbalance, metis.Imbalance);
  }
}

// Moving: every cell once over all ranks, each on the rank that owns its piece.
void MoveCase(vtkMPIController* controller, vtkUnstructuredGrid* wind, int pieces)
{
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  const Run moved = Partition(wind, vtkAPCGraphPartition::PTSCOTCH, pieces, false);
  bool owned = true;
  for (const int p : moved.Labels)
  {
    owned = owned && static_cast<long long>(rank) * pieces / ranks <= p &&
      p < static_cast<long long>(rank + 1) * pieces / ranks;
  }
  Check(owned, rank, "moved: every cell on the rank owning its piece");
  auto* ids = vtkIdTypeArray::SafeDownCast(moved.Output->GetCellData()->GetArray("OriginalCell"));
  vtkIdType n[2] = { wind->GetNumberOfCells(), moved.Output->GetNumberOfCells() };
  vtkIdType totals[2] = { 0, 0 };
  controller->AllReduce(n, totals, 2, vtkCommunicator::SUM_OP);
  std::vector<long long> seen(static_cast<std::size_t>(totals[0]), 0), all(seen.size(), 0);
  for (vtkIdType c = 0; ids && c < ids->GetNumberOfValues(); ++c)
  {
    ++seen[ids->GetValue(c)];
  }
  controller->AllReduce(seen.data(), all.data(), totals[0], vtkCommunicator::SUM_OP);
  Check(ids && totals[1] == totals[0] &&
      std::all_of(all.begin(), all.end(), [](long long k) { return k == 1; }),
    rank, "moved: every cell exactly once");
}
} // namespace

int main(int argc, char* argv[])
{
  vtkSmartPointer<vtkMPIController> controller = apctest::StartMPI(&argc, &argv);
  const int ranks = controller->GetNumberOfProcesses();
  const int rank = controller->GetLocalProcessId();
  vtkSmartPointer<vtkUnstructuredGrid> wind = ReadWind(controller);
  LabelCase(controller, wind, std::max(ranks, 2), "K = ranks");
  LabelCase(controller, wind, 3 * ranks + 1, "K = 3 ranks + 1");
  MoveCase(controller, wind, ranks);
  if (ranks > 1)
  {
    vtkSmartPointer<vtkUnstructuredGrid> gap = ReadWind(controller, 0);
    LabelCase(controller, gap, 2 * ranks, "rank 0 empty");
  }
  // AUTO: METIS on one rank, PT-Scotch on more (the same labels as the explicit choice).
  const Run automatic = Partition(wind, vtkAPCGraphPartition::AUTO, 4, true);
  const Run chosen = Partition(
    wind, ranks > 1 ? vtkAPCGraphPartition::PTSCOTCH : vtkAPCGraphPartition::METIS, 4, true);
  Check(automatic.Labels == chosen.Labels, rank, "AUTO picks METIS on 1 rank, PT-Scotch on more");
  return apctest::FinishMPITest(controller);
}
