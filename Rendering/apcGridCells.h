// SPDX-License-Identifier: BSD-3-Clause
// The fast path of CellMeshFromVTK (apcCellMeshFromVTK.h) for a plain vtkUnstructuredGrid:
// its points, scalars and cells read straight from the grid's arrays (cell types, ghost
// flags, vtkCellArray's offsets and connectivity), in parallel over fixed blocks of cells
// joined in cell order, so the mesh is exactly the one the cell-by-cell path makes.
#ifndef apcGridCells_h
#define apcGridCells_h

#include <cstdint>
#include <vector>

#include "vtkType.h"

class vtkUnstructuredGrid;
class vtkUnstructuredGridBase;

namespace apc
{
class CellMesh;
class ScalarReader;
struct InputReport;

// True for the 3D cell types vtkDataSetTriangleFilter cuts into tetrahedra (quadratic cells,
// pentagonal and hexagonal prisms): both conversion paths hand them to the filter.
bool TriangulatedByTheFilter(int vtkType);

// Fills mesh.Points and, for point scalars, mesh.PointScalars (parallel where the arrays can be
// read from any thread).
void CopyPointsAndScalars(
  vtkUnstructuredGridBase* input, const ScalarReader& value, bool cellData, CellMesh& mesh);

/**
 * The cells APC takes as they are into mesh (SetCells), with their scalars if cellData and
 * each one's input cell in origin; the cells vtkDataSetTriangleFilter must cut go to
 * forTheFilter (ascending), other types to the report. Returns false, having changed nothing,
 * if grid holds polyhedra (they take the cell-by-cell path). A grid whose cells are all taken
 * as they are (no ghosts left out, no voxels, nothing cut or skipped) in 64-bit cell arrays
 * lends the mesh those arrays instead of a copy (CellMesh::SetCells with an owner, which
 * holds them and tells whether they were reallocated or modified since: CellsIntact).
 */
bool ConvertGridCells(vtkUnstructuredGrid* grid, bool cellData, const ScalarReader& value,
  CellMesh& mesh, InputReport& report, std::vector<long long>& origin,
  std::vector<vtkIdType>& forTheFilter);

}

#endif
