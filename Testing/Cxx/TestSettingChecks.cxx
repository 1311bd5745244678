// Settings outside their meaning are checked once, where they enter: every setter of
// vtkAPCVolumeMapper and vtkAPCCompositePass says one warning naming the setting and its
// range and clamps the value (no silent clamp, nothing said twice); a sample distance that
// would take more than FrameEngine::kMaxSamplesPerRay samples along a ray through the data is
// raised to that limit, with one warning saying what to change.

#include "apcFrameEngine.h"
#include "apcTestGrids.h"
#include "apcTestMessages.h"
#include "apcTestRender.h"

#include "vtkAPCCompositePass.h"
#include "vtkPoints.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <string>

namespace
{
using apctest::MessageLog;

// Sets a bad value and expects one warning naming the setting, and the clamped value.
void ExpectChecked(vtkObject* object, MessageLog* log, const std::string& name,
  const std::function<void()>& set, const std::function<double()>& get, double clamped)
{
  log->Clear();
  set();
  EXPECT_EQ(log->Warnings.size(), 1u) << name << ": " << log->All();
  EXPECT_TRUE(MessageLog::Mentions(log->Warnings, name + " must be in [")) << log->All();
  EXPECT_EQ(get(), clamped) << name;
  log->Clear();
  (void)object;
}
}

TEST(SettingChecks, MapperSetters)
{
  vtkNew<vtkAPCVolumeMapper> m;
  vtkNew<MessageLog> log;
  log->Watch(m);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ExpectChecked(
    m, log, "SampleDistance", [&] { m->SetSampleDistance(-1); },
    [&] { return m->GetSampleDistance(); }, 0.0);
  ExpectChecked(
    m, log, "SampleDistance", [&] { m->SetSampleDistance(nan); },
    [&] { return m->GetSampleDistance(); }, 0.0);
  ExpectChecked(
    m, log, "Overestimation", [&] { m->SetOverestimation(5); },
    [&] { return m->GetOverestimation(); }, 1.0);
  ExpectChecked(
    m, log, "MomentBias", [&] { m->SetMomentBias(-3); }, [&] { return m->GetMomentBias(); }, -1.0);
  ExpectChecked(
    m, log, "SampleCacheSize", [&] { m->SetSampleCacheSize(-5); },
    [&] { return m->GetSampleCacheSize(); }, -1);
  ExpectChecked(
    m, log, "NumberOfThreads", [&] { m->SetNumberOfThreads(-2); },
    [&] { return m->GetNumberOfThreads(); }, 0);
  ExpectChecked(
    m, log, "Mode", [&] { m->SetMode(7); }, [&] { return m->GetMode(); },
    vtkAPCVolumeMapper::MBOIT);
  ExpectChecked(
    m, log, "ResolveMode", [&] { m->SetResolveMode(-1); }, [&] { return m->GetResolveMode(); },
    vtkAPCVolumeMapper::RENORMALISED);
  ExpectChecked(
    m, log, "SampleEndWeights", [&] { m->SetSampleEndWeights(5); },
    [&] { return m->GetSampleEndWeights(); }, vtkAPCVolumeMapper::END_WEIGHTS_BOUNDARY);
  ExpectChecked(
    m, log, "SampleEndWeights", [&] { m->SetSampleEndWeights(-1); },
    [&] { return m->GetSampleEndWeights(); }, vtkAPCVolumeMapper::END_WEIGHTS_OFF);
  ExpectChecked(
    m, log, "VectorMode", [&] { m->SetVectorMode(9); }, [&] { return m->GetVectorMode(); },
    vtkScalarsToColors::RGBCOLORS);

  // Values in range: silent, kept exactly.
  log->Clear();
  m->SetSampleDistance(0.02);
  m->SetOverestimation(0.5);
  m->SetSampleCacheSize(0);
  m->SetNumberOfThreads(2);
  m->SetSampleEndWeights(vtkAPCVolumeMapper::END_WEIGHTS_BOUNDARY);
  m->SetSampleEndWeights(true);
  EXPECT_TRUE(log->Warnings.empty()) << log->All();
  EXPECT_EQ(m->GetSampleEndWeights(), vtkAPCVolumeMapper::END_WEIGHTS_ALL);
  EXPECT_EQ(m->GetSampleDistance(), 0.02);
  EXPECT_EQ(m->GetOverestimation(), 0.5);
}

TEST(SettingChecks, CompositePassSetters)
{
  vtkNew<vtkAPCCompositePass> p;
  vtkNew<MessageLog> log;
  log->Watch(p);
  ExpectChecked(
    p, log, "MaxBandPixels", [&] { p->SetMaxBandPixels(0); },
    [&] { return static_cast<double>(p->GetMaxBandPixels()); }, 1.0);
  ExpectChecked(
    p, log, "MaxMessageBytes", [&] { p->SetMaxMessageBytes(8); },
    [&] { return static_cast<double>(p->GetMaxMessageBytes()); }, 64.0);
  ExpectChecked(
    p, log, "CompositeMode", [&] { p->SetCompositeMode(9); }, [&] { return p->GetCompositeMode(); },
    vtkAPCCompositePass::AUTO);
  ExpectChecked(
    p, log, "InteractiveImageReduction", [&] { p->SetInteractiveImageReduction(0); },
    [&] { return p->GetInteractiveImageReduction(); }, 1);
  ExpectChecked(
    p, log, "InteractiveSampleDistanceFactor", [&] { p->SetInteractiveSampleDistanceFactor(40); },
    [&] { return p->GetInteractiveSampleDistanceFactor(); }, 16.0);
  ExpectChecked(
    p, log, "Verbosity", [&] { p->SetVerbosity(3); }, [&] { return p->GetVerbosity(); }, 1);
  ExpectChecked(
    p, log, "DisplayProcess", [&] { p->SetDisplayProcess(-1); },
    [&] { return p->GetDisplayProcess(); }, 0);

  // The defaults, each written once (apc::FrameSettings), as documented.
  vtkNew<vtkAPCCompositePass> fresh;
  EXPECT_EQ(fresh->GetCompositeMode(), vtkAPCCompositePass::APC);
  EXPECT_EQ(fresh->GetMaxBandPixels(), vtkIdType(1) << 21);
  EXPECT_EQ(fresh->GetMaxMessageBytes(), vtkIdType(8) << 20);
  EXPECT_EQ(fresh->GetInteractiveImageReduction(), 4);
  EXPECT_EQ(fresh->GetInteractiveSampleDistanceFactor(), 2.0);
  EXPECT_FALSE(fresh->GetCompositeInDouble());
  EXPECT_TRUE(fresh->GetDisplayDepthComposited());
}

// A sample distance 1e-5 on [-1,1]^3 (diagonal 2 sqrt 3) would take ~346,000 samples per ray:
// it is raised to diagonal / kMaxSamplesPerRay and said once, in one warning saying what to
// change (that later frames say nothing more: PvbatchMessages.sample_cap).
TEST(SettingChecks, SamplesPerRayCapped)
{
  auto grid = apctest::HexBlock(4, [](double x, double, double) { return 0.5 + 0.4 * x; });
  vtkNew<MessageLog> log;
  apctest::View view;
  view.Width = 24;
  view.Height = 24;
  const auto start = std::chrono::steady_clock::now();
  const apctest::Frame frame = apctest::Render(
    grid,
    [&](vtkAPCVolumeMapper* m)
    {
      log->Watch(m);
      m->SetSampleDistance(1e-5);
    },
    {}, view);
  const double seconds =
    std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double diagonal = 2 * std::sqrt(3.0);
  EXPECT_NEAR(frame.SampleDistance, diagonal / apc::FrameEngine::kMaxSamplesPerRay, 1e-12);
  ASSERT_EQ(log->Warnings.size(), 1u) << log->All();
  EXPECT_TRUE(MessageLog::Mentions(log->Warnings, "Sample Distance 1e-05 would take up to"))
    << log->All();
  EXPECT_TRUE(MessageLog::Mentions(log->Warnings, "Raise Sample Distance to at least"))
    << log->All();
  EXPECT_LT(seconds, 30.0) << "a capped frame is bounded";
  std::cout << "capped warning: " << log->Warnings[0] << "\n";

  // At the limit exactly: nothing to say.
  log->Clear();
  apctest::Render(
    grid,
    [&](vtkAPCVolumeMapper* m)
    {
      log->Watch(m);
      m->SetSampleDistance(diagonal / apc::FrameEngine::kMaxSamplesPerRay * 1.0001);
    },
    {}, view);
  EXPECT_TRUE(log->Warnings.empty()) << log->All();
}

// Sample distance 0 depends on the lattice the volume samples (apcDefaultSpacing.h): with
// weighted ends (Sample End Weights Boundary, the default, or All, in MBOIT) 1.25 mean cell
// sizes and at least 96 samples along the diagonal; on the plain lattice (Off, EXACT, the
// HYBRID resolve) one mean cell size and at least 128. The 8^3 cells of [-1,1]^3 are large
// next to the diagonal (2 sqrt 3), so the floor decides.
TEST(SettingChecks, DefaultSampleDistanceFollowsTheLattice)
{
  auto grid = apctest::HexBlock(8, [](double x, double, double) { return 0.5 + 0.4 * x; });
  apctest::View view;
  view.Width = 16;
  view.Height = 16;
  const double diagonal = 2 * std::sqrt(3.0);
  auto distance = [&](int mode, int endWeights, int resolve)
  {
    return apctest::Render(
      grid,
      [&](vtkAPCVolumeMapper* m)
      {
        m->SetMode(mode);
        m->SetSampleEndWeights(endWeights);
        m->SetResolveMode(resolve);
      },
      {}, view)
      .SampleDistance;
  };
  const int mboit = vtkAPCVolumeMapper::MBOIT;
  const int renormalised = vtkAPCVolumeMapper::RENORMALISED;
  EXPECT_DOUBLE_EQ(
    distance(mboit, vtkAPCVolumeMapper::END_WEIGHTS_BOUNDARY, renormalised), diagonal / 96);
  EXPECT_DOUBLE_EQ(
    distance(mboit, vtkAPCVolumeMapper::END_WEIGHTS_ALL, renormalised), diagonal / 96);
  EXPECT_DOUBLE_EQ(
    distance(mboit, vtkAPCVolumeMapper::END_WEIGHTS_OFF, renormalised), diagonal / 128);
  EXPECT_DOUBLE_EQ(
    distance(vtkAPCVolumeMapper::EXACT, vtkAPCVolumeMapper::END_WEIGHTS_BOUNDARY, renormalised),
    diagonal / 128);
  EXPECT_DOUBLE_EQ(
    distance(mboit, vtkAPCVolumeMapper::END_WEIGHTS_BOUNDARY, vtkAPCVolumeMapper::HYBRID),
    diagonal / 128);
}

TEST(SettingChecks, DefaultSampleDistanceCapped)
{
  // A slab 3e-6 thick of 48 x 48 x 48 cells (each 6.25e-8 thick, 1.5e-6 of its width: still a
  // volume, not a flat cell): the default (1.25 mean cell sizes with Boundary's weights, the
  // cube root of the volume per cell, 4.77e-4, rounded down to 4.73e-4) would take 4,800
  // samples along the diagonal. The cap holds for the default too, and says so, naming the
  // default.
  auto grid = apctest::HexBlock(48, [](double x, double, double) { return 0.5 + 0.4 * x; });
  vtkPoints* points = grid->GetPoints();
  for (vtkIdType p = 0; p < points->GetNumberOfPoints(); ++p)
  {
    double x[3];
    points->GetPoint(p, x);
    x[2] *= 1.5e-6;
    points->SetPoint(p, x);
  }
  vtkNew<MessageLog> log;
  apctest::View view;
  view.Width = 24;
  view.Height = 24;
  view.Position = { 0, -5, 2 };
  view.ViewUp = { 0, 0, 1 };
  const apctest::Frame frame = apctest::Render(
    grid, [&](vtkAPCVolumeMapper* m) { log->Watch(m); }, {}, view);
  const double diagonal = std::sqrt(8.0 + 9e-12);
  EXPECT_NEAR(frame.SampleDistance, diagonal / apc::FrameEngine::kMaxSamplesPerRay, 1e-9);
  EXPECT_EQ(log->Warnings.size(), 1u) << log->All();
  EXPECT_TRUE(MessageLog::Mentions(log->Warnings, "The default Sample Distance")) << log->All();
  EXPECT_TRUE(MessageLog::Mentions(log->Warnings, "the limit is 4096")) << log->All();
}
