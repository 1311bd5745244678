// SPDX-License-Identifier: BSD-3-Clause
#include "apcGridCells.h"

#include "apcCellMesh.h"
#include "apcInputReport.h"
#include "apcParallel.h"
#include "apcScalarReader.h"

#include "vtkCellArray.h"
#include "vtkCellType.h"
#include "vtkDataSetAttributes.h"
#include "vtkPoints.h"
#include "vtkSmartPointer.h"
#include "vtkTypeInt64Array.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

#include <algorithm>
#include <array>
#include <memory>

namespace apc
{
// 3D cells vtkDataSetTriangleFilter cuts into tetrahedra over their own points with its
// ordered triangulator, as for ParaView's Volume. Higher-order Lagrange and Bezier cells are
// left out: the triangulator would ignore their curvature.
bool TriangulatedByTheFilter(int vtkType)
{
  switch (vtkType)
  {
    case VTK_QUADRATIC_TETRA:
    case VTK_QUADRATIC_PYRAMID:
    case VTK_QUADRATIC_WEDGE:
    case VTK_QUADRATIC_HEXAHEDRON:
    case VTK_TRIQUADRATIC_HEXAHEDRON:
    case VTK_TRIQUADRATIC_PYRAMID:
    case VTK_QUADRATIC_LINEAR_WEDGE:
    case VTK_BIQUADRATIC_QUADRATIC_WEDGE:
    case VTK_BIQUADRATIC_QUADRATIC_HEXAHEDRON:
    case VTK_PENTAGONAL_PRISM:
    case VTK_HEXAGONAL_PRISM:
      return true;
    default:
      return false;
  }
}

namespace
{
// Cells per block: blocks are the unit of parallel work and of the join in cell order.
constexpr int64_t kBlock = 16384;

// The shape APC renders a VTK cell type as: its corner count (0 if not rendered as it is).
int CornersOf(unsigned char type)
{
  switch (type)
  {
    case VTK_TETRA:
      return 4;
    case VTK_PYRAMID:
      return 5;
    case VTK_WEDGE:
      return 6;
    case VTK_HEXAHEDRON:
    case VTK_VOXEL:
      return 8;
    default:
      return 0;
  }
}

// What one block of input cells gives.
struct Block
{
  int64_t Cells = 0;   // rendered as they are
  int64_t Corners = 0; // their corner ids
  bool Polyhedra = false;
  // Every cell rendered as it is, with VTK's corner order and exactly its shape's ids: the
  // grid's own offsets and connectivity are then the mesh's.
  bool AsTheGrid = true;
  std::vector<vtkIdType> ForTheFilter;
  std::vector<unsigned char> Unsupported;
};

// The grid's raw arrays, with ids of type Id (vtkCellArray stores 32- or 64-bit ids).
template <class Id>
struct Cells
{
  const unsigned char* Types;
  const unsigned char* Ghosts; // null without ghost flags
  const Id* Offsets;
  const Id* Connectivity;

  bool Skipped(vtkIdType c) const
  {
    const unsigned char mask =
      vtkDataSetAttributes::DUPLICATECELL | vtkDataSetAttributes::HIDDENCELL;
    return this->Ghosts && (this->Ghosts[c] & mask);
  }
};

// Pass 1 over a block: counts, and the cells that go elsewhere.
template <class Id>
void CountBlock(const Cells<Id>& cells, vtkIdType begin, vtkIdType end, Block& block)
{
  for (vtkIdType c = begin; c < end; ++c)
  {
    if (cells.Skipped(c))
    {
      block.AsTheGrid = false;
      continue;
    }
    const unsigned char type = cells.Types[c];
    if (const int corners = CornersOf(type))
    {
      ++block.Cells;
      block.Corners += corners;
      block.AsTheGrid = block.AsTheGrid && type != VTK_VOXEL &&
        cells.Offsets[c + 1] - cells.Offsets[c] == static_cast<Id>(corners);
      continue;
    }
    block.AsTheGrid = false;
    if (type == VTK_POLYHEDRON)
    {
      block.Polyhedra = true;
    }
    else if (TriangulatedByTheFilter(type))
    {
      block.ForTheFilter.push_back(c);
    }
    else
    {
      block.Unsupported.push_back(type);
    }
  }
}

// The output arrays, filled by blocks at their own ranges.
struct Output
{
  UninitializedVector<CellShape> Shapes;
  UninitializedVector<int64_t> Offsets;
  UninitializedVector<int64_t> Connectivity;
  std::vector<float> Scalars;
  std::vector<long long> Origin;
};

// Pass 2 over a block: its cells written from output cell `cell` and corner `corner` on (their
// ids only if ids: not when the mesh borrows the grid's).
template <class Id>
void FillBlock(const Cells<Id>& cells, vtkIdType begin, vtkIdType end, bool cellData,
  const ScalarReader& value, int64_t cell, int64_t corner, bool ids, Output& out)
{
  for (vtkIdType c = begin; c < end; ++c)
  {
    const int corners = cells.Skipped(c) ? 0 : CornersOf(cells.Types[c]);
    if (corners == 0)
    {
      continue;
    }
    if (ids)
    {
      const Id* from = cells.Connectivity + cells.Offsets[c];
      const bool voxel = cells.Types[c] == VTK_VOXEL;
      for (int i = 0; i < corners; ++i)
      {
        out.Connectivity[corner + i] = from[voxel ? kVoxelToHexahedron[i] : i];
      }
    }
    out.Shapes[cell] = static_cast<CellShape>(corners);
    out.Origin[cell] = c;
    if (cellData)
    {
      out.Scalars[cell] = value(c);
    }
    corner += corners;
    ++cell;
    if (ids)
    {
      out.Offsets[cell] = corner;
    }
  }
}

// A grid's 64-bit offsets and connectivity lent to a mesh: held, and compared with what they were
// when lent (where their values are, how many, their modification times) before each use.
class LentGridCells : public CellMesh::CellsOwner
{
public:
  LentGridCells(vtkTypeInt64Array* offsets, vtkTypeInt64Array* connectivity)
    : Offsets(offsets)
    , Connectivity(connectivity)
    , OffsetsData(offsets->GetPointer(0))
    , ConnectivityData(connectivity->GetPointer(0))
    , OffsetsCount(offsets->GetNumberOfValues())
    , ConnectivityCount(connectivity->GetNumberOfValues())
    , OffsetsTime(offsets->GetMTime())
    , ConnectivityTime(connectivity->GetMTime())
  {
  }
  bool Intact() const override
  {
    return this->Offsets->GetPointer(0) == this->OffsetsData &&
      this->Connectivity->GetPointer(0) == this->ConnectivityData &&
      this->Offsets->GetNumberOfValues() == this->OffsetsCount &&
      this->Connectivity->GetNumberOfValues() == this->ConnectivityCount &&
      this->Offsets->GetMTime() == this->OffsetsTime &&
      this->Connectivity->GetMTime() == this->ConnectivityTime;
  }
  // vtkTypeInt64 and int64_t are both 64-bit two's complement integers (long long and long
  // here), read only.
  const int64_t* OffsetIds() const { return reinterpret_cast<const int64_t*>(this->OffsetsData); }
  const int64_t* CornerIds() const
  {
    return reinterpret_cast<const int64_t*>(this->ConnectivityData);
  }

private:
  vtkSmartPointer<vtkTypeInt64Array> Offsets;
  vtkSmartPointer<vtkTypeInt64Array> Connectivity;
  const vtkTypeInt64* OffsetsData;
  const vtkTypeInt64* ConnectivityData;
  vtkIdType OffsetsCount;
  vtkIdType ConnectivityCount;
  vtkMTimeType OffsetsTime;
  vtkMTimeType ConnectivityTime;
};
static_assert(sizeof(vtkTypeInt64) == sizeof(int64_t), "the lent ids are read as int64_t");

// lender: the grid's cell arrays, to be lent to the mesh if it takes every cell as it is (null:
// the ids are copied).
template <class Id>
bool Convert(const Cells<Id>& cells, vtkIdType numCells, bool cellData, const ScalarReader& value,
  CellMesh& mesh, InputReport& report, std::vector<long long>& origin,
  std::vector<vtkIdType>& forTheFilter, std::shared_ptr<const LentGridCells> lender)
{
  const int64_t blocks = (numCells + kBlock - 1) / kBlock;
  std::vector<Block> counts(static_cast<size_t>(blocks));
  auto range = [numCells](int64_t b) { return std::min<int64_t>(numCells, (b + 1) * kBlock); };
  ParallelFor(0, blocks, 1,
    [&](int64_t first, int64_t last)
    {
      for (int64_t b = first; b < last; ++b)
      {
        CountBlock(cells, b * kBlock, range(b), counts[b]);
      }
    });
  std::vector<int64_t> cellStart(blocks + 1, 0);
  std::vector<int64_t> cornerStart(blocks + 1, 0);
  bool asTheGrid = lender != nullptr && numCells > 0;
  for (int64_t b = 0; b < blocks; ++b)
  {
    if (counts[b].Polyhedra)
    {
      return false;
    }
    asTheGrid = asTheGrid && counts[b].AsTheGrid;
    cellStart[b + 1] = cellStart[b] + counts[b].Cells;
    cornerStart[b + 1] = cornerStart[b] + counts[b].Corners;
  }
  // Borrowing the grid's ids spares writing as many (17 MB on the wind data), memory a first
  // frame would touch afresh, and their copy.
  const bool ids = !asTheGrid;
  Output out;
  out.Shapes.resize(cellStart[blocks]);
  if (ids)
  {
    out.Offsets.resize(cellStart[blocks] + 1);
    out.Offsets[0] = 0;
    out.Connectivity.resize(cornerStart[blocks]);
  }
  out.Origin.resize(cellStart[blocks]);
  out.Scalars.resize(cellData ? cellStart[blocks] : 0);
  // Scalars read through vtkDataArray are read by one thread.
  ParallelFor(cellData && !value.IsDirect() ? 1 : 0, blocks, 1,
    [&](int64_t first, int64_t last)
    {
      for (int64_t b = first; b < last; ++b)
      {
        FillBlock(
          cells, b * kBlock, range(b), cellData, value, cellStart[b], cornerStart[b], ids, out);
      }
    });
  for (const Block& block : counts)
  {
    forTheFilter.insert(forTheFilter.end(), block.ForTheFilter.begin(), block.ForTheFilter.end());
    for (unsigned char type : block.Unsupported)
    {
      report.AddUnsupported(type);
    }
  }
  if (ids)
  {
    mesh.SetCells(std::move(out.Shapes), std::move(out.Offsets), std::move(out.Connectivity));
  }
  else
  {
    const int64_t* offsets = lender->OffsetIds();
    const int64_t* corners = lender->CornerIds();
    mesh.SetCells(std::move(out.Shapes), offsets, corners, std::move(lender));
  }
  mesh.CellScalars = std::move(out.Scalars);
  origin = std::move(out.Origin);
  return true;
}
}

//------------------------------------------------------------------------------
void CopyPointsAndScalars(
  vtkUnstructuredGridBase* input, const ScalarReader& value, bool cellData, CellMesh& mesh)
{
  const vtkIdType numPoints = input->GetNumberOfPoints();
  mesh.Points.resize(numPoints);
  vtkPoints* points = input->GetPoints();
  vtkDataArray* data = points ? points->GetData() : nullptr;
  auto* floats = vtkFloatArray::FastDownCast(data);
  auto* doubles = vtkDoubleArray::FastDownCast(data);
  const bool direct = (floats || doubles) && data->GetNumberOfComponents() == 3;
  ParallelFor(direct ? 0 : 1, numPoints, 16384,
    [&](int64_t first, int64_t last)
    {
      for (int64_t p = first; p < last; ++p)
      {
        auto& x = mesh.Points[p];
        if (floats && direct)
        {
          const float* f = floats->GetPointer(3 * p);
          x = { f[0], f[1], f[2] };
        }
        else if (direct)
        {
          const double* d = doubles->GetPointer(3 * p);
          x = { d[0], d[1], d[2] };
        }
        else
        {
          input->GetPoint(p, x.data());
        }
      }
    });
  if (cellData)
  {
    return;
  }
  mesh.PointScalars.resize(numPoints);
  ParallelFor(value.IsDirect() ? 0 : 1, numPoints, 16384,
    [&](int64_t first, int64_t last)
    {
      for (int64_t p = first; p < last; ++p)
      {
        mesh.PointScalars[p] = value(p);
      }
    });
}

//------------------------------------------------------------------------------
bool ConvertGridCells(vtkUnstructuredGrid* grid, bool cellData, const ScalarReader& value,
  CellMesh& mesh, InputReport& report, std::vector<long long>& origin,
  std::vector<vtkIdType>& forTheFilter)
{
  vtkCellArray* cellArray = grid->GetCells();
  vtkUnsignedCharArray* types = grid->GetCellTypesArray();
  const vtkIdType numCells = grid->GetNumberOfCells();
  if (!cellArray || !types || types->GetNumberOfValues() != numCells ||
    cellArray->GetNumberOfCells() != numCells)
  {
    return false;
  }
  vtkUnsignedCharArray* ghosts = grid->GetCellGhostArray();
  const unsigned char* ghostFlags = ghosts ? ghosts->GetPointer(0) : nullptr;
  if (cellArray->IsStorage64Bit())
  {
    vtkTypeInt64Array* offsets = cellArray->GetOffsetsArray64();
    vtkTypeInt64Array* connectivity = cellArray->GetConnectivityArray64();
    const Cells<vtkTypeInt64> cells{ types->GetPointer(0), ghostFlags, offsets->GetPointer(0),
      connectivity->GetPointer(0) };
    return Convert(cells, numCells, cellData, value, mesh, report, origin, forTheFilter,
      std::make_shared<const LentGridCells>(offsets, connectivity));
  }
  const Cells<vtkTypeInt32> cells{ types->GetPointer(0), ghostFlags,
    cellArray->GetOffsetsArray32()->GetPointer(0),
    cellArray->GetConnectivityArray32()->GetPointer(0) };
  return Convert(cells, numCells, cellData, value, mesh, report, origin, forTheFilter, nullptr);
}

}
