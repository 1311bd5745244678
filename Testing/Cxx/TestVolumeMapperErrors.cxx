// Bad input gives vtkAPCVolumeMapper a clear error (or warning) and a blank or partial
// image, never a crash or a hang: no scalars, no cells, NaN scalars, unsupported cell types
// (lower-dimensional, higher-order Lagrange),
// a 1 x 1 window, the camera inside the volume, an invalid number of moments, an input that
// is not an unstructured grid, fully opaque transfer functions, NaN point coordinates.

#include "apcMomentTransmittance.h"
#include "apcTestFailures.h"
#include "apcTestGrids.h"
#include "apcTestImages.h"
#include "apcTestMessages.h"
#include "apcTestRender.h"

#include "vtkCommand.h"
#include "vtkExecutive.h"
#include "vtkTrivialProducer.h"

#include <gtest/gtest.h>

#include <csignal>
#include <cstdlib>
#include <iostream>
#include <string>
#include <unistd.h>
#include <vector>

namespace
{
using apctest::Frame;

using apctest::MessageLog;

const double kSigma = -std::log(0.8); // the default test transfer function's alpha_tf 0.2

auto Configure(int mode, MessageLog* log)
{
  return [mode, log](vtkAPCVolumeMapper* m)
  {
    log->Watch(m);
    m->SetMode(mode);
    m->SetSampleDistance(0.01);
  };
}

const char* ModeName(int mode)
{
  return mode == vtkAPCVolumeMapper::EXACT ? "EXACT" : "MBOIT";
}

// The float image is absent or all zero, and so is the window (black background).
void ExpectBlank(const Frame& frame, const std::string& what)
{
  double maxRGBA = 0;
  for (float v : frame.RGBA)
  {
    maxRGBA = std::max(maxRGBA, std::abs(static_cast<double>(v)));
  }
  int lit = 0;
  for (unsigned char v : frame.Window)
  {
    lit += v != 0;
  }
  EXPECT_EQ(maxRGBA, 0.0) << what << ": the float image must be blank";
  EXPECT_EQ(frame.Window.size(), static_cast<size_t>(3 * frame.Width * frame.Height)) << what;
  EXPECT_EQ(lit, 0) << what << ": the window must show only the background";
}

// Every value finite.
int NonFinite(const std::vector<float>& values)
{
  int bad = 0;
  for (float v : values)
  {
    bad += !std::isfinite(v);
  }
  return bad;
}

//------------------------------------------------------------------------------
TEST(VolumeMapperErrors, NoScalars)
{
  auto grid = apctest::HexBlock(4, [](double, double, double) { return 0.5; });
  // Positive control: the array selected by name renders without complaint, so the blank
  // checks below can fail.
  grid->GetPointData()->SetActiveScalars(nullptr);
  ASSERT_EQ(grid->GetPointData()->GetScalars(), nullptr);
  {
    vtkNew<MessageLog> log;
    const Frame frame = apctest::Render(grid,
      [&log](vtkAPCVolumeMapper* m)
      {
        Configure(vtkAPCVolumeMapper::MBOIT, log)(m);
        m->SetScalarModeToUsePointFieldData();
        m->SelectScalarArray("f");
      });
    EXPECT_TRUE(log->Errors.empty()) << log->All();
    EXPECT_GT(apctest::MaxChannel(frame.RGBA, 4, 3), 0.3) << "the named array must render";
  }
  grid->GetPointData()->RemoveArray("f");
  for (int mode : { vtkAPCVolumeMapper::MBOIT, vtkAPCVolumeMapper::EXACT })
  {
    vtkNew<MessageLog> log;
    const Frame frame = apctest::Render(grid, Configure(mode, log));
    std::cout << ModeName(mode) << ", no scalars: " << log->All() << "\n";
    ASSERT_FALSE(log->Errors.empty()) << "an error is expected";
    EXPECT_TRUE(MessageLog::Mentions(log->Errors, "scalars")) << log->All();
    ExpectBlank(frame, "no scalars");
  }
  // A named array that does not exist.
  {
    auto named = apctest::HexBlock(2, [](double, double, double) { return 0.5; });
    vtkNew<MessageLog> log;
    const Frame frame = apctest::Render(named,
      [&log](vtkAPCVolumeMapper* m)
      {
        Configure(vtkAPCVolumeMapper::MBOIT, log)(m);
        m->SetScalarModeToUsePointFieldData();
        m->SelectScalarArray("nonexistent");
      });
    std::cout << "missing named array: " << log->All() << "\n";
    EXPECT_TRUE(MessageLog::Mentions(log->Errors, "nonexistent")) << log->All();
    ExpectBlank(frame, "missing named array");
  }
}

TEST(VolumeMapperErrors, EmptyGrids)
{
  // No points and no cells; points but no cells. Both silent and blank.
  auto none = vtkSmartPointer<vtkUnstructuredGrid>::New();
  vtkNew<vtkFloatArray> scalars;
  scalars->SetName("f");
  none->GetPointData()->SetScalars(scalars);
  none->SetPoints(vtkNew<vtkPoints>());
  auto pointsOnly = apctest::HexBlock(2, [](double, double, double) { return 0.5; });
  pointsOnly->SetCells(VTK_HEXAHEDRON, vtkNew<vtkCellArray>());
  ASSERT_EQ(pointsOnly->GetNumberOfCells(), 0);
  for (auto* grid : { none.Get(), pointsOnly.Get() })
  {
    for (int mode : { vtkAPCVolumeMapper::MBOIT, vtkAPCVolumeMapper::EXACT })
    {
      vtkNew<MessageLog> log;
      const Frame frame = apctest::Render(grid, Configure(mode, log));
      EXPECT_TRUE(log->Errors.empty() && log->Warnings.empty()) << log->All();
      ExpectBlank(frame, std::string("empty grid, ") + ModeName(mode));
    }
  }
}

TEST(VolumeMapperErrors, NaNScalarsAreTransparent)
{
  auto full = apctest::HexBlock(6, [](double, double, double) { return 0.5; });
  auto grid = apctest::HexBlock(6, [](double, double, double) { return 0.5; });
  auto* f = vtkFloatArray::SafeDownCast(grid->GetPointData()->GetScalars());
  int nans = 0;
  for (vtkIdType p = 0; p < f->GetNumberOfTuples(); p += 29)
  {
    f->SetValue(p, std::nanf(""));
    ++nans;
  }
  for (int mode : { vtkAPCVolumeMapper::MBOIT, vtkAPCVolumeMapper::EXACT })
  {
    vtkNew<MessageLog> log;
    const Frame frame = apctest::Render(grid, Configure(mode, log));
    vtkNew<MessageLog> fullLog;
    const Frame reference = apctest::Render(full, Configure(mode, fullLog));
    EXPECT_EQ(NonFinite(frame.RGBA), 0) << ModeName(mode);
    EXPECT_EQ(NonFinite(frame.Moments), 0) << ModeName(mode);
    EXPECT_EQ(NonFinite(frame.ColourSums), 0) << ModeName(mode);
    // NaN samples are transparent: no pixel gains opacity (1e-6: float rounding), and the
    // cells with a NaN corner visibly lose theirs.
    double gained = 0;
    double lost = 0;
    for (size_t p = 3; p < frame.RGBA.size(); p += 4)
    {
      gained = std::max(gained, static_cast<double>(frame.RGBA[p] - reference.RGBA[p]));
      lost = std::max(lost, static_cast<double>(reference.RGBA[p] - frame.RGBA[p]));
    }
    std::cout << ModeName(mode) << ", " << nans << " NaN point scalars: max alpha gained " << gained
              << ", max alpha lost " << lost << ", max alpha "
              << apctest::MaxChannel(frame.RGBA, 4, 3) << "; " << log->All() << "\n";
    EXPECT_LE(gained, 1e-6) << ModeName(mode);
    EXPECT_GT(lost, 0.01) << ModeName(mode);
    EXPECT_GT(apctest::MaxChannel(frame.RGBA, 4, 3), 0.3) << ModeName(mode);
  }
  // All scalars NaN: nothing visible, nothing non-finite.
  for (vtkIdType p = 0; p < f->GetNumberOfTuples(); ++p)
  {
    f->SetValue(p, std::nanf(""));
  }
  f->Modified();
  for (int mode : { vtkAPCVolumeMapper::MBOIT, vtkAPCVolumeMapper::EXACT })
  {
    vtkNew<MessageLog> log;
    const Frame frame = apctest::Render(grid, Configure(mode, log));
    EXPECT_EQ(NonFinite(frame.RGBA), 0) << ModeName(mode);
    ExpectBlank(frame, std::string("all-NaN scalars, ") + ModeName(mode));
  }
}

TEST(VolumeMapperErrors, UnsupportedCellsAreNamedAndSkipped)
{
  auto f = [](double x, double y, double z) { return 0.5 + 0.3 * x * y + 0.2 * z; };
  auto reference = apctest::HexBlock(3, f);
  auto grid = apctest::HexBlock(3, f);
  // A triangle (no volume to render) over existing points and a second-order Lagrange
  // tetrahedron (not supported: cutting it into tetrahedra would ignore its curvature) over new
  // points (appended, so the hexahedra keep their point ids). Polyhedra and quadratic cells
  // render: TestVolumeMapperInputs.cxx.
  {
    const vtkIdType triangle[3] = { 0, 1, 5 };
    grid->InsertNextCell(VTK_TRIANGLE, 3, triangle);
    auto* points = grid->GetPoints();
    auto* s = vtkFloatArray::SafeDownCast(grid->GetPointData()->GetScalars());
    const double corners[4][3] = { { -0.5, -0.5, -0.5 }, { 0.5, -0.5, -0.5 }, { 0, 0.5, -0.5 },
      { 0, 0, 0.5 } };
    const int edges[6][2] = { { 0, 1 }, { 1, 2 }, { 2, 0 }, { 0, 3 }, { 1, 3 }, { 2, 3 } };
    vtkIdType ids[10];
    for (int i = 0; i < 4; ++i)
    {
      ids[i] = points->InsertNextPoint(corners[i]);
      s->InsertNextValue(1.0f);
    }
    for (int e = 0; e < 6; ++e)
    {
      double m[3];
      for (int d = 0; d < 3; ++d)
      {
        m[d] = 0.5 * (corners[edges[e][0]][d] + corners[edges[e][1]][d]);
      }
      ids[4 + e] = points->InsertNextPoint(m);
      s->InsertNextValue(1.0f);
    }
    grid->InsertNextCell(VTK_LAGRANGE_TETRAHEDRON, 10, ids);
  }
  ASSERT_EQ(grid->GetNumberOfCells(), reference->GetNumberOfCells() + 2);
  for (int mode : { vtkAPCVolumeMapper::MBOIT, vtkAPCVolumeMapper::EXACT })
  {
    vtkNew<MessageLog> log;
    apctest::TransferFunction tf;
    tf.Opacities = { { 0.0, 0.1 }, { 1.0, 0.5 } };
    const Frame frame = apctest::Render(grid, Configure(mode, log), tf);
    vtkNew<MessageLog> referenceLog;
    const Frame expected = apctest::Render(reference, Configure(mode, referenceLog), tf);
    std::cout << ModeName(mode) << ": " << log->All() << "\n";
    EXPECT_TRUE(MessageLog::Mentions(log->Errors, "1 x vtkTriangle")) << log->All();
    EXPECT_TRUE(MessageLog::Mentions(log->Errors, "1 x vtkLagrangeTetra")) << log->All();
    EXPECT_EQ(log->Errors.size(), 1u) << "one message for all the skipped cells: " << log->All();
    EXPECT_TRUE(referenceLog->Errors.empty()) << referenceLog->All();
    // The supported cells are the reference grid's cells on the same point ids: the same
    // image, to float rounding (1e-6).
    const double diff = apctest::MaxAbsDiff(frame.RGBA, expected.RGBA);
    std::cout << ModeName(mode) << ": max |with unsupported cells - without| = " << diff
              << ", max alpha " << apctest::MaxChannel(expected.RGBA, 4, 3) << "\n";
    EXPECT_LE(diff, 1e-6) << ModeName(mode);
    EXPECT_GT(apctest::MaxChannel(frame.RGBA, 4, 3), 0.3) << ModeName(mode);
  }
  // Only unsupported cells: an error and a blank image.
  {
    auto only = vtkSmartPointer<vtkUnstructuredGrid>::New();
    only->SetPoints(grid->GetPoints());
    only->GetPointData()->ShallowCopy(grid->GetPointData());
    vtkNew<vtkIdList> ids;
    grid->GetCellPoints(grid->GetNumberOfCells() - 1, ids);
    only->InsertNextCell(VTK_LAGRANGE_TETRAHEDRON, ids);
    vtkNew<MessageLog> log;
    const Frame frame = apctest::Render(only, Configure(vtkAPCVolumeMapper::MBOIT, log));
    std::cout << "only a Lagrange tetra: " << log->All() << "\n";
    EXPECT_TRUE(MessageLog::Mentions(log->Errors, "vtkLagrangeTetra")) << log->All();
    ExpectBlank(frame, "only unsupported cells");
  }
}

TEST(VolumeMapperErrors, OneByOneWindow)
{
  // Odd block (faces at +-1/3) so that the single ray, through the centre, lies in no face
  // plane. Parallel rays along -z: L = 2, alpha = 1 - exp(-2 sigma), within the lattice
  // error exp(-2 sigma) (exp(sigma * 0.01) - 1) ~ 1.5e-3.
  auto grid = apctest::HexBlock(3, [](double, double, double) { return 0.5; });
  apctest::View view;
  view.Width = view.Height = 1;
  for (int mode : { vtkAPCVolumeMapper::MBOIT, vtkAPCVolumeMapper::EXACT })
  {
    vtkNew<MessageLog> log;
    const Frame frame = apctest::Render(grid, Configure(mode, log), {}, view);
    ASSERT_EQ(frame.RGBA.size(), 4u) << ModeName(mode);
    std::cout << ModeName(mode) << ", 1x1: RGBA " << frame.RGBA[0] << " " << frame.RGBA[1] << " "
              << frame.RGBA[2] << " " << frame.RGBA[3] << "\n";
    EXPECT_EQ(NonFinite(frame.RGBA), 0);
    EXPECT_NEAR(frame.RGBA[3], -std::expm1(-2 * kSigma), 2e-3) << ModeName(mode);
    EXPECT_TRUE(log->Errors.empty()) << log->All();
  }
}

TEST(VolumeMapperErrors, CameraInsideTheVolume)
{
  // The eye at (0.1, 0.2, 0.3) inside the block, looking down -z: the central ray sees
  // L = 1.3 of the block, alpha = 1 - exp(-1.3 sigma) (lattice error < 1.6e-3: tolerance
  // 2e-3). Every ray starts inside and runs at least 0.8 through the block (the eye is 0.8
  // from the nearest side face), so every pixel has alpha >= 1 - exp(-0.8 sigma) = 0.16:
  // require > 0.05. MBOIT's renormalised alpha is 1 - exp(-b0) of the same samples as
  // EXACT: equal to 1e-5 (float output of double sums).
  auto grid = apctest::HexBlock(5, [](double, double, double) { return 0.5; });
  apctest::View view;
  view.Parallel = false;
  view.Position = { 0.1, 0.2, 0.3 };
  view.FocalPoint = { 0.1, 0.2, -1.0 };
  view.ViewAngle = 60;
  view.Width = view.Height = 33; // odd: the central pixel looks along the view direction
  Frame frames[2];
  for (int mode : { vtkAPCVolumeMapper::MBOIT, vtkAPCVolumeMapper::EXACT })
  {
    vtkNew<MessageLog> log;
    // The plain lattice in both modes (EXACT keeps it whatever Sample End Weights says): the
    // same samples. The default (Boundary) is checked below.
    const Frame frame = apctest::Render(
      grid,
      [&](vtkAPCVolumeMapper* m)
      {
        Configure(mode, log)(m);
        m->SetSampleEndWeights(vtkAPCVolumeMapper::END_WEIGHTS_OFF);
      },
      {}, view);
    ASSERT_EQ(frame.RGBA.size(), static_cast<size_t>(4 * 33 * 33)) << ModeName(mode);
    EXPECT_EQ(NonFinite(frame.RGBA), 0) << ModeName(mode);
    double minAlpha = 1;
    for (size_t p = 3; p < frame.RGBA.size(); p += 4)
    {
      minAlpha = std::min(minAlpha, static_cast<double>(frame.RGBA[p]));
    }
    const double centre = frame.RGBA[4 * (16 * 33 + 16) + 3];
    std::cout << ModeName(mode) << ", eye inside: centre alpha " << centre << " (expected "
              << -std::expm1(-1.3 * kSigma) << "), min alpha " << minAlpha << "; " << log->All()
              << "\n";
    EXPECT_NEAR(centre, -std::expm1(-1.3 * kSigma), 2e-3) << ModeName(mode);
    EXPECT_GT(minAlpha, 0.05) << ModeName(mode);
    EXPECT_TRUE(log->Errors.empty()) << log->All();
    frames[mode] = frame;
  }
  double alphaDiff = 0;
  for (size_t p = 3; p < frames[0].RGBA.size(); p += 4)
  {
    alphaDiff =
      std::max(alphaDiff, std::abs(static_cast<double>(frames[0].RGBA[p] - frames[1].RGBA[p])));
  }
  std::cout << "eye inside: max |alpha MBOIT - alpha EXACT| = " << alphaDiff << "\n";
  EXPECT_LE(alphaDiff, 1e-5);

  // MBOIT with its default end weights (Boundary): the same analytic alpha, every pixel seen.
  vtkNew<MessageLog> log;
  const Frame weighted = apctest::Render(grid, Configure(vtkAPCVolumeMapper::MBOIT, log), {}, view);
  ASSERT_EQ(weighted.RGBA.size(), static_cast<size_t>(4 * 33 * 33));
  EXPECT_EQ(NonFinite(weighted.RGBA), 0);
  double minWeighted = 1;
  for (size_t p = 3; p < weighted.RGBA.size(); p += 4)
  {
    minWeighted = std::min(minWeighted, static_cast<double>(weighted.RGBA[p]));
  }
  std::cout << "MBOIT (Boundary), eye inside: centre alpha "
            << weighted.RGBA[4 * (16 * 33 + 16) + 3] << ", min alpha " << minWeighted << "\n";
  EXPECT_NEAR(weighted.RGBA[4 * (16 * 33 + 16) + 3], -std::expm1(-1.3 * kSigma), 2e-3);
  EXPECT_GT(minWeighted, 0.05);
  EXPECT_TRUE(log->Errors.empty()) << log->All();
}

// The defaults chosen from the quality evaluation (docs/evaluation.md): 4 moments, the core's
// overestimation (the mapper's header repeats it as a literal), MBOIT's renormalised resolve;
// end weights at the mesh's boundary (docs/sampler.md).
TEST(VolumeMapperErrors, Defaults)
{
  vtkNew<vtkAPCVolumeMapper> mapper;
  EXPECT_EQ(mapper->GetMode(), vtkAPCVolumeMapper::MBOIT);
  EXPECT_EQ(mapper->GetNumberOfMoments(), 4);
  EXPECT_EQ(mapper->GetOverestimation(), apc::kDefaultOverestimation);
  EXPECT_EQ(apc::kDefaultOverestimation, 0.3);
  EXPECT_EQ(mapper->GetResolveMode(), vtkAPCVolumeMapper::RENORMALISED);
  EXPECT_EQ(mapper->GetSampleEndWeights(), vtkAPCVolumeMapper::END_WEIGHTS_BOUNDARY);
}

TEST(VolumeMapperErrors, NumberOfMoments)
{
  vtkNew<vtkAPCVolumeMapper> mapper;
  vtkNew<MessageLog> log;
  log->Watch(mapper);
  const int requests[][2] = { { 4, 4 }, { 6, 6 }, { 8, 8 }, { 5, 6 }, { 3, 4 }, { 7, 8 }, { 9, 8 },
    { 0, 4 }, { -3, 4 }, { 1000, 8 } };
  for (const auto& r : requests)
  {
    log->Warnings.clear();
    mapper->SetNumberOfMoments(r[0]);
    EXPECT_EQ(mapper->GetNumberOfMoments(), r[1]) << "requested " << r[0];
    if (r[0] == r[1])
    {
      EXPECT_TRUE(log->Warnings.empty()) << "requested " << r[0] << ": " << log->All();
    }
    else
    {
      ASSERT_EQ(log->Warnings.size(), 1u) << "requested " << r[0];
      EXPECT_TRUE(MessageLog::Mentions(log->Warnings, "4, 6 or 8")) << log->All();
      if (r[0] == 5)
      {
        std::cout << "SetNumberOfMoments(5): " << log->Warnings[0] << "\n";
      }
    }
  }

  // 4, 6 and 8 render finite images with N+1 moments; the renormalised alpha
  // (1 - exp(-b0)) does not depend on N: equal to 1e-6 (float output of the same b0).
  auto grid =
    apctest::HexBlock(6, [](double x, double y, double z) { return 0.5 + 0.4 * x * y * z; });
  apctest::TransferFunction tf;
  tf.Colours = { { 0.0, 0.1, 0.2, 1.0 }, { 1.0, 1.0, 0.1, 0.0 } };
  tf.Opacities = { { 0.0, 0.05 }, { 1.0, 0.8 } };
  apctest::View view;
  view.Parallel = false;
  view.Position = { 2.0, -1.0, 4.0 };
  std::vector<Frame> frames;
  for (int n : { 4, 6, 8 })
  {
    vtkNew<MessageLog> renderLog;
    frames.push_back(apctest::Render(
      grid,
      [&](vtkAPCVolumeMapper* m)
      {
        Configure(vtkAPCVolumeMapper::MBOIT, renderLog)(m);
        m->SetNumberOfMoments(n);
      },
      tf, view));
    const Frame& frame = frames.back();
    EXPECT_EQ(frame.Moments.size(), static_cast<size_t>((n + 1) * view.Width * view.Height));
    EXPECT_EQ(NonFinite(frame.RGBA), 0) << n << " moments";
    EXPECT_EQ(NonFinite(frame.Moments), 0) << n << " moments";
    EXPECT_GT(apctest::MaxChannel(frame.RGBA, 4, 3), 0.3) << n << " moments";
    EXPECT_TRUE(renderLog->Errors.empty() && renderLog->Warnings.empty()) << renderLog->All();
  }
  for (size_t f = 1; f < frames.size(); ++f)
  {
    double alphaDiff = 0;
    double colourDiff = 0;
    for (size_t v = 0; v < frames[0].RGBA.size(); ++v)
    {
      const double d = std::abs(static_cast<double>(frames[f].RGBA[v] - frames[0].RGBA[v]));
      (v % 4 == 3 ? alphaDiff : colourDiff) = std::max(v % 4 == 3 ? alphaDiff : colourDiff, d);
    }
    std::cout << (f == 1 ? 6 : 8) << " vs 4 moments: max alpha diff " << alphaDiff
              << ", max colour diff " << colourDiff << "\n";
    EXPECT_LE(alphaDiff, 1e-6);
  }
}

TEST(VolumeMapperErrors, InputThatIsNotAnUnstructuredGrid)
{
  vtkNew<vtkImageData> image;
  image->SetDimensions(4, 4, 4);
  image->AllocateScalars(VTK_FLOAT, 1);
  image->GetPointData()->GetScalars()->Fill(0.5);

  // SetInputData with a vtkImageData: the mapper refuses it.
  {
    vtkNew<MessageLog> log;
    vtkNew<vtkAPCVolumeMapper> mapper;
    log->Watch(mapper);
    mapper->SetInputData(static_cast<vtkDataSet*>(image.Get()));
    std::cout << "SetInputData(vtkImageData): " << log->All() << "\n";
    EXPECT_TRUE(MessageLog::Mentions(log->Errors, "vtkUnstructuredGrid")) << log->All();
    EXPECT_EQ(mapper->GetInput(), nullptr);
  }

  // An image source connected to the input port: VTK's pipeline rejects it (an error from
  // the executive or the mapper), the render goes on, blank.
  vtkNew<vtkTrivialProducer> producer;
  producer->SetOutput(image);
  for (int mode : { vtkAPCVolumeMapper::MBOIT, vtkAPCVolumeMapper::EXACT })
  {
    vtkNew<MessageLog> log;
    // Render sets this grid as input first; configure replaces it with the connection.
    auto placeholder = apctest::HexBlock(1, [](double, double, double) { return 0.5; });
    const Frame frame = apctest::Render(placeholder,
      [&](vtkAPCVolumeMapper* m)
      {
        Configure(mode, log)(m);
        m->SetInputConnection(producer->GetOutputPort());
        log->Watch(m->GetExecutive());
      });
    std::cout << ModeName(mode) << ", vtkImageData on the input port: " << log->All() << "\n";
    EXPECT_FALSE(log->Errors.empty()) << "an error is expected";
    EXPECT_TRUE(MessageLog::Mentions(log->Errors, "vtkImageData") ||
      MessageLog::Mentions(log->Errors, "vtkUnstructuredGrid"))
      << log->All();
    ExpectBlank(frame, "image input");
  }
}

TEST(VolumeMapperErrors, OpaqueTransferFunction)
{
  // alpha_tf = 1: infinite absorbance per unit length, clamped by the transfer table. The
  // image must be finite and (almost) opaque where the block is: alpha > 0.999.
  auto grid = apctest::HexBlock(4, [](double x, double, double) { return 0.5 + 0.4 * x; });
  apctest::TransferFunction tf;
  tf.Opacities = { { 0.0, 1.0 }, { 1.0, 1.0 } };
  for (int mode : { vtkAPCVolumeMapper::MBOIT, vtkAPCVolumeMapper::EXACT })
  {
    for (int n : { 4, 8 })
    {
      vtkNew<MessageLog> log;
      const Frame frame = apctest::Render(
        grid,
        [&](vtkAPCVolumeMapper* m)
        {
          Configure(mode, log)(m);
          m->SetNumberOfMoments(n);
        },
        tf);
      EXPECT_EQ(NonFinite(frame.RGBA), 0) << ModeName(mode);
      EXPECT_EQ(NonFinite(frame.Moments), 0) << ModeName(mode);
      const double centre = frame.RGBA[4 * (32 * 64 + 32) + 3];
      const double red = frame.RGBA[4 * (32 * 64 + 32)];
      std::cout << ModeName(mode) << ", " << n << " moments, opaque: centre RGBA " << red << " ... "
                << centre << "; " << log->All() << "\n";
      EXPECT_GT(centre, 0.999) << ModeName(mode);
      // Colour (1, 0.5, 0.25) premultiplied by alpha ~ 1.
      EXPECT_NEAR(red, centre, 1e-3) << ModeName(mode);
      EXPECT_TRUE(log->Errors.empty()) << log->All();
    }
  }
}

// Memory running out in one process's pass 1 or pass 2 (no composite pass: no collective to
// agree in) skips the frame with an error naming the pass, instead of an exception leaving
// Render and aborting the program; the next frame is the undisturbed one, bit for bit.
TEST(VolumeMapperErrors, MemoryRunningOutSkipsTheFrame)
{
  auto grid = apctest::HexBlock(4, [](double x, double, double) { return 0.5 + 0.4 * x; });
  apctest::LiveWindow live;
  live.Mapper->SetInputData(grid);
  live.Mapper->SetSampleDistance(0.01);
  vtkNew<MessageLog> log;
  log->Watch(live.Mapper);
  const Frame undisturbed = live.Render();
  ASSERT_TRUE(log->Errors.empty()) << log->All();
  ASSERT_GT(apctest::MaxChannel(undisturbed.RGBA, 4, 3), 0.1) << "the positive control renders";
  const std::pair<apc::FailurePoint, const char*> points[] = {
    { apc::FailurePoint::PassOne, "pass 1" },
    { apc::FailurePoint::PassTwo, "pass 2" },
  };
  for (const auto& [point, name] : points)
  {
    log->Errors.clear();
    apc::FailForTesting(point, 1);
    const Frame failed = live.Render();
    std::cout << name << " failing: " << log->All() << "\n";
    EXPECT_TRUE(MessageLog::Mentions(log->Errors, std::string("APC frame skipped: ") + name))
      << log->All();
    ExpectBlank(failed, name);
    log->Errors.clear();
    const Frame again = live.Render();
    EXPECT_TRUE(log->Errors.empty()) << log->All();
    EXPECT_EQ(again.RGBA, undisturbed.RGBA) << name << ": the next frame is the undisturbed one";
    EXPECT_EQ(again.Window, undisturbed.Window) << name;
  }
}

// A NaN point coordinate must not hang the renderer: the cell's faces through that point
// have no plane, and the remaining planes leave the ray unbounded, [t_in, +inf), so the
// sample loop never ends. A collapsed cell (all corners at one point, which projects onto a
// pixel centre) has no planes at all: the whole ray [0, +inf). Each case runs in a child
// process with an alarm, so that a hang fails the test instead of stalling the suite. MBOIT
// mode: EXACT would also store the endless samples, growing memory without bound.
void ExpectRendersWithin20Seconds(vtkUnstructuredGrid* grid)
{
  alarm(20);
  vtkNew<MessageLog> log;
  const Frame frame = apctest::Render(grid, Configure(vtkAPCVolumeMapper::MBOIT, log));
  std::fprintf(
    stderr, "rendered, %d non-finite values; %s\n", NonFinite(frame.RGBA), log->All().c_str());
  std::exit(NonFinite(frame.RGBA) == 0 ? 0 : 3);
}

TEST(VolumeMapperErrors, NaNPointCoordinatesDoNotHang)
{
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  auto grid = apctest::HexBlock(4, [](double, double, double) { return 0.5; });
  const double nan = std::nan("");
  grid->GetPoints()->SetPoint(31, nan, nan, nan);
  EXPECT_EXIT(ExpectRendersWithin20Seconds(grid), ::testing::ExitedWithCode(0), "rendered");
}

TEST(VolumeMapperErrors, CollapsedCellDoesNotHang)
{
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  auto grid = apctest::HexBlock(3, [](double, double, double) { return 0.5; });
  // The default view (parallel, scale 1.5, 64 pixels) has a pixel centre at x = y =
  // 1.5 / 64 = 0.0234375 (exact in binary).
  const vtkIdType p = grid->GetPoints()->InsertNextPoint(0.0234375, 0.0234375, 0.0);
  vtkFloatArray::SafeDownCast(grid->GetPointData()->GetScalars())->InsertNextValue(0.5f);
  const vtkIdType collapsed[8] = { p, p, p, p, p, p, p, p };
  grid->InsertNextCell(VTK_HEXAHEDRON, 8, collapsed);
  EXPECT_EXIT(ExpectRendersWithin20Seconds(grid), ::testing::ExitedWithCode(0), "rendered");
}
}
