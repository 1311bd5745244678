// SPDX-License-Identifier: BSD-3-Clause
// vtkAPCGraphPartition's first stage: the input walked into the meshes to partition. A mesh
// ("unit") is an unstructured grid, an unstructured-grid leaf of a multiblock, or a
// vtkPartitionedDataSet (its partitions on all ranks together); the output tree is built on
// the way, and each unit knows where its result goes. The walk is in a fixed order, so every
// rank sees the same units when the composite structure is the same on all ranks.
#ifndef apcPartitionInput_h
#define apcPartitionInput_h

#include "vtkSmartPointer.h"
#include "vtkType.h"

#include <chrono>
#include <functional>
#include <string>
#include <vector>

class vtkDataObject;
class vtkUnstructuredGrid;

namespace apc
{
namespace partition
{
using UGrids = std::vector<vtkSmartPointer<vtkUnstructuredGrid>>;

// The stages' wall clock (the filter's Last*Seconds).
using Clock = std::chrono::steady_clock;
inline double SecondsSince(Clock::time_point start)
{
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// One mesh to partition: an unstructured-grid leaf (one part, or none where the leaf is absent
// on this rank) or a vtkPartitionedDataSet (its partitions on this rank).
struct Unit
{
  std::vector<vtkUnstructuredGrid*> Parts;
  bool Partitioned = false;
  // Puts the result into the output: one grid for a leaf, the pieces this rank owns (one
  // partition each) for a partitioned dataset.
  std::function<void(const UGrids&)> Install;
};

// Fills units from the input and builds the output's composite structure. Returns an error
// message (the input is not an unstructured grid or a composite of them), or "".
std::string CollectUnits(vtkDataObject* input, vtkDataObject* output, std::vector<Unit>& units);

// This rank's cells of one unit, in graph order: the parts one after the other, ghost
// (duplicate) cells left out.
struct LocalCells
{
  std::vector<std::vector<vtkIdType>> Kept; // per part: the input cell ids in graph order
  vtkIdType Count = 0;
};

LocalCells KeptCells(const Unit& unit);

} // namespace partition
} // namespace apc

#endif
