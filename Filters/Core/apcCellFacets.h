// SPDX-License-Identifier: BSD-3-Clause
// The facets of VTK's fixed-topology cell types: the faces of a 3D cell, the edges of a 2D
// cell, the end points of a line, in VTK's corner numbering. One table for every user: the
// graph partition matches cells by the point sets of their facets, the renderer's shape
// check sums its volume over the faces, and its cell mesh takes its face planes from them.
//
// The faces of a 3D cell are consistently oriented, which the volume needs: all outward for
// the tetrahedron, pyramid, hexahedron and voxel, all inward for the wedge, whose corner
// order VTK flips. The tetrahedron, pyramid, wedge and hexahedron list their faces as VTK does.
//
// VTK-free, so that it is unit-tested alone and shared by Rendering/Core and Filters/Core
// without either depending on VTK or on the other. The cell types are VTK's numbers
// (vtkCellType.h): they are part of VTK's file formats and do not change; the VTK side checks
// them at compile time.
#ifndef apcCellFacets_h
#define apcCellFacets_h

namespace apc
{

/// VTK's cell type numbers for the types with a table below.
namespace CellType
{
constexpr int Line = 3;
constexpr int Triangle = 5;
constexpr int Pixel = 8;
constexpr int Quad = 9;
constexpr int Tetra = 10;
constexpr int Voxel = 11;
constexpr int Hexahedron = 12;
constexpr int Wedge = 13;
constexpr int Pyramid = 14;
}

/// Facet f of a cell has the Size[f] corners Corner[f][0 .. Size[f]).
struct CellFacets
{
  int Count;
  int Size[6];
  int Corner[6][4];
};

/// The facets of a VTK cell type, or null for a type without a fixed table (polygons,
/// polyhedra, quadratic and higher-order cells: their facets come from the cell itself).
const CellFacets* FacetsOfCellType(int vtkCellType);

} // namespace apc

#endif
