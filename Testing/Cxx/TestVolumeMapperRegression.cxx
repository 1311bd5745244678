// Regression images. Each baseline PNG is a rendering of the MBOIT mode, and the test holds it
// to two things: the current MBOIT render must reproduce it (up to 8-bit rounding), and the
// baseline itself must stay close to the current EXACT render (SSIM/PSNR), so a baseline
// can never quietly encode a wrong picture. APC_UPDATE_BASELINES=1 rewrites the baselines,
// only after the second check passed; look at every rewritten PNG before committing it.

#include "apcTestScenes.h"

#include "apcImageMetrics.h"
#include "vtkAPCPuzzleSource.h"
#include "vtkPNGReader.h"
#include "vtkXMLPUnstructuredGridReader.h"

#include <gtest/gtest.h>

#include <fstream>

namespace
{
using apctest::Frame;

std::vector<float> ToRGB8Floats(const std::vector<float>& rgba, int pixels)
{
  // The same conversion WritePNG applies: over white, rounded to 8 bits.
  std::vector<float> rgb(3 * pixels);
  for (int p = 0; p < pixels; ++p)
  {
    for (int c = 0; c < 3; ++c)
    {
      const double v = rgba[4 * p + c] + (1.0 - rgba[4 * p + 3]);
      rgb[3 * p + c] = std::lround(255.0 * std::min(1.0, std::max(0.0, v))) / 255.0f;
    }
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
  auto configure = [spacing](int mode)
  {
    return [mode, spacing](vtkAPCVolumeMapper* m)
    {
      m->SetMode(mode);
      m->SetSampleDistance(spacing);
    };
  };
  const Frame exact = apctest::Render(grid, configure(vtkAPCVolumeMapper::EXACT), tf, view);
  const Frame mboit = apctest::Render(grid, configure(vtkAPCVolumeMapper::MBOIT), tf, view);
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
  vtkNew<vtkAPCPuzzleSource> source;
  source->SetField(vtkAPCPuzzleSource::SPHERES);
  source->SetNumberOfPuzzlePieces(4);
  source->SetResolution(32);
  source->Update();
  apctest::TransferFunction tf;
  tf.Colours = { { 0.0, 0.0, 0.0, 0.0 }, { 0.5, 0.15, 0.3, 1.0 }, { 1.0, 1.0, 0.15, 0.1 } };
  tf.Opacities = { { 0.0, 0.0 }, { 0.2, 0.0 }, { 0.5, 0.12 }, { 0.75, 0.05 }, { 1.0, 0.95 } };
  tf.UnitDistance = 0.1;
  apctest::View view;
  view.Parallel = false;
  view.Position = { 2.2, 1.5, 2.7 };
  view.ViewAngle = 30;
  view.Width = view.Height = 128;
  CheckAgainstBaseline("spheres_mboit", source->GetOutput(), tf, view, 0.01, 0.99, 38.0);
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
