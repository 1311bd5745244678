#include "apcMomentTransmittance.h"
#include "apcOrderedReference.h"
#include "apcResolve.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <vector>

namespace
{

using apc::Sample;

// The full APC pipeline for one pixel on one rank: moments, T per sample, colour sums.
template <int N>
apc::ColourSums WeightedSums(const std::vector<Sample>& samples, double beta, double* b0)
{
  apc::PowerMoments<N> moments;
  for (const Sample& s : samples)
  {
    moments.AddAlpha(s.Depth, s.Alpha);
  }
  apc::MomentSettings<N> settings;
  settings.Overestimation = beta;
  const apc::MomentTransmittance<N> t(moments, settings);
  apc::ColourSums sums;
  for (const Sample& s : samples)
  {
    sums.Add(s.Alpha * t(s.Depth), s.Colour);
  }
  *b0 = moments.B0();
  return sums;
}

TEST(Resolve, SingleLayer)
{
  const std::vector<Sample> one = { { 0.1, 0.6, { 0.2, 0.4, 0.8 } } };
  const apc::RGBA exact = apc::CompositeOrdered(one);
  for (const double beta : { 0.0, 0.3 })
  {
    double b0 = 0.0;
    const apc::ColourSums sums = WeightedSums<4>(one, beta, &b0);
    // Renormalised is exact for one layer whatever T is: alpha from b0, colour from C/W.
    // 1e-15: exp/log1p round trip of alpha.
    const apc::RGBA renormalised = apc::Resolve(apc::ResolveMode::Renormalised, sums, b0);
    for (int k = 0; k < 4; ++k)
    {
      EXPECT_NEAR(renormalised[k], exact[k], 1e-15) << "beta " << beta << " channel " << k;
    }
    // The paper's sum weights the layer by T at its own depth, (1-alpha)^beta (to 1e-6,
    // the on-layer accuracy of 4 moments measured in TestMomentTransmittance).
    const apc::RGBA paper = apc::Resolve(apc::ResolveMode::PaperSum, sums, b0);
    const double w = 0.6 * std::pow(0.4, beta);
    EXPECT_NEAR(paper[3], w, 1e-6);
    EXPECT_NEAR(paper[0], 0.2 * w, 1e-6);
    EXPECT_NEAR(paper[2], 0.8 * w, 1e-6);
  }
}

// Two layers: opacity of Renormalised is exact; its colour is off only by how T weights the
// layers at their own depths: front (1-0.5)^beta, back 0.5 (1-0.4)^beta. For beta = 0 the
// weights are exact (measured 1e-6 error); for beta = 0.3 the mix shifts (measured 0.0079 in
// red and green), bounded at 0.01. PaperSum underestimates by the same factors (measured
// 0.122 in alpha, 0.094 in red for beta = 0.3), bounded at 0.13.
TEST(Resolve, TwoLayersAgainstOrderedBlend)
{
  const std::vector<Sample> two = { { 0.3, 0.4, { 0.0, 1.0, 0.0 } },
    { -0.5, 0.5, { 1.0, 0.0, 0.0 } } };
  const apc::RGBA exact = apc::CompositeOrdered(two);
  ASSERT_NEAR(exact[3], 0.7, 1e-15);
  ASSERT_NEAR(exact[0], 0.5, 1e-15);
  ASSERT_NEAR(exact[1], 0.2, 1e-15);
  for (const double beta : { 0.0, 0.3 })
  {
    double b0 = 0.0;
    const apc::ColourSums sums = WeightedSums<6>(two, beta, &b0);
    const apc::RGBA renormalised = apc::Resolve(apc::ResolveMode::Renormalised, sums, b0);
    const apc::RGBA paper = apc::Resolve(apc::ResolveMode::PaperSum, sums, b0);
    EXPECT_NEAR(renormalised[3], 0.7, 1e-15);
    const double colourTolerance = beta == 0.0 ? 1e-5 : 0.01;
    const double paperTolerance = beta == 0.0 ? 1e-5 : 0.13;
    for (int k = 0; k < 3; ++k)
    {
      EXPECT_NEAR(renormalised[k], exact[k], colourTolerance) << "beta " << beta << " ch " << k;
      EXPECT_NEAR(paper[k], exact[k], paperTolerance) << "beta " << beta << " ch " << k;
    }
    EXPECT_NEAR(paper[3], exact[3], paperTolerance);
    std::cout << "two layers beta=" << beta << ": exact (" << exact[0] << ", " << exact[1] << ", "
              << exact[3] << ") renormalised (" << renormalised[0] << ", " << renormalised[1]
              << ", " << renormalised[3] << ") paper (" << paper[0] << ", " << paper[1] << ", "
              << paper[3] << ")\n";
  }
}

TEST(Resolve, ZeroWeightIsGuarded)
{
  const apc::ColourSums empty;
  const apc::RGBA paper = apc::Resolve(apc::ResolveMode::PaperSum, empty, 0.0);
  for (double v : paper)
  {
    EXPECT_EQ(v, 0.0);
  }
  const apc::RGBA renormalised = apc::Resolve(apc::ResolveMode::Renormalised, empty, 1.0);
  EXPECT_EQ(renormalised[0], 0.0);
  EXPECT_EQ(renormalised[1], 0.0);
  EXPECT_EQ(renormalised[2], 0.0);
  EXPECT_NEAR(renormalised[3], 1.0 - std::exp(-1.0), 1e-15);

  apc::ColourSums nonFinite;
  nonFinite.Sums = { 1.0, 1.0, 1.0, std::numeric_limits<double>::infinity() };
  for (const apc::ResolveMode mode : { apc::ResolveMode::PaperSum, apc::ResolveMode::Renormalised })
  {
    for (double v : apc::Resolve(mode, nonFinite, std::numeric_limits<double>::quiet_NaN()))
    {
      EXPECT_TRUE(std::isfinite(v));
    }
  }
  EXPECT_EQ(
    apc::Resolve(apc::ResolveMode::Renormalised, empty, std::numeric_limits<double>::infinity())[3],
    1.0);
}

TEST(Resolve, PaperSumClampsOverfullWeight)
{
  apc::ColourSums sums;
  sums.Add(0.8, { 1.0, 0.5, 0.0 });
  sums.Add(0.8, { 0.0, 0.5, 1.0 });
  const apc::RGBA out = apc::Resolve(apc::ResolveMode::PaperSum, sums, 5.0);
  EXPECT_EQ(out[3], 1.0);
  // Scaled by 1/W = 1/1.6 so that the colour stays premultiplied (rgb <= alpha).
  EXPECT_NEAR(out[0], 0.5, 1e-15);
  EXPECT_NEAR(out[1], 0.5, 1e-15);
  EXPECT_NEAR(out[2], 0.5, 1e-15);
}

TEST(Resolve, ColourSumsAddUp)
{
  apc::ColourSums a, b, all;
  a.Add(0.25, { 1.0, 0.0, 0.5 });
  b.Add(0.5, { 0.0, 1.0, 0.5 });
  b.Add(std::numeric_limits<double>::quiet_NaN(), { 9.0, 9.0, 9.0 });
  b.Add(-1.0, { 9.0, 9.0, 9.0 });
  all.Add(0.25, { 1.0, 0.0, 0.5 });
  all.Add(0.5, { 0.0, 1.0, 0.5 });
  a += b;
  EXPECT_EQ(a.Sums, all.Sums);
  EXPECT_EQ(a.W(), 0.75);
  EXPECT_EQ(a.Data()[2], 0.375);
}

TEST(Resolve, BlendOverBackground)
{
  const apc::RGB out = apc::BlendOverBackground({ 0.3, 0.0, 0.1, 0.4 }, { 1.0, 0.5, 0.0 });
  EXPECT_DOUBLE_EQ(out[0], 0.3 + 0.6);
  EXPECT_DOUBLE_EQ(out[1], 0.3);
  EXPECT_DOUBLE_EQ(out[2], 0.1);
}

} // namespace
