// SPDX-License-Identifier: BSD-3-Clause
// Copies a VTK unstructured grid into the ray marcher's apc::CellMesh: the one place where
// VTK's cell types, ghost flags and scalar arrays meet the VTK-free core. Used by
// vtkAPCVolumeMapper, and by code that drives apc::VolumeRayMarcher directly (the
// distributed compositing pass, tests, benchmarks).
#ifndef apcCellMeshFromVTK_h
#define apcCellMeshFromVTK_h

#include "APCRenderingModule.h" // for export macro

#include "vtkScalarsToColors.h" // for the vector modes

#include <string>
#include <vector>

class vtkDataArray;
class vtkUnstructuredGridBase;

namespace apc
{
class CellMesh;
struct InputReport;

// Which values of which array are rendered.
struct ScalarSelection
{
  vtkDataArray* Array = nullptr;
  bool CellData = false; // a cell array of the input, or a point array
  // vtkScalarsToColors::MAGNITUDE, COMPONENT (VectorComponent, clamped to the array's
  // components, as VTK's lookup tables do) or RGBCOLORS (not supported: the magnitude, with a
  // warning in the report). Single-component arrays give their value in every mode.
  int VectorMode = vtkScalarsToColors::MAGNITUDE;
  int VectorComponent = 0;
};

/**
 * Fills mesh (replacing its contents) with the cells of input that the ray marcher renders:
 * tetrahedra, pyramids, wedges, hexahedra and voxels (reordered as hexahedra) as they are;
 * polyhedra through vtkPolyhedron::Triangulate and quadratic cells (and pentagonal and
 * hexagonal prisms) through the tetrahedra vtkDataSetTriangleFilter makes of them, which is
 * what ParaView's own Volume representation renders: their point scalars are interpolated
 * linearly over those tetrahedra. Cells flagged DUPLICATECELL or HIDDENCELL in vtkGhostType
 * are skipped. report (replaced) counts what the user should hear about: cells of other
 * types (skipped), flat cells and cells with non-finite corners (skipped), cells with
 * non-finite scalars (transparent). Returns false, with error, only if the result is
 * unusable.
 */
APCRENDERING_EXPORT bool CellMeshFromVTK(vtkUnstructuredGridBase* input,
  const ScalarSelection& scalars, CellMesh& mesh, InputReport& report, std::string& error,
  std::vector<long long>* sources = nullptr);

/**
 * A new step of the same mesh: only the scalars change. Replaces mesh's scalars with the
 * selected values of input (which must have the points and cells mesh was made from, in the
 * same order; sources is what CellMeshFromVTK gave: the input cell of every mesh cell) and
 * refreshes the per-cell scalar ranges: no cell conversion, shape check or plane again.
 * The report's scalar entries are updated. Returns false, with error, if sizes do not match.
 */
APCRENDERING_EXPORT bool RefreshScalarsFromVTK(vtkUnstructuredGridBase* input,
  const ScalarSelection& scalars, const std::vector<long long>& sources, CellMesh& mesh,
  InputReport& report, std::string& error);

/**
 * The same for the magnitude of scalars; message gets the report's errors and warnings and
 * the error, if any.
 */
APCRENDERING_EXPORT bool CellMeshFromVTK(vtkUnstructuredGridBase* input, vtkDataArray* scalars,
  bool cellData, CellMesh& mesh, std::string& message);
}

#endif
