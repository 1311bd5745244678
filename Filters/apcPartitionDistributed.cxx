// SPDX-License-Identifier: BSD-3-Clause
#include "apcPartitionDistributed.h"

#include "apcDistributedPartitioner.h"

#include "vtkMPI.h"
#include "vtkMPICommunicator.h"
#include "vtkMultiProcessController.h"

#include <algorithm>
#include <chrono>
#include <cstring>

namespace apc
{
namespace partition
{
namespace
{
using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start)
{
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Sends send[r] to rank r and returns what every rank sent this one, in rank order.
template <typename T>
std::vector<T> AllToAll(MPI_Comm comm, const std::vector<std::vector<T>>& send, MPI_Datatype type)
{
  const int ranks = static_cast<int>(send.size());
  std::vector<int> sendCounts(ranks), receiveCounts(ranks), sendOffsets(ranks + 1, 0),
    receiveOffsets(ranks + 1, 0);
  for (int r = 0; r < ranks; ++r)
  {
    sendCounts[r] = static_cast<int>(send[r].size());
    sendOffsets[r + 1] = sendOffsets[r] + sendCounts[r];
  }
  MPI_Alltoall(sendCounts.data(), 1, MPI_INT, receiveCounts.data(), 1, MPI_INT, comm);
  for (int r = 0; r < ranks; ++r)
  {
    receiveOffsets[r + 1] = receiveOffsets[r] + receiveCounts[r];
  }
  std::vector<T> flat;
  flat.reserve(static_cast<std::size_t>(sendOffsets[ranks]));
  for (const auto& part : send)
  {
    flat.insert(flat.end(), part.begin(), part.end());
  }
  std::vector<T> received(static_cast<std::size_t>(std::max(receiveOffsets[ranks], 1)));
  flat.resize(std::max<std::size_t>(flat.size(), 1));
  MPI_Alltoallv(flat.data(), sendCounts.data(), sendOffsets.data(), type, received.data(),
    receiveCounts.data(), receiveOffsets.data(), type, comm);
  received.resize(static_cast<std::size_t>(receiveOffsets[ranks]));
  return received;
}

// Where the rank's cells start in the global numbering, and the first cell of every rank.
struct Numbering
{
  std::vector<std::int64_t> First; // per rank, plus the total at the end
  int Rank = 0;

  int Owner(std::int64_t cell) const
  {
    return static_cast<int>(
             std::upper_bound(this->First.begin(), this->First.end(), cell) - this->First.begin()) -
      1;
  }
};

Numbering NumberCells(MPI_Comm comm, std::int64_t localCells)
{
  Numbering numbering;
  int ranks = 1;
  MPI_Comm_size(comm, &ranks);
  MPI_Comm_rank(comm, &numbering.Rank);
  std::vector<long long> counts(static_cast<std::size_t>(ranks));
  long long mine = localCells;
  MPI_Allgather(&mine, 1, MPI_LONG_LONG, counts.data(), 1, MPI_LONG_LONG, comm);
  numbering.First.assign(static_cast<std::size_t>(ranks) + 1, 0);
  for (int r = 0; r < ranks; ++r)
  {
    numbering.First[r + 1] = numbering.First[r] + counts[r];
  }
  return numbering;
}

// The rank a facet goes to: a hash of its point positions, whatever their order.
int FacetHome(std::vector<std::array<double, 3>>& points, int ranks)
{
  std::sort(points.begin(), points.end());
  std::uint64_t h = 1469598103934665603ULL;
  for (const auto& p : points)
  {
    for (const double v : p)
    {
      std::uint64_t bits;
      std::memcpy(&bits, &v, sizeof(bits));
      h = (h ^ bits) * 1099511628211ULL;
      h ^= h >> 29;
    }
  }
  return static_cast<int>(h % static_cast<std::uint64_t>(ranks));
}

// Each unmatched facet to its home rank: [global cell, size] ids and its positions.
void SendBoundary(MPI_Comm comm, const apc::Facets& facets, const apc::FacetMatches& matches,
  const PositionKeys& keys, const Numbering& numbering, std::vector<std::int64_t>& ids,
  std::vector<double>& positions)
{
  const int ranks = static_cast<int>(numbering.First.size()) - 1;
  std::vector<std::vector<std::int64_t>> sendIds(static_cast<std::size_t>(ranks));
  std::vector<std::vector<double>> sendPositions(static_cast<std::size_t>(ranks));
  std::vector<std::array<double, 3>> points;
  for (const std::int64_t f : matches.Unmatched)
  {
    points.clear();
    for (std::int64_t k = facets.Offsets[f]; k < facets.Offsets[f + 1]; ++k)
    {
      points.push_back(keys.Positions[facets.Points[k]]);
    }
    const int home = FacetHome(points, ranks);
    sendIds[home].push_back(numbering.First[numbering.Rank] + facets.Cell[f]);
    sendIds[home].push_back(static_cast<std::int64_t>(points.size()));
    for (const auto& p : points)
    {
      sendPositions[home].insert(sendPositions[home].end(), p.begin(), p.end());
    }
  }
  ids = AllToAll(comm, sendIds, MPI_INT64_T);
  positions = AllToAll(comm, sendPositions, MPI_DOUBLE);
}

// At a facet's home: the pairs of cells (global ids) that share it, sent to both cells' ranks.
// Returns this rank's edges to other ranks' cells as (local global id, remote global id).
std::vector<std::int64_t> MatchBoundary(MPI_Comm comm, const std::vector<std::int64_t>& ids,
  const std::vector<double>& positions, const Numbering& numbering)
{
  apc::Facets boundary;
  PositionKeys keys;
  std::vector<std::int64_t> facet;
  std::size_t positionAt = 0;
  for (std::size_t at = 0; at < ids.size(); at += 2)
  {
    facet.resize(static_cast<std::size_t>(ids[at + 1]));
    for (auto& key : facet)
    {
      key = keys.Key(positions.data() + positionAt);
      positionAt += 3;
    }
    boundary.Add(ids[at], facet.data(), facet.size());
  }
  const int ranks = static_cast<int>(numbering.First.size()) - 1;
  std::vector<std::vector<std::int64_t>> edges(static_cast<std::size_t>(ranks));
  for (const auto& pair : apc::MatchFacets(boundary).Pairs)
  {
    auto& toFirst = edges[numbering.Owner(pair.first)];
    toFirst.insert(toFirst.end(), { pair.first, pair.second });
    auto& toSecond = edges[numbering.Owner(pair.second)];
    toSecond.insert(toSecond.end(), { pair.second, pair.first });
  }
  return AllToAll(comm, edges, MPI_INT64_T);
}

// This rank's rows of the graph: its own pairs both ways and its edges to other ranks.
apc::DistributedGraph LocalRows(const apc::FacetMatches& matches,
  const std::vector<std::int64_t>& crossEdges, const Numbering& numbering, std::int64_t cells)
{
  const std::int64_t first = numbering.First[numbering.Rank];
  std::vector<std::pair<std::int64_t, std::int64_t>> arcs; // (local cell, global neighbour)
  arcs.reserve(2 * matches.Pairs.size() + crossEdges.size() / 2);
  for (const auto& pair : matches.Pairs)
  {
    if (pair.first != pair.second)
    {
      arcs.emplace_back(pair.first, first + pair.second);
      arcs.emplace_back(pair.second, first + pair.first);
    }
  }
  for (std::size_t i = 0; i < crossEdges.size(); i += 2)
  {
    arcs.emplace_back(crossEdges[i] - first, crossEdges[i + 1]);
  }
  std::sort(arcs.begin(), arcs.end());
  arcs.erase(std::unique(arcs.begin(), arcs.end()), arcs.end());
  apc::DistributedGraph graph;
  graph.FirstCell = first;
  graph.TotalCells = numbering.First.back();
  graph.Offsets.assign(static_cast<std::size_t>(cells) + 1, 0);
  graph.Adjacency.reserve(arcs.size());
  for (const auto& arc : arcs)
  {
    ++graph.Offsets[arc.first + 1];
    graph.Adjacency.push_back(arc.second);
  }
  for (std::int64_t c = 0; c < cells; ++c)
  {
    graph.Offsets[c + 1] += graph.Offsets[c];
  }
  return graph;
}

// Cut edges (each counted once, at its lower endpoint's rank) and the largest piece over the
// mean, the same on every rank.
void MeasurePartition(MPI_Comm comm, const apc::DistributedGraph& graph, const Numbering& numbering,
  const std::vector<int>& part, int pieces, PartitionOutcome& out)
{
  const int ranks = static_cast<int>(numbering.First.size()) - 1;
  std::vector<std::vector<std::int64_t>> ask(static_cast<std::size_t>(ranks));
  long long cut = 0;
  for (std::int64_t c = 0; c + 1 < static_cast<std::int64_t>(graph.Offsets.size()); ++c)
  {
    const std::int64_t self = graph.FirstCell + c;
    for (std::int64_t k = graph.Offsets[c]; k < graph.Offsets[c + 1]; ++k)
    {
      const std::int64_t other = graph.Adjacency[k];
      if (other <= self)
      {
        continue;
      }
      const int owner = numbering.Owner(other);
      if (owner == numbering.Rank)
      {
        cut += part[other - graph.FirstCell] != part[c];
      }
      else
      {
        ask[owner].insert(ask[owner].end(), { other, part[c] });
      }
    }
  }
  const std::vector<std::int64_t> asked = AllToAll(comm, ask, MPI_INT64_T);
  for (std::size_t i = 0; i < asked.size(); i += 2)
  {
    cut += part[asked[i] - graph.FirstCell] != asked[i + 1];
  }
  std::vector<long long> sizes(static_cast<std::size_t>(pieces), 0), total(sizes.size(), 0);
  for (const int p : part)
  {
    ++sizes[p];
  }
  MPI_Allreduce(sizes.data(), total.data(), pieces, MPI_LONG_LONG, MPI_SUM, comm);
  MPI_Allreduce(&cut, &out.EdgeCut, 1, MPI_LONG_LONG, MPI_SUM, comm);
  const double mean = static_cast<double>(graph.TotalCells) / pieces;
  out.Imbalance = *std::max_element(total.begin(), total.end()) / mean;
}

// The MPI communicator under the controller, or null.
MPI_Comm* CommunicatorOf(vtkMultiProcessController* controller)
{
  auto* communicator =
    controller ? vtkMPICommunicator::SafeDownCast(controller->GetCommunicator()) : nullptr;
  return communicator && communicator->GetMPIComm() ? communicator->GetMPIComm()->GetHandle()
                                                    : nullptr;
}
} // namespace

//------------------------------------------------------------------------------
PartitionOutcome PartitionCellsDistributed(const Unit& unit, const LocalCells& cells, int pieces,
  int seed, vtkMultiProcessController* controller)
{
  PartitionOutcome outcome;
  MPI_Comm* handle = CommunicatorOf(controller);
  if (!handle)
  {
    // Every rank has the same kind of controller, so they all say it.
    outcome.Error = "the PT-Scotch partitioner needs an MPI controller";
    return outcome;
  }
  const MPI_Comm comm = *handle;
  const Clock::time_point start = Clock::now();
  PositionKeys keys;
  const apc::Facets facets = BuildFacets(unit, cells, keys);
  const apc::FacetMatches matches = apc::MatchFacets(facets);
  const Numbering numbering = NumberCells(comm, cells.Count);
  std::vector<std::int64_t> ids;
  std::vector<double> positions;
  SendBoundary(comm, facets, matches, keys, numbering, ids, positions);
  const std::vector<std::int64_t> crossEdges = MatchBoundary(comm, ids, positions, numbering);
  const apc::DistributedGraph graph = LocalRows(matches, crossEdges, numbering, cells.Count);
  double seconds[2] = { SecondsSince(start), 0 };

  const Clock::time_point partitionStart = Clock::now();
  apc::DistributedPartition partition = apc::PartitionDistributedGraph(comm, graph, pieces, seed);
  seconds[1] = SecondsSince(partitionStart);
  double slowest[2] = { 0, 0 };
  MPI_Allreduce(seconds, slowest, 2, MPI_DOUBLE, MPI_MAX, comm);
  outcome.GraphSeconds = slowest[0];
  outcome.PartitionSeconds = slowest[1];
  if (!partition.Ok)
  {
    outcome.Error = partition.Error;
    return outcome;
  }
  MeasurePartition(comm, graph, numbering, partition.Part, pieces, outcome);
  outcome.Piece = std::move(partition.Part);
  return outcome;
}

} // namespace partition
} // namespace apc
