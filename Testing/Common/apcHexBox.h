// A box of n x n x n hexahedra generated in memory, each rank building only its own slab of
// z layers, so that no rank ever holds the whole mesh: the partition tests and benchmark use it
// for meshes of millions of cells. The plane shared by two slabs is generated on both ranks from
// the same integers, so its points have bit-identical coordinates (what the partitioner matches
// facets by). Each cell carries its global id (`OriginalCell`, x fastest, then y, then z) for
// the "every cell exactly once" checks.
#ifndef apcHexBox_h
#define apcHexBox_h

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkCellType.h"
#include "vtkIdTypeArray.h"
#include "vtkNew.h"
#include "vtkPoints.h"
#include "vtkSmartPointer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

namespace apctest
{

// The z layers [first, last) of rank `rank` of `ranks`: contiguous and as equal as possible.
inline void HexBoxLayers(int n, int rank, int ranks, int& first, int& last)
{
  first = static_cast<int>(static_cast<long long>(n) * rank / ranks);
  last = static_cast<int>(static_cast<long long>(n) * (rank + 1) / ranks);
}

// This rank's slab of the unit cube cut into n^3 hexahedra.
inline vtkSmartPointer<vtkUnstructuredGrid> HexBoxSlab(int n, int rank, int ranks)
{
  int k0 = 0, k1 = 0;
  HexBoxLayers(n, rank, ranks, k0, k1);
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  vtkNew<vtkPoints> points;
  grid->SetPoints(points);
  if (k1 <= k0)
  {
    return grid;
  }
  const vtkIdType row = n + 1, plane = row * row;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(plane * (k1 - k0 + 1));
  const double h = 1.0 / n;
  vtkIdType p = 0;
  for (int k = k0; k <= k1; ++k)
  {
    for (int j = 0; j <= n; ++j)
    {
      for (int i = 0; i <= n; ++i)
      {
        points->SetPoint(p++, i * h, j * h, k * h);
      }
    }
  }
  const vtkIdType cells = static_cast<vtkIdType>(n) * n * (k1 - k0);
  vtkNew<vtkIdTypeArray> offsets, connectivity, original;
  offsets->SetNumberOfValues(cells + 1);
  connectivity->SetNumberOfValues(8 * cells);
  original->SetName("OriginalCell");
  original->SetNumberOfValues(cells);
  vtkNew<vtkUnsignedCharArray> types;
  types->SetNumberOfValues(cells);
  types->FillValue(VTK_HEXAHEDRON);
  vtkIdType c = 0;
  for (int k = k0; k < k1; ++k)
  {
    for (int j = 0; j < n; ++j)
    {
      for (int i = 0; i < n; ++i, ++c)
      {
        const vtkIdType a = (k - k0) * plane + j * row + i;
        const vtkIdType corners[8] = { a, a + 1, a + row + 1, a + row, a + plane, a + plane + 1,
          a + plane + row + 1, a + plane + row };
        for (int v = 0; v < 8; ++v)
        {
          connectivity->SetValue(8 * c + v, corners[v]);
        }
        offsets->SetValue(c, 8 * c);
        original->SetValue(c, (static_cast<vtkIdType>(k) * n + j) * n + i);
      }
    }
  }
  offsets->SetValue(cells, 8 * cells);
  vtkNew<vtkCellArray> array;
  array->SetData(offsets, connectivity);
  grid->SetCells(types, array);
  grid->GetCellData()->AddArray(original);
  return grid;
}

} // namespace apctest

#endif
