// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAPCGraphPartition.h"

#include "apcDualGraph.h"
#include "apcGraphPartitioner.h"

#include "vtkAppendFilter.h"
#include "vtkCell.h"
#include "vtkCellData.h"
#include "vtkDIYDataExchanger.h"
#include "vtkDataObjectTree.h"
#include "vtkDataSetAttributes.h"
#include "vtkDoubleArray.h"
#include "vtkExtractCells.h"
#include "vtkGenericCell.h"
#include "vtkIdList.h"
#include "vtkIdTypeArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkMultiProcessController.h"
#include "vtkMultiProcessStream.h"
#include "vtkObjectFactory.h"
#include "vtkPartitionedDataSet.h"
#include "vtkPartitionedDataSetCollection.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkSmartPointer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <functional>
#include <string>
#include <unordered_map>
#include <vector>

vtkStandardNewMacro(vtkAPCGraphPartition);
vtkCxxSetObjectMacro(vtkAPCGraphPartition, Controller, vtkMultiProcessController);

namespace
{
using UGrids = std::vector<vtkSmartPointer<vtkUnstructuredGrid>>;

double SecondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// One mesh to partition: an unstructured-grid leaf (one part) or a vtkPartitionedDataSet (its
// partitions on this rank), and where its result goes in the output.
struct Unit
{
  std::vector<vtkUnstructuredGrid*> Parts;
  bool Partitioned = false;
  std::function<void(const UGrids&)> Install;
};

// An empty part stands for a leaf absent on this rank, so every rank sees the same units.
std::string AddParts(vtkPartitionedDataSet* pds, Unit& unit, const std::string& where)
{
  if (!pds)
  {
    return {};
  }
  for (unsigned int i = 0; i < pds->GetNumberOfPartitions(); ++i)
  {
    vtkDataObject* part = pds->GetPartitionAsDataObject(i);
    if (!part)
    {
      continue;
    }
    auto* ug = vtkUnstructuredGrid::SafeDownCast(part);
    if (!ug)
    {
      return where + " partition " + std::to_string(i) + " is a " + part->GetClassName() +
        ", not a vtkUnstructuredGrid";
    }
    unit.Parts.push_back(ug);
  }
  return {};
}

void InstallPartitions(vtkPartitionedDataSet* out, const UGrids& pieces)
{
  out->SetNumberOfPartitions(static_cast<unsigned int>(pieces.size()));
  for (std::size_t i = 0; i < pieces.size(); ++i)
  {
    out->SetPartition(static_cast<unsigned int>(i), pieces[i]);
  }
}

// Walks a composite input in a fixed order (the same on every rank when the structure is),
// building the output tree and one unit per mesh. Returns an error message or "".
std::string CollectTree(
  vtkDataObject* in, vtkDataObject* out, std::vector<Unit>& units, const std::string& where)
{
  if (auto* inMb = vtkMultiBlockDataSet::SafeDownCast(in))
  {
    auto* outMb = vtkMultiBlockDataSet::SafeDownCast(out);
    outMb->SetNumberOfBlocks(inMb->GetNumberOfBlocks());
    for (unsigned int i = 0; i < inMb->GetNumberOfBlocks(); ++i)
    {
      if (inMb->HasMetaData(i))
      {
        outMb->GetMetaData(i)->Copy(inMb->GetMetaData(i));
      }
      vtkDataObject* child = inMb->GetBlock(i);
      const std::string childWhere = where + " block " + std::to_string(i);
      if (!child || vtkUnstructuredGrid::SafeDownCast(child))
      {
        Unit unit;
        if (child)
        {
          unit.Parts.push_back(vtkUnstructuredGrid::SafeDownCast(child));
        }
        unit.Install = [outMb, i](const UGrids& pieces) { outMb->SetBlock(i, pieces[0]); };
        units.push_back(std::move(unit));
      }
      else if (auto* childPds = vtkPartitionedDataSet::SafeDownCast(child))
      {
        vtkSmartPointer<vtkPartitionedDataSet> outChild;
        outChild.TakeReference(childPds->NewInstance());
        outMb->SetBlock(i, outChild);
        Unit unit;
        unit.Partitioned = true;
        const std::string error = AddParts(childPds, unit, childWhere);
        if (!error.empty())
        {
          return error;
        }
        vtkPartitionedDataSet* target = outChild;
        unit.Install = [target](const UGrids& pieces) { InstallPartitions(target, pieces); };
        units.push_back(std::move(unit));
      }
      else if (vtkMultiBlockDataSet::SafeDownCast(child))
      {
        vtkNew<vtkMultiBlockDataSet> outChild;
        outMb->SetBlock(i, outChild);
        const std::string error = CollectTree(child, outChild, units, childWhere);
        if (!error.empty())
        {
          return error;
        }
      }
      else
      {
        return childWhere + " is a " + child->GetClassName() + ", not a vtkUnstructuredGrid";
      }
    }
    return {};
  }
  if (auto* inPdc = vtkPartitionedDataSetCollection::SafeDownCast(in))
  {
    auto* outPdc = vtkPartitionedDataSetCollection::SafeDownCast(out);
    outPdc->SetNumberOfPartitionedDataSets(inPdc->GetNumberOfPartitionedDataSets());
    outPdc->SetDataAssembly(inPdc->GetDataAssembly());
    for (unsigned int i = 0; i < inPdc->GetNumberOfPartitionedDataSets(); ++i)
    {
      if (inPdc->HasMetaData(i))
      {
        outPdc->GetMetaData(i)->Copy(inPdc->GetMetaData(i));
      }
      vtkNew<vtkPartitionedDataSet> outChild;
      outPdc->SetPartitionedDataSet(i, outChild);
      Unit unit;
      unit.Partitioned = true;
      const std::string error = AddParts(
        inPdc->GetPartitionedDataSet(i), unit, where + " partitioned dataset " + std::to_string(i));
      if (!error.empty())
      {
        return error;
      }
      vtkPartitionedDataSet* target = outChild;
      unit.Install = [target](const UGrids& pieces) { InstallPartitions(target, pieces); };
      units.push_back(std::move(unit));
    }
    return {};
  }
  if (auto* inPds = vtkPartitionedDataSet::SafeDownCast(in))
  {
    Unit unit;
    unit.Partitioned = true;
    const std::string error = AddParts(inPds, unit, where);
    if (!error.empty())
    {
      return error;
    }
    auto* target = vtkPartitionedDataSet::SafeDownCast(out);
    unit.Install = [target](const UGrids& pieces) { InstallPartitions(target, pieces); };
    units.push_back(std::move(unit));
    return {};
  }
  return std::string("the input is a ") + (in ? in->GetClassName() : "null data object") +
    ": vtkAPCGraphPartition needs a vtkUnstructuredGrid or a multiblock / partitioned "
    "dataset (collection) of them";
}

// Facets of the linear cells as (size, local point indices...) streams ending in 0. Only the
// set of points of a facet matters, not its orientation.
const int TetraFacets[] = { 3, 0, 1, 2, 3, 0, 1, 3, 3, 0, 2, 3, 3, 1, 2, 3, 0 };
const int HexahedronFacets[] = { 4, 0, 4, 7, 3, 4, 1, 2, 6, 5, 4, 0, 1, 5, 4, 4, 3, 7, 6, 2, 4, 0,
  3, 2, 1, 4, 4, 5, 6, 7, 0 };
const int VoxelFacets[] = { 4, 0, 2, 6, 4, 4, 1, 3, 7, 5, 4, 0, 1, 5, 4, 4, 2, 3, 7, 6, 4, 0, 1, 3,
  2, 4, 4, 5, 7, 6, 0 };
const int WedgeFacets[] = { 3, 0, 1, 2, 3, 3, 4, 5, 4, 0, 1, 4, 3, 4, 1, 2, 5, 4, 4, 2, 0, 3, 5,
  0 };
const int PyramidFacets[] = { 4, 0, 1, 2, 3, 3, 0, 1, 4, 3, 1, 2, 4, 3, 2, 3, 4, 3, 3, 0, 4, 0 };
const int PixelFacets[] = { 2, 0, 1, 2, 1, 3, 2, 3, 2, 2, 2, 0, 0 };

const int* LinearFacets(int type)
{
  switch (type)
  {
    case VTK_TETRA:
      return TetraFacets;
    case VTK_HEXAHEDRON:
      return HexahedronFacets;
    case VTK_VOXEL:
      return VoxelFacets;
    case VTK_WEDGE:
      return WedgeFacets;
    case VTK_PYRAMID:
      return PyramidFacets;
    case VTK_PIXEL:
      return PixelFacets;
    default:
      return nullptr;
  }
}

// Points identified by their exact position: pieces cut from one mesh repeat a shared point
// bit for bit, while point ids mean nothing across pieces (or across a reader's appended
// pieces on one rank).
struct PositionKeys
{
  struct Hash
  {
    std::size_t operator()(const std::array<double, 3>& p) const
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
  };
  std::unordered_map<std::array<double, 3>, std::int64_t, Hash> Ids;
  std::vector<std::array<double, 3>> Positions; // by key

  std::int64_t Key(const double x[3])
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
};

// This rank's cells of one unit, in graph order: the parts one after the other, ghost
// (duplicate) cells left out.
struct LocalCells
{
  std::vector<std::vector<vtkIdType>> Kept; // per part: the input cell ids in graph order
  vtkIdType Count = 0;
};

LocalCells KeptCells(const Unit& unit)
{
  LocalCells cells;
  for (vtkUnstructuredGrid* part : unit.Parts)
  {
    std::vector<vtkIdType> kept;
    const vtkIdType n = part->GetNumberOfCells();
    kept.reserve(static_cast<std::size_t>(n));
    vtkUnsignedCharArray* ghosts = part->GetCellGhostArray();
    for (vtkIdType c = 0; c < n; ++c)
    {
      if (!ghosts || !(ghosts->GetValue(c) & vtkDataSetAttributes::DUPLICATECELL))
      {
        kept.push_back(c);
      }
    }
    cells.Count += static_cast<vtkIdType>(kept.size());
    cells.Kept.push_back(std::move(kept));
  }
  return cells;
}

// The facets of this rank's cells of one unit, keyed by point position.
apc::Facets BuildFacets(const Unit& unit, const LocalCells& cells, PositionKeys& keys)
{
  apc::Facets facets;
  // Hexahedra-dominated meshes: about 6 facets of 4 points per cell.
  facets.Cell.reserve(static_cast<std::size_t>(6 * cells.Count));
  facets.Offsets.reserve(static_cast<std::size_t>(6 * cells.Count + 1));
  facets.Points.reserve(static_cast<std::size_t>(24 * cells.Count));
  vtkNew<vtkGenericCell> cell;
  vtkNew<vtkIdList> ids;
  std::vector<std::int64_t> pointKey;
  std::vector<std::int64_t> facet;
  std::int64_t graphCell = 0;
  for (std::size_t p = 0; p < unit.Parts.size(); ++p)
  {
    vtkUnstructuredGrid* part = unit.Parts[p];
    const vtkIdType numberOfPoints = part->GetNumberOfPoints();
    pointKey.resize(static_cast<std::size_t>(numberOfPoints));
    keys.Ids.reserve(keys.Ids.size() + static_cast<std::size_t>(numberOfPoints));
    double x[3];
    for (vtkIdType i = 0; i < numberOfPoints; ++i)
    {
      part->GetPoint(i, x);
      pointKey[i] = keys.Key(x);
    }
    auto addFacet = [&](const vtkIdType* pts, vtkIdType n)
    {
      facet.resize(static_cast<std::size_t>(n));
      for (vtkIdType k = 0; k < n; ++k)
      {
        facet[k] = pointKey[pts[k]];
      }
      facets.Add(graphCell, facet.data(), facet.size());
    };
    for (const vtkIdType c : cells.Kept[p])
    {
      const int type = part->GetCellType(c);
      if (const int* stream = LinearFacets(type))
      {
        vtkIdType npts;
        const vtkIdType* pts;
        part->GetCellPoints(c, npts, pts);
        for (; *stream; stream += *stream + 1)
        {
          facet.resize(static_cast<std::size_t>(*stream));
          for (int k = 0; k < *stream; ++k)
          {
            facet[k] = pointKey[pts[stream[k + 1]]];
          }
          facets.Add(graphCell, facet.data(), facet.size());
        }
      }
      else if (type == VTK_POLYHEDRON)
      {
        vtkIdType nfaces;
        const vtkIdType* stream;
        part->GetFaceStream(c, nfaces, stream);
        for (vtkIdType f = 0; f < nfaces; ++f)
        {
          addFacet(stream + 1, stream[0]);
          stream += stream[0] + 1;
        }
      }
      else if (type == VTK_TRIANGLE || type == VTK_QUAD || type == VTK_POLYGON)
      {
        vtkIdType npts;
        const vtkIdType* pts;
        part->GetCellPoints(c, npts, pts);
        for (vtkIdType k = 0; k < npts; ++k)
        {
          const vtkIdType edge[2] = { pts[k], pts[(k + 1) % npts] };
          addFacet(edge, 2);
        }
      }
      else if (type == VTK_LINE)
      {
        vtkIdType npts;
        const vtkIdType* pts;
        part->GetCellPoints(c, npts, pts);
        addFacet(pts, 1);
        addFacet(pts + 1, 1);
      }
      else if (type != VTK_EMPTY_CELL && type != VTK_VERTEX && type != VTK_POLY_VERTEX)
      {
        // Quadratic, higher-order and the rarer linear cells: VTK's own faces/edges (their
        // point ids are the grid's).
        part->GetCell(c, cell);
        const int dimension = cell->GetCellDimension();
        if (dimension == 3)
        {
          for (int f = 0; f < cell->GetNumberOfFaces(); ++f)
          {
            vtkIdList* face = cell->GetFace(f)->GetPointIds();
            addFacet(face->GetPointer(0), face->GetNumberOfIds());
          }
        }
        else if (dimension == 2)
        {
          for (int e = 0; e < cell->GetNumberOfEdges(); ++e)
          {
            vtkIdList* edge = cell->GetEdge(e)->GetPointIds();
            addFacet(edge->GetPointer(0), edge->GetNumberOfIds());
          }
        }
        else if (dimension == 1 && cell->GetNumberOfPoints() >= 2)
        {
          vtkIdList* pts = cell->GetPointIds();
          addFacet(pts->GetPointer(0), 1);
          addFacet(pts->GetPointer(1), 1);
        }
      }
      ++graphCell;
    }
  }
  return facets;
}

// A shallow copy of a part with its piece ids (-1 on ghost cells) and without ghost arrays.
vtkSmartPointer<vtkUnstructuredGrid> Labelled(
  vtkUnstructuredGrid* part, const std::vector<vtkIdType>& kept, const int* piece, bool dropGhosts)
{
  auto copy = vtkSmartPointer<vtkUnstructuredGrid>::New();
  copy->ShallowCopy(part);
  vtkIdTypeArray* locations = part->GetFaceLocations();
  if (locations && locations->GetNumberOfValues() != part->GetNumberOfCells())
  {
    // Empty face arrays on a grid without polyhedra (ParaView's parallel XML reader leaves
    // them on some ranks) make vtkExtractCells read past their end.
    copy->SetCells(part->GetCellTypesArray(), part->GetCells(), nullptr, nullptr);
  }
  vtkNew<vtkIntArray> ids;
  ids->SetName(vtkAPCGraphPartition::GetPartitionIdArrayName());
  ids->SetNumberOfValues(part->GetNumberOfCells());
  ids->FillValue(-1);
  for (std::size_t i = 0; i < kept.size(); ++i)
  {
    ids->SetValue(kept[i], piece[i]);
  }
  copy->GetCellData()->AddArray(ids);
  if (dropGhosts)
  {
    copy->GetCellData()->RemoveArray(vtkDataSetAttributes::GhostArrayName());
    copy->GetPointData()->RemoveArray(vtkDataSetAttributes::GhostArrayName());
  }
  return copy;
}

vtkSmartPointer<vtkUnstructuredGrid> Extract(
  vtkUnstructuredGrid* grid, const std::vector<vtkIdType>& ids)
{
  if (static_cast<vtkIdType>(ids.size()) == grid->GetNumberOfCells())
  {
    bool identity = true;
    for (std::size_t i = 0; i < ids.size() && identity; ++i)
    {
      identity = ids[i] == static_cast<vtkIdType>(i);
    }
    if (identity)
    {
      return grid;
    }
  }
  vtkNew<vtkIdList> list;
  list->SetNumberOfIds(static_cast<vtkIdType>(ids.size()));
  std::copy(ids.begin(), ids.end(), list->GetPointer(0));
  vtkNew<vtkExtractCells> extract;
  extract->SetInputData(grid);
  extract->SetCellList(list);
  extract->AssumeSortedAndUniqueIdsOn();
  extract->PassThroughCellIdsOff();
  extract->Update();
  return vtkUnstructuredGrid::SafeDownCast(extract->GetOutput());
}

vtkSmartPointer<vtkUnstructuredGrid> Append(const UGrids& grids)
{
  if (grids.size() == 1)
  {
    return grids[0];
  }
  vtkNew<vtkAppendFilter> append;
  append->MergePointsOff();
  for (const auto& g : grids)
  {
    append->AddInputData(g);
  }
  append->Update();
  return vtkUnstructuredGrid::SafeDownCast(append->GetOutput());
}

// Rank r of R owns pieces [r*K/R, (r+1)*K/R).
int RankOfPiece(int piece, int pieces, int ranks)
{
  int r = static_cast<int>((static_cast<long long>(piece) * ranks) / pieces);
  while (r > 0 && static_cast<long long>(r) * pieces / ranks > piece)
  {
    --r;
  }
  while (r + 1 < ranks && static_cast<long long>(r + 1) * pieces / ranks <= piece)
  {
    ++r;
  }
  return r;
}
} // namespace

//------------------------------------------------------------------------------
vtkAPCGraphPartition::vtkAPCGraphPartition()
{
  this->SetController(vtkMultiProcessController::GetGlobalController());
}

//------------------------------------------------------------------------------
vtkAPCGraphPartition::~vtkAPCGraphPartition()
{
  this->SetController(nullptr);
}

//------------------------------------------------------------------------------
int vtkAPCGraphPartition::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkDataObject* input = vtkDataObject::GetData(inputVector[0], 0);
  vtkDataObject* output = vtkDataObject::GetData(outputVector, 0);
  vtkMultiProcessController* controller = this->Controller;
  const int ranks = controller ? controller->GetNumberOfProcesses() : 1;
  const int rank = controller ? controller->GetLocalProcessId() : 0;
  this->LastEdgeCut = 0;
  this->LastImbalance = 0;
  this->LastGraphSeconds = this->LastPartitionSeconds = this->LastExchangeSeconds = 0;

  // Every failure below is agreed on by all ranks before the next collective, so a rank that
  // fails never leaves the others waiting in one.
  auto agree = [&](int localFailure)
  {
    int any = localFailure;
    if (ranks > 1)
    {
      controller->AllReduce(&localFailure, &any, 1, vtkCommunicator::MAX_OP);
    }
    return any != 0;
  };

  std::string error;
  std::vector<Unit> units;
  if (auto* ug = vtkUnstructuredGrid::SafeDownCast(input))
  {
    Unit unit;
    unit.Parts.push_back(ug);
    unit.Install = [output](const UGrids& pieces) { output->ShallowCopy(pieces[0]); };
    units.push_back(std::move(unit));
  }
  else
  {
    // Composite inputs are walked; anything else only gets its error message from here.
    error = CollectTree(input, output, units, "input");
  }
  if (error.empty() && this->NumberOfPartitions < 0)
  {
    error = "NumberOfPartitions is " + std::to_string(this->NumberOfPartitions) +
      ": it must be 0 (one piece per rank) or more";
  }

  // Status and the number of units in one reduction: [failure, units, -units].
  int header[3] = { error.empty() ? 0 : 1, static_cast<int>(units.size()),
    -static_cast<int>(units.size()) };
  int agreed[3] = { header[0], header[1], header[2] };
  if (ranks > 1)
  {
    controller->AllReduce(header, agreed, 3, vtkCommunicator::MAX_OP);
  }
  if (agreed[0])
  {
    vtkErrorMacro(<< (error.empty() ? std::string("failed on another rank (see its error)")
                                    : error));
    output->Initialize();
    return 0;
  }
  if (agreed[1] != -agreed[2])
  {
    vtkErrorMacro(<< "the composite input has " << units.size()
                  << " meshes on this rank but not on every rank: its structure must be the "
                     "same on all ranks");
    output->Initialize();
    return 0;
  }

  std::vector<LocalCells> cells;
  std::vector<vtkIdType> localCounts;
  for (const Unit& unit : units)
  {
    cells.push_back(KeptCells(unit));
    localCounts.push_back(cells.back().Count);
  }
  std::vector<vtkIdType> totalCounts = localCounts;
  if (ranks > 1 && !units.empty())
  {
    controller->AllReduce(localCounts.data(), totalCounts.data(),
      static_cast<vtkIdType>(units.size()), vtkCommunicator::SUM_OP);
  }
  vtkIdType total = 0;
  for (const vtkIdType n : totalCounts)
  {
    total += n;
  }
  if (total == 0)
  {
    vtkErrorMacro(<< "no cells to partition (the input has no cells on any rank)");
    output->Initialize();
    return 0;
  }
  const int pieces = this->NumberOfPartitions > 0 ? this->NumberOfPartitions : ranks;

  for (std::size_t u = 0; u < units.size(); ++u)
  {
    const Unit& unit = units[u];
    const LocalCells& local = cells[u];
    if (totalCounts[u] == 0)
    {
      // An empty block stays empty (with its arrays), whatever the mode.
      UGrids empty;
      for (std::size_t p = 0; p < unit.Parts.size(); ++p)
      {
        empty.push_back(Labelled(unit.Parts[p], local.Kept[p], nullptr, true));
      }
      if (!unit.Partitioned && empty.empty())
      {
        empty.push_back(vtkSmartPointer<vtkUnstructuredGrid>::New());
      }
      unit.Install(unit.Partitioned ? empty : UGrids{ empty[0] });
      continue;
    }

    // --- the dual graph: local facets matched here, the unmatched ones on rank 0 ---------
    auto start = std::chrono::steady_clock::now();
    PositionKeys keys;
    const apc::Facets facets = BuildFacets(unit, local, keys);
    apc::FacetMatches matches = apc::MatchFacets(facets);
    std::vector<int> piece(static_cast<std::size_t>(local.Count), 0);
    int failed = 0;
    std::string message;
    apc::GraphPartition partition;
    double graphSeconds = 0, partitionSeconds = 0;

    if (ranks == 1)
    {
      const apc::CellGraph graph = apc::BuildCellGraph(local.Count, matches.Pairs);
      graphSeconds = SecondsSince(start);
      start = std::chrono::steady_clock::now();
      partition = apc::PartitionCellGraph(graph, pieces, this->Seed);
      partitionSeconds = SecondsSince(start);
      if (!partition.Ok)
      {
        vtkErrorMacro(<< partition.Error);
        output->Initialize();
        return 0;
      }
      piece = partition.Part;
    }
    else
    {
      // [cells, pair ids, unmatched facets, their keys] per rank.
      vtkIdType counts[4] = { local.Count, static_cast<vtkIdType>(2 * matches.Pairs.size()),
        static_cast<vtkIdType>(matches.Unmatched.size()), 0 };
      vtkNew<vtkIdTypeArray> ids;
      vtkNew<vtkDoubleArray> positions;
      ids->Allocate(counts[1] + 2 * counts[2]);
      for (const auto& pair : matches.Pairs)
      {
        ids->InsertNextValue(pair.first);
        ids->InsertNextValue(pair.second);
      }
      for (const std::int64_t f : matches.Unmatched)
      {
        ids->InsertNextValue(facets.Cell[f]);
        ids->InsertNextValue(facets.Offsets[f + 1] - facets.Offsets[f]);
        for (std::int64_t k = facets.Offsets[f]; k < facets.Offsets[f + 1]; ++k)
        {
          const auto& x = keys.Positions[facets.Points[k]];
          positions->InsertNextTuple1(x[0]);
          positions->InsertNextTuple1(x[1]);
          positions->InsertNextTuple1(x[2]);
          ++counts[3];
        }
      }
      std::vector<vtkIdType> allCounts(4 * static_cast<std::size_t>(ranks), 0);
      controller->Gather(counts, allCounts.data(), 4, 0);
      vtkNew<vtkIdTypeArray> allIds;
      vtkNew<vtkDoubleArray> allPositions;
      controller->GatherV(ids, allIds, 0);
      controller->GatherV(positions, allPositions, 0);

      std::vector<int> allPieces;
      std::vector<vtkIdType> cellOffsets(static_cast<std::size_t>(ranks) + 1, 0);
      for (int r = 0; r < ranks; ++r)
      {
        cellOffsets[r + 1] = cellOffsets[r] + allCounts[4 * r];
      }
      if (rank == 0)
      {
        std::vector<std::pair<std::int64_t, std::int64_t>> pairs;
        apc::Facets boundary;
        PositionKeys globalKeys;
        std::vector<std::int64_t> facet;
        vtkIdType idAt = 0, positionAt = 0;
        for (int r = 0; r < ranks; ++r)
        {
          const vtkIdType offset = cellOffsets[r];
          for (vtkIdType i = 0; i < allCounts[4 * r + 1]; i += 2, idAt += 2)
          {
            pairs.emplace_back(
              allIds->GetValue(idAt) + offset, allIds->GetValue(idAt + 1) + offset);
          }
          for (vtkIdType f = 0; f < allCounts[4 * r + 2]; ++f)
          {
            const vtkIdType owner = allIds->GetValue(idAt++) + offset;
            const vtkIdType n = allIds->GetValue(idAt++);
            facet.resize(static_cast<std::size_t>(n));
            for (vtkIdType k = 0; k < n; ++k, positionAt += 3)
            {
              facet[k] = globalKeys.Key(allPositions->GetPointer(positionAt));
            }
            boundary.Add(owner, facet.data(), facet.size());
          }
        }
        const apc::FacetMatches across = apc::MatchFacets(boundary);
        pairs.insert(pairs.end(), across.Pairs.begin(), across.Pairs.end());
        const apc::CellGraph graph = apc::BuildCellGraph(cellOffsets[ranks], pairs);
        graphSeconds = SecondsSince(start);
        start = std::chrono::steady_clock::now();
        partition = apc::PartitionCellGraph(graph, pieces, this->Seed);
        partitionSeconds = SecondsSince(start);
        failed = partition.Ok ? 0 : 1;
        message = partition.Error;
        allPieces = std::move(partition.Part);
      }
      vtkMultiProcessStream verdict;
      if (rank == 0)
      {
        verdict << failed << message << graphSeconds << partitionSeconds
                << static_cast<long long>(partition.EdgeCut);
      }
      controller->Broadcast(verdict, 0);
      long long edgeCut = 0;
      verdict >> failed >> message >> graphSeconds >> partitionSeconds >> edgeCut;
      partition.EdgeCut = edgeCut;
      if (failed)
      {
        vtkErrorMacro(<< "rank 0: " << message);
        output->Initialize();
        return 0;
      }
      std::vector<vtkIdType> lengths(static_cast<std::size_t>(ranks));
      for (int r = 0; r < ranks; ++r)
      {
        lengths[r] = allCounts[4 * r];
      }
      controller->ScatterV(
        allPieces.data(), piece.data(), lengths.data(), cellOffsets.data(), local.Count, 0);
      if (rank == 0)
      {
        partition.Part = std::move(allPieces);
      }
    }
    this->LastGraphSeconds += graphSeconds;
    this->LastPartitionSeconds += partitionSeconds;
    this->LastEdgeCut += partition.EdgeCut;
    double imbalance = rank == 0 ? apc::PartitionImbalance(partition.Part, pieces) : 0;
    if (ranks > 1)
    {
      controller->Broadcast(&imbalance, 1, 0);
    }
    this->LastImbalance = std::max(this->LastImbalance, imbalance);

    // --- label or move ------------------------------------------------------------------------
    start = std::chrono::steady_clock::now();
    UGrids labelled;
    vtkIdType at = 0;
    for (std::size_t p = 0; p < unit.Parts.size(); ++p)
    {
      labelled.push_back(
        Labelled(unit.Parts[p], local.Kept[p], piece.data() + at, !this->LabelOnly));
      at += static_cast<vtkIdType>(local.Kept[p].size());
    }
    if (this->LabelOnly)
    {
      if (!unit.Partitioned && labelled.empty())
      {
        labelled.push_back(vtkSmartPointer<vtkUnstructuredGrid>::New());
      }
      unit.Install(labelled);
      this->LastExchangeSeconds += SecondsSince(start);
      continue;
    }

    // Chunks for rank r must be contiguous in the send buffer (vtkDIYDataExchanger's
    // contract), so they are collected per rank first.
    std::vector<UGrids> toRank(static_cast<std::size_t>(ranks));
    std::vector<std::vector<vtkIdType>> byRank(static_cast<std::size_t>(ranks));
    at = 0;
    for (std::size_t p = 0; p < unit.Parts.size(); ++p)
    {
      for (auto& list : byRank)
      {
        list.clear();
      }
      for (const vtkIdType c : local.Kept[p])
      {
        byRank[RankOfPiece(piece[at++], pieces, ranks)].push_back(c);
      }
      for (int r = 0; r < ranks; ++r)
      {
        if (!byRank[r].empty())
        {
          toRank[r].push_back(Extract(labelled[p], byRank[r]));
        }
      }
    }
    std::vector<vtkSmartPointer<vtkDataSet>> send;
    std::vector<int> sendCounts(static_cast<std::size_t>(ranks), 0);
    for (int r = 0; r < ranks; ++r)
    {
      if (r != rank)
      {
        send.insert(send.end(), toRank[r].begin(), toRank[r].end());
        sendCounts[r] = static_cast<int>(toRank[r].size());
      }
    }

    int exchangeFailed = 0;
    std::vector<vtkSmartPointer<vtkDataSet>> received;
    std::vector<int> receivedCounts;
    if (ranks > 1)
    {
      vtkNew<vtkDIYDataExchanger> exchanger;
      exchanger->SetController(controller);
      exchangeFailed = exchanger->AllToAll(send, sendCounts, received, receivedCounts) ? 0 : 1;
    }
    if (agree(exchangeFailed))
    {
      vtkErrorMacro(<< "moving the pieces between ranks failed"
                    << (exchangeFailed ? " on this rank" : " on another rank"));
      output->Initialize();
      return 0;
    }
    // This rank's own cells first, then what came from the others, in rank order.
    UGrids mine = toRank[rank];
    for (const auto& ds : received)
    {
      if (auto* ug = vtkUnstructuredGrid::SafeDownCast(ds))
      {
        if (ug->GetNumberOfCells() > 0)
        {
          mine.emplace_back(ug);
        }
      }
    }
    vtkSmartPointer<vtkUnstructuredGrid> result;
    if (mine.empty())
    {
      // No piece here: an empty grid that still has the input's arrays.
      result =
        labelled.empty() ? vtkSmartPointer<vtkUnstructuredGrid>::New() : Extract(labelled[0], {});
    }
    else
    {
      result = Append(mine);
    }
    if (!unit.Partitioned)
    {
      unit.Install({ result });
    }
    else
    {
      // One partition per piece this rank owns.
      UGrids owned;
      auto* ids = vtkIntArray::SafeDownCast(
        result->GetCellData()->GetArray(vtkAPCGraphPartition::GetPartitionIdArrayName()));
      std::vector<std::vector<vtkIdType>> byPiece(static_cast<std::size_t>(pieces));
      for (vtkIdType c = 0; ids && c < result->GetNumberOfCells(); ++c)
      {
        byPiece[ids->GetValue(c)].push_back(c);
      }
      for (int p = 0; p < pieces; ++p)
      {
        if (!byPiece[p].empty())
        {
          owned.push_back(Extract(result, byPiece[p]));
        }
      }
      unit.Install(owned);
    }
    this->LastExchangeSeconds += SecondsSince(start);
  }
  return 1;
}

//------------------------------------------------------------------------------
void vtkAPCGraphPartition::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "NumberOfPartitions: " << this->NumberOfPartitions << "\n";
  os << indent << "Seed: " << this->Seed << "\n";
  os << indent << "LabelOnly: " << this->LabelOnly << "\n";
  os << indent << "Controller: " << this->Controller << "\n";
  os << indent << "LastEdgeCut: " << this->LastEdgeCut << "\n";
  os << indent << "LastImbalance: " << this->LastImbalance << "\n";
}
