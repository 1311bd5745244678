// vtkAPCVolumeMapper's StopWhereOpaque: on by default; it reaches the ray marcher (an
// opaque block takes far fewer samples), the exact mode ignores it, and the stopped MBOIT
// image stays within the stop's bound of where marching every sample leaves it against the
// exact ordered blend (no pixel farther from the exact image by more than 1/255, no alpha by
// more than exp(-threshold), 1e-3 at the recommended ln 10^3).

#include "apcTestGrids.h"
#include "apcTestRender.h"
#include "apcVolumeRayMarcher.h"

#include "vtkFieldData.h"
#include "vtkImageData.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace
{
double SampleCount(vtkAPCVolumeMapper* mapper)
{
  vtkDataArray* count = mapper->GetLastImage()->GetFieldData()->GetArray("SampleCount");
  return count ? count->GetComponent(0, 0) : -1.0;
}

// A block of non-affine hexahedra, opaque within a fraction of its depth, coloured by a field
// that varies along the view direction (so what the stop leaves out would show if it were
// visible).
apctest::TransferFunction OpaqueTF()
{
  apctest::TransferFunction tf;
  tf.Colours = { { 0.0, 0.0, 0.2, 1.0 }, { 0.5, 0.2, 1.0, 0.2 }, { 1.0, 1.0, 0.1, 0.0 } };
  tf.Opacities = { { 0.0, 0.6 }, { 1.0, 0.9 } };
  tf.UnitDistance = 0.1;
  return tf;
}
}

TEST(VolumeMapperOpaqueStop, ReachesTheMarcherWithinTheBound)
{
  auto grid = apctest::HexBlock(12,
    [](double x, double y, double z)
    { return 0.5 + 0.3 * std::sin(2 * x) * std::cos(3 * z) + 0.15 * y; });
  apctest::View view;
  view.Parallel = false;
  view.Position = { 1.5, 2.0, 4.5 };
  apctest::LiveWindow live(OpaqueTF(), view);
  live.Mapper->SetInputData(grid);
  live.Mapper->SetSampleDistance(0.02);
  // The plain lattice, which the exact mode keeps whatever Sample End Weights says: the same
  // samples in every mode, so the exact mode's count is the stop-off count.
  live.Mapper->SetSampleEndWeights(vtkAPCVolumeMapper::END_WEIGHTS_OFF);
  ASSERT_TRUE(live.Mapper->GetStopWhereOpaque()) << "on by default";

  live.Mapper->StopWhereOpaqueOff();
  const apctest::Frame all = live.Render();
  const double allSamples = SampleCount(live.Mapper);
  live.Mapper->StopWhereOpaqueOn();
  const apctest::Frame stopped = live.Render();
  const double stoppedSamples = SampleCount(live.Mapper);
  live.Mapper->SetMode(vtkAPCVolumeMapper::EXACT);
  const apctest::Frame exact = live.Render();
  const double exactSamples = SampleCount(live.Mapper);

  ASSERT_GT(allSamples, 0);
  EXPECT_LT(stoppedSamples, 0.5 * allSamples) << "the stop must reach the ray marcher";
  EXPECT_EQ(exactSamples, allSamples) << "the exact mode marches every sample";

  double worse = 0;
  double worseAlpha = 0;
  int opaque = 0;
  for (int p = 0; p < all.Width * all.Height; ++p)
  {
    double errAll = 0;
    double errStopped = 0;
    for (int c = 0; c < 3; ++c)
    {
      errAll = std::max(errAll, double(std::abs(all.RGBA[4 * p + c] - exact.RGBA[4 * p + c])));
      errStopped =
        std::max(errStopped, double(std::abs(stopped.RGBA[4 * p + c] - exact.RGBA[4 * p + c])));
    }
    worse = std::max(worse, errStopped - errAll);
    const float alpha = exact.RGBA[4 * p + 3];
    worseAlpha = std::max(worseAlpha,
      double(std::abs(stopped.RGBA[4 * p + 3] - alpha) - std::abs(all.RGBA[4 * p + 3] - alpha)));
    opaque += alpha > 0.9999f;
  }
  EXPECT_GT(opaque, all.Width * all.Height / 8) << "the block must be opaque on much of the view";
  EXPECT_LE(worse, 1.0 / 255.0) << "colour farther from the exact blend than without the stop";
  EXPECT_LE(worseAlpha, std::exp(-apc::VolumeRayMarcher::kRecommendedOpaqueAbsorbance) + 1e-6)
    << "alpha farther from the exact blend than the bound";
  RecordProperty("SampleRatio", std::to_string(stoppedSamples / allSamples));
  RecordProperty("WorseColour", std::to_string(worse));
}
