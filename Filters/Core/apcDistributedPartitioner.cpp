// SPDX-License-Identifier: BSD-3-Clause
#include "apcDistributedPartitioner.h"

#include <cstdio> // scotch.h needs FILE
#include <scotch/ptscotch.h>

#include <limits>

namespace apc
{
namespace
{
// The one verdict every process returns: any local failure fails all.
bool AllOk(MPI_Comm comm, bool ok)
{
  int local = ok ? 0 : 1;
  int any = 0;
  MPI_Allreduce(&local, &any, 1, MPI_INT, MPI_MAX, comm);
  return any == 0;
}

// The cases that need no partitioner, as apcGraphPartitioner answers them.
bool PartitionTrivially(
  MPI_Comm comm, const DistributedGraph& graph, int parts, DistributedPartition& result)
{
  const std::int64_t n = graph.NumberOfLocalCells();
  long long edges = static_cast<long long>(graph.Adjacency.size());
  long long allEdges = 0;
  MPI_Allreduce(&edges, &allEdges, 1, MPI_LONG_LONG, MPI_SUM, comm);
  result.Part.assign(static_cast<std::size_t>(n), 0);
  if (parts == 1)
  {
    result.Method = "single";
  }
  else if (parts >= graph.TotalCells)
  {
    for (std::int64_t c = 0; c < n; ++c)
    {
      result.Part[c] = static_cast<int>(graph.FirstCell + c);
    }
    result.Method = "one-cell-per-part";
  }
  else if (allEdges == 0)
  {
    for (std::int64_t c = 0; c < n; ++c)
    {
      result.Part[c] = static_cast<int>((graph.FirstCell + c) * parts / graph.TotalCells);
    }
    result.Method = "blocks";
  }
  else
  {
    return false;
  }
  result.Ok = true;
  return true;
}

// SCOTCH_dgraphPart on the graph; false (and an error) where Scotch fails on this process.
bool RunScotch(MPI_Comm comm, const DistributedGraph& graph, int parts, int seed,
  std::vector<SCOTCH_Num>& part, std::string& error)
{
  const std::int64_t n = graph.NumberOfLocalCells();
  // Scotch wants valid arrays even where a process has no cells or edges.
  std::vector<SCOTCH_Num> vertices(graph.Offsets.begin(), graph.Offsets.end());
  std::vector<SCOTCH_Num> edges(graph.Adjacency.begin(), graph.Adjacency.end());
  edges.resize(std::max<std::size_t>(edges.size(), 1));
  part.assign(static_cast<std::size_t>(std::max<std::int64_t>(n, 1)), 0);
  int processes = 1;
  MPI_Comm_size(comm, &processes);
  // A context asking for a deterministic run with a fixed seed: Debian's Scotch is threaded,
  // and threads otherwise make runs differ.
  SCOTCH_Context context;
  SCOTCH_contextInit(&context);
  SCOTCH_contextOptionSetNum(&context, SCOTCH_OPTIONNUMDETERMINISTIC, 1);
  SCOTCH_contextOptionSetNum(&context, SCOTCH_OPTIONNUMRANDOMFIXEDSEED, 1);
  SCOTCH_contextRandomSeed(&context, seed);
  SCOTCH_Dgraph dgraph;
  SCOTCH_Dgraph bound; // dgraph seen through the context
  SCOTCH_Strat strategy;
  if (SCOTCH_dgraphInit(&dgraph, comm) != 0 || SCOTCH_dgraphInit(&bound, comm) != 0)
  {
    error = "SCOTCH_dgraphInit failed";
    SCOTCH_contextExit(&context);
    return false;
  }
  SCOTCH_stratInit(&strategy);
  const auto local = static_cast<SCOTCH_Num>(n);
  const auto arcs = static_cast<SCOTCH_Num>(graph.Adjacency.size());
  bool ok = SCOTCH_dgraphBuild(&dgraph, 0, local, local, vertices.data(), nullptr, nullptr, nullptr,
              arcs, arcs, edges.data(), nullptr, nullptr) == 0;
  error = ok ? "" : "SCOTCH_dgraphBuild failed";
  if (AllOk(comm, ok))
  {
    ok = SCOTCH_stratDgraphMapBuild(
           &strategy, SCOTCH_STRATQUALITY | SCOTCH_STRATBALANCE, processes, parts, 0.03) == 0;
    ok = ok && SCOTCH_contextBindDgraph(&context, &dgraph, &bound) == 0;
    ok = ok && SCOTCH_dgraphPart(&bound, parts, &strategy, part.data()) == 0;
    error = ok ? "" : "SCOTCH_dgraphPart failed";
  }
  SCOTCH_stratExit(&strategy);
  SCOTCH_dgraphExit(&bound);
  SCOTCH_dgraphExit(&dgraph);
  SCOTCH_contextExit(&context);
  part.resize(static_cast<std::size_t>(n));
  return ok;
}
} // namespace

//------------------------------------------------------------------------------
DistributedPartition PartitionDistributedGraph(
  MPI_Comm comm, const DistributedGraph& graph, int parts, int seed)
{
  DistributedPartition result;
  constexpr auto kMaxId = static_cast<std::int64_t>(std::numeric_limits<SCOTCH_Num>::max());
  if (graph.TotalCells <= 0)
  {
    result.Error = "no cells to partition";
  }
  else if (parts < 1)
  {
    result.Error = "the number of parts must be at least 1, not " + std::to_string(parts);
  }
  else if (graph.TotalCells > kMaxId || static_cast<std::int64_t>(graph.Adjacency.size()) > kMaxId)
  {
    result.Error =
      "graph of " + std::to_string(graph.TotalCells) + " cells exceeds PT-Scotch's 32-bit ids";
  }
  if (!AllOk(comm, result.Error.empty()))
  {
    result.Error = result.Error.empty() ? "failed on another process" : result.Error;
    return result;
  }
  if (PartitionTrivially(comm, graph, parts, result))
  {
    return result;
  }
  std::vector<SCOTCH_Num> part;
  const bool ok = RunScotch(comm, graph, parts, seed, part, result.Error);
  if (!AllOk(comm, ok))
  {
    result.Error = ok ? "PT-Scotch failed on another process" : result.Error;
    result.Part.clear();
    return result;
  }
  result.Part.assign(part.begin(), part.end());
  result.Ok = true;
  result.Method = "ptscotch";
  return result;
}

} // namespace apc
