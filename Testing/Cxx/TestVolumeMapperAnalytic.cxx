// vtkAPCVolumeMapper against closed-form answers: a homogeneous block gives
// alpha = 1 - exp(-sigma L) per pixel (L from VTK's own camera, not the mapper's), hexahedra
// and tetrahedra of the same linear field give the same image, and opaque geometry stops
// the rays where it is.

#include "apcTestGrids.h"
#include "apcTestRender.h"

#include "vtkPlaneSource.h"
#include "vtkPolyDataMapper.h"
#include "vtkProperty.h"

#include <gtest/gtest.h>

#include <cmath>

namespace
{
using apctest::Frame;

// alpha_tf = 0.2 per unit distance: sigma = -ln(0.8).
const double kSigma = -std::log(0.8);

// The lattice puts round(L / spacing) +- 1 samples on a ray of length L, so the absorbance
// is sigma L within sigma * spacing, and alpha = 1 - exp(-absorbance) within
// exp(-sigma L) * (exp(sigma * spacing) - 1).
double LatticeTolerance(double length, double spacing)
{
  return std::exp(-kSigma * length) * std::expm1(kSigma * spacing) + 1e-6;
}

void ExpectHomogeneousBlock(const Frame& frame, double* maxError)
{
  int inside = 0;
  *maxError = 0;
  for (int p = 0; p < frame.Width * frame.Height; ++p)
  {
    const double length = apctest::LengthInUnitBox(frame.Rays[p]);
    const double expected = -std::expm1(-kSigma * length);
    const double alpha = frame.RGBA[4 * p + 3];
    // Rays grazing the block's edges meet the face planes within rounding; skip them.
    const double shrunk = apctest::LengthInUnitBox(frame.Rays[p], 1.0 - 1e-3);
    const double grown = apctest::LengthInUnitBox(frame.Rays[p], 1.0 + 1e-3);
    if (std::abs(grown - shrunk) > 0.01)
    {
      continue;
    }
    inside += length > 0;
    const double error = std::abs(alpha - expected);
    *maxError = std::max(*maxError, error);
    ASSERT_LE(error, LatticeTolerance(length, frame.SampleDistance))
      << "pixel " << p << " L=" << length;
    // Constant colour (1, 0.5, 0.25), premultiplied.
    ASSERT_NEAR(frame.RGBA[4 * p + 1], 0.5 * alpha, 1e-5);
  }
  EXPECT_GT(inside, frame.Width * frame.Height / 4) << "the block must cover the view";
}

TEST(VolumeMapperAnalytic, HomogeneousHexBlockExactParallel)
{
  auto grid = apctest::HexBlock(6, [](double, double, double) { return 0.5; });
  const Frame frame = apctest::Render(grid,
    [](vtkAPCVolumeMapper* m)
    {
      m->SetMode(vtkAPCVolumeMapper::EXACT);
      m->SetSampleDistance(0.02);
    });
  double maxError;
  ExpectHomogeneousBlock(frame, &maxError);
  RecordProperty("MaxAlphaError", std::to_string(maxError));
}

TEST(VolumeMapperAnalytic, HomogeneousBlocksExactPerspective)
{
  apctest::View view;
  view.Parallel = false;
  view.Position = { 1.5, 2.0, 4.5 };
  auto hexes = apctest::HexBlock(5, [](double, double, double) { return 0.5; });
  auto tets = apctest::Tetrahedralized(hexes);
  for (vtkUnstructuredGrid* grid : { hexes.Get(), tets.Get() })
  {
    const Frame frame = apctest::Render(
      grid,
      [](vtkAPCVolumeMapper* m)
      {
        m->SetMode(vtkAPCVolumeMapper::EXACT);
        m->SetSampleDistance(0.01);
      },
      {}, view);
    double maxError;
    ExpectHomogeneousBlock(frame, &maxError);
    std::cout << grid->GetNumberOfCells()
              << " cells: max |alpha - (1 - exp(-sigma L))| = " << maxError << "\n";
  }
}

TEST(VolumeMapperAnalytic, HexAndTetBlocksOfALinearFieldAgree)
{
  // Trilinear interpolation in hexahedra and linear interpolation in tetrahedra both
  // reproduce a linear field exactly, and both meshes fill the same block, so the images
  // may differ only by rounding. On the plain lattice: with Sample End Weights = Boundary (the
  // default) a boundary cell's piece of ray with no lattice point takes a middle sample, and
  // which pieces have none depends on how the block is cut into cells (docs/sampler.md).
  auto linear = [](double x, double y, double z) { return 0.5 + (x + 2 * y - z) / 8.0; };
  auto hexes = apctest::HexBlock(4, linear);
  auto tets = apctest::Tetrahedralized(hexes);
  apctest::TransferFunction tf;
  tf.Colours = { { 0.0, 0.1, 0.2, 1.0 }, { 0.5, 0.9, 0.9, 0.2 }, { 1.0, 1.0, 0.1, 0.0 } };
  tf.Opacities = { { 0.0, 0.0 }, { 0.4, 0.05 }, { 1.0, 0.6 } };
  apctest::View view;
  view.Parallel = false;
  view.Position = { 2.0, -1.0, 4.0 };
  for (int mode : { vtkAPCVolumeMapper::EXACT, vtkAPCVolumeMapper::MBOIT })
  {
    auto configure = [mode](vtkAPCVolumeMapper* m)
    {
      m->SetMode(mode);
      m->SetSampleDistance(0.01);
      m->SetSampleEndWeights(vtkAPCVolumeMapper::END_WEIGHTS_OFF);
    };
    const Frame a = apctest::Render(hexes, configure, tf, view);
    const Frame b = apctest::Render(tets, configure, tf, view);
    double maxDiff = 0;
    double maxAlpha = 0;
    for (size_t v = 0; v < a.RGBA.size(); ++v)
    {
      maxDiff = std::max(maxDiff, static_cast<double>(std::abs(a.RGBA[v] - b.RGBA[v])));
      maxAlpha = v % 4 == 3 ? std::max(maxAlpha, static_cast<double>(a.RGBA[v])) : maxAlpha;
    }
    std::cout << "mode " << mode << ": max |hex - tet| = " << maxDiff
              << ", max alpha = " << maxAlpha << "\n";
    EXPECT_GT(maxAlpha, 0.3) << "the block must be visible";
    // Float storage of point coordinates and scalars: differences of a few ulps of 1.
    EXPECT_LE(maxDiff, 2e-5);
  }
}

TEST(VolumeMapperAnalytic, OpaquePlaneStopsTheRays)
{
  // An opaque plane at z = 0 inside the block, seen from +z: in front of it lies half the
  // block (L = 1), so alpha = 1 - exp(-sigma), over the plane's colour.
  vtkNew<vtkPlaneSource> plane;
  plane->SetOrigin(-0.5, -0.5, 0);
  plane->SetPoint1(0.5, -0.5, 0);
  plane->SetPoint2(-0.5, 0.5, 0);
  vtkNew<vtkPolyDataMapper> planeMapper;
  planeMapper->SetInputConnection(plane->GetOutputPort());
  vtkNew<vtkActor> actor;
  actor->SetMapper(planeMapper);
  actor->GetProperty()->SetColor(0, 1, 0);
  actor->GetProperty()->SetLighting(false);

  auto grid = apctest::HexBlock(4, [](double, double, double) { return 0.5; });
  apctest::View view;
  view.Width = view.Height = 48;
  const Frame frame = apctest::Render(grid,
    [](vtkAPCVolumeMapper* m)
    {
      m->SetMode(vtkAPCVolumeMapper::EXACT);
      m->SetSampleDistance(0.01);
    },
    {}, view, { actor });
  int onPlane = 0;
  for (int j = 0; j < view.Height; ++j)
  {
    for (int i = 0; i < view.Width; ++i)
    {
      const int p = j * view.Width + i;
      const auto& ray = frame.Rays[p];
      const double x = ray[0];
      const double y = ray[1];
      const bool plane = std::abs(x) < 0.45 && std::abs(y) < 0.45;
      const bool clear = std::abs(x) > 0.55 && std::abs(x) < 0.95 && std::abs(y) < 0.95;
      if (!plane && !clear)
      {
        continue; // edges of the plane or of the block
      }
      const double length = plane ? 1.0 : 2.0;
      const double expected = -std::expm1(-kSigma * length);
      ASSERT_NEAR(frame.RGBA[4 * p + 3], expected, LatticeTolerance(length, 0.01))
        << "pixel " << i << "," << j << (plane ? " over the plane" : " beside it");
      if (plane)
      {
        ++onPlane;
        // The window shows the volume blended over the green plane: green = 0.5 * alpha +
        // (1 - alpha) * 1, within 8-bit rounding.
        const double green = (0.5 * expected + (1 - expected)) * 255.0;
        ASSERT_NEAR(frame.Window[3 * p + 1], green, 2.5) << "pixel " << i << "," << j;
      }
    }
  }
  EXPECT_GT(onPlane, 100);
}
}
