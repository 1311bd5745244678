// SPDX-License-Identifier: BSD-3-Clause
// Run under mpirun -np N (N = 2, 4): vtkAPCGraphPartition with PT-Scotch on a mesh of
// 2,097,152 hexahedra (a 128^3 box), each rank generating only its own slab, so no rank
// ever holds the whole mesh (Testing/Common/apcHexBox.h):
// - every cell gets one piece in [0, K), and the pieces are balanced within PT-Scotch's 3 %
//   (largest <= 1.03 mean + 1), with no empty piece;
// - the edge cut is the same on every rank, equals the cut counted from the box's own
//   neighbours (so no facet between ranks' slabs was missed), and is no worse than 1.5x that of
//   a known partition of the box, K - 1 planes of n^2 faces (cutting it into K slabs);
// - moving the pieces keeps every cell exactly once (by its global id), each on the rank that
//   owns its piece.
// K = N + 1, so pieces do not line up with the ranks' slabs.

#include "apcHexBox.h"
#include "apcMPITest.h"
#include "vtkAPCGraphPartition.h"

#include "vtkCellData.h"
#include "vtkIdTypeArray.h"
#include "vtkIntArray.h"
#include "vtkMPIController.h"
#include "vtkNew.h"
#include "vtkUnstructuredGrid.h"

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

namespace
{
using apctest::Check;

constexpr int kBox = 128; // 2,097,152 cells

// Global cell counts per piece; inRange tells whether every label is in [0, pieces).
std::vector<long long> PieceSizes(
  vtkMPIController* controller, vtkIntArray* labels, int pieces, bool& inRange)
{
  std::vector<long long> local(static_cast<std::size_t>(pieces), 0), total(local.size(), 0);
  inRange = labels != nullptr;
  for (vtkIdType c = 0; labels && c < labels->GetNumberOfValues(); ++c)
  {
    const int p = labels->GetValue(c);
    inRange = inRange && p >= 0 && p < pieces;
    if (p >= 0 && p < pieces)
    {
      ++local[p];
    }
  }
  controller->AllReduce(local.data(), total.data(), pieces, vtkCommunicator::SUM_OP);
  return total;
}

// Every rank's output cells by global id (OriginalCell): how many times each was seen, and its
// piece (the largest label seen), summed and gathered over all ranks.
void GlobalLabels(vtkMPIController* controller, vtkUnstructuredGrid* output, vtkIdType total,
  std::vector<int>& seen, std::vector<int>& label)
{
  auto* ids = vtkIdTypeArray::SafeDownCast(output->GetCellData()->GetArray("OriginalCell"));
  auto* pieces = vtkIntArray::SafeDownCast(
    output->GetCellData()->GetArray(vtkAPCGraphPartition::GetPartitionIdArrayName()));
  std::vector<int> mySeen(static_cast<std::size_t>(total), 0), myLabel(mySeen.size(), -1);
  for (vtkIdType c = 0; ids && pieces && c < ids->GetNumberOfValues(); ++c)
  {
    const vtkIdType id = ids->GetValue(c);
    if (id >= 0 && id < total)
    {
      ++mySeen[id];
      myLabel[id] = pieces->GetValue(c);
    }
  }
  seen.assign(mySeen.size(), 0);
  label.assign(mySeen.size(), -1);
  controller->AllReduce(mySeen.data(), seen.data(), total, vtkCommunicator::SUM_OP);
  controller->AllReduce(myLabel.data(), label.data(), total, vtkCommunicator::MAX_OP);
}

// The faces between cells of different pieces, counted from the box's own neighbours (x, y, z
// steps in the global id), independent of the graph the filter built.
long long BoxEdgeCut(const std::vector<int>& label, int n)
{
  long long cut = 0;
  for (int k = 0; k < n; ++k)
  {
    for (int j = 0; j < n; ++j)
    {
      for (int i = 0; i < n; ++i)
      {
        const std::size_t id = (static_cast<std::size_t>(k) * n + j) * n + i;
        cut += i + 1 < n && label[id] != label[id + 1];
        cut += j + 1 < n && label[id] != label[id + n];
        cut += k + 1 < n && label[id] != label[id + static_cast<std::size_t>(n) * n];
      }
    }
  }
  return cut;
}
} // namespace

int main(int argc, char* argv[])
{
  vtkSmartPointer<vtkMPIController> controller = apctest::StartMPI(&argc, &argv);
  const int ranks = controller->GetNumberOfProcesses();
  const int rank = controller->GetLocalProcessId();
  const int pieces = ranks + 1;
  const vtkIdType total = static_cast<vtkIdType>(kBox) * kBox * kBox;
  vtkSmartPointer<vtkUnstructuredGrid> box = apctest::HexBoxSlab(kBox, rank, ranks);

  const auto start = std::chrono::steady_clock::now();
  vtkNew<vtkAPCGraphPartition> filter;
  filter->SetInputData(box);
  filter->SetPartitioner(vtkAPCGraphPartition::PTSCOTCH);
  filter->SetNumberOfPartitions(pieces);
  filter->Update();
  auto* output = vtkUnstructuredGrid::SafeDownCast(filter->GetOutput());
  auto* labels = vtkIntArray::SafeDownCast(
    output->GetCellData()->GetArray(vtkAPCGraphPartition::GetPartitionIdArrayName()));

  bool inRange = false;
  const std::vector<long long> sizes = PieceSizes(controller, labels, pieces, inRange);
  long long counted = 0;
  for (const long long s : sizes)
  {
    counted += s;
  }
  const long long largest = *std::max_element(sizes.begin(), sizes.end());
  const long long smallest = *std::min_element(sizes.begin(), sizes.end());
  Check(counted == total, rank, "every cell labelled (" + std::to_string(counted) + ")");
  Check(inRange && smallest > 0, rank, "labels in [0, K), no empty piece");
  Check(largest <= 1.03 * total / pieces + 1, rank,
    "balanced within 3 % (largest " + std::to_string(largest) + " of mean " +
      std::to_string(total / pieces) + ")");

  const vtkIdType cut = filter->GetLastEdgeCut();
  vtkIdType cuts[2] = { cut, -cut };
  vtkIdType agreed[2] = { 0, 0 };
  controller->AllReduce(cuts, agreed, 2, vtkCommunicator::MAX_OP);
  Check(agreed[0] == -agreed[1], rank, "the same edge cut on every rank");
  const vtkIdType slabs = static_cast<vtkIdType>(pieces - 1) * kBox * kBox;
  Check(cut > 0 && cut <= 1.5 * slabs, rank,
    "edge cut " + std::to_string(cut) + " within 1.5x the slabs' " + std::to_string(slabs));

  bool owned = labels != nullptr;
  for (vtkIdType c = 0; labels && c < labels->GetNumberOfValues(); ++c)
  {
    const int p = labels->GetValue(c);
    owned = owned && static_cast<long long>(rank) * pieces / ranks <= p &&
      p < static_cast<long long>(rank + 1) * pieces / ranks;
  }
  Check(owned, rank, "every cell on the rank owning its piece");
  std::vector<int> seen, label;
  GlobalLabels(controller, output, total, seen, label);
  Check(std::all_of(seen.begin(), seen.end(), [](int k) { return k == 1; }), rank,
    "every cell exactly once after the move");
  const long long boxCut = BoxEdgeCut(label, kBox);
  Check(boxCut == cut, rank,
    "the reported edge cut " + std::to_string(cut) + " is the box's own " + std::to_string(boxCut) +
      " (no facet missed across ranks)");
  if (rank == 0)
  {
    std::printf("%lld cells, %d ranks, K %d: edge cut %lld (slabs %lld), imbalance %.4f, "
                "graph %.1f s, PT-Scotch %.1f s, move %.1f s, all %.1f s\n",
      static_cast<long long>(total), ranks, pieces, static_cast<long long>(cut),
      static_cast<long long>(slabs), filter->GetLastImbalance(), filter->GetLastGraphSeconds(),
      filter->GetLastPartitionSeconds(), filter->GetLastExchangeSeconds(),
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return apctest::FinishMPITest(controller);
}
