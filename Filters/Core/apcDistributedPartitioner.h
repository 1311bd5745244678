// SPDX-License-Identifier: BSD-3-Clause
// K-way partition of a distributed cell graph with PT-Scotch: the only place that talks to
// PT-Scotch. Each process holds only its own cells (a contiguous range of global ids) with
// their neighbours' global ids, so no process ever holds more than its share of the graph;
// METIS (apcGraphPartitioner.h) needs the whole graph on one process instead.
//
// VTK-free (plain C++17 and MPI) so that the VTK filter and the tests see plain vectors.
#ifndef apcDistributedPartitioner_h
#define apcDistributedPartitioner_h

// MPI's C API only (as vtkMPI.h does): the C++ bindings are deprecated and not linked.
#ifndef OMPI_SKIP_MPICXX
#define OMPI_SKIP_MPICXX
#endif
#ifndef MPICH_SKIP_MPICXX
#define MPICH_SKIP_MPICXX
#endif
#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

namespace apc
{

/// This process's part of a symmetric cell graph: cells [FirstCell, FirstCell + n) of
/// TotalCells, their neighbours in compressed rows of global ids (no self loops, no repeats).
struct DistributedGraph
{
  std::int64_t FirstCell = 0;
  std::int64_t TotalCells = 0;
  std::vector<std::int64_t> Offsets{ 0 };
  std::vector<std::int64_t> Adjacency;

  std::int64_t NumberOfLocalCells() const
  {
    return static_cast<std::int64_t>(this->Offsets.size()) - 1;
  }
};

struct DistributedPartition
{
  bool Ok = false;       // the same on every process
  std::string Error;     // why not, when !Ok
  std::vector<int> Part; // per local cell, in [0, parts)
  std::string Method;    // "ptscotch", "single", "one-cell-per-part", "blocks"
};

/// Partitions the graph into `parts` pieces of balanced cell counts (imbalance tolerance 3 %,
/// as METIS's default) with few cut edges: SCOTCH_dgraphPart, seeded, so that the same graph
/// on the same processes gives the same parts. One part, more parts than cells, or a graph
/// with no edge at all are answered directly (see Method). Collective over comm; a failure on
/// any process is a failure on all. Fails on no cells, parts < 1, or a graph too large for
/// Scotch's 32-bit ids.
DistributedPartition PartitionDistributedGraph(
  MPI_Comm comm, const DistributedGraph& graph, int parts, int seed);

} // namespace apc

#endif
