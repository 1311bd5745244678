// The lanes' hand-over four pixels at a time (walk::LaneMomentsAvx2, with Moments::LaneRunEnd
// in the walker; LaneWeightedMomentsAvx2 with end weights) against the scalar path: each lane's
// five sums, its records' warped depths, its quanta, its steps and visible steps the same bit for
// bit as Moments::RunAdd and OpaqueBins::Quanta per visible sample, on random steps (steps past a
// lane's end, clear steps, unused lanes, jittered depths and indices outside the depth warp's
// table); and the marcher with the lanes against its scalar sample loops (pass 1's moments, the
// opaque profile and cut, pass 2 from the cache) on a block of distorted hexahedra and pyramids.
// Where the processor has AVX-512, the eight-wide hand-over (LaneMomentsAvx512: two groups at
// once) against the four-wide one, bit for bit.
#include "apcCellMesh.h"
#include "apcDepthWarp.h"
#include "apcLaneMoments.h"
#include "apcOpaqueBins.h"
#include "apcPowerMoments.h"
#include "apcRayCamera.h"
#include "apcRayClip.h"
#include "apcTestBlock.h"
#include "apcTransferTable.h"
#include "apcVolumeRayMarcher.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace
{

using apc::walk::kLaneSteps;

bool Same(double a, double b)
{
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// Weighted: LaneWeightedMomentsAvx2 against RunAddWeighted's float product per step (random
// first and last indices before, inside and past the call's steps, equal ones as a pair
// without a lattice point has, weights of 0 and 1 among them), with each step's record weight.
void CheckAgainstRunAdd(bool weighted)
{
  std::mt19937 rng(weighted ? 11 : 7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double spacing = 0.0137;
  const apc::LogDepthWarp log(1.0, 9.0);
  const apc::LatticeDepthWarp warp(log, spacing);
  const int64_t base = warp.GetBase();
  const int64_t entries = warp.GetNumberOfEntries();
  ASSERT_GT(entries, 100);
  const apc::OpaqueBins bins = apc::OpaqueBins::Make(2.5, 1.0, 9.0, spacing);
  ASSERT_TRUE(bins.Active());
  int visibleSteps = 0;
  int jittered = 0;
  int outside = 0;
  int opaqueQuanta = 0;
  int firstSteps = 0;
  int lastSteps = 0;
  int eightCompared = 0; // trials whose eight-wide hand-over was compared
  for (int trial = 0; trial < 20000; ++trial)
  {
    apc::walk::LaneRays rays;
    apc::walk::LaneSteps steps;
    apc::walk::LaneWeights weights;
    const int taken = 1 + static_cast<int>(u(rng) * kLaneSteps) % kLaneSteps;
    const bool withQuanta = trial % 3 != 0;
    std::array<std::array<double, 5>, 4> sums;
    const double* pointers[4];
    for (int i = 0; i < 4; ++i)
    {
      // Mostly inside the table, some before or past it.
      const double where = u(rng);
      int64_t k = base + static_cast<int64_t>(u(rng) * static_cast<double>(entries));
      if (where < 0.05)
      {
        k = base - 1 - static_cast<int64_t>(u(rng) * 20);
      }
      else if (where < 0.1)
      {
        k = base + entries - 4 + static_cast<int64_t>(u(rng) * 8);
      }
      rays.K[i] = static_cast<double>(k);
      // The pair's ends: its first index up to two steps before the call's first or past its
      // last, its last from that on (equal to it in a fifth of the lanes).
      const int64_t first = k - 2 + static_cast<int64_t>(u(rng) * (kLaneSteps + 4));
      const int64_t last =
        first + (u(rng) < 0.2 ? 0 : 1 + static_cast<int64_t>(u(rng) * (kLaneSteps + 2)));
      weights.First[i] = static_cast<double>(first);
      weights.Last[i] = static_cast<double>(last);
      const auto weight = [&]()
      {
        const double v = u(rng);
        return v < 0.05 ? 0.f : (v < 0.1 ? 1.f : static_cast<float>(u(rng)));
      };
      weights.FirstWeight[i] = weight();
      weights.LastWeight[i] = weight();
      // Jittered lanes' depths are not k times the spacing.
      rays.Offset[i] = u(rng) < 0.2 ? u(rng) - 0.5 : 0.0;
      const double tout =
        (static_cast<double>(k) + rays.Offset[i] + u(rng) * (kLaneSteps + 1)) * spacing;
      rays.Tout[i] = u(rng) < 0.05 ? -std::numeric_limits<double>::infinity() : tout;
      for (int s = 0; s < kLaneSteps; ++s)
      {
        steps.T[s][i] = (static_cast<double>(k + s) + rays.Offset[i]) * spacing;
        const double v = u(rng);
        // Clear steps, and past the end values that must not count (NaN, huge).
        float a = v < 0.25 ? 0.f : static_cast<float>(u(rng) * 3.0);
        if (!(steps.T[s][i] < rays.Tout[i]) && v > 0.8)
        {
          a = v > 0.9 ? std::numeric_limits<float>::quiet_NaN() : 1e30f;
        }
        steps.Absorbance[s][i] = a;
        steps.Scalar[s][i] = u(rng);
      }
      for (double& b : sums[i])
      {
        b = u(rng) < 0.3 ? 0.0 : u(rng) * 10.0 - 2.0;
      }
      pointers[i] = sums[i].data();
    }
    apc::walk::LaneMoments out;
    const double perAbsorbance = withQuanta ? bins.QuantaPerAbsorbance : 0.0;
    if (weighted)
    {
      apc::walk::LaneWeightedMomentsAvx2(
        steps, taken, rays, pointers, warp, perAbsorbance, weights, out);
    }
    else
    {
      apc::walk::LaneMomentsAvx2(steps, taken, rays, pointers, warp, perAbsorbance, out);
      if (apc::walk::HasAvx512())
      {
        // Eight lanes: this group low and the same lanes in reverse order high, each half the
        // same bit for bit as the four-wide hand-over of its group.
        apc::walk::LaneRays reversed;
        apc::walk::LaneSteps reversedSteps;
        const double* reversedSums[4];
        for (int i = 0; i < 4; ++i)
        {
          const int j = 3 - i;
          reversed.K[i] = rays.K[j];
          reversed.Offset[i] = rays.Offset[j];
          reversed.Tout[i] = rays.Tout[j];
          for (int d = 0; d < 3; ++d)
          {
            reversed.D[d][i] = rays.D[d][j];
          }
          for (int st = 0; st < kLaneSteps; ++st)
          {
            reversedSteps.T[st][i] = steps.T[st][j];
            reversedSteps.Scalar[st][i] = steps.Scalar[st][j];
            reversedSteps.Absorbance[st][i] = steps.Absorbance[st][j];
          }
          reversedSums[i] = pointers[j];
        }
        apc::walk::LaneMoments low;
        apc::walk::LaneMoments high;
        apc::walk::LaneMomentsAvx512(steps, reversedSteps, taken, rays, reversed, pointers,
          reversedSums, warp, perAbsorbance, low, high);
        for (int i = 0; i < 4; ++i)
        {
          const int j = 3 - i;
          for (int m = 0; m < 4; ++m)
          {
            ASSERT_TRUE(Same(low.Sums[i][m], out.Sums[i][m])) << "trial " << trial;
            ASSERT_TRUE(Same(high.Sums[i][m], out.Sums[j][m])) << "trial " << trial;
          }
          ASSERT_TRUE(Same(low.Sum4[i], out.Sum4[i])) << "trial " << trial;
          ASSERT_TRUE(Same(high.Sum4[i], out.Sum4[j])) << "trial " << trial;
          ASSERT_EQ(low.Steps[i], out.Steps[i]);
          ASSERT_EQ(high.Steps[i], out.Steps[j]);
          ASSERT_EQ(low.Visible[i], out.Visible[i]);
          ASSERT_EQ(high.Visible[i], out.Visible[j]);
          ASSERT_EQ(low.QuantaSum[i], out.QuantaSum[i]);
          ASSERT_EQ(high.QuantaSum[i], out.QuantaSum[j]);
          for (int st = 0; st < taken; ++st)
          {
            ASSERT_EQ(std::memcmp(&low.Z[st][i], &out.Z[st][i], sizeof(float)), 0);
            ASSERT_EQ(std::memcmp(&high.Z[st][i], &out.Z[st][j], sizeof(float)), 0);
            ASSERT_EQ(low.Quanta[st][i], out.Quanta[st][i]);
            ASSERT_EQ(high.Quanta[st][i], out.Quanta[st][j]);
          }
        }
        ++eightCompared;
      }
    }
    for (int i = 0; i < 4; ++i)
    {
      double expected[5];
      std::copy(sums[i].begin(), sums[i].end(), expected);
      int64_t count = 0;
      int64_t visible = 0;
      int64_t quanta = 0;
      for (int s = 0; s < taken && steps.T[s][i] < rays.Tout[i]; ++s)
      {
        ++count;
        const int64_t k = static_cast<int64_t>(rays.K[i]) + s;
        float a = steps.Absorbance[s][i];
        float weight = 1;
        if (weighted)
        {
          // The walker's scalar hand-over: a float weight and a float product.
          const int64_t first = static_cast<int64_t>(weights.First[i]);
          const int64_t last = static_cast<int64_t>(weights.Last[i]);
          weight = k == first ? weights.FirstWeight[i] : (k == last ? weights.LastWeight[i] : 1.f);
          firstSteps += k == first ? 1 : 0;
          lastSteps += k == last && k != first ? 1 : 0;
          a *= weight;
        }
        if (!(a > 0))
        {
          EXPECT_EQ(out.Quanta[s][i], 0u);
          if (weighted)
          {
            EXPECT_EQ(out.Weight[s][i], 1.f) << "trial " << trial << " lane " << i;
          }
          continue;
        }
        if (weighted)
        {
          // RunAddWeighted keeps a visible step's weight bit for bit.
          EXPECT_EQ(std::memcmp(&out.Weight[s][i], &weight, sizeof weight), 0)
            << "trial " << trial << " lane " << i << " step " << s;
        }
        const double t = steps.T[s][i];
        const double z = warp(k, t);
        jittered += rays.Offset[i] != 0 ? 1 : 0;
        outside += k < base || k >= base + entries ? 1 : 0;
        ++visibleSteps;
        apc::AccumulateCheckedPowerMoments<4>(expected, z, a);
        visible |= int64_t(1) << s;
        EXPECT_EQ(out.Z[s][i], static_cast<float>(z)) << "trial " << trial << " lane " << i;
        const uint32_t q = withQuanta ? bins.Quanta(a) : 0u;
        opaqueQuanta += q == apc::OpaqueBins::kOpaque ? 1 : 0;
        EXPECT_EQ(out.Quanta[s][i], q);
        quanta += q;
      }
      EXPECT_EQ(out.Steps[i], count) << "trial " << trial << " lane " << i;
      EXPECT_EQ(out.Visible[i], visible) << "trial " << trial << " lane " << i;
      EXPECT_EQ(out.QuantaSum[i], quanta) << "trial " << trial << " lane " << i;
      for (int m = 0; m < 4; ++m)
      {
        EXPECT_TRUE(Same(out.Sums[i][m], expected[m]))
          << "trial " << trial << " lane " << i << " moment " << m;
      }
      EXPECT_TRUE(Same(out.Sum4[i], expected[4])) << "trial " << trial << " lane " << i;
    }
  }
  // Each path was taken.
  EXPECT_GT(visibleSteps, 100000);
  EXPECT_GT(jittered, 1000);
  EXPECT_GT(outside, 1000);
  EXPECT_GT(opaqueQuanta, 100);
  EXPECT_TRUE(weighted || !apc::walk::HasAvx512() || eightCompared == 20000) << eightCompared;
  if (weighted)
  {
    EXPECT_GT(firstSteps, 5000);
    EXPECT_GT(lastSteps, 5000);
  }
}

TEST(LaneMoments, FourPixelsAtOnceMatchRunAddBitForBit)
{
  if (!apc::walk::HasAvx2())
  {
    GTEST_SKIP() << "no AVX2";
  }
  CheckAgainstRunAdd(false);
}

TEST(LaneMoments, WeightedStepsMatchRunAddWeightedBitForBit)
{
  if (!apc::walk::HasAvx2())
  {
    GTEST_SKIP() << "no AVX2";
  }
  CheckAgainstRunAdd(true);
}

constexpr int kSize = 64;

using Frame = apctest::BlockFrame;

Frame Render(const apc::CellMesh& mesh, bool lanes, bool stop, bool jitter, double spacing)
{
  // Clear below a quarter of the range and at its middle: runs with clear steps between
  // visible ones.
  const apc::TransferTable table(0.0, 1.0,
    { { 1.f, 0.f, 0.f }, { 0.f, 1.f, 0.f }, { 0.f, 0.f, 1.f }, { 1.f, 1.f, 0.f },
      { 0.f, 1.f, 1.f } },
    { 0.0, 0.0, 0.6, 0.0, 0.9 }, spacing, stop ? 0.02 : 1.0);
  const apc::RayCamera camera(
    { 0.2, 0.95, 4.0 }, { 0.0, 0.45, 0.0 }, { 0, 1, 0 }, 40.0, false, 1.0, kSize, kSize, 0.1, 20.0);
  return apctest::RenderBlockFrame(mesh, table, camera, static_cast<size_t>(kSize) * kSize, stop,
    [&](apc::VolumeRayMarcher& marcher)
    {
      marcher.SetSampleLanes(lanes);
      marcher.SetLatticeJitter(jitter);
    });
}

TEST(LaneMoments, MarcherLanesTakeTheScalarLoopsSamples)
{
  // Pass 1's moments, the opaque profile and cut, and pass 2 from the cache (its records)
  // with the lanes equal the scalar loops' bit for bit; at the finer spacing pairs hold more
  // than a call's kLaneSteps samples, and jittered lattices miss the depth warp's table.
  std::mt19937 rng(5);
  for (int mesh = 0; mesh < 4; ++mesh)
  {
    const apc::CellMesh block = apctest::DistortedBlock(rng);
    const double spacing = mesh < 2 ? 0.1 : 0.02;
    for (bool stop : { false, true })
    {
      for (bool jitter : { false, true })
      {
        const Frame lanes = Render(block, true, stop, jitter, spacing);
        const Frame scalar = Render(block, false, stop, jitter, spacing);
        EXPECT_GT(lanes.Pass1Samples, 1000);
        EXPECT_EQ(lanes.Pass1Samples, scalar.Pass1Samples);
        EXPECT_EQ(lanes.Pass2Samples, scalar.Pass2Samples);
        EXPECT_TRUE(lanes.Profile == scalar.Profile);
        int differ = 0;
        for (size_t v = 0; v < lanes.Moments.size(); ++v)
        {
          differ += Same(lanes.Moments[v], scalar.Moments[v]) ? 0 : 1;
        }
        for (size_t v = 0; v < lanes.Colour.size(); ++v)
        {
          differ += Same(lanes.Colour[v], scalar.Colour[v]) ? 0 : 1;
        }
        EXPECT_EQ(differ, 0) << "mesh " << mesh << (stop ? " with the stop" : "")
                             << (jitter ? " jittered" : "");
      }
    }
  }
}

} // namespace
