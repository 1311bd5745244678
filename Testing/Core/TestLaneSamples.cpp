// Pass 1's samples of four rays at a time (LaneSamplesAvx2) against the walker's scalar
// sample loop, written out here with the same calls (LinearRayOrigin, LinearRayDirection,
// p0 + t dp, LinearScalarAt or a twisted pyramid's PyramidScalarAt, the clamp,
// TransferTable::Lookup): every depth, scalar and absorbance the same bit for bit, on random
// distorted cells, rays, lattice offsets and tables; and with pass 1's own stop, each lane's
// opaque bin (RayProgress::BinOf). Where the processor has AVX-512, the eight-wide kernel
// (LaneSamplesAvx512: two groups of four at once) against the four-wide one, bit for bit.
#include "apcCellInterpolation.h"
#include "apcLaneSamples.h"
#include "apcOpaqueBins.h"
#include "apcRayClip.h"
#include "apcRayWalk.h"
#include "apcTestCells.h"
#include "apcTransferTable.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <vector>

namespace
{

using apc::CellCorners;
using apc::CellInterpolator;
using apc::CellShape;

// A table over [0, 10] whose opacity is zero over random stretches (transparent samples).
apc::TransferTable RandomTable(std::mt19937& rng)
{
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int entries = 16 + static_cast<int>(u(rng) * 200);
  std::vector<std::array<float, 3>> colours(entries, { 0.5f, 0.5f, 0.5f });
  std::vector<double> opacities(entries);
  for (auto& o : opacities)
  {
    o = u(rng) < 0.3 ? 0.0 : u(rng);
  }
  return apc::TransferTable(0.0, 10.0, colours, opacities, 0.05, 0.3);
}

bool SameBits(double a, double b)
{
  return std::memcmp(&a, &b, sizeof a) == 0;
}
bool SameBits(float a, float b)
{
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// Whether PyramidCoordinates took its quadratic's other root at a (its w is not the first
// root's, written out as it forms that root).
bool TookOtherRoot(const CellInterpolator& interpolator, const double a[3])
{
  const auto& g = interpolator.GetPyramidG();
  const double A = g[2] - g[0] * g[1];
  const double B = 1.0 - a[2] + a[0] * g[1] + a[1] * g[0];
  const double C = a[0] * a[1];
  const double root = std::sqrt(std::max(B * B + 4.0 * A * C, 0.0));
  const double denom = B >= 0 ? B + root : B - root;
  const double first = denom != 0 ? 2.0 * C / denom : 0.0;
  double q[3];
  double w = 0;
  interpolator.PyramidCoordinates(a, q, w);
  return !SameBits(w, first) && !(std::isnan(w) && std::isnan(first));
}

// Random cells, each with four rays from one eye (a random lattice index to start from, a
// random end, unused lanes included); overflow gives some lanes a direction whose
// coordinates overflow, so that their scalars are infinite or NaN. twisted: pyramids only,
// by their closed-form inverse (LaneCell::Twisted), with rays aimed through the cell.
void CheckLanes(double distortion, bool jitter, bool overflow, bool twisted = false)
{
  std::mt19937 rng(1234);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const CellShape shapes[] = { CellShape::Hexahedron, CellShape::Tetra, CellShape::Wedge,
    CellShape::Pyramid };
  const double inf = std::numeric_limits<double>::infinity();
  int compared = 0;
  int visible = 0;
  int binsCompared = 0;
  int binsAboveZero = 0;
  int otherRoots = 0;    // twisted: samples whose closed form took the quadratic's other root
  int eightCompared = 0; // steps of LaneSamplesAvx512 compared with LaneSamplesAvx2's
  for (int trial = 0; trial < 2000; ++trial)
  {
    const CellShape shape = twisted ? CellShape::Pyramid : shapes[trial % 4];
    const CellCorners corners = apctest::DistortedCell(shape, distortion, rng);
    CellInterpolator interpolator;
    interpolator.Set(corners);
    const apc::TransferTable table = RandomTable(rng);
    const apc::TransferTable::Layout layout = table.GetLayout();
    const apc::walk::Lattice lattice(0.05 + 0.2 * unit(rng));
    const double eye[3] = { 50.0 + 10 * u(rng), 50.0 + 10 * u(rng), 40.0 + 5 * u(rng) };

    apc::walk::LaneCell cell;
    cell.Pyramid = shape == CellShape::Pyramid;
    cell.Twisted = twisted;
    const auto& g = interpolator.GetPyramidG();
    std::copy(g, g + 3, cell.G);
    const auto& inverse = interpolator.GetLinearInverse();
    double p0[3];
    interpolator.LinearRayOrigin(eye, p0);
    for (int i = 0; i < 3; ++i)
    {
      std::copy(inverse[i], inverse[i] + 3, cell.Inverse[i]);
      cell.P0[i] = p0[i];
    }
    const auto& coefficients = interpolator.GetScalarCoefficients();
    std::copy(coefficients, coefficients + 8, cell.SC);
    // A range narrower than the corners' sometimes, so that the clamp acts.
    cell.Lo = trial % 2 ? 2.0 + unit(rng) : 0.0;
    cell.Hi = trial % 2 ? 7.0 + unit(rng) : 10.0;
    cell.Table = layout;
    cell.Spacing = lattice.Spacing;

    // Pass 1's own stop on every other trial: bins around the rays' indices (a bin or two
    // per call's steps, so that some lanes start past the last end and some before the
    // first).
    auto progress = std::make_unique<apc::walk::RayProgress>();
    apc::OpaqueBins bins;
    if (trial % 2 == 0)
    {
      const double nearT = lattice.Spacing * std::floor(30.0 + 40.0 * unit(rng));
      const double span = 2.0 + 150.0 * unit(rng);
      bins = apc::OpaqueBins::Make(1.0, nearT, nearT + span * lattice.Spacing, lattice.Spacing);
      progress->Begin(1, &bins);
      cell.BinEnds = progress->BinEnds;
    }
    // The cell's constants formed once, then read by several calls with other rays (as the
    // walker's calls of one cell do).
    apc::walk::LaneCellVectors vectors;
    apc::walk::SetUpLaneCell(cell, vectors);
    // The previous call's rays and four-wide steps: the eight-wide kernel's second group.
    apc::walk::LaneRays previous;
    apc::walk::LaneSteps previousSteps;
    int previousCount = -1;
    for (int call = 0; call < 3; ++call)
    {
      apc::walk::LaneRays rays;
      for (int i = 0; i < 4; ++i)
      {
        double k = std::floor(40.0 + 60.0 * unit(rng));
        double through[3] = { 0, 0, 0 };
        if (twisted)
        {
          // Towards a point in or near the cell (corners at about 50 to 53), from a few steps
          // before it.
          double length = 0;
          for (int d = 0; d < 3; ++d)
          {
            through[d] = 50.0 + 3.0 * unit(rng) - eye[d];
            length += through[d] * through[d];
          }
          length = std::sqrt(length);
          for (auto& d : through)
          {
            d /= length;
          }
          k = std::floor(length / lattice.Spacing - 8.0 * unit(rng));
        }
        rays.K[i] = k;
        rays.Offset[i] = jitter ? unit(rng) : 0.0;
        const double t0 = lattice.At(static_cast<int64_t>(k), rays.Offset[i]);
        // Up to 12 samples (past a call's kLaneSteps), none, or an unused lane.
        const double r = unit(rng);
        rays.Tout[i] = r < 0.1 ? -inf : t0 + lattice.Spacing * 12.0 * unit(rng);
        for (int d = 0; d < 3; ++d)
        {
          rays.D[d][i] = twisted ? through[d] : u(rng);
        }
        if (overflow && i == trial % 4)
        {
          rays.D[trial % 3][i] = (trial % 2 ? 1 : -1) * 1e307;
        }
      }
      apc::walk::LaneSteps steps;
      const int n = apc::walk::LaneSamplesAvx2(vectors, rays, steps);
      if (apc::walk::HasAvx512())
      {
        // Two groups at once: this call's rays low, the previous call's (or these again) high.
        const bool again = previousCount < 0;
        apc::walk::LaneSteps low;
        apc::walk::LaneSteps high;
        const int n8 =
          apc::walk::LaneSamplesAvx512(vectors, rays, again ? rays : previous, low, high);
        const int other = again ? n : previousCount;
        ASSERT_EQ(n8, std::max(n, other)) << "trial " << trial;
        const apc::walk::LaneSteps* expected[2] = { &steps, again ? &steps : &previousSteps };
        const apc::walk::LaneSteps* got[2] = { &low, &high };
        const int counts[2] = { n, other };
        for (int g = 0; g < 2; ++g)
        {
          for (int i = 0; i < 4; ++i)
          {
            if (cell.BinEnds)
            {
              ASSERT_EQ(got[g]->Bin[i], expected[g]->Bin[i]) << "trial " << trial;
            }
            for (int s = 0; s < counts[g]; ++s)
            {
              const double a = got[g]->Scalar[s][i];
              const double b = expected[g]->Scalar[s][i];
              ASSERT_TRUE(SameBits(got[g]->T[s][i], expected[g]->T[s][i]))
                << "trial " << trial << " group " << g << " lane " << i << " step " << s;
              ASSERT_TRUE(SameBits(a, b) || (std::isnan(a) && std::isnan(b)))
                << "trial " << trial << " group " << g << " lane " << i << " step " << s;
              ASSERT_TRUE(SameBits(got[g]->Absorbance[s][i], expected[g]->Absorbance[s][i]))
                << "trial " << trial << " group " << g << " lane " << i << " step " << s;
              ++eightCompared;
            }
          }
        }
      }
      previous = rays;
      previousSteps = steps;
      previousCount = n;
      if (cell.BinEnds)
      {
        for (int i = 0; i < 4; ++i)
        {
          const int64_t k = static_cast<int64_t>(rays.K[i]);
          ASSERT_EQ(steps.Bin[i], progress->BinOf(k)) << "trial " << trial << " lane " << i;
          binsCompared += 1;
          binsAboveZero += steps.Bin[i] > 0 && steps.Bin[i] < apc::OpaqueBins::kBins - 1 ? 1 : 0;
        }
      }

      // The walker's scalar loop, lane by lane.
      int expected = 0;
      for (int s = 0; s < apc::walk::kLaneSteps; ++s)
      {
        bool any = false;
        for (int i = 0; i < 4; ++i)
        {
          const int64_t k = static_cast<int64_t>(rays.K[i]) + s;
          any = any || lattice.At(k, rays.Offset[i]) < rays.Tout[i];
        }
        if (!any)
        {
          break;
        }
        ++expected;
      }
      ASSERT_EQ(n, expected) << "trial " << trial;
      for (int i = 0; i < 4; ++i)
      {
        const double d[3] = { rays.D[0][i], rays.D[1][i], rays.D[2][i] };
        double dp[3];
        interpolator.LinearRayDirection(d, dp);
        for (int s = 0; s < n; ++s)
        {
          const double t = lattice.At(static_cast<int64_t>(rays.K[i]) + s, rays.Offset[i]);
          if (!(t < rays.Tout[i]))
          {
            break;
          }
          double pcoords[3];
          for (int a = 0; a < 3; ++a)
          {
            pcoords[a] = p0[a] + t * dp[a];
          }
          const double interpolated =
            twisted ? interpolator.PyramidScalarAt(pcoords) : interpolator.LinearScalarAt(pcoords);
          const double scalar = std::min(std::max(interpolated, cell.Lo), cell.Hi);
          if (twisted)
          {
            otherRoots += TookOtherRoot(interpolator, pcoords) ? 1 : 0;
          }
          const apc::TransferSample sample = apc::TransferTable::Lookup(layout, scalar);
          ASSERT_TRUE(SameBits(steps.T[s][i], t)) << "trial " << trial << " lane " << i;
          ASSERT_TRUE(SameBits(steps.Scalar[s][i], scalar) ||
            (std::isnan(steps.Scalar[s][i]) && std::isnan(scalar)))
            << "trial " << trial << " lane " << i << ": " << steps.Scalar[s][i] << " vs " << scalar;
          ASSERT_TRUE(SameBits(steps.Absorbance[s][i], sample.Absorbance))
            << "trial " << trial << " lane " << i << ": " << steps.Absorbance[s][i] << " vs "
            << sample.Absorbance;
          ++compared;
          visible += sample.Absorbance > 0 ? 1 : 0;
        }
      }
    }
  }
  // Enough samples, and both visible and transparent ones.
  EXPECT_GT(compared, 5000);
  EXPECT_GT(visible, compared / 4);
  EXPECT_LT(visible, compared);
  // The bins of pass 1's own stop (LaneSteps::Bin): inside, before and past the ends.
  EXPECT_GT(binsCompared, 1000);
  EXPECT_GT(binsAboveZero, binsCompared / 4);
  // The second root's blend is exercised.
  EXPECT_TRUE(!twisted || otherRoots > 100) << otherRoots << " other roots";
  // The eight-wide kernel was compared wherever the processor has it.
  EXPECT_TRUE(!apc::walk::HasAvx512() || eightCompared > 5000) << eightCompared;
}

} // namespace

TEST(LaneSamples, FourRaysMatchTheScalarLoopBitForBit)
{
  if (!apc::walk::HasAvx2())
  {
    GTEST_SKIP() << "no AVX2";
  }
  CheckLanes(0.05, false, false);
}

TEST(LaneSamples, JitteredAndDistortedCellsMatchBitForBit)
{
  if (!apc::walk::HasAvx2())
  {
    GTEST_SKIP() << "no AVX2";
  }
  CheckLanes(0.2, true, false);
}

TEST(LaneSamples, TwistedPyramidsClosedFormMatchesBitForBit)
{
  if (!apc::walk::HasAvx2())
  {
    GTEST_SKIP() << "no AVX2";
  }
  CheckLanes(0.3, false, false, true);
  CheckLanes(0.3, true, true, true);
}

TEST(LaneSamples, ScalarsThatAreNotFiniteGiveNoAbsorbance)
{
  if (!apc::walk::HasAvx2())
  {
    GTEST_SKIP() << "no AVX2";
  }
  CheckLanes(0.05, false, true);
}

// Each lane's bin against BinOf for bins of every width up to OpaqueBins' largest (kMaxSpan /
// kBins), lanes at each bin end, one before it and one past it: (K - Base) times the width's
// rounded inverse falls just below an integer for some widths (49 is the first), which the
// bin's correction must undo.
TEST(LaneSamples, BinsOfEveryWidthMatchBinOfAtTheirEnds)
{
  if (!apc::walk::HasAvx2())
  {
    GTEST_SKIP() << "no AVX2";
  }
  std::mt19937 rng(7);
  const apc::TransferTable table = RandomTable(rng);
  apc::walk::LaneCell cell{};
  cell.Pyramid = false;
  for (int i = 0; i < 3; ++i)
  {
    cell.Inverse[i][i] = 1.0;
  }
  cell.Lo = 0.0;
  cell.Hi = 10.0;
  cell.Table = table.GetLayout();
  cell.Spacing = 0.5;
  auto progress = std::make_unique<apc::walk::RayProgress>();
  int compared = 0;
  const int widest = static_cast<int>(apc::OpaqueBins::kMaxSpan) / apc::OpaqueBins::kBins;
  for (int width = 1; width <= widest; ++width)
  {
    // Bins from lattice index 37 on, width steps each.
    const double span = static_cast<double>(width * apc::OpaqueBins::kBins);
    const apc::OpaqueBins bins =
      apc::OpaqueBins::Make(1.0, 37 * cell.Spacing, (37 + span) * cell.Spacing, cell.Spacing);
    ASSERT_EQ(bins.Width, width);
    progress->Begin(1, &bins);
    cell.BinEnds = progress->BinEnds;
    apc::walk::LaneCellVectors vectors;
    apc::walk::SetUpLaneCell(cell, vectors);
    for (int end = 0; end < apc::OpaqueBins::kBins; end += 1)
    {
      apc::walk::LaneRays rays{};
      const int64_t at = bins.Base + static_cast<int64_t>(end) * width;
      const int64_t k[4] = { at - 1, at, at + 1, at + width - 1 };
      for (int i = 0; i < 4; ++i)
      {
        rays.K[i] = static_cast<double>(k[i]);
        rays.Tout[i] = -std::numeric_limits<double>::infinity();
        rays.D[0][i] = 1.0;
      }
      apc::walk::LaneSteps steps;
      apc::walk::LaneSamplesAvx2(vectors, rays, steps);
      for (int i = 0; i < 4; ++i)
      {
        ASSERT_EQ(steps.Bin[i], progress->BinOf(k[i])) << "width " << width << " k " << k[i];
        compared += 1;
      }
    }
  }
  EXPECT_EQ(compared, widest * apc::OpaqueBins::kBins * 4);
}
