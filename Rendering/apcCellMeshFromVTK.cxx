// SPDX-License-Identifier: BSD-3-Clause
#include "apcCellMeshFromVTK.h"

#include "apcCellMesh.h"
#include "apcCellShapeCheck.h"
#include "apcGridCells.h"
#include "apcInputReport.h"
#include "apcParallel.h"
#include "apcScalarReader.h"

#include "vtkCellData.h"
#include "vtkCellType.h"
#include "vtkDataArray.h"
#include "vtkDataSetAttributes.h"
#include "vtkDataSetTriangleFilter.h"
#include "vtkGenericCell.h"
#include "vtkIdList.h"
#include "vtkIdTypeArray.h"
#include "vtkNew.h"
#include "vtkPoints.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"
#include "vtkUnstructuredGridBase.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace apc
{
namespace
{
bool ShapeOf(int vtkType, CellShape& shape)
{
  switch (vtkType)
  {
    case VTK_TETRA:
      shape = CellShape::Tetra;
      return true;
    case VTK_PYRAMID:
      shape = CellShape::Pyramid;
      return true;
    case VTK_WEDGE:
      shape = CellShape::Wedge;
      return true;
    case VTK_HEXAHEDRON:
    case VTK_VOXEL:
      shape = CellShape::Hexahedron;
      return true;
    default:
      return false;
  }
}

// Appends the tetrahedra of one decomposed cell (4 point ids each), leaving out the flat ones
// a triangulation makes of coplanar points: they hold no volume. Returns how many it added.
int AddTetrahedra(
  CellMesh& mesh, const vtkIdType* ids, vtkIdType count, bool cellData, float cellScalar)
{
  int added = 0;
  for (vtkIdType t = 0; t + 3 < count; t += 4)
  {
    int64_t corners[4];
    std::array<std::array<double, 3>, 8> x{};
    bool finite = true;
    for (int i = 0; i < 4; ++i)
    {
      corners[i] = ids[t + i];
      x[i] = mesh.Points[corners[i]];
      finite = finite && std::isfinite(x[i][0] + x[i][1] + x[i][2]);
    }
    // Non-finite corners go in: CellMesh::Finalize skips and counts them.
    if (finite && IsFlat(CellShape::Tetra, x))
    {
      continue;
    }
    mesh.AddCell(CellShape::Tetra, corners);
    if (cellData)
    {
      mesh.CellScalars.push_back(cellScalar);
    }
    ++added;
  }
  return added;
}
}

namespace
{
// The cells APC takes as they are (and polyhedra, by VTK's own triangulation) into mesh, with
// each one's input cell in origin; the cells vtkDataSetTriangleFilter must cut go to
// forTheFilter. Returns the polyhedra left without a tetrahedron with volume.
int64_t ConvertCells(vtkUnstructuredGridBase* input, const ScalarSelection& scalars,
  const ScalarReader& value, CellMesh& mesh, InputReport& report, std::vector<long long>& origin,
  std::vector<vtkIdType>& forTheFilter)
{
  int64_t flatDecomposed = 0;
  vtkUnsignedCharArray* ghosts = input->GetCellGhostArray();
  const unsigned char skipMask =
    vtkDataSetAttributes::DUPLICATECELL | vtkDataSetAttributes::HIDDENCELL;
  vtkNew<vtkIdList> cellPoints;
  vtkNew<vtkGenericCell> cell;
  vtkNew<vtkPoints> tetPoints;
  const vtkIdType numCells = input->GetNumberOfCells();
  for (vtkIdType c = 0; c < numCells; ++c)
  {
    if (ghosts && (ghosts->GetValue(c) & skipMask))
    {
      continue;
    }
    const int type = input->GetCellType(c);
    CellShape shape;
    if (ShapeOf(type, shape))
    {
      input->GetCellPoints(c, cellPoints);
      const vtkIdType* ids = cellPoints->GetPointer(0);
      int64_t corners[8];
      for (int i = 0; i < NumberOfCorners(shape); ++i)
      {
        corners[i] = type == VTK_VOXEL ? ids[kVoxelToHexahedron[i]] : ids[i];
      }
      mesh.AddCell(shape, corners);
      origin.push_back(c);
      if (scalars.CellData)
      {
        mesh.CellScalars.push_back(value(c));
      }
    }
    else if (type == VTK_POLYHEDRON)
    {
      // What vtkDataSetTriangleFilter does with a polyhedron: its own triangulation (global
      // point ids, no new points).
      input->GetCell(c, cell);
      const bool triangulated = cell->Triangulate(0, cellPoints, tetPoints) != 0;
      const int added = triangulated
        ? AddTetrahedra(mesh, cellPoints->GetPointer(0), cellPoints->GetNumberOfIds(),
            scalars.CellData, scalars.CellData ? value(c) : 0.f)
        : 0;
      // A polyhedron VTK cannot cut into tetrahedra with volume has none to render.
      flatDecomposed += added == 0 ? 1 : 0;
      origin.insert(origin.end(), added, c);
    }
    else if (TriangulatedByTheFilter(type))
    {
      forTheFilter.push_back(c);
    }
    else
    {
      report.AddUnsupported(type);
    }
  }
  return flatDecomposed;
}

// The filter itself, on just the cells in forTheFilter over the input's points: the same
// tetrahedra as ParaView's Volume renders, point ids unchanged. A cell array carries each
// tetrahedron's source cell. Returns the cells left without a tetrahedron with volume.
int64_t TriangulateWithTheFilter(vtkUnstructuredGridBase* input, const ScalarSelection& scalars,
  const ScalarReader& value, const std::vector<vtkIdType>& forTheFilter, CellMesh& mesh,
  std::vector<long long>& origin)
{
  vtkNew<vtkIdList> cellPoints;
  vtkNew<vtkUnstructuredGrid> cells;
  cells->SetPoints(input->GetPoints());
  cells->AllocateEstimate(static_cast<vtkIdType>(forTheFilter.size()), 27);
  vtkNew<vtkIdTypeArray> source;
  source->SetName("APCSourceCell");
  for (vtkIdType c : forTheFilter)
  {
    input->GetCellPoints(c, cellPoints);
    cells->InsertNextCell(input->GetCellType(c), cellPoints);
    source->InsertNextValue(c);
  }
  cells->GetCellData()->AddArray(source);
  vtkNew<vtkDataSetTriangleFilter> triangulate;
  triangulate->TetrahedraOnlyOn();
  triangulate->SetInputData(cells);
  triangulate->Update();
  vtkUnstructuredGrid* tets = triangulate->GetOutput();
  auto* sourceCells = vtkIdTypeArray::SafeDownCast(tets->GetCellData()->GetArray("APCSourceCell"));
  std::vector<int> kept(forTheFilter.size(), 0);
  for (vtkIdType t = 0; sourceCells && t < tets->GetNumberOfCells(); ++t)
  {
    vtkIdType count;
    const vtkIdType* ids;
    tets->GetCellPoints(t, count, ids);
    const vtkIdType c = sourceCells->GetValue(t);
    if (tets->GetCellType(t) == VTK_TETRA && count == 4)
    {
      const auto at = std::lower_bound(forTheFilter.begin(), forTheFilter.end(), c);
      const int added =
        AddTetrahedra(mesh, ids, 4, scalars.CellData, scalars.CellData ? value(c) : 0.f);
      kept[at - forTheFilter.begin()] += added;
      origin.insert(origin.end(), added, c);
    }
  }
  return std::count(kept.begin(), kept.end(), 0);
}
}

//------------------------------------------------------------------------------
bool CellMeshFromVTK(vtkUnstructuredGridBase* input, const ScalarSelection& scalars, CellMesh& mesh,
  InputReport& report, std::string& error, std::vector<long long>* sources)
{
  std::vector<long long> unused;
  std::vector<long long>& origin = sources ? *sources : unused;
  origin.clear();
  mesh = CellMesh();
  report = InputReport();
  error.clear();
  if (!input || !scalars.Array)
  {
    error = "no input grid or no scalars";
    return false;
  }
  const ScalarReader value(scalars, report);
  CopyPointsAndScalars(input, value, scalars.CellData, mesh);

  // A plain grid without polyhedra straight from its arrays, in parallel; else cell by cell.
  std::vector<vtkIdType> forTheFilter;
  auto* grid = vtkUnstructuredGrid::SafeDownCast(input);
  int64_t flatDecomposed = 0;
  if (!grid || !ConvertGridCells(grid, scalars.CellData, value, mesh, report, origin, forTheFilter))
  {
    flatDecomposed = ConvertCells(input, scalars, value, mesh, report, origin, forTheFilter);
  }
  if (!forTheFilter.empty())
  {
    flatDecomposed += TriangulateWithTheFilter(input, scalars, value, forTheFilter, mesh, origin);
  }

  const bool usable = mesh.Finalize(&error);
  if (!usable)
  {
    error = "unusable mesh: " + error;
    return false;
  }
  report[InputReport::FlatCells] =
    static_cast<double>(mesh.GetNumberOfFlatCells() + flatDecomposed);
  report[InputReport::NonFiniteCorners] =
    static_cast<double>(mesh.GetNumberOfNonFiniteCornerCells());
  report[InputReport::NonFiniteScalars] =
    static_cast<double>(mesh.GetNumberOfNonFiniteScalarCells());
  return true;
}

//------------------------------------------------------------------------------
bool RefreshScalarsFromVTK(vtkUnstructuredGridBase* input, const ScalarSelection& scalars,
  const std::vector<long long>& sources, CellMesh& mesh, InputReport& report, std::string& error)
{
  error.clear();
  if (!input || !scalars.Array || static_cast<int64_t>(sources.size()) != mesh.GetNumberOfCells() ||
    static_cast<size_t>(input->GetNumberOfPoints()) != mesh.Points.size())
  {
    error = "the input is not the mesh's";
    return false;
  }
  const ScalarReader value(scalars, report);
  const vtkIdType tuples = scalars.Array->GetNumberOfTuples();
  if (scalars.CellData)
  {
    mesh.PointScalars.clear();
    mesh.CellScalars.resize(sources.size());
    for (size_t i = 0; i < sources.size(); ++i)
    {
      mesh.CellScalars[i] = sources[i] < tuples ? value(sources[i]) : NAN;
    }
  }
  else
  {
    mesh.CellScalars.clear();
    mesh.PointScalars.resize(mesh.Points.size());
    ParallelFor(value.IsDirect() ? 0 : 1, static_cast<int64_t>(mesh.PointScalars.size()), 16384,
      [&](int64_t first, int64_t last)
      {
        for (int64_t p = first; p < last; ++p)
        {
          mesh.PointScalars[p] = p < tuples ? value(p) : NAN;
        }
      });
  }
  if (!mesh.RefreshScalarRanges(&error))
  {
    return false;
  }
  report[InputReport::NonFiniteScalars] =
    static_cast<double>(mesh.GetNumberOfNonFiniteScalarCells());
  return true;
}

//------------------------------------------------------------------------------
bool CellMeshFromVTK(vtkUnstructuredGridBase* input, vtkDataArray* scalars, bool cellData,
  CellMesh& mesh, std::string& message)
{
  ScalarSelection selection;
  selection.Array = scalars;
  selection.CellData = cellData;
  InputReport report;
  std::string error;
  const bool usable = CellMeshFromVTK(input, selection, mesh, report, error);
  message.clear();
  for (const std::string& part : { report.Errors(), report.Warnings(), error })
  {
    if (!part.empty())
    {
      message += (message.empty() ? "" : "; ") + part;
    }
  }
  return usable;
}
}
