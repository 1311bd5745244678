// Micro-benchmark of MBOIT pass 2's transmittance query (apc::MomentTransmittance<N>): the
// per-pixel set-up and the query, as pass 2 uses them.
//
//   apcTransmittanceBenchmark [pixels] [repeats] [4|6|8]
//
// Pixels are volume rays: 5-40 samples at random depths in [-1,1] with absorbances
// log-uniform in [1e-3, 3], accumulated into N power moments; every pixel is queried at its
// own sample depths, as pass 2 does. The pixels depend only on the seed, so another build of
// this program sees the very same queries. Prints CSV: moments, pixels, queries, ns/query
// (best of the repeats, 1 thread), ns/pixel of the set-up, bytes per pixel, fallbacks, and
// the mean transmittance over the queries plus a sweep of 65 depths per pixel (to 17 digits:
// two builds that answer alike print the same).
//
// Before/after: run-transmittance-benchmark.sh with APC_BASELINE_BUILD runs another build's
// copy of this program alternately with this one and prints the ratios; no old code is kept
// here. Not run by ctest.

#include "apcMomentTransmittance.h"
#include "apcPowerMoments.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <vector>

namespace
{

struct Pixel
{
  std::vector<double> Sums;
  std::vector<double> Depths;
};

template <int N>
std::vector<Pixel> MakePixels(int count, unsigned seed)
{
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> samples(5, 40);
  std::uniform_real_distribution<double> depth(-1.0, 1.0);
  std::uniform_real_distribution<double> logAbsorbance(std::log(1e-3), std::log(3.0));
  std::vector<Pixel> pixels(count);
  for (Pixel& p : pixels)
  {
    p.Sums.assign(N + 1, 0.0);
    const int n = samples(rng);
    for (int i = 0; i < n; ++i)
    {
      const double z = depth(rng);
      p.Depths.push_back(z);
      apc::AccumulatePowerMoments<N>(p.Sums.data(), z, std::exp(logAbsorbance(rng)));
    }
    // A ray visits its samples front to back.
    std::sort(p.Depths.begin(), p.Depths.end());
  }
  return pixels;
}

using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point a, Clock::time_point b)
{
  return std::chrono::duration<double>(b - a).count();
}

// Best-of-repeats seconds for querying every pixel at its depths; the sum defeats dead code
// elimination.
template <typename T>
double TimeQueries(
  const std::vector<T>& objects, const std::vector<Pixel>& pixels, int repeats, double& sink)
{
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < repeats; ++r)
  {
    double sum = 0.0;
    const Clock::time_point start = Clock::now();
    for (std::size_t p = 0; p < pixels.size(); ++p)
    {
      for (const double z : pixels[p].Depths)
      {
        sum += objects[p].Query(z).Transmittance;
      }
    }
    best = std::min(best, Seconds(start, Clock::now()));
    sink += sum;
  }
  return best;
}

template <typename T, int N>
double TimeBuild(const std::vector<Pixel>& pixels, int repeats, std::vector<T>& objects)
{
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < repeats; ++r)
  {
    objects.clear();
    objects.reserve(pixels.size());
    const Clock::time_point start = Clock::now();
    for (const Pixel& p : pixels)
    {
      objects.emplace_back(p.Sums.data());
    }
    best = std::min(best, Seconds(start, Clock::now()));
  }
  return best;
}

template <int N>
void Run(int pixelCount, int repeats)
{
  const std::vector<Pixel> pixels = MakePixels<N>(pixelCount, 1234u + N);
  std::size_t queries = 0;
  for (const Pixel& p : pixels)
  {
    queries += p.Depths.size();
  }
  std::vector<apc::MomentTransmittance<N>> objects;
  const double build = TimeBuild<apc::MomentTransmittance<N>, N>(pixels, repeats, objects);

  // What the queries answer, over the benchmark's depths plus a dense sweep of each pixel.
  double sum = 0.0;
  long answers = 0;
  long fallbacks = 0;
  for (std::size_t p = 0; p < pixels.size(); ++p)
  {
    std::vector<double> zs = pixels[p].Depths;
    for (int i = 0; i <= 64; ++i)
    {
      zs.push_back(-1.0 + i / 32.0);
    }
    for (const double z : zs)
    {
      const apc::TransmittanceQuery q = objects[p].Query(z);
      sum += q.Transmittance;
      fallbacks += q.Fallback;
      ++answers;
    }
  }

  double sink = 0.0;
  const double time = TimeQueries(objects, pixels, repeats, sink);
  std::printf("%d,%d,%zu,%.2f,%.1f,%zu,%ld,%.17g,%.3g\n", N, pixelCount, queries,
    1e9 * time / queries, 1e9 * build / pixelCount, sizeof(apc::MomentTransmittance<N>), fallbacks,
    sum / answers, sink * 0.0);
}

} // namespace

int main(int argc, char** argv)
{
  const int pixels = argc > 1 ? std::atoi(argv[1]) : 4000;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 40;
  std::printf("moments,pixels,queries,ns_per_query,ns_per_build,bytes,fallbacks,mean_T,zero\n");
  const int only = argc > 3 ? std::atoi(argv[3]) : 0; // one number of moments, for perf
  if (only == 0 || only == 4)
  {
    Run<4>(pixels, repeats);
  }
  if (only == 0 || only == 6)
  {
    Run<6>(pixels, repeats);
  }
  if (only == 0 || only == 8)
  {
    Run<8>(pixels, repeats);
  }
  return 0;
}
