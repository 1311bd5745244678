// SPDX-License-Identifier: BSD-3-Clause
#include "apcCellFacets.h"

namespace apc
{

//------------------------------------------------------------------------------
const CellFacets* FacetsOfCellType(int vtkCellType)
{
  static const CellFacets line = { 2, { 1, 1 }, { { 0 }, { 1 } } };
  static const CellFacets triangle = { 3, { 2, 2, 2 }, { { 0, 1 }, { 1, 2 }, { 2, 0 } } };
  static const CellFacets quad = { 4, { 2, 2, 2, 2 }, { { 0, 1 }, { 1, 2 }, { 2, 3 }, { 3, 0 } } };
  static const CellFacets pixel = { 4, { 2, 2, 2, 2 }, { { 0, 1 }, { 1, 3 }, { 3, 2 }, { 2, 0 } } };
  static const CellFacets tetra = { 4, { 3, 3, 3, 3 },
    { { 0, 1, 3 }, { 1, 2, 3 }, { 2, 0, 3 }, { 0, 2, 1 } } };
  static const CellFacets pyramid = { 5, { 4, 3, 3, 3, 3 },
    { { 0, 3, 2, 1 }, { 0, 1, 4 }, { 1, 2, 4 }, { 2, 3, 4 }, { 3, 0, 4 } } };
  static const CellFacets wedge = { 5, { 3, 3, 4, 4, 4 },
    { { 0, 1, 2 }, { 3, 5, 4 }, { 0, 3, 4, 1 }, { 1, 4, 5, 2 }, { 2, 5, 3, 0 } } };
  static const CellFacets hexahedron = { 6, { 4, 4, 4, 4, 4, 4 },
    { { 0, 4, 7, 3 }, { 1, 2, 6, 5 }, { 0, 1, 5, 4 }, { 3, 7, 6, 2 }, { 0, 3, 2, 1 },
      { 4, 5, 6, 7 } } };
  // The hexahedron's faces through the voxel's corner numbering (corners 2 and 3, 6 and 7
  // swapped), so that they stay outward.
  static const CellFacets voxel = { 6, { 4, 4, 4, 4, 4, 4 },
    { { 0, 4, 6, 2 }, { 1, 3, 7, 5 }, { 0, 1, 5, 4 }, { 2, 6, 7, 3 }, { 0, 2, 3, 1 },
      { 4, 5, 7, 6 } } };
  switch (vtkCellType)
  {
    case CellType::Line:
      return &line;
    case CellType::Triangle:
      return &triangle;
    case CellType::Quad:
      return &quad;
    case CellType::Pixel:
      return &pixel;
    case CellType::Tetra:
      return &tetra;
    case CellType::Pyramid:
      return &pyramid;
    case CellType::Wedge:
      return &wedge;
    case CellType::Hexahedron:
      return &hexahedron;
    case CellType::Voxel:
      return &voxel;
    default:
      return nullptr;
  }
}

} // namespace apc
