// SPDX-License-Identifier: BSD-3-Clause
// Copies a VTK unstructured grid into the ray marcher's apc::CellMesh: the one place where
// VTK's cell types, ghost flags and scalar arrays meet the VTK-free core. Used by
// vtkAPCVolumeMapper, and by code that drives apc::VolumeRayMarcher directly (the
// distributed compositing pass, tests, benchmarks).
#ifndef apcCellMeshFromVTK_h
#define apcCellMeshFromVTK_h

#include "APCRenderingModule.h" // for export macro

#include <string>

class vtkDataArray;
class vtkUnstructuredGridBase;

namespace apc
{
class CellMesh;

/**
 * Fills mesh (replacing its contents) with the cells of input that the ray marcher renders:
 * tetrahedra, pyramids, wedges, hexahedra and voxels (reordered as hexahedra). Cells flagged
 * DUPLICATECELL or HIDDENCELL in vtkGhostType are skipped. scalars is a point array
 * (cellData false) or a cell array (cellData true) of input; multi-component arrays give
 * their magnitude. Cells of other types are skipped and named in message; returns false
 * (with message) only if the result is unusable.
 */
APCRENDERING_EXPORT bool CellMeshFromVTK(vtkUnstructuredGridBase* input, vtkDataArray* scalars,
  bool cellData, CellMesh& mesh, std::string& message);
}

#endif
