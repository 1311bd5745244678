// SPDX-License-Identifier: BSD-3-Clause
// vtkAPCGraphPartition's second and third stages: the cell dual graph of one mesh and its
// K-way partition.
//
// Each rank keys the points of its cells by their exact position, lists its cells' facets
// (Filters/Core/apcCellFacets for the fixed-topology cells, the face stream for polyhedra,
// VTK's own faces and edges for the rest) and matches them (Filters/Core/apcDualGraph). On one
// rank that is the whole graph. On several, each rank gathers to rank 0 only its graph edges
// and the facets it could not match (its boundary, with point coordinates); rank 0 matches
// those across ranks, partitions the whole graph (Filters/Core/apcGraphPartitioner) and
// scatters each rank's cells' pieces back. So rank 0 holds the graph (O(cells)) but never the
// cells or their arrays. Every rank gets the same verdict, so a failure is an error on all.
#ifndef apcPartitionGraph_h
#define apcPartitionGraph_h

#include "apcDualGraph.h"
#include "apcPartitionInput.h"

#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

class vtkMultiProcessController;

namespace apc
{
namespace partition
{

// Points identified by their exact position: pieces cut from one mesh repeat a shared point
// bit for bit, while point ids mean nothing across pieces (or across a reader's appended
// pieces on one rank).
struct PositionKeys
{
  struct Hash
  {
    std::size_t operator()(const std::array<double, 3>& p) const;
  };
  std::unordered_map<std::array<double, 3>, std::int64_t, Hash> Ids;
  std::vector<std::array<double, 3>> Positions; // by key

  std::int64_t Key(const double x[3]);
};

// The facets of this rank's cells of one unit (cells numbered in graph order), their points
// keyed by position in keys.
apc::Facets BuildFacets(const Unit& unit, const LocalCells& cells, PositionKeys& keys);

struct PartitionOutcome
{
  std::string Error;      // empty when the partition succeeded (the same on every rank)
  std::vector<int> Piece; // per cell of LocalCells, in graph order: its piece in [0, K)
  long long EdgeCut = 0;  // the same on every rank
  double Imbalance = 0;   // largest piece over the mean piece, the same on every rank
  double GraphSeconds = 0;
  double PartitionSeconds = 0;
};

// Partitions this unit's cells, over all ranks of controller (null: one process), into
// `pieces` pieces with METIS seeded by `seed`. Collective: every rank calls it for every unit
// with cells somewhere.
PartitionOutcome PartitionCells(const Unit& unit, const LocalCells& cells, int pieces, int seed,
  vtkMultiProcessController* controller);

} // namespace partition
} // namespace apc

#endif
