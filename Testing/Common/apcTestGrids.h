// The meshes the tests render, built so that the right answer is known: lattice blocks of
// hexahedra or mixed cells, shuffled copies, cell subsets and splits, the puzzle source's
// output, and the core ray marcher's view of them.
#ifndef apcTestGrids_h
#define apcTestGrids_h

#include "apcCellMesh.h"
#include "apcCellMeshFromVTK.h"
#include "apcRayCamera.h"
#include "vtkCellData.h"
#include "vtkDataSetAttributes.h"
#include "vtkDataSetTriangleFilter.h"
#include "vtkExtractCells.h"
#include "vtkFloatArray.h"
#include "vtkIdList.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkSmartPointer.h"
#include "vtkUnstructuredGrid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace apctest
{

// The (n+1)^3 lattice points of [-1,1]^3, of the given VTK data type, with point scalars
// f(x, y, z) named "f"; no cells yet.
inline vtkSmartPointer<vtkUnstructuredGrid> LatticePoints(
  int n, const std::function<double(double, double, double)>& f, int pointType)
{
  vtkNew<vtkPoints> points;
  points->SetDataType(pointType);
  vtkNew<vtkFloatArray> scalars;
  scalars->SetName("f");
  for (int k = 0; k <= n; ++k)
  {
    for (int j = 0; j <= n; ++j)
    {
      for (int i = 0; i <= n; ++i)
      {
        const double x = -1 + 2.0 * i / n;
        const double y = -1 + 2.0 * j / n;
        const double z = -1 + 2.0 * k / n;
        points->InsertNextPoint(x, y, z);
        scalars->InsertNextValue(static_cast<float>(f(x, y, z)));
      }
    }
  }
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->SetPoints(points);
  grid->GetPointData()->SetScalars(scalars);
  return grid;
}

// Calls cube(i, j, k, h) for every cube of the lattice of LatticePoints(n, ...), h its 8
// corner ids in VTK's hexahedron order.
inline void ForEachLatticeCube(
  int n, const std::function<void(int, int, int, const vtkIdType*)>& cube)
{
  auto id = [n](int i, int j, int k)
  { return static_cast<vtkIdType>((k * (n + 1) + j) * (n + 1) + i); };
  for (int k = 0; k < n; ++k)
  {
    for (int j = 0; j < n; ++j)
    {
      for (int i = 0; i < n; ++i)
      {
        const vtkIdType h[8] = { id(i, j, k), id(i + 1, j, k), id(i + 1, j + 1, k), id(i, j + 1, k),
          id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1) };
        cube(i, j, k, h);
      }
    }
  }
}

// An n x n x n block of hexahedra on [-1,1]^3 with point scalars f(x, y, z).
inline vtkSmartPointer<vtkUnstructuredGrid> HexBlock(
  int n, const std::function<double(double, double, double)>& f)
{
  auto grid = LatticePoints(n, f, VTK_FLOAT);
  ForEachLatticeCube(
    n, [&](int, int, int, const vtkIdType* h) { grid->InsertNextCell(VTK_HEXAHEDRON, 8, h); });
  return grid;
}

// The same block cut into tetrahedra by VTK.
inline vtkSmartPointer<vtkUnstructuredGrid> Tetrahedralized(vtkUnstructuredGrid* grid)
{
  vtkNew<vtkDataSetTriangleFilter> tets;
  tets->SetInputData(grid);
  tets->Update();
  return tets->GetOutput();
}

// An n x n x n block on [-1,1]^3 whose lattice cells are, in turn, a hexahedron, two wedges,
// six tetrahedra (around the main diagonal) or six pyramids around an extra centre point.
// Point scalars f(x, y, z). With n a power of two every coordinate is a binary fraction, so
// the face planes of neighbouring cells of different types (a quad next to two triangles)
// come out identical and no lattice sample is counted twice or lost at those interfaces.
inline vtkSmartPointer<vtkUnstructuredGrid> MixedBlock(
  int n, const std::function<double(double, double, double)>& f)
{
  auto grid = LatticePoints(n, f, VTK_DOUBLE);
  vtkPoints* points = grid->GetPoints();
  auto* scalars = vtkFloatArray::SafeDownCast(grid->GetPointData()->GetScalars());
  ForEachLatticeCube(n,
    [&](int i, int j, int k, const vtkIdType* h)
    {
      switch ((i + 2 * j + 3 * k) % 4)
      {
        case 0:
          grid->InsertNextCell(VTK_HEXAHEDRON, 8, h);
          break;
        case 1:
        {
          // VTK's wedge: the normal of (0,1,2) points away from (3,4,5).
          const vtkIdType w0[6] = { h[0], h[2], h[1], h[4], h[6], h[5] };
          const vtkIdType w1[6] = { h[0], h[3], h[2], h[4], h[7], h[6] };
          grid->InsertNextCell(VTK_WEDGE, 6, w0);
          grid->InsertNextCell(VTK_WEDGE, 6, w1);
          break;
        }
        case 2:
        {
          const int tets[6][4] = { { 0, 1, 2, 6 }, { 0, 2, 3, 6 }, { 0, 3, 7, 6 }, { 0, 7, 4, 6 },
            { 0, 4, 5, 6 }, { 0, 5, 1, 6 } };
          for (const auto& t : tets)
          {
            const vtkIdType tet[4] = { h[t[0]], h[t[1]], h[t[2]], h[t[3]] };
            grid->InsertNextCell(VTK_TETRA, 4, tet);
          }
          break;
        }
        default:
        {
          double a[3];
          double b[3];
          points->GetPoint(h[0], a);
          points->GetPoint(h[6], b);
          const double c[3] = { 0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2]) };
          scalars->InsertNextValue(static_cast<float>(f(c[0], c[1], c[2])));
          const vtkIdType centre = points->InsertNextPoint(c);
          // Bases ordered so that their normals point at the centre (VTK's pyramid).
          const int faces[6][4] = { { 0, 1, 2, 3 }, { 4, 7, 6, 5 }, { 0, 4, 5, 1 }, { 3, 2, 6, 7 },
            { 0, 3, 7, 4 }, { 1, 5, 6, 2 } };
          for (const auto& q : faces)
          {
            const vtkIdType pyramid[5] = { h[q[0]], h[q[1]], h[q[2]], h[q[3]], centre };
            grid->InsertNextCell(VTK_PYRAMID, 5, pyramid);
          }
        }
      }
    });
  return grid;
}

// A copy of grid with the cells in random order and the points renumbered at random (same
// coordinates, scalars and cell data; each cell keeps its corner order).
inline vtkSmartPointer<vtkUnstructuredGrid> Shuffled(vtkUnstructuredGrid* grid, unsigned seed)
{
  std::mt19937 random(seed);
  const vtkIdType numPoints = grid->GetNumberOfPoints();
  const vtkIdType numCells = grid->GetNumberOfCells();
  std::vector<vtkIdType> newId(numPoints);
  std::iota(newId.begin(), newId.end(), 0);
  std::shuffle(newId.begin(), newId.end(), random);
  std::vector<vtkIdType> cellOrder(numCells);
  std::iota(cellOrder.begin(), cellOrder.end(), 0);
  std::shuffle(cellOrder.begin(), cellOrder.end(), random);

  auto out = vtkSmartPointer<vtkUnstructuredGrid>::New();
  vtkNew<vtkPoints> points;
  points->SetDataType(grid->GetPoints()->GetDataType());
  points->SetNumberOfPoints(numPoints);
  out->GetPointData()->CopyAllocate(grid->GetPointData(), numPoints);
  for (vtkIdType p = 0; p < numPoints; ++p)
  {
    points->SetPoint(newId[p], grid->GetPoint(p));
    out->GetPointData()->CopyData(grid->GetPointData(), p, newId[p]);
  }
  out->SetPoints(points);
  out->GetCellData()->CopyAllocate(grid->GetCellData(), numCells);
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < numCells; ++c)
  {
    const vtkIdType old = cellOrder[c];
    grid->GetCellPoints(old, ids);
    for (vtkIdType i = 0; i < ids->GetNumberOfIds(); ++i)
    {
      ids->SetId(i, newId[ids->GetId(i)]);
    }
    const vtkIdType cell = out->InsertNextCell(grid->GetCellType(old), ids);
    out->GetCellData()->CopyData(grid->GetCellData(), old, cell);
  }
  return out;
}

// The cells of grid for which keep(cell) holds, in their order, on the very same points
// (shared vtkPoints and point data, so every face plane is computed from the same ids).
inline vtkSmartPointer<vtkUnstructuredGrid> CellSubset(
  vtkUnstructuredGrid* grid, const std::function<bool(vtkIdType)>& keep)
{
  auto out = vtkSmartPointer<vtkUnstructuredGrid>::New();
  out->SetPoints(grid->GetPoints());
  out->GetPointData()->ShallowCopy(grid->GetPointData());
  out->GetCellData()->CopyAllocate(grid->GetCellData());
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    if (keep(c))
    {
      grid->GetCellPoints(c, ids);
      const vtkIdType cell = out->InsertNextCell(grid->GetCellType(c), ids);
      out->GetCellData()->CopyData(grid->GetCellData(), c, cell);
    }
  }
  return out;
}

// Centre of a cell's bounding box.
inline std::array<double, 3> CellCentre(vtkUnstructuredGrid* grid, vtkIdType cell)
{
  double b[6];
  grid->GetCellBounds(cell, b);
  return { 0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]), 0.5 * (b[4] + b[5]) };
}

// A well-mixed 32-bit hash of a cell id (splitmix64's finaliser).
inline uint32_t CellHash(vtkIdType cell)
{
  uint64_t x = static_cast<uint64_t>(cell) + 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return static_cast<uint32_t>(x ^ (x >> 31));
}

// The grid cut into k pieces by cell: owner(c) in [0, k) picks cell c's piece. Each piece is
// extracted with vtkExtractCells, so it has its own, compacted point ids (as on a rank).
inline std::vector<vtkSmartPointer<vtkUnstructuredGrid>> SplitCells(
  vtkUnstructuredGrid* grid, int k, const std::function<int(vtkIdType)>& owner)
{
  std::vector<vtkNew<vtkIdList>> lists(k);
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    lists[owner(c)]->InsertNextId(c);
  }
  std::vector<vtkSmartPointer<vtkUnstructuredGrid>> pieces;
  for (int p = 0; p < k; ++p)
  {
    vtkNew<vtkExtractCells> extract;
    extract->SetInputData(grid);
    extract->SetCellList(lists[p]);
    extract->Update();
    pieces.push_back(extract->GetOutput());
  }
  return pieces;
}

// Length of a ray inside the box [-1,1]^3 (slab method), independent of the mapper.
inline double LengthInUnitBox(const std::array<double, 6>& ray, double halfSize = 1.0)
{
  double t0 = -1e300;
  double t1 = 1e300;
  for (int d = 0; d < 3; ++d)
  {
    if (std::abs(ray[3 + d]) < 1e-15)
    {
      if (std::abs(ray[d]) > halfSize)
      {
        return 0.0;
      }
      continue;
    }
    double a = (-halfSize - ray[d]) / ray[3 + d];
    double b = (halfSize - ray[d]) / ray[3 + d];
    if (a > b)
    {
      std::swap(a, b);
    }
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  return t1 > t0 ? t1 - t0 : 0.0;
}

// The ray marcher's copy of a grid with point scalars (a test failure if unusable).
inline apc::CellMesh ToMesh(vtkUnstructuredGrid* grid)
{
  apc::CellMesh mesh;
  std::string message;
  const bool ok =
    apc::CellMeshFromVTK(grid, grid->GetPointData()->GetScalars(), false, mesh, message);
  EXPECT_TRUE(ok) << message;
  EXPECT_TRUE(message.empty()) << message;
  return mesh;
}

// The core camera of ObliqueView (apcTestScenes.h), for tests that drive the ray marcher.
inline apc::RayCamera ObliqueCamera(int size)
{
  return apc::RayCamera(
    { 3.6, 2.5, 4.5 }, { 0, 0, 0 }, { 0, 1, 0 }, 35.0, false, 1.0, size, size, 0.1, 100.0);
}

} // namespace apctest

#endif
