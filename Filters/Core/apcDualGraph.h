// SPDX-License-Identifier: BSD-3-Clause
// The cell dual graph of a mesh (cells are vertices, cells sharing a facet are neighbours),
// built from facets given as lists of point keys. VTK-free so that it is unit-tested alone and
// works the same on one process and on the facets gathered from many.
#ifndef apcDualGraph_h
#define apcDualGraph_h

#include <cstdint>
#include <utility>
#include <vector>

namespace apc
{

/// Facets (faces of 3D cells, edges of 2D cells, end points of 1D cells) in compressed rows:
/// facet f belongs to cell Cell[f] and has the point keys Points[Offsets[f] .. Offsets[f+1]).
/// Two facets are the same facet when they have the same set of keys, in any order: a key is
/// whatever identifies a point across all cells (a point id, a global id, a merged position).
struct Facets
{
  std::vector<std::int64_t> Cell;
  std::vector<std::int64_t> Offsets{ 0 };
  std::vector<std::int64_t> Points;

  std::size_t Size() const { return this->Cell.size(); }
  void Add(std::int64_t cell, const std::int64_t* keys, std::size_t n);
  void Append(const Facets& other, std::int64_t cellOffset);
};

/// What matching facets by their keys gives: the pairs of distinct cells that share a facet
/// (first < second, possibly repeated when two cells share several facets) and the facets no
/// other facet matched (the boundary of the cells given, e.g. a process's part of the mesh).
struct FacetMatches
{
  std::vector<std::pair<std::int64_t, std::int64_t>> Pairs;
  std::vector<std::int64_t> Unmatched;
};

/// Sorts the facets by their key sets (hash, then exact comparison: never a false match).
/// A facet shared by more than two cells (non-manifold) links each of them to the first.
FacetMatches MatchFacets(const Facets& facets);

/// A symmetric adjacency in compressed rows (METIS's xadj/adjncy): no self loops, no
/// repeated neighbours, neighbours sorted.
struct CellGraph
{
  std::vector<std::int64_t> Offsets;
  std::vector<std::int64_t> Adjacency;

  std::int64_t NumberOfCells() const
  {
    return this->Offsets.empty() ? 0 : static_cast<std::int64_t>(this->Offsets.size()) - 1;
  }
  std::int64_t NumberOfEdges() const
  {
    return static_cast<std::int64_t>(this->Adjacency.size()) / 2;
  }
};

/// The graph of numberOfCells vertices with an edge for every pair (either order, repeats
/// and self pairs ignored). Pairs must name cells in [0, numberOfCells).
CellGraph BuildCellGraph(
  std::int64_t numberOfCells, const std::vector<std::pair<std::int64_t, std::int64_t>>& pairs);

/// Dual graph of cells given by their facets: MatchFacets then BuildCellGraph.
CellGraph BuildDualGraph(std::int64_t numberOfCells, const Facets& facets);

} // namespace apc

#endif
