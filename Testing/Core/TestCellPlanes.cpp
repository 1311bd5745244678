// The marcher's clipping of a ray against a cell's face planes (walk::CellPlanes::Clip, two
// planes per SSE2 instruction, and walk::ClipRays, a tile's rays four per AVX2 instruction)
// against the plain per-plane form they replaced: the same interval, bit for bit, for any
// planes and rays, parallel ones included. Neighbouring cells and ranks rely on these exact
// numbers to give every lattice sample to exactly one cell.
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
using apc::walk::Lattice;
using apc::walk::RayRect;
using apc::walk::RaySetup;
using apc::walk::TileRays;

// The per-plane loop with a division and a branch per plane, as the marcher had it.
void ReferenceClip(
  const FacePlane* planes, int count, const RaySetup& ray, double& tin, double& tout)
{
  for (int p = 0; p < count && tin < tout; ++p)
  {
    const double n[3] = { planes[p].Normal[0], planes[p].Normal[1], planes[p].Normal[2] };
    const double denom = n[0] * ray.D[0] + n[1] * ray.D[1] + n[2] * ray.D[2];
    const double num = planes[p].Offset - (n[0] * ray.O[0] + n[1] * ray.O[1] + n[2] * ray.O[2]);
    if (denom < 0)
    {
      tin = std::max(tin, num / denom);
    }
    else if (denom > 0)
    {
      tout = std::min(tout, num / denom);
    }
    else if (num < 0 || (num == 0 && !apc::InPositiveHalf(planes[p].Normal)))
    {
      tout = -std::numeric_limits<double>::infinity();
    }
  }
}

bool SameBits(double a, double b)
{
  return std::memcmp(&a, &b, sizeof(double)) == 0;
}

} // namespace

TEST(CellPlanes, ClipMatchesPerPlaneDivision)
{
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> small(-2, 2);
  int nonEmpty = 0;
  int parallel = 0;
  for (int trial = 0; trial < 20000; ++trial)
  {
    RaySetup ray{};
    // Rays along an axis half of the time, so that planes with a zero component are
    // parallel to them exactly.
    const bool axis = trial % 2 == 0;
    for (int d = 0; d < 3; ++d)
    {
      ray.O[d] = axis ? small(rng) : 3 * u(rng);
      ray.D[d] = axis ? (d == trial % 3 ? 1.0 : 0.0) : u(rng);
    }
    const int count = 4 + trial % 3;
    FacePlane planes[6];
    for (int p = 0; p < count; ++p)
    {
      for (int d = 0; d < 3; ++d)
      {
        planes[p].Normal[d] = axis ? static_cast<float>(small(rng)) : static_cast<float>(u(rng));
      }
      planes[p].Offset = axis ? static_cast<float>(small(rng)) : static_cast<float>(u(rng));
      // The mesh's conversion stores which copy of a plane keeps a parallel ray.
      planes[p] = FacePlane::Make(planes[p].Normal, planes[p].Offset);
      parallel += planes[p].Normal[0] * ray.D[0] + planes[p].Normal[1] * ray.D[1] +
          planes[p].Normal[2] * ray.D[2] ==
        0;
    }
    for (bool shared : { false, true })
    {
      CellPlanes cell;
      cell.Set(planes, count, ray, shared);
      double tin = 0, tout = 10, rin = 0, rout = 10;
      cell.Clip(ray, tin, tout);
      ReferenceClip(planes, count, ray, rin, rout);
      const bool empty = !(tin < tout);
      ASSERT_EQ(empty, !(rin < rout)) << "trial " << trial;
      if (!empty)
      {
        ASSERT_TRUE(SameBits(tin, rin) && SameBits(tout, rout)) << "trial " << trial;
        nonEmpty += shared ? 1 : 0;
      }
    }
  }
  // The cases must include both outcomes and rays parallel to planes.
  EXPECT_GT(nonEmpty, 1000);
  EXPECT_GT(parallel, 1000);
}

namespace
{

// A tile's width x width rays for trial `trial`: along the axes with integer origins (even
// trials) or random, sharing the first ray's origin (a perspective camera) in half the trials.
// Along an axis either way: a plane parallel to the ray then has a denominator of +0 or -0
// (every product -0), and some pass through the ray's origin (0 / 0). ends(p, ray) sets each
// ray's end and lattice offset right after its origin and direction, so the random stream is
// the one the tests were checked with.
template <typename Ends>
std::vector<RaySetup> RandomTileRays(std::mt19937& rng, std::uniform_real_distribution<double>& u,
  std::uniform_int_distribution<int>& small, int trial, int width, Ends ends)
{
  const bool axis = trial % 2 == 0;
  const bool shared = trial % 4 < 2;
  std::vector<RaySetup> rays(static_cast<size_t>(width) * width);
  for (size_t p = 0; p < rays.size(); ++p)
  {
    RaySetup& ray = rays[p];
    for (int d = 0; d < 3; ++d)
    {
      ray.O[d] = shared ? rays[0].O[d] : (axis ? small(rng) : 3 * u(rng));
      ray.D[d] =
        axis ? (d == static_cast<int>(p + trial) % 3 ? (p % 2 ? -1.0 : 1.0) : 0.0) : u(rng);
    }
    ends(p, ray);
  }
  return rays;
}

using ClipRaysForm = int (*)(const CellPlanes&, const TileRays&, const RayRect&, const double*,
  double, const Lattice*, ClippedRays&);

// A tile of rays (a perspective camera's, sharing one origin, or a parallel one's; some with a
// lattice offset) against random cells, over random rectangles of the tile, with and without
// an opaque stop and a lattice: each form of ClipRays against the per-plane division and
// Lattice::First, ray by ray.
void CheckClipRays(ClipRaysForm form)
{
  constexpr int kWidth = 16;
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> small(-2, 2);
  std::uniform_int_distribution<int> pixel(0, kWidth - 1);
  int inside = 0;
  int outside = 0;
  int stopped = 0;
  int negativeZero = 0;
  int sampled = 0;
  int unsampled = 0;
  for (int trial = 0; trial < 4000; ++trial)
  {
    const bool axis = trial % 2 == 0;
    const bool shared = trial % 4 < 2;
    const std::vector<RaySetup> rays = RandomTileRays(rng, u, small, trial, kWidth,
      [&](size_t p, RaySetup& ray)
      {
        ray.End = p % 7 == 3 ? 0.5 : 10.0;
        ray.Offset = p % 3 == 0 ? 0.5 * (u(rng) + 1.0) : 0.0;
      });
    const int count = 4 + trial % 3;
    FacePlane planes[6];
    for (int p = 0; p < count; ++p)
    {
      for (int d = 0; d < 3; ++d)
      {
        planes[p].Normal[d] = axis ? static_cast<float>(small(rng)) : static_cast<float>(u(rng));
      }
      planes[p].Offset = axis ? static_cast<float>(small(rng)) : static_cast<float>(u(rng));
      // The mesh's conversion stores which copy of a plane keeps a parallel ray.
      planes[p] = FacePlane::Make(planes[p].Normal, planes[p].Offset);
    }
    CellPlanes cell;
    cell.Set(planes, count, rays[0], shared);
    for (const RaySetup& ray : rays)
    {
      for (int p = 0; p < count; ++p)
      {
        const double denom = cell.Nx[p] * ray.D[0] + cell.Ny[p] * ray.D[1] + cell.Nz[p] * ray.D[2];
        negativeZero += denom == 0 && std::signbit(denom) ? 1 : 0;
      }
    }
    TileRays packed;
    packed.Set(rays.data(), kWidth * kWidth, 8.0);
    std::vector<double> stop(kWidth * kWidth, std::numeric_limits<double>::infinity());
    const bool withStop = trial % 3 == 0;
    const double near = 0.25 * (trial % 5);
    for (double& s : stop)
    {
      // Some stops at the cell's near bound exactly: that cell lies behind them.
      s = withStop && rng() % 2 ? (rng() % 4 == 0 ? near : 2.0 * (u(rng) + 1.0)) : s;
    }
    // Whole rows behind the cell (at or in front of near, the rays opaque before it) beside
    // rows partly so: packets of four rays all out, the runs an opaque region gives, and
    // packets out but for one lane.
    const bool stoppedRows = withStop && trial % 4 == 3;
    for (int j = 0; stoppedRows && j < kWidth; ++j)
    {
      for (int i = 0; i < kWidth && j % 3 != 2; ++i)
      {
        const bool open = j % 3 == 1 && i % 5 == 2;
        stop[j * kWidth + i] = open ? stop[j * kWidth + i] : (i % 2 ? near : 0.5 * near);
      }
    }
    // Spacings from a tenth of the cells to several times them, some with a periodic binary
    // expansion (a quotient that rounds).
    const Lattice grid(trial % 5 == 0 ? 0.1 : 0.013 * (1 + trial % 300));
    const bool withLattice = trial % 8 < 6;
    int i0 = pixel(rng), i1 = pixel(rng), j0 = pixel(rng), j1 = pixel(rng);
    if (i0 > i1)
    {
      std::swap(i0, i1);
    }
    if (j0 > j1)
    {
      std::swap(j0, j1);
    }
    ClippedRays out;
    const int n = form(cell, packed, RayRect{ j0 * kWidth + i0, i1 - i0 + 1, j1 - j0 + 1, kWidth },
      withStop ? stop.data() : nullptr, near, withLattice ? &grid : nullptr, out);
    int h = 0;
    for (int j = j0; j <= j1; ++j)
    {
      for (int i = i0; i <= i1; ++i)
      {
        const int l = j * kWidth + i;
        double rin = 0;
        double rout = std::min(rays[l].End, 8.0);
        bool skipped = false;
        if (withStop)
        {
          rout = std::min(rout, stop[l]);
          skipped = near >= stop[l];
          stopped += skipped ? 1 : 0;
        }
        if (!skipped)
        {
          ReferenceClip(planes, count, rays[l], rin, rout);
        }
        const bool empty = skipped || !(rin < rout);
        ASSERT_EQ(empty, !(out.Tin[l] < out.Tout[l])) << "trial " << trial << " ray " << l;
        if (empty)
        {
          ++outside;
          continue;
        }
        ++inside;
        ASSERT_TRUE(SameBits(out.Tin[l], rin) && SameBits(out.Tout[l], rout))
          << "trial " << trial << " ray " << l;
        if (withLattice)
        {
          // The smallest k with t_k >= tin, found by walking the lattice.
          int64_t k = static_cast<int64_t>(std::floor(rin / grid.Spacing)) - 3;
          while (grid.At(k, rays[l].Offset) < rin)
          {
            ++k;
          }
          if (!(grid.At(k, rays[l].Offset) < rout))
          {
            ++unsampled;
            continue;
          }
          ++sampled;
          ASSERT_EQ(out.Lattice[l], static_cast<double>(k)) << "trial " << trial << " ray " << l;
        }
        ASSERT_LT(h, n) << "trial " << trial;
        ASSERT_EQ(out.Hits[h++], l) << "trial " << trial;
      }
    }
    ASSERT_EQ(h, n) << "trial " << trial;
  }
  EXPECT_GT(sampled, 5000);
  EXPECT_GT(unsampled, 1000);
  EXPECT_GT(inside, 10000);
  EXPECT_GT(outside, 10000);
  EXPECT_GT(stopped, 1000);
  EXPECT_GT(negativeZero, 1000);
}

} // namespace

TEST(CellPlanes, ClipRaysMatchesPerPlaneDivision)
{
  CheckClipRays(apc::walk::ClipRaysScalar);
  CheckClipRays(apc::walk::ClipRays);
}

TEST(CellPlanes, ClipRaysAvx2MatchesPerPlaneDivision)
{
  if (!apc::walk::HasAvx2())
  {
    GTEST_SKIP() << "no AVX2 on this processor";
  }
  CheckClipRays(apc::walk::ClipRaysAvx2);
}

TEST(CellPlanes, ClipRaysAvx512MatchesPerPlaneDivision)
{
  if (!apc::walk::HasAvx512())
  {
    GTEST_SKIP() << "no AVX-512 on this processor";
  }
  CheckClipRays(apc::walk::ClipRaysAvx512);
}

// Sample End Weights = Boundary's ends four rays at a time (walk::BoundaryEnds, both forms):
// for random cells, boundary masks and rays (shared origin or not, rays along the axes too,
// so that quotients tie between planes and denominators are +-0), the flags of
// CellPlanes::BoundaryEnds for every ray ClipRays kept, bit for bit.
TEST(CellPlanes, BoundaryEndsFourAtATimeMatchRayByRay)
{
  using Form = void (*)(
    const CellPlanes&, const TileRays&, const ClippedRays&, const uint16_t*, int, uint8_t*);
  std::vector<Form> forms{ apc::walk::BoundaryEndsScalar, apc::walk::BoundaryEnds };
  if (apc::walk::HasAvx2())
  {
    forms.push_back(apc::walk::BoundaryEndsAvx2);
  }
  constexpr int kWidth = 16;
  std::mt19937 rng(53);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> small(-2, 2);
  int counts[4] = { 0, 0, 0, 0 };
  for (int trial = 0; trial < 3000; ++trial)
  {
    const bool axis = trial % 2 == 0;
    const bool shared = trial % 4 < 2;
    const std::vector<RaySetup> rays = RandomTileRays(rng, u, small, trial, kWidth,
      [](size_t, RaySetup& ray)
      {
        ray.End = 10.0;
        ray.Offset = 0.0;
      });
    const int count = 4 + trial % 3;
    FacePlane planes[6];
    for (int p = 0; p < count; ++p)
    {
      for (int d = 0; d < 3; ++d)
      {
        planes[p].Normal[d] = axis ? static_cast<float>(small(rng)) : static_cast<float>(u(rng));
      }
      planes[p].Offset = axis ? static_cast<float>(small(rng)) : static_cast<float>(u(rng));
      // The mesh's conversion stores which copy of a plane keeps a parallel ray.
      planes[p] = FacePlane::Make(planes[p].Normal, planes[p].Offset);
    }
    CellPlanes cell;
    cell.Set(planes, count, rays[0], shared);
    // Bits past the cell's planes too: BoundaryEnds reads only the cell's.
    cell.BoundaryMask = static_cast<unsigned>(rng() % 256);
    TileRays packed;
    packed.Set(rays.data(), kWidth * kWidth, 8.0);
    ClippedRays clipped;
    const int n = apc::walk::ClipRays(
      cell, packed, RayRect{ 0, kWidth, kWidth, kWidth }, nullptr, 0.0, nullptr, clipped);
    for (Form form : forms)
    {
      uint8_t ends[apc::walk::kTilePixels + 3];
      form(cell, packed, clipped, clipped.Hits, n, ends);
      for (int h = 0; h < n; ++h)
      {
        const int l = clipped.Hits[h];
        bool in = false;
        bool out = false;
        cell.BoundaryEnds(rays[l], clipped.Tin[l], clipped.Tout[l], in, out);
        ASSERT_EQ(ends[h], (in ? 1 : 0) | (out ? 2 : 0)) << "trial " << trial << " ray " << l;
        ++counts[ends[h]];
      }
    }
  }
  // Every combination of the two flags occurs.
  for (int c : counts)
  {
    EXPECT_GT(c, 1000);
  }
}

// Rays entering a cell exactly at a lattice point t_k or at the next double above it (a plane
// across axis-parallel rays from the origin, at that value): the first index must be k,
// respectively k + 1, where the quotient tin / spacing - offset rounds to either side of an
// integer, so that the first guess (its ceiling) is one too high or one too low. Each form
// against the known index and Lattice::First.
TEST(CellPlanes, ClipRaysFindTheFirstLatticeIndexOnALatticePoint)
{
  std::vector<ClipRaysForm> forms{ apc::walk::ClipRaysScalar, apc::walk::ClipRays };
  if (apc::walk::HasAvx2())
  {
    forms.push_back(apc::walk::ClipRaysAvx2);
  }
  if (apc::walk::HasAvx512())
  {
    forms.push_back(apc::walk::ClipRaysAvx512);
  }
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int guessHigh = 0;
  int guessLow = 0;
  for (int trial = 0; trial < 20000; ++trial)
  {
    const Lattice grid(0.001 + u(rng));
    const double offset = trial % 2 ? u(rng) : 0.0;
    const int64_t k = static_cast<int64_t>(u(rng) * 2000);
    const bool above = trial % 4 >= 2;
    const double tin = above ? std::nextafter(grid.At(k, offset), 1e300) : grid.At(k, offset);
    const int64_t first = above ? k + 1 : k;
    const double guess = std::ceil(tin * grid.InverseSpacing - offset);
    guessHigh += guess > static_cast<double>(first) ? 1 : 0;
    guessLow += guess < static_cast<double>(first) ? 1 : 0;
    // Enter through z = tin (normal -z), leave far behind it.
    FacePlane planes[2];
    planes[0] = FacePlane::Make({ 0.0f, 0.0f, -1.0f }, -tin);
    planes[1] = FacePlane::Make({ 0.0f, 0.0f, 1.0f }, 4000.0);
    std::vector<RaySetup> rays(4, RaySetup{ { 0, 0, 0 }, { 0, 0, 1 }, 5000.0, offset });
    CellPlanes cell;
    cell.Set(planes, 2, rays[0], trial % 8 < 4);
    TileRays packed;
    packed.Set(rays.data(), 4, 5000.0);
    for (ClipRaysForm form : forms)
    {
      ClippedRays out;
      const int n = form(cell, packed, RayRect{ 0, 4, 1, 4 }, nullptr, 0.0, &grid, out);
      ASSERT_EQ(n, 4) << "trial " << trial;
      for (int l = 0; l < 4; ++l)
      {
        ASSERT_TRUE(SameBits(out.Tin[l], tin)) << "trial " << trial;
        ASSERT_EQ(out.Lattice[l], static_cast<double>(first)) << "trial " << trial;
        ASSERT_EQ(grid.First(tin, offset), first) << "trial " << trial;
      }
    }
  }
  // Both ways of missing must occur, or the test would not show that both are corrected.
  EXPECT_GT(guessHigh, 100);
  EXPECT_GT(guessLow, 100);
}
