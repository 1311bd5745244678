// SPDX-License-Identifier: BSD-3-Clause
// vtkAPCGraphPartition's dual graph and partition without a gathering rank (PT-Scotch): each
// rank matches its own cells' facets, sends the facets it could not match to the rank their
// point positions hash to, where they meet their other half, and gets back the edges to
// other ranks' cells, all point to point (all-to-all). Each rank then holds exactly its cells
// and their neighbours' global ids, and PT-Scotch partitions that distributed graph. No rank
// holds more than its own share of the graph.
#ifndef apcPartitionDistributed_h
#define apcPartitionDistributed_h

#include "apcPartitionGraph.h"

class vtkMultiProcessController;

namespace apc
{
namespace partition
{

// As PartitionCells, with PT-Scotch on the distributed graph. The controller must be an MPI
// controller (an error on every rank otherwise). Collective.
PartitionOutcome PartitionCellsDistributed(const Unit& unit, const LocalCells& cells, int pieces,
  int seed, vtkMultiProcessController* controller);

} // namespace partition
} // namespace apc

#endif
