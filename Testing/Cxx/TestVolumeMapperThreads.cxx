// vtkAPCVolumeMapper's threading and caching: 1, 2 and "TBB decides" threads give bitwise
// identical images (each pixel's sums are made in its tile by one task, from cells taken in
// index order, and added once to a zeroed buffer), repeated renders are identical, and the
// cached mesh follows changes of the input's points, scalars and pipeline.

#include "apcTestGrids.h"
#include "apcTestImages.h"
#include "apcTestPuzzles.h"
#include "apcTestRender.h"

#include <gtest/gtest.h>

#include <cstring>
#include <iostream>

namespace
{
using apctest::Frame;

// Number of values whose bit patterns differ (0 = bitwise identical); -1 for other sizes.
template <class T>
long BitwiseDifferences(const std::vector<T>& a, const std::vector<T>& b)
{
  if (a.size() != b.size())
  {
    return -1;
  }
  long n = 0;
  for (size_t v = 0; v < a.size(); ++v)
  {
    n += std::memcmp(&a[v], &b[v], sizeof(T)) != 0;
  }
  return n;
}

TEST(VolumeMapperThreads, ThreadCountDoesNotChangeTheImage)
{
  // 160 x 160 pixels: 100 tiles of 16 x 16, so 2 threads really share the work.
  auto grid = apctest::PuzzleGrid(vtkAPCPuzzleSource::SPHERES, 4, 4, 16);
  for (int mode : { vtkAPCVolumeMapper::MBOIT, vtkAPCVolumeMapper::EXACT })
  {
    std::vector<Frame> frames;
    for (int threads : { 1, 2, 0 })
    {
      frames.push_back(apctest::Render(
        grid,
        [mode, threads](vtkAPCVolumeMapper* m)
        {
          m->SetMode(mode);
          m->SetSampleDistance(0.01);
          m->SetNumberOfThreads(threads);
          m->SetComputeSegmentCount(true);
        },
        apctest::SpheresTF(), apctest::ObliqueView(160)));
    }
    EXPECT_GT(apctest::MaxChannel(frames[0].RGBA, 4, 3), 0.3);
    for (size_t f = 1; f < frames.size(); ++f)
    {
      const long rgba = BitwiseDifferences(frames[0].RGBA, frames[f].RGBA);
      const long moments = BitwiseDifferences(frames[0].Moments, frames[f].Moments);
      const long colour = BitwiseDifferences(frames[0].ColourSums, frames[f].ColourSums);
      const long segments = BitwiseDifferences(frames[0].SegmentCount, frames[f].SegmentCount);
      const char* name = f == 1 ? "2 threads" : "TBB's choice";
      std::cout << (mode == vtkAPCVolumeMapper::EXACT ? "EXACT" : "MBOIT") << ", " << name
                << " vs 1 thread: values differing in RGBA " << rgba << ", moments " << moments
                << ", colour sums " << colour << ", segment counts " << segments
                << " (max |RGBA diff| " << apctest::MaxAbsDiff(frames[0].RGBA, frames[f].RGBA)
                << ")\n";
      EXPECT_EQ(rgba, 0) << name;
      EXPECT_EQ(moments, 0) << name;
      EXPECT_EQ(colour, 0) << name;
      EXPECT_EQ(segments, 0) << name;
    }
  }
}

TEST(VolumeMapperThreads, RepeatedRendersAreIdentical)
{
  auto grid =
    apctest::MixedBlock(8, [](double x, double y, double z) { return 0.5 + 0.4 * x * y * z; });
  apctest::LiveWindow scene(apctest::SpheresTF(), apctest::ObliqueView(96));
  scene.Mapper->SetInputData(grid);
  scene.Mapper->SetSampleDistance(0.01);
  const Frame first = scene.Render();
  const Frame second = scene.Render();
  const Frame third = scene.Render();
  std::cout << "repeated renders: differing RGBA values "
            << BitwiseDifferences(first.RGBA, second.RGBA) << ", "
            << BitwiseDifferences(first.RGBA, third.RGBA) << "\n";
  EXPECT_GT(apctest::MaxChannel(first.RGBA, 4, 3), 0.05);
  EXPECT_EQ(BitwiseDifferences(first.RGBA, second.RGBA), 0);
  EXPECT_EQ(BitwiseDifferences(first.RGBA, third.RGBA), 0);
  EXPECT_EQ(BitwiseDifferences(first.Moments, third.Moments), 0);
}

// The mapper caches its copy of the mesh; changing the points or the scalars of the same
// grid object must give the image a fresh mapper renders (bitwise: the same mesh and view).
TEST(VolumeMapperThreads, CachedMeshFollowsDataChanges)
{
  auto field = [](double x, double y, double z) { return 0.5 + 0.4 * x * y * z; };
  auto grid = apctest::HexBlock(6, field);
  apctest::TransferFunction tf = apctest::SpheresTF();
  apctest::LiveWindow scene(tf, apctest::ObliqueView(64));
  scene.Mapper->SetInputData(grid);
  scene.Mapper->SetSampleDistance(0.01);
  const Frame before = scene.Render();

  auto fresh = [&](vtkUnstructuredGrid* g)
  {
    return apctest::Render(
      g, [](vtkAPCVolumeMapper* m) { m->SetSampleDistance(0.01); }, tf, apctest::ObliqueView(64));
  };

  // New scalar values in the same array.
  auto* scalars = vtkFloatArray::SafeDownCast(grid->GetPointData()->GetScalars());
  for (vtkIdType p = 0; p < scalars->GetNumberOfTuples(); ++p)
  {
    scalars->SetValue(p, 1.0f - scalars->GetValue(p));
  }
  scalars->Modified();
  const Frame afterScalars = scene.Render();
  const Frame expectScalars = fresh(grid);
  // Points moved (the block shrunk by half towards the origin).
  for (vtkIdType p = 0; p < grid->GetNumberOfPoints(); ++p)
  {
    double x[3];
    grid->GetPoint(p, x);
    grid->GetPoints()->SetPoint(p, 0.5 * x[0], 0.5 * x[1], 0.5 * x[2]);
  }
  grid->GetPoints()->Modified();
  const Frame afterPoints = scene.Render();
  const Frame expectPoints = fresh(grid);
  std::cout << "after new scalars: max diff to a fresh mapper "
            << apctest::MaxAbsDiff(afterScalars.RGBA, expectScalars.RGBA) << " (changed by "
            << apctest::MaxAbsDiff(before.RGBA, afterScalars.RGBA)
            << "); after moved points: " << apctest::MaxAbsDiff(afterPoints.RGBA, expectPoints.RGBA)
            << " (changed by " << apctest::MaxAbsDiff(afterScalars.RGBA, afterPoints.RGBA) << ")\n";
  EXPECT_GT(apctest::MaxAbsDiff(before.RGBA, afterScalars.RGBA), 0.01) << "the change is visible";
  EXPECT_EQ(BitwiseDifferences(afterScalars.RGBA, expectScalars.RGBA), 0);
  EXPECT_GT(apctest::MaxAbsDiff(afterScalars.RGBA, afterPoints.RGBA), 0.01) << "visible";
  EXPECT_EQ(BitwiseDifferences(afterPoints.RGBA, expectPoints.RGBA), 0);
}

// A source connected with SetInputConnection (plain VTK use, not ParaView's delivered
// data): the first render must show it, and a change of the source must show in the next.
TEST(VolumeMapperThreads, PipelineInputIsUpdated)
{
  vtkNew<vtkAPCPuzzleSource> source;
  source->SetNumberOfPuzzlePieces(2);
  source->SetSlabsPerPiece(2);
  source->SetResolution(8);
  source->SetField(vtkAPCPuzzleSource::SPHERES);
  apctest::TransferFunction tf = apctest::SpheresTF();
  apctest::LiveWindow scene(tf, apctest::ObliqueView(64));
  scene.Mapper->SetInputConnection(source->GetOutputPort());
  scene.Mapper->SetSampleDistance(0.01);
  const Frame spheres = scene.Render();
  source->SetField(vtkAPCPuzzleSource::SMOOTH);
  const Frame smooth = scene.Render();

  source->Update();
  vtkNew<vtkUnstructuredGrid> copy;
  copy->DeepCopy(source->GetOutput());
  const Frame expected = apctest::Render(
    copy, [](vtkAPCVolumeMapper* m) { m->SetSampleDistance(0.01); }, tf, apctest::ObliqueView(64));
  std::cout << "pipeline input: max alpha first render " << apctest::MaxChannel(spheres.RGBA, 4, 3)
            << ", after changing the field max diff to a fresh render "
            << apctest::MaxAbsDiff(smooth.RGBA, expected.RGBA) << "\n";
  EXPECT_GT(apctest::MaxChannel(spheres.RGBA, 4, 3), 0.1) << "the first render shows the source";
  EXPECT_LE(apctest::MaxAbsDiff(smooth.RGBA, expected.RGBA), 1e-6)
    << "the render after the change shows the changed source";
}
}
