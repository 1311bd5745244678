// SPDX-License-Identifier: BSD-3-Clause
// K-way partition of a cell graph with METIS: the only place that talks to METIS, so that the
// VTK filter and the tests see plain vectors.
#ifndef apcGraphPartitioner_h
#define apcGraphPartitioner_h

#include "apcDualGraph.h"

#include <string>
#include <vector>

namespace apc
{

struct GraphPartition
{
  bool Ok = false;
  std::string Error;     // why not, when !Ok
  std::vector<int> Part; // per cell, in [0, parts)
  std::int64_t EdgeCut = 0;
  std::string Method; // "metis-kway", "single", "one-cell-per-part", "blocks"
};

/// Partitions the graph into `parts` pieces of balanced cell counts with the fewest cut
/// edges (METIS_PartGraphKway, default imbalance 1.03, seeded). One part, more parts than
/// cells, or a graph with no edge at all need no partitioner and are answered directly
/// (see Method). Fails on no cells, parts < 1, or a graph too large for METIS's 32-bit ids.
GraphPartition PartitionCellGraph(const CellGraph& graph, int parts, int seed);

/// Largest part over the mean part size: 1 is perfect balance; METIS aims at <= 1.03.
double PartitionImbalance(const std::vector<int>& part, int parts);

} // namespace apc

#endif
