// Moment sums of sample sets and rays shared by the moment tests (TestMomentTransmittance,
// TestMomentReferences, TestMomentQueries): 4, 6 and 8 power moments as gtest type parameters.
#ifndef apcMomentTestRays_h
#define apcMomentTestRays_h

#include "apcMomentTransmittance.h"
#include "apcOrderedReference.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <type_traits>
#include <vector>

namespace apctest
{

using MomentOrders = ::testing::Types<std::integral_constant<int, 4>,
  std::integral_constant<int, 6>, std::integral_constant<int, 8>>;

template <int N>
apc::PowerMoments<N> MomentsOf(const std::vector<apc::Sample>& samples)
{
  apc::PowerMoments<N> m;
  for (const apc::Sample& s : samples)
  {
    m.AddAlpha(s.Depth, s.Alpha);
  }
  return m;
}

template <int N>
apc::MomentSettings<N> WithBeta(double beta)
{
  apc::MomentSettings<N> settings;
  settings.Overestimation = beta;
  return settings;
}

// Random layers: depths uniform in [-1, 1], alphas uniform in [0, 0.8].
inline std::vector<apc::Sample> RandomSamples(std::mt19937_64& rng, int count)
{
  std::uniform_real_distribution<double> depth(-1.0, 1.0);
  std::uniform_real_distribution<double> alpha(0.0, 0.8);
  std::vector<apc::Sample> samples(count);
  for (apc::Sample& s : samples)
  {
    s.Depth = depth(rng);
    s.Alpha = alpha(rng);
  }
  return samples;
}

// Volume rays as pass 2 sees them: 5-40 samples, absorbances log-uniform in [1e-3, 3].
inline std::vector<double> RayMoments(std::mt19937_64& rng, int order, std::vector<double>& depths)
{
  std::uniform_int_distribution<int> count(5, 40);
  std::uniform_real_distribution<double> depth(-1.0, 1.0);
  std::uniform_real_distribution<double> logAbsorbance(std::log(1e-3), std::log(3.0));
  std::vector<double> sums(order + 1, 0.0);
  depths.clear();
  const int n = count(rng);
  for (int i = 0; i < n; ++i)
  {
    const double z = depth(rng);
    const double a = std::exp(logAbsorbance(rng));
    depths.push_back(z);
    double w = a;
    for (int k = 0; k <= order; ++k)
    {
      sums[k] += w;
      w *= z;
    }
  }
  return sums;
}

} // namespace apctest

#endif
