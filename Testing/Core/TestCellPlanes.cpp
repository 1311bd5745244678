// The marcher's clipping of a ray against a cell's face planes (walk::CellPlanes::Clip, two
// planes per SSE2 instruction) against the plain per-plane form it replaced: the same
// interval, bit for bit, for any planes and rays, parallel ones included. Neighbouring cells
// and ranks rely on these exact numbers to give every lattice sample to exactly one cell.
#include "apcRayWalk.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <random>

namespace
{

using apc::FacePlane;
using apc::walk::CellPlanes;
using apc::walk::RaySetup;

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
    else if (num < 0 || (num == 0 && !apc::walk::InPositiveHalf(planes[p].Normal)))
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
