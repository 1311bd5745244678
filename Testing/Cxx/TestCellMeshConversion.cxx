// CellMeshFromVTK read back through VTK's own cell interface: a plain vtkUnstructuredGrid is
// converted straight from its arrays, in parallel blocks; every mesh cell must be the input
// cell its source names (corners in VTK's order, a voxel reordered), in input order, with the
// input's points and scalars, whatever the id width of the cell array, the point type, the
// scalar kind (point or cell, one component or the magnitude or one component of three) and
// the ghost flags. Enough cells for several blocks, and every kind of cell the path meets.

#include "apcCellMesh.h"
#include "apcCellMeshFromVTK.h"
#include "apcFrameEngine.h"
#include "apcInputReport.h"
#include "apcTestGrids.h"

#include "vtkAPCVolumeMapper.h"
#include "vtkTypeInt64Array.h"

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
#include <cstring>
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

namespace
{
// Everything a mesh holds of its cells after Finalize, compared bit for bit.
void ExpectSameMesh(const apc::CellMesh& a, const apc::CellMesh& b)
{
  ASSERT_EQ(a.GetNumberOfCells(), b.GetNumberOfCells());
  for (int64_t c = 0; c < a.GetNumberOfCells(); ++c)
  {
    ASSERT_EQ(a.GetShape(c), b.GetShape(c)) << "cell " << c;
    for (int k = 0; k < apc::NumberOfCorners(a.GetShape(c)); ++k)
    {
      ASSERT_EQ(a.GetCellPoints(c)[k], b.GetCellPoints(c)[k]) << "cell " << c;
    }
    int na = 0;
    int nb = 0;
    const apc::FacePlane* pa = a.GetPlanes(c, na);
    const apc::FacePlane* pb = b.GetPlanes(c, nb);
    ASSERT_EQ(na, nb) << "cell " << c;
    for (int f = 0; f < na; ++f)
    {
      ASSERT_EQ(0, std::memcmp(pa[f].Normal.data(), pb[f].Normal.data(), sizeof(pa[f].Normal)));
      ASSERT_EQ(0, std::memcmp(&pa[f].Offset, &pb[f].Offset, sizeof(double)));
    }
    ASSERT_EQ(a.GetScalarRange(c), b.GetScalarRange(c)) << "cell " << c;
  }
}
}

TEST(CellMeshConversion, APlainGridLendsItsCellsAndTheMeshIsTheCopiedOne)
{
  auto grid = apctest::MixedBlock(12, [](double x, double y, double z) { return x - y * z; });
  apc::ScalarSelection selection;
  selection.Array = grid->GetPointData()->GetScalars();
  apc::InputReport report;
  std::string error;
  grid->GetCells()->ConvertTo64BitStorage();
  apc::CellMesh lent;
  ASSERT_TRUE(apc::CellMeshFromVTK(grid, selection, lent, report, error)) << error;
  ASSERT_TRUE(lent.BorrowsCells());
  EXPECT_TRUE(lent.CellsIntact());
  EXPECT_EQ(lent.GetCellPoints(0),
    reinterpret_cast<const int64_t*>(grid->GetCells()->GetConnectivityArray64()->GetPointer(0)));
  auto copy32 = vtkSmartPointer<vtkUnstructuredGrid>::New();
  copy32->DeepCopy(grid);
  ASSERT_TRUE(copy32->GetCells()->ConvertTo32BitStorage());
  apc::CellMesh copied;
  ASSERT_TRUE(apc::CellMeshFromVTK(copy32, selection, copied, report, error)) << error;
  ASSERT_FALSE(copied.BorrowsCells());
  ExpectSameMesh(lent, copied);
  lent.FindBoundaryPlanes();
  copied.FindBoundaryPlanes();
  for (int64_t c = 0; c < lent.GetNumberOfCells(); ++c)
  {
    ASSERT_EQ(lent.GetBoundaryPlanes(c), copied.GetBoundaryPlanes(c)) << "cell " << c;
  }

  // A copy of a lent mesh reads the same arrays; one that then takes a cell of its own holds
  // its own copy of them, the lent mesh unchanged.
  apc::CellMesh grown = lent;
  EXPECT_TRUE(grown.BorrowsCells());
  ExpectSameMesh(grown, lent);
  const int64_t extra[4] = { 0, 1, 2, 3 };
  grown.AddCell(apc::CellShape::Tetra, extra);
  EXPECT_FALSE(grown.BorrowsCells());
  ASSERT_EQ(grown.GetNumberOfCells(), lent.GetNumberOfCells() + 1);
  for (int64_t c = 0; c < lent.GetNumberOfCells(); ++c)
  {
    for (int k = 0; k < apc::NumberOfCorners(lent.GetShape(c)); ++k)
    {
      ASSERT_EQ(grown.GetCellPoints(c)[k], lent.GetCellPoints(c)[k]) << "cell " << c;
    }
  }
  EXPECT_EQ(std::vector<int64_t>(grown.GetCellPoints(lent.GetNumberOfCells()),
              grown.GetCellPoints(lent.GetNumberOfCells()) + 4),
    std::vector<int64_t>(extra, extra + 4));

  // The grid gone, the lent arrays stay as long as the mesh needs them.
  apc::CellMesh moved = std::move(lent);
  grid = nullptr;
  EXPECT_TRUE(moved.CellsIntact());
  ExpectSameMesh(moved, copied);

  // Reallocated (the same values elsewhere) or modified: no longer intact.
  auto other = apctest::MixedBlock(4, [](double x, double, double) { return x; });
  other->GetCells()->ConvertTo64BitStorage();
  selection.Array = other->GetPointData()->GetScalars();
  apc::CellMesh mesh;
  ASSERT_TRUE(apc::CellMeshFromVTK(other, selection, mesh, report, error)) << error;
  ASSERT_TRUE(mesh.BorrowsCells());
  vtkTypeInt64Array* connectivity = other->GetCells()->GetConnectivityArray64();
  connectivity->Modified();
  EXPECT_FALSE(mesh.CellsIntact());
  ASSERT_TRUE(apc::CellMeshFromVTK(other, selection, mesh, report, error)) << error;
  EXPECT_TRUE(mesh.CellsIntact());
  const vtkIdType values = connectivity->GetNumberOfValues();
  connectivity->Resize(4 * values);
  connectivity->SetNumberOfValues(values);
  EXPECT_FALSE(mesh.CellsIntact());
}

TEST(CellMeshConversion, TheEngineConvertsAgainOnceTheLentCellsMoved)
{
  auto grid = apctest::MixedBlock(4, [](double x, double, double) { return x; });
  grid->GetCells()->ConvertTo64BitStorage();
  vtkNew<vtkAPCVolumeMapper> mapper;
  mapper->SetInputData(grid);
  apc::FrameEngine engine;
  auto update = [&]
  {
    engine.BeginFrame(mapper->GetVolumeSettings());
    EXPECT_TRUE(engine.UpdateInput(mapper->GetInput(), mapper));
    return engine.GetNumberOfMeshConversions();
  };
  EXPECT_EQ(update(), 1);
  EXPECT_TRUE(engine.GetMeshForSharing().BorrowsCells());
  EXPECT_EQ(update(), 1);
  // The same values in a new block of memory: the mesh must not read the old one.
  vtkTypeInt64Array* connectivity = grid->GetCells()->GetConnectivityArray64();
  const vtkIdType values = connectivity->GetNumberOfValues();
  const void* before = connectivity->GetPointer(0);
  connectivity->Resize(4 * values);
  connectivity->SetNumberOfValues(values);
  ASSERT_NE(before, static_cast<const void*>(connectivity->GetPointer(0)));
  EXPECT_EQ(update(), 2);
  EXPECT_TRUE(engine.GetMeshForSharing().CellsIntact());
  EXPECT_EQ(update(), 2);
}
