// CellMeshFromVTK read back through VTK's own cell interface: a plain vtkUnstructuredGrid is
// converted straight from its arrays, in parallel blocks; every mesh cell must be the input
// cell its source names (corners in VTK's order, a voxel reordered), in input order, with the
// input's points and scalars, whatever the id width of the cell array, the point type, the
// scalar kind (point or cell, one component or the magnitude or one component of three) and
// the ghost flags. Enough cells for several blocks, and every kind of cell the path meets.

#include "apcCellMesh.h"
#include "apcCellMeshFromVTK.h"
#include "apcInputReport.h"
#include "apcTestGrids.h"

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkDataSetAttributes.h"
#include "vtkDoubleArray.h"
#include "vtkFloatArray.h"
#include "vtkIdList.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace
{
// A mixed block (hexahedra, wedges, tetrahedra, pyramids) of 40^3 lattice cells, then voxels,
// triangles (not rendered), quadratic tetrahedra (cut by VTK's filter), a 3-component point
// array "v", a 2-component cell array "w", and every 11th cell a duplicate or hidden ghost.
vtkSmartPointer<vtkUnstructuredGrid> Grid(int pointType)
{
  auto mixed = apctest::MixedBlock(40, [](double x, double y, double z) { return x - y * z; });
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  vtkNew<vtkPoints> points;
  points->SetDataType(pointType);
  points->DeepCopy(mixed->GetPoints());
  grid->SetPoints(points);
  grid->Allocate(mixed->GetNumberOfCells() + 300);
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < mixed->GetNumberOfCells(); ++c)
  {
    mixed->GetCellPoints(c, ids);
    grid->InsertNextCell(mixed->GetCellType(c), ids);
    if (c % 500 == 7)
    {
      // A voxel over the first lattice cube (41 points a side), in the voxel's corner order.
      const vtkIdType v[8] = { 0, 1, 41, 42, 1681, 1682, 1722, 1723 };
      grid->InsertNextCell(VTK_VOXEL, 8, v);
      grid->InsertNextCell(VTK_TRIANGLE, 3, v);
      // Corners at lattice (0,0,0) (2,0,0) (0,2,0) (0,0,2), then the edges' midpoints.
      const vtkIdType q[10] = { 0, 2, 82, 3362, 1, 42, 41, 1681, 1682, 1722 };
      grid->InsertNextCell(VTK_QUADRATIC_TETRA, 10, q);
    }
  }
  vtkNew<vtkDoubleArray> v;
  v->SetName("v");
  v->SetNumberOfComponents(3);
  for (vtkIdType p = 0; p < grid->GetNumberOfPoints(); ++p)
  {
    const double* x = grid->GetPoint(p);
    v->InsertNextTuple3(x[0] * x[1], std::sin(3 * x[2]), 0.1 * p);
  }
  grid->GetPointData()->AddArray(v);
  vtkNew<vtkFloatArray> w;
  w->SetName("w");
  w->SetNumberOfComponents(2);
  vtkNew<vtkUnsignedCharArray> ghosts;
  ghosts->SetName(vtkDataSetAttributes::GhostArrayName());
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    w->InsertNextTuple2(0.001 * c, -0.5 * (c % 13));
    ghosts->InsertNextValue(c % 11 == 3 ? vtkDataSetAttributes::DUPLICATECELL
        : c % 11 == 5                   ? vtkDataSetAttributes::HIDDENCELL
        : c % 11 == 8                   ? vtkDataSetAttributes::DUPLICATEPOINT // drawn
                                        : 0);
  }
  grid->GetCellData()->AddArray(w);
  grid->GetCellData()->AddArray(ghosts);
  return grid;
}

bool Linear(int type)
{
  return type == VTK_TETRA || type == VTK_PYRAMID || type == VTK_WEDGE || type == VTK_HEXAHEDRON ||
    type == VTK_VOXEL;
}

// The value the selection asks for, computed here from the array's tuples.
float Expected(vtkDataArray* array, vtkIdType tuple, int component)
{
  if (component >= 0)
  {
    return static_cast<float>(array->GetComponent(tuple, component));
  }
  double sum = 0;
  for (int c = 0; c < array->GetNumberOfComponents(); ++c)
  {
    sum += array->GetComponent(tuple, c) * array->GetComponent(tuple, c);
  }
  return static_cast<float>(std::sqrt(sum));
}

void Check(vtkUnstructuredGrid* grid, bool cellData, int component)
{
  SCOPED_TRACE(std::string(cellData ? "cell" : "point") + " data, component " +
    std::to_string(component) + ", " + (grid->GetCells()->IsStorage64Bit() ? "64" : "32") +
    "-bit ids, " + grid->GetPoints()->GetData()->GetClassName());
  apc::ScalarSelection selection;
  selection.CellData = cellData;
  selection.Array =
    cellData ? grid->GetCellData()->GetArray("w") : grid->GetPointData()->GetArray("v");
  selection.VectorMode =
    component >= 0 ? vtkScalarsToColors::COMPONENT : vtkScalarsToColors::MAGNITUDE;
  selection.VectorComponent = std::max(component, 0);
  apc::CellMesh mesh;
  apc::InputReport report;
  std::string error;
  std::vector<long long> sources;
  ASSERT_TRUE(apc::CellMeshFromVTK(grid, selection, mesh, report, error, &sources)) << error;
  ASSERT_EQ(static_cast<int64_t>(sources.size()), mesh.GetNumberOfCells());

  // Points as VTK gives them.
  ASSERT_EQ(static_cast<vtkIdType>(mesh.Points.size()), grid->GetNumberOfPoints());
  for (vtkIdType p = 0; p < grid->GetNumberOfPoints(); ++p)
  {
    double x[3];
    grid->GetPoint(p, x);
    ASSERT_TRUE(x[0] == mesh.Points[p][0] && x[1] == mesh.Points[p][1] && x[2] == mesh.Points[p][2])
      << "point " << p;
    if (!cellData)
    {
      ASSERT_EQ(mesh.PointScalars[p], Expected(selection.Array, p, component)) << "point " << p;
    }
  }
  // The linear cells that are not ghosts, in input order, then the filter's tetrahedra.
  const unsigned char skip = vtkDataSetAttributes::DUPLICATECELL | vtkDataSetAttributes::HIDDENCELL;
  auto* ghosts = grid->GetCellGhostArray();
  std::vector<vtkIdType> linear;
  int triangles = 0;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    const bool drawn = !(ghosts->GetValue(c) & skip);
    if (drawn && Linear(grid->GetCellType(c)))
    {
      linear.push_back(c);
    }
    triangles += drawn && grid->GetCellType(c) == VTK_TRIANGLE ? 1 : 0;
  }
  ASSERT_GT(mesh.GetNumberOfCells(), static_cast<int64_t>(linear.size()));
  vtkNew<vtkIdList> ids;
  for (size_t i = 0; i < linear.size(); ++i)
  {
    const vtkIdType c = linear[i];
    ASSERT_EQ(sources[i], c) << "mesh cell " << i;
    grid->GetCellPoints(c, ids);
    const bool voxel = grid->GetCellType(c) == VTK_VOXEL;
    ASSERT_EQ(static_cast<int>(mesh.GetShape(i)), ids->GetNumberOfIds()) << "cell " << c;
    const int64_t* corners = mesh.GetCellPoints(i);
    for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k)
    {
      ASSERT_EQ(corners[k], ids->GetId(voxel ? apc::kVoxelToHexahedron[k] : k)) << "cell " << c;
    }
    if (cellData)
    {
      ASSERT_EQ(mesh.CellScalars[i], Expected(selection.Array, c, component)) << "cell " << c;
    }
  }
  for (size_t i = linear.size(); i < sources.size(); ++i)
  {
    ASSERT_EQ(grid->GetCellType(sources[i]), VTK_QUADRATIC_TETRA);
    ASSERT_EQ(mesh.GetShape(i), apc::CellShape::Tetra);
  }
  EXPECT_EQ(report.Counts[apc::InputReport::CountKinds + VTK_TRIANGLE], triangles);
}
}

TEST(CellMeshConversion, EveryCellAsVTKGivesIt)
{
  for (int pointType : { VTK_FLOAT, VTK_DOUBLE })
  {
    auto grid = Grid(pointType);
    ASSERT_GT(grid->GetNumberOfCells(), 3 * 16384); // several blocks
    for (bool storage64 : { true, false })
    {
      if (storage64)
      {
        grid->GetCells()->ConvertTo64BitStorage();
      }
      else
      {
        ASSERT_TRUE(grid->GetCells()->ConvertTo32BitStorage());
      }
      Check(grid, false, -1);
      Check(grid, false, 1);
      Check(grid, true, -1);
      Check(grid, true, 0);
    }
  }
}
