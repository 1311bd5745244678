// walk::ClipRaysWeighted, the clipping that also finds each kept pair's end weights (four rays
// per AVX2 instruction): the same intervals and kept rays as ClipRays without a lattice, those
// with a lattice point in Hits and the others in MidHits, in order, and the weights
// EndWeightsOf gives from the pair's interval, its end clipped again without the
// opaque stop, bit for bit. The weighted marcher's lanes take their weights from it, so a
// weight one ulp off would change a sample no test of images could see.
#include "apcRayClip.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace
{

using apc::FacePlane;
using apc::walk::CellPlanes;
using apc::walk::ClippedRays;
using apc::walk::ClippedWeights;
using apc::walk::EndWeights;
using apc::walk::Lattice;
using apc::walk::RayRect;
using apc::walk::RaySetup;
using apc::walk::TileRays;

using WeightedForm = int (*)(const CellPlanes&, const TileRays&, const RayRect&, const double*,
  double, const Lattice&, ClippedRays&, ClippedWeights&);

bool SameBits(double a, double b)
{
  return std::memcmp(&a, &b, sizeof(double)) == 0;
}

struct Counts
{
  int Mid = 0;       // pairs without a lattice point
  int Single = 0;    // with one
  int Several = 0;   // with more
  int CutAtStop = 0; // pairs the stop cut short (their weights from the uncut end)
};

// Random cells (4 to 6 planes) against a tile of perspective or parallel rays, some with a
// lattice offset, over random rectangles, with and without an opaque stop; spacings from a
// tenth of the cells to several times them, so that pairs hold none, one or many samples.
void CheckForm(WeightedForm form, Counts& counts)
{
  constexpr int kWidth = 16;
  constexpr double kFar = 8.0;
  std::mt19937 rng(53);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> pixel(0, kWidth - 1);
  for (int trial = 0; trial < 3000; ++trial)
  {
    const bool shared = trial % 2 == 0;
    std::vector<RaySetup> rays(kWidth * kWidth);
    for (size_t p = 0; p < rays.size(); ++p)
    {
      RaySetup& ray = rays[p];
      for (int d = 0; d < 3; ++d)
      {
        ray.O[d] = shared ? rays[0].O[d] : 3 * u(rng);
        ray.D[d] = u(rng);
      }
      ray.End = p % 7 == 3 ? 0.5 : 10.0;
      ray.Offset = p % 3 == 0 ? 0.5 * (u(rng) + 1.0) : 0.0;
    }
    const int count = 4 + trial % 3;
    FacePlane planes[6];
    for (int p = 0; p < count; ++p)
    {
      for (int d = 0; d < 3; ++d)
      {
        planes[p].Normal[d] = static_cast<float>(u(rng));
      }
      planes[p].Offset = static_cast<float>(u(rng));
      // The mesh's conversion stores which copy of a plane keeps a parallel ray.
      planes[p] = FacePlane::Make(planes[p].Normal, planes[p].Offset);
    }
    CellPlanes cell;
    cell.Set(planes, count, rays[0], shared);
    TileRays packed;
    packed.Set(rays.data(), kWidth * kWidth, kFar);
    const bool withStop = trial % 3 != 0;
    const double near = 0.1 * (trial % 4);
    std::vector<double> stop(kWidth * kWidth, std::numeric_limits<double>::infinity());
    for (double& s : stop)
    {
      s = withStop && rng() % 2 ? (rng() % 8 == 0 ? near : 2.0 * (u(rng) + 1.0)) : s;
    }
    const Lattice grid(trial % 5 == 0 ? 0.1 : 0.011 * (1 + trial % 200));
    int i0 = pixel(rng), i1 = pixel(rng), j0 = pixel(rng), j1 = pixel(rng);
    if (i0 > i1)
    {
      std::swap(i0, i1);
    }
    if (j0 > j1)
    {
      std::swap(j0, j1);
    }
    const RayRect rect{ j0 * kWidth + i0, i1 - i0 + 1, j1 - j0 + 1, kWidth };
    const double* stops = withStop ? stop.data() : nullptr;
    ClippedRays plain;
    const int n = apc::walk::ClipRaysScalar(cell, packed, rect, stops, near, nullptr, plain);
    ClippedRays out;
    ClippedWeights weights;
    const int sampled = form(cell, packed, rect, stops, near, grid, out, weights);
    ASSERT_EQ(sampled + weights.MidCount, n) << "trial " << trial;
    int h1 = 0;
    int h2 = 0;
    for (int h = 0; h < n; ++h)
    {
      const int l = plain.Hits[h];
      // The kept ray is the next of one of the two lists.
      const bool inHits = h1 < sampled && out.Hits[h1] == l;
      const bool inMids = h2 < weights.MidCount && weights.MidHits[h2] == l;
      ASSERT_TRUE(inHits != inMids) << "trial " << trial << " ray " << l;
      h1 += inHits ? 1 : 0;
      h2 += inMids ? 1 : 0;
      ASSERT_TRUE(SameBits(out.Tin[l], plain.Tin[l]) && SameBits(out.Tout[l], plain.Tout[l]))
        << "trial " << trial << " ray " << l;
      // The pair's own end: the cell clipped from the ray's end, without the stop.
      double tin = 0;
      double end = std::min(rays[l].End, kFar);
      cell.Clip(rays[l], tin, end);
      counts.CutAtStop += end != out.Tout[l] ? 1 : 0;
      const EndWeights w = apc::walk::EndWeightsOf(grid, out.Tin[l], end, rays[l].Offset);
      const EndWeights got = weights.Of(l);
      ASSERT_EQ(got.Mid, w.Mid) << "trial " << trial << " ray " << l;
      ASSERT_EQ(inMids, w.Mid) << "trial " << trial << " ray " << l;
      ASSERT_EQ(got.First, w.First) << "trial " << trial << " ray " << l;
      if (w.Mid)
      {
        ++counts.Mid;
        ASSERT_TRUE(SameBits(got.MidT, w.MidT) && SameBits(got.MidOffset, w.MidOffset) &&
          SameBits(got.MidWeight, w.MidWeight))
          << "trial " << trial << " ray " << l;
        continue;
      }
      counts.Single += w.Last == w.First ? 1 : 0;
      counts.Several += w.Last > w.First ? 1 : 0;
      ASSERT_EQ(got.Last, w.Last) << "trial " << trial << " ray " << l;
      ASSERT_TRUE(SameBits(got.FirstWeight, w.FirstWeight)) << "trial " << trial << " ray " << l;
      ASSERT_TRUE(SameBits(got.LastWeight, w.LastWeight)) << "trial " << trial << " ray " << l;
    }
  }
}

void CheckEveryCase(WeightedForm form)
{
  Counts counts;
  CheckForm(form, counts);
  EXPECT_GT(counts.Mid, 500);
  EXPECT_GT(counts.Single, 1000);
  EXPECT_GT(counts.Several, 5000);
  EXPECT_GT(counts.CutAtStop, 300);
}

} // namespace

TEST(ClipRaysWeighted, ScalarMatchesEndWeightsOf)
{
  CheckEveryCase(apc::walk::ClipRaysWeightedScalar);
  CheckEveryCase(apc::walk::ClipRaysWeighted);
}

TEST(ClipRaysWeighted, Avx2MatchesEndWeightsOf)
{
  if (!apc::walk::HasAvx2())
  {
    GTEST_SKIP() << "no AVX2 on this processor";
  }
  CheckEveryCase(apc::walk::ClipRaysWeightedAvx2);
}
