// A new time step of the same mesh (what a simulation hands to Catalyst every step: the same
// points and cells, new values, often in freshly copied arrays) refreshes only the scalars and
// the per-cell scalar ranges. Held to a full conversion of the same input: every cell's range,
// the scalars and the count of non-finite cells must be identical; and a moved point, other
// cells or another scalar association must convert the whole input again.

#include "apcCellMesh.h"
#include "apcCellMeshFromVTK.h"
#include "apcFrameEngine.h"
#include "apcInputReport.h"
#include "apcTestGrids.h"

#include "vtkAPCVolumeMapper.h"
#include "vtkCellData.h"
#include "vtkFloatArray.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkUnstructuredGrid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace
{
// A deep copy (new arrays, the same content) whose point array "f" and cell array "g" hold
// other values: step's field.
vtkSmartPointer<vtkUnstructuredGrid> NextStep(vtkUnstructuredGrid* grid, int step)
{
  auto next = vtkSmartPointer<vtkUnstructuredGrid>::New();
  next->DeepCopy(grid);
  vtkNew<vtkFloatArray> f;
  f->SetName("f");
  for (vtkIdType p = 0; p < next->GetNumberOfPoints(); ++p)
  {
    const double* x = next->GetPoint(p);
    f->InsertNextValue(static_cast<float>(std::sin(x[0] * step) + x[1] * x[2]));
  }
  next->GetPointData()->SetScalars(f);
  vtkNew<vtkFloatArray> g;
  g->SetName("g");
  for (vtkIdType c = 0; c < next->GetNumberOfCells(); ++c)
  {
    // One transparent (NaN) cell in seven, and the set moves with the step.
    g->InsertNextValue(
      (c + step) % 7 == 0 ? std::numeric_limits<float>::quiet_NaN() : 0.01f * (c % 97) * step);
  }
  next->GetCellData()->AddArray(g);
  return next;
}

void ExpectSameScalars(const apc::CellMesh& refreshed, const apc::CellMesh& converted)
{
  ASSERT_EQ(refreshed.GetNumberOfCells(), converted.GetNumberOfCells());
  EXPECT_EQ(
    refreshed.GetNumberOfNonFiniteScalarCells(), converted.GetNumberOfNonFiniteScalarCells());
  for (int64_t c = 0; c < converted.GetNumberOfCells(); ++c)
  {
    const auto a = refreshed.GetScalarRange(c);
    const auto b = converted.GetScalarRange(c);
    for (int i = 0; i < 2; ++i)
    {
      ASSERT_TRUE(a[i] == b[i] || (std::isnan(a[i]) && std::isnan(b[i])))
        << "cell " << c << ": " << a[i] << " vs " << b[i];
    }
  }
}

// Converts step 1, refreshes to step 2 and compares with a conversion of step 2.
void CheckRefresh(vtkUnstructuredGrid* block, bool cellData)
{
  auto first = NextStep(block, 1);
  auto second = NextStep(block, 2);
  apc::ScalarSelection selection;
  selection.CellData = cellData;
  selection.Array =
    cellData ? first->GetCellData()->GetArray("g") : first->GetPointData()->GetArray("f");
  apc::CellMesh mesh;
  apc::InputReport report;
  std::string error;
  std::vector<long long> sources;
  ASSERT_TRUE(apc::CellMeshFromVTK(first, selection, mesh, report, error, &sources)) << error;
  EXPECT_EQ(static_cast<int64_t>(sources.size()), mesh.GetNumberOfCells());
  selection.Array =
    cellData ? second->GetCellData()->GetArray("g") : second->GetPointData()->GetArray("f");
  ASSERT_TRUE(apc::RefreshScalarsFromVTK(second, selection, sources, mesh, report, error)) << error;
  apc::CellMesh converted;
  apc::InputReport convertedReport;
  ASSERT_TRUE(apc::CellMeshFromVTK(second, selection, converted, convertedReport, error)) << error;
  ExpectSameScalars(mesh, converted);
  EXPECT_EQ(report[apc::InputReport::NonFiniteScalars],
    convertedReport[apc::InputReport::NonFiniteScalars]);
}
}

TEST(ScalarRefresh, PointScalarsEqualAFullConversion)
{
  CheckRefresh(apctest::MixedBlock(4, [](double x, double, double) { return x; }), false);
}

TEST(ScalarRefresh, CellScalarsEqualAFullConversion)
{
  // Mixed linear cells, and VTK's tetrahedra of the same block.
  auto mixed = apctest::MixedBlock(4, [](double x, double, double) { return x; });
  CheckRefresh(mixed, true);
  CheckRefresh(apctest::Tetrahedralized(mixed), true);
}

TEST(ScalarRefresh, TheEngineConvertsOnlyWhenTheMeshChanges)
{
  auto block = apctest::MixedBlock(4, [](double x, double, double) { return x; });
  vtkNew<vtkAPCVolumeMapper> mapper;
  mapper->SetScalarModeToUsePointFieldData();
  mapper->SelectScalarArray("f");
  // The engine as vtkAPCCompositePass drives it: the mapper's settings, then its input.
  apc::FrameEngine engine;
  auto step = [&](vtkUnstructuredGrid* grid)
  {
    mapper->SetInputData(grid);
    engine.BeginFrame(mapper->GetVolumeSettings());
    EXPECT_TRUE(engine.UpdateInput(mapper->GetInput(), mapper));
    return std::make_pair(engine.GetNumberOfMeshConversions(), engine.GetNumberOfScalarRefreshes());
  };
  EXPECT_EQ(step(NextStep(block, 1)), std::make_pair(int64_t{ 1 }, int64_t{ 0 }));
  // New arrays, same points and cells: only the scalars.
  EXPECT_EQ(step(NextStep(block, 2)), std::make_pair(int64_t{ 1 }, int64_t{ 1 }));
  EXPECT_EQ(step(NextStep(block, 3)), std::make_pair(int64_t{ 1 }, int64_t{ 2 }));
  // One point moved: the whole conversion.
  auto moved = NextStep(block, 4);
  double x[3];
  moved->GetPoints()->GetPoint(5, x);
  x[2] += 1e-3;
  moved->GetPoints()->SetPoint(5, x);
  EXPECT_EQ(step(moved), std::make_pair(int64_t{ 2 }, int64_t{ 2 }));
  // Other cells (a subset): the whole conversion.
  EXPECT_EQ(step(apctest::CellSubset(NextStep(block, 5), [](vtkIdType c) { return c % 2 == 0; })),
    std::make_pair(int64_t{ 3 }, int64_t{ 2 }));
  // The same mesh coloured by a cell array instead: the whole conversion, then refreshes.
  mapper->SetScalarModeToUseCellFieldData();
  mapper->SelectScalarArray("g");
  EXPECT_EQ(step(NextStep(block, 6)), std::make_pair(int64_t{ 4 }, int64_t{ 2 }));
  EXPECT_EQ(step(NextStep(block, 7)), std::make_pair(int64_t{ 4 }, int64_t{ 3 }));
}
