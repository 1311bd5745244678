// Where the mesh sits must not change the picture: the wind data and the camera moved 1e7
// away along x, y and z (points in double, so the moved mesh is the same mesh) render the
// unmoved picture, in both modes. The face planes' offsets are what this holds: a plane whose
// offset belongs to another normal than the stored one misses its face by the normal's
// rounding times the distance from the origin (a tenth of a metre at 1e7), and then rays
// enter and leave the cells at the wrong depths (2/3 of the pixels off, by up to 0.28).
#include "apcTestImages.h"
#include "apcTestRender.h"

#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkUnstructuredGrid.h"
#include "vtkXMLPUnstructuredGridReader.h"

#include <gtest/gtest.h>

#include <iostream>

namespace
{
// The grid with every point moved by offset along x, y and z, in double.
vtkSmartPointer<vtkUnstructuredGrid> Moved(vtkUnstructuredGrid* grid, double offset)
{
  auto moved = vtkSmartPointer<vtkUnstructuredGrid>::New();
  moved->ShallowCopy(grid);
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(grid->GetNumberOfPoints());
  for (vtkIdType p = 0; p < grid->GetNumberOfPoints(); ++p)
  {
    double x[3];
    grid->GetPoint(p, x);
    points->SetPoint(p, x[0] + offset, x[1] + offset, x[2] + offset);
  }
  moved->SetPoints(points);
  return moved;
}
}

TEST(VolumeMapperFarAway, WindMovedAwayRendersTheSamePicture)
{
  vtkNew<vtkXMLPUnstructuredGridReader> reader;
  reader->SetFileName(APC_DATA_DIR "/windAroundBuildings/wind.pvtu");
  reader->Update();
  auto* wind = vtkUnstructuredGrid::SafeDownCast(reader->GetOutputAsDataSet());
  ASSERT_NE(wind, nullptr);
  wind->GetPointData()->SetActiveScalars("U_mag");
  const double offset = 1e7;
  auto far = Moved(wind, offset);
  for (int mode : { vtkAPCVolumeMapper::MBOIT, vtkAPCVolumeMapper::EXACT })
  {
    auto configure = [mode](vtkAPCVolumeMapper* m)
    {
      m->SetMode(mode);
      m->SetSampleDistance(2.0);
    };
    apctest::View view = apctest::WindView(160, 120);
    const auto here = apctest::Render(wind, configure, apctest::WindTF(), view);
    for (int d = 0; d < 3; ++d)
    {
      view.Position[d] += offset;
      view.FocalPoint[d] += offset;
    }
    const auto there = apctest::Render(far, configure, apctest::WindTF(), view);
    const double diff = apctest::MaxAbsDiff(here.RGBA, there.RGBA);
    const char* name = mode == vtkAPCVolumeMapper::EXACT ? "EXACT" : "MBOIT";
    std::cout << name << ": max |moved 1e7 - unmoved| = " << diff << " (max alpha "
              << apctest::MaxChannel(here.RGBA, 4, 3) << ")\n";
    EXPECT_GT(apctest::MaxChannel(here.RGBA, 4, 3), 0.5) << name;
    // Float rounding of the images and the moments' sums: ~1e-7 measured.
    EXPECT_LE(diff, 1e-5) << name;
  }
}
