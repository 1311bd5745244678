// Regression images. Each baseline PNG is a rendering of the MBOIT mode, and the test holds it
// to two things: the current MBOIT render must reproduce it (up to 8-bit rounding), and the
// baseline itself must stay close to the current EXACT render on a 4x finer lattice
// (SSIM/PSNR), so a baseline can never quietly encode a wrong picture. APC_UPDATE_BASELINES=1
// rewrites the baselines, only after the second check passed; look at every rewritten PNG
// before committing it.

#include "apcTestImages.h"
#include "apcTestPuzzles.h"
#include "apcTestRender.h"

#include "apcImageMetrics.h"
#include "vtkAPCPuzzleSource.h"
#include "vtkPNGReader.h"
#include "vtkXMLPUnstructuredGridReader.h"

#include <gtest/gtest.h>

#include <fstream>

namespace
{
using apctest::Frame;

// What WritePNG writes, as floats in [0, 1].
std::vector<float> ToRGB8Floats(const std::vector<float>& rgba, int pixels)
{
  const std::vector<unsigned char> rgb8 = apctest::ToRGB8(rgba, pixels);
  std::vector<float> rgb(rgb8.size());
  for (size_t v = 0; v < rgb8.size(); ++v)
  {
    rgb[v] = rgb8[v] / 255.0f;
  }
  return rgb;
}

std::vector<float> ReadPNG(const std::string& path, int& width, int& height)
{
  std::ifstream exists(path);
  if (!exists)
  {
    return {};
  }
  vtkNew<vtkPNGReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  int dims[3];
  image->GetDimensions(dims);
  width = dims[0];
  height = dims[1];
  const int components = image->GetNumberOfScalarComponents();
  std::vector<float> rgb(3 * width * height);
  auto* data = static_cast<unsigned char*>(image->GetScalarPointer());
  for (int p = 0; p < width * height; ++p)
  {
    for (int c = 0; c < 3; ++c)
    {
      rgb[3 * p + c] = data[components * p + c] / 255.0f;
    }
  }
  return rgb;
}

void CheckAgainstBaseline(const std::string& name, vtkDataSet* grid,
  const apctest::TransferFunction& tf, const apctest::View& view, double spacing, double minSsim,
  double minPsnr)
{
  auto configure = [](int mode, double distance)
  {
    return [mode, distance](vtkAPCVolumeMapper* m)
    {
      m->SetMode(mode);
      m->SetSampleDistance(distance);
    };
  };
  // The ground truth: the exact ordered blend on a 4x finer lattice, so that the lattice's own
  // staircase at grazing silhouettes (which Sample End Weights removes) counts as an error.
  const Frame exact =
    apctest::Render(grid, configure(vtkAPCVolumeMapper::EXACT, spacing / 4), tf, view);
  const Frame mboit =
    apctest::Render(grid, configure(vtkAPCVolumeMapper::MBOIT, spacing), tf, view);
  const int pixels = view.Width * view.Height;
  const auto exactRGB = ToRGB8Floats(exact.RGBA, pixels);
  const auto mboitRGB = ToRGB8Floats(mboit.RGBA, pixels);

  const std::string path = std::string(APC_BASELINE_DIR) + "/" + name + ".png";
  const bool update = std::getenv("APC_UPDATE_BASELINES") != nullptr;
  int width = 0;
  int height = 0;
  std::vector<float> baseline = update ? mboitRGB : ReadPNG(path, width, height);
  if (update)
  {
    width = view.Width;
    height = view.Height;
  }
  ASSERT_FALSE(baseline.empty()) << "missing baseline " << path;
  ASSERT_EQ(width, view.Width);
  ASSERT_EQ(height, view.Height);

  // The baseline is a faithful picture: close to the ground truth rendered now.
  const auto truth =
    apc::CompareImages(baseline.data(), exactRGB.data(), width, height, 3, 1.0, 0.1);
  std::cout << name << " baseline vs exact: SSIM " << truth.Ssim << ", PSNR " << truth.Psnr
            << " dB\n";
  EXPECT_GE(truth.Ssim, minSsim);
  EXPECT_GE(truth.Psnr, minPsnr);

  // And MBOIT still renders it: at most one 8-bit step where a value sits on a rounding edge.
  const auto now =
    apc::CompareImages(mboitRGB.data(), baseline.data(), width, height, 3, 1.0, 1.5 / 255);
  std::cout << name << " MBOIT vs baseline: max |diff| " << now.MaxAbsDiff * 255 << "/255, "
            << now.PixelsOverThreshold << " pixels over 1/255\n";
  EXPECT_EQ(now.PixelsOverThreshold, 0);

  apctest::WritePNG(apctest::OutputPath(name + "_exact.png"), exact.RGBA, width, height);
  apctest::WritePNG(apctest::OutputPath(name + "_mboit.png"), mboit.RGBA, width, height);
  if (update && !::testing::Test::HasFailure())
  {
    apctest::WritePNG(path, mboit.RGBA, width, height);
    std::cout << "wrote " << path << ": look at it before committing\n";
  }
}

TEST(VolumeMapperRegression, Spheres)
{
  apctest::View view;
  view.Parallel = false;
  view.Position = { 2.2, 1.5, 2.7 };
  view.ViewAngle = 30;
  view.Width = view.Height = 128;
  CheckAgainstBaseline("spheres_mboit", apctest::PuzzleGrid(vtkAPCPuzzleSource::SPHERES, 4, 4, 32),
    apctest::SpheresTF(), view, 0.01, 0.99, 38.0);
}

TEST(VolumeMapperRegression, WindAroundBuildings)
{
  // Real data: OpenFOAM's windAroundBuildings, 8 Scotch pieces read as one grid.
  vtkNew<vtkXMLPUnstructuredGridReader> reader;
  reader->SetFileName(APC_DATA_DIR "/windAroundBuildings/wind.pvtu");
  reader->Update();
  vtkDataSet* wind = reader->GetOutputAsDataSet();
  ASSERT_EQ(wind->GetNumberOfCells(), 331699);
  wind->GetPointData()->SetActiveScalars("U_mag");
  CheckAgainstBaseline(
    "wind_mboit", wind, apctest::WindTF(), apctest::WindView(160, 120), 1.0, 0.95, 30.0);
}
}
