#include "apcOrderedReference.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <vector>

namespace
{

using apc::Sample;

TEST(OrderedReference, HandComputed)
{
  // Red 0.5 in front of green 0.5 in front of blue 1: red 0.5, green 0.25, blue 0.25.
  const std::vector<Sample> samples = { { 2.0, 0.5, { 0, 1, 0 } }, { 3.0, 1.0, { 0, 0, 1 } },
    { 1.0, 0.5, { 1, 0, 0 } } };
  const apc::RGBA out = apc::CompositeOrdered(samples);
  EXPECT_EQ(out[0], 0.5);
  EXPECT_EQ(out[1], 0.25);
  EXPECT_EQ(out[2], 0.25);
  EXPECT_EQ(out[3], 1.0);
  EXPECT_EQ(apc::ExactTransmittance(samples, 0.5), 1.0);
  EXPECT_EQ(apc::ExactTransmittance(samples, 1.0), 1.0) << "a sample at z is not in front";
  EXPECT_EQ(apc::ExactTransmittance(samples, 1.5), 0.5);
  EXPECT_EQ(apc::ExactTransmittance(samples, 2.5), 0.25);
  EXPECT_EQ(apc::ExactTransmittance(samples, 9.0), 0.0);
}

TEST(OrderedReference, InputOrderDoesNotMatter)
{
  // Includes two samples at the same depth, whose blend order changes the colour.
  std::vector<Sample> samples = { { 0.1, 0.3, { 0.9, 0.1, 0.2 } }, { 0.4, 0.7, { 0.0, 1.0, 0.3 } },
    { 0.4, 0.2, { 1.0, 0.0, 0.0 } }, { -0.6, 0.15, { 0.5, 0.5, 0.5 } },
    { 0.8, 0.9, { 0.1, 0.2, 0.9 } }, { -0.2, 0.05, { 0.3, 0.6, 0.0 } } };
  const auto less = [](const Sample& a, const Sample& b)
  { return std::tie(a.Depth, a.Alpha) < std::tie(b.Depth, b.Alpha); };
  std::sort(samples.begin(), samples.end(), less);
  const apc::RGBA first = apc::CompositeOrdered(samples);
  const double t = apc::ExactTransmittance(samples, 0.5);
  int permutations = 0;
  do
  {
    // Bitwise equal: the reference sorts (with a full tie-break) before blending.
    EXPECT_EQ(apc::CompositeOrdered(samples), first);
    EXPECT_EQ(apc::ExactTransmittance(samples, 0.5), t);
    ++permutations;
  } while (std::next_permutation(samples.begin(), samples.end(), less));
  EXPECT_EQ(permutations, 720);
  EXPECT_GT(first[3], 0.0);
}

TEST(OrderedReference, InvalidSamples)
{
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Sample> samples = { { nan, 0.5, { 1, 0, 0 } }, { 1.0, nan, { 1, 0, 0 } },
    { 2.0, 1.5, { 0, 0, 1 } }, { 0.5, -0.2, { 1, 1, 1 } } };
  const apc::RGBA out = apc::CompositeOrdered(samples);
  EXPECT_EQ(out, (apc::RGBA{ 0.0, 0.0, 1.0, 1.0 })) << "alpha clamped to [0,1], NaN skipped";
  EXPECT_EQ(apc::ExactTransmittance(samples, 5.0), 0.0);
  EXPECT_EQ(apc::ExactTransmittance(samples, 1.5), 1.0);
  EXPECT_EQ(apc::CompositeOrdered({}), (apc::RGBA{ 0.0, 0.0, 0.0, 0.0 }));
}

} // namespace
