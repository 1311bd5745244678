// SPDX-License-Identifier: BSD-3-Clause
#include "apcPartitionGraph.h"

#include "apcCellFacets.h"
#include "apcDualGraph.h"
#include "apcGraphPartitioner.h"

#include "vtkCell.h"
#include "vtkCellType.h"
#include "vtkDoubleArray.h"
#include "vtkGenericCell.h"
#include "vtkIdList.h"
#include "vtkIdTypeArray.h"
#include "vtkMultiProcessController.h"
#include "vtkMultiProcessStream.h"
#include "vtkNew.h"
#include "vtkUnstructuredGrid.h"

#include <array>
#include <chrono>
#include <cstring>
#include <unordered_map>

// The facet table is VTK-free and names VTK's cell types by number.
static_assert(apc::CellType::Line == VTK_LINE && apc::CellType::Triangle == VTK_TRIANGLE &&
    apc::CellType::Pixel == VTK_PIXEL && apc::CellType::Quad == VTK_QUAD &&
    apc::CellType::Tetra == VTK_TETRA && apc::CellType::Voxel == VTK_VOXEL &&
    apc::CellType::Hexahedron == VTK_HEXAHEDRON && apc::CellType::Wedge == VTK_WEDGE &&
    apc::CellType::Pyramid == VTK_PYRAMID,
  "apcCellFacets.h's cell type numbers must be VTK's");

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

// Lists the facets of one part's cells, their points keyed by position.
struct FacetLister
{
  apc::Facets& Out;
  std::vector<std::int64_t> PointKey; // the part's point ids to keys
  std::vector<std::int64_t> Facet;
  std::int64_t GraphCell = 0;
  vtkNew<vtkGenericCell> Cell;

  void Add(const vtkIdType* pts, vtkIdType n)
  {
    this->Facet.resize(static_cast<std::size_t>(n));
    for (vtkIdType k = 0; k < n; ++k)
    {
      this->Facet[k] = this->PointKey[pts[k]];
    }
    this->Out.Add(this->GraphCell, this->Facet.data(), this->Facet.size());
  }

  void KeyPoints(vtkUnstructuredGrid* part, PositionKeys& keys)
  {
    const vtkIdType numberOfPoints = part->GetNumberOfPoints();
    this->PointKey.resize(static_cast<std::size_t>(numberOfPoints));
    keys.Ids.reserve(keys.Ids.size() + static_cast<std::size_t>(numberOfPoints));
    double x[3];
    for (vtkIdType i = 0; i < numberOfPoints; ++i)
    {
      part->GetPoint(i, x);
      this->PointKey[i] = keys.Key(x);
    }
  }

  // Quadratic, higher-order and the rarer linear cells: VTK's own faces or edges (their point
  // ids are the grid's).
  void AddFromVTKCell(vtkUnstructuredGrid* part, vtkIdType c)
  {
    part->GetCell(c, this->Cell);
    const int dimension = this->Cell->GetCellDimension();
    if (dimension == 3)
    {
      for (int f = 0; f < this->Cell->GetNumberOfFaces(); ++f)
      {
        vtkIdList* face = this->Cell->GetFace(f)->GetPointIds();
        this->Add(face->GetPointer(0), face->GetNumberOfIds());
      }
    }
    else if (dimension == 2)
    {
      for (int e = 0; e < this->Cell->GetNumberOfEdges(); ++e)
      {
        vtkIdList* edge = this->Cell->GetEdge(e)->GetPointIds();
        this->Add(edge->GetPointer(0), edge->GetNumberOfIds());
      }
    }
    else if (dimension == 1 && this->Cell->GetNumberOfPoints() >= 2)
    {
      vtkIdList* pts = this->Cell->GetPointIds();
      this->Add(pts->GetPointer(0), 1);
      this->Add(pts->GetPointer(1), 1);
    }
  }

  void AddCell(vtkUnstructuredGrid* part, vtkIdType c)
  {
    const int type = part->GetCellType(c);
    vtkIdType npts;
    const vtkIdType* pts;
    if (const apc::CellFacets* table = apc::FacetsOfCellType(type))
    {
      part->GetCellPoints(c, npts, pts);
      vtkIdType facet[4];
      for (int f = 0; f < table->Count; ++f)
      {
        for (int k = 0; k < table->Size[f]; ++k)
        {
          facet[k] = pts[table->Corner[f][k]];
        }
        this->Add(facet, table->Size[f]);
      }
    }
    else if (type == VTK_POLYHEDRON)
    {
      vtkIdType nfaces;
      part->GetFaceStream(c, nfaces, pts);
      for (vtkIdType f = 0; f < nfaces; ++f)
      {
        this->Add(pts + 1, pts[0]);
        pts += pts[0] + 1;
      }
    }
    else if (type == VTK_POLYGON)
    {
      part->GetCellPoints(c, npts, pts);
      for (vtkIdType k = 0; k < npts; ++k)
      {
        const vtkIdType edge[2] = { pts[k], pts[(k + 1) % npts] };
        this->Add(edge, 2);
      }
    }
    else if (type != VTK_EMPTY_CELL && type != VTK_VERTEX && type != VTK_POLY_VERTEX)
    {
      this->AddFromVTKCell(part, c);
    }
  }
};

// What a rank sends rank 0: its graph edges and its unmatched facets with their positions.
// Counts are [cells, pair ids, unmatched facets, their point coordinates' triples].
struct RankBoundary
{
  vtkIdType Counts[4] = { 0, 0, 0, 0 };
  vtkNew<vtkIdTypeArray> Ids; // pairs, then per unmatched facet: cell, size
  vtkNew<vtkDoubleArray> Positions;
};

void PackBoundary(vtkIdType cellCount, const apc::Facets& facets, const apc::FacetMatches& matches,
  const PositionKeys& keys, RankBoundary& out)
{
  out.Counts[0] = cellCount;
  out.Counts[1] = static_cast<vtkIdType>(2 * matches.Pairs.size());
  out.Counts[2] = static_cast<vtkIdType>(matches.Unmatched.size());
  out.Ids->Allocate(out.Counts[1] + 2 * out.Counts[2]);
  for (const auto& pair : matches.Pairs)
  {
    out.Ids->InsertNextValue(pair.first);
    out.Ids->InsertNextValue(pair.second);
  }
  for (const std::int64_t f : matches.Unmatched)
  {
    out.Ids->InsertNextValue(facets.Cell[f]);
    out.Ids->InsertNextValue(facets.Offsets[f + 1] - facets.Offsets[f]);
    for (std::int64_t k = facets.Offsets[f]; k < facets.Offsets[f + 1]; ++k)
    {
      const auto& x = keys.Positions[facets.Points[k]];
      out.Positions->InsertNextTuple1(x[0]);
      out.Positions->InsertNextTuple1(x[1]);
      out.Positions->InsertNextTuple1(x[2]);
      ++out.Counts[3];
    }
  }
}

// Every rank's boundary, as rank 0 receives it.
struct GatheredBoundaries
{
  std::vector<vtkIdType> Counts;      // 4 per rank, as RankBoundary::Counts
  std::vector<vtkIdType> CellOffsets; // rank r's cells are global cells [CellOffsets[r], [r+1])
  vtkNew<vtkIdTypeArray> Ids;
  vtkNew<vtkDoubleArray> Positions;
};

void GatherBoundaries(
  vtkMultiProcessController* controller, RankBoundary& mine, GatheredBoundaries& all)
{
  const int ranks = controller->GetNumberOfProcesses();
  all.Counts.assign(4 * static_cast<std::size_t>(ranks), 0);
  controller->Gather(mine.Counts, all.Counts.data(), 4, 0);
  controller->GatherV(mine.Ids, all.Ids, 0);
  controller->GatherV(mine.Positions, all.Positions, 0);
  all.CellOffsets.assign(static_cast<std::size_t>(ranks) + 1, 0);
  for (int r = 0; r < ranks; ++r)
  {
    all.CellOffsets[r + 1] = all.CellOffsets[r] + all.Counts[4 * r];
  }
}

// Rank 0: the whole dual graph, the ranks' own edges plus their boundaries matched across.
apc::CellGraph MatchAcrossRanks(const GatheredBoundaries& all, int ranks)
{
  std::vector<std::pair<std::int64_t, std::int64_t>> pairs;
  apc::Facets boundary;
  PositionKeys globalKeys;
  std::vector<std::int64_t> facet;
  vtkIdType idAt = 0, positionAt = 0;
  for (int r = 0; r < ranks; ++r)
  {
    const vtkIdType offset = all.CellOffsets[r];
    for (vtkIdType i = 0; i < all.Counts[4 * r + 1]; i += 2, idAt += 2)
    {
      pairs.emplace_back(all.Ids->GetValue(idAt) + offset, all.Ids->GetValue(idAt + 1) + offset);
    }
    for (vtkIdType f = 0; f < all.Counts[4 * r + 2]; ++f)
    {
      const vtkIdType owner = all.Ids->GetValue(idAt++) + offset;
      const vtkIdType n = all.Ids->GetValue(idAt++);
      facet.resize(static_cast<std::size_t>(n));
      for (vtkIdType k = 0; k < n; ++k, positionAt += 3)
      {
        facet[k] = globalKeys.Key(all.Positions->GetPointer(positionAt));
      }
      boundary.Add(owner, facet.data(), facet.size());
    }
  }
  const apc::FacetMatches across = apc::MatchFacets(boundary);
  pairs.insert(pairs.end(), across.Pairs.begin(), across.Pairs.end());
  return apc::BuildCellGraph(all.CellOffsets[ranks], pairs);
}

PartitionOutcome PartitionOnOneRank(const apc::FacetMatches& matches, vtkIdType cellCount,
  int pieces, int seed, Clock::time_point start)
{
  PartitionOutcome outcome;
  const apc::CellGraph graph = apc::BuildCellGraph(cellCount, matches.Pairs);
  outcome.GraphSeconds = SecondsSince(start);
  start = Clock::now();
  apc::GraphPartition partition = apc::PartitionCellGraph(graph, pieces, seed);
  outcome.PartitionSeconds = SecondsSince(start);
  if (!partition.Ok)
  {
    outcome.Error = partition.Error;
    return outcome;
  }
  outcome.EdgeCut = partition.EdgeCut;
  outcome.Imbalance = apc::PartitionImbalance(partition.Part, pieces);
  outcome.Piece = std::move(partition.Part);
  return outcome;
}

// Rank 0's verdict (failure, message, times, edge cut, imbalance) to every rank.
void BroadcastVerdict(vtkMultiProcessController* controller, PartitionOutcome& outcome)
{
  vtkMultiProcessStream verdict;
  if (controller->GetLocalProcessId() == 0)
  {
    verdict << outcome.Error << outcome.GraphSeconds << outcome.PartitionSeconds << outcome.EdgeCut
            << outcome.Imbalance;
  }
  controller->Broadcast(verdict, 0);
  verdict >> outcome.Error >> outcome.GraphSeconds >> outcome.PartitionSeconds >> outcome.EdgeCut >>
    outcome.Imbalance;
}

PartitionOutcome PartitionOnRanks(const apc::Facets& facets, const apc::FacetMatches& matches,
  const PositionKeys& keys, vtkIdType cellCount, int pieces, int seed,
  vtkMultiProcessController* controller, Clock::time_point start)
{
  const int ranks = controller->GetNumberOfProcesses();
  RankBoundary mine;
  PackBoundary(cellCount, facets, matches, keys, mine);
  GatheredBoundaries all;
  GatherBoundaries(controller, mine, all);
  PartitionOutcome outcome;
  std::vector<int> allPieces;
  if (controller->GetLocalProcessId() == 0)
  {
    const apc::CellGraph graph = MatchAcrossRanks(all, ranks);
    outcome.GraphSeconds = SecondsSince(start);
    const Clock::time_point partitionStart = Clock::now();
    apc::GraphPartition partition = apc::PartitionCellGraph(graph, pieces, seed);
    outcome.PartitionSeconds = SecondsSince(partitionStart);
    outcome.Error = partition.Ok ? std::string() : "rank 0: " + partition.Error;
    outcome.EdgeCut = partition.EdgeCut;
    outcome.Imbalance = partition.Ok ? apc::PartitionImbalance(partition.Part, pieces) : 0;
    allPieces = std::move(partition.Part);
  }
  BroadcastVerdict(controller, outcome);
  if (!outcome.Error.empty())
  {
    return outcome;
  }
  std::vector<vtkIdType> lengths(static_cast<std::size_t>(ranks));
  for (int r = 0; r < ranks; ++r)
  {
    lengths[r] = all.Counts[4 * r];
  }
  outcome.Piece.assign(static_cast<std::size_t>(cellCount), 0);
  controller->ScatterV(
    allPieces.data(), outcome.Piece.data(), lengths.data(), all.CellOffsets.data(), cellCount, 0);
  return outcome;
}
} // namespace

//------------------------------------------------------------------------------
apc::Facets BuildFacets(const Unit& unit, const LocalCells& cells, PositionKeys& keys)
{
  apc::Facets facets;
  // Hexahedra-dominated meshes: about 6 facets of 4 points per cell.
  facets.Cell.reserve(static_cast<std::size_t>(6 * cells.Count));
  facets.Offsets.reserve(static_cast<std::size_t>(6 * cells.Count + 1));
  facets.Points.reserve(static_cast<std::size_t>(24 * cells.Count));
  FacetLister lister{ facets };
  for (std::size_t p = 0; p < unit.Parts.size(); ++p)
  {
    vtkUnstructuredGrid* part = unit.Parts[p];
    lister.KeyPoints(part, keys);
    for (const vtkIdType c : cells.Kept[p])
    {
      lister.AddCell(part, c);
      ++lister.GraphCell;
    }
  }
  return facets;
}

//------------------------------------------------------------------------------
std::int64_t PositionKeys::Key(const double x[3])
{
  // + 0.0 turns -0.0 into 0.0, which compares equal but hashes differently.
  const std::array<double, 3> p{ x[0] + 0.0, x[1] + 0.0, x[2] + 0.0 };
  auto inserted = this->Ids.emplace(p, static_cast<std::int64_t>(this->Positions.size()));
  if (inserted.second)
  {
    this->Positions.push_back(p);
  }
  return inserted.first->second;
}

//------------------------------------------------------------------------------
std::size_t PositionKeys::Hash::operator()(const std::array<double, 3>& p) const
{
  std::size_t h = 1469598103934665603ULL;
  for (double v : p)
  {
    std::uint64_t bits;
    std::memcpy(&bits, &v, sizeof(bits));
    h = (h ^ bits) * 1099511628211ULL;
    h ^= h >> 29;
  }
  return h;
}

//------------------------------------------------------------------------------
PartitionOutcome PartitionCells(const Unit& unit, const LocalCells& cells, int pieces, int seed,
  vtkMultiProcessController* controller)
{
  const Clock::time_point start = Clock::now();
  PositionKeys keys;
  const apc::Facets facets = BuildFacets(unit, cells, keys);
  const apc::FacetMatches matches = apc::MatchFacets(facets);
  if (!controller || controller->GetNumberOfProcesses() == 1)
  {
    return PartitionOnOneRank(matches, cells.Count, pieces, seed, start);
  }
  return PartitionOnRanks(facets, matches, keys, cells.Count, pieces, seed, controller, start);
}

} // namespace partition
} // namespace apc
