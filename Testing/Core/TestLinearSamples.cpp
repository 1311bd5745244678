// Pass 1's four-at-a-time samples of nearly affine cells (apcLinearSamples.h) against the
// per-sample path they replace: the lattice depth, the linear coordinates p0 + t dp, ScalarAt
// (LinearScalarAt for pyramids), the clamp to the cell's range, TransferTable::Lookup's
// absorbance, the lattice depth warp's table and the opaque stop's quanta, bit for bit, on
// random distorted hexahedra, wedges and pyramids, random rays and lattice offsets (whose
// depths the warp's table does not hold), depths before, in and past the table, scalars
// beyond the table on both sides, cell ranges that clip the interpolant, and non-finite
// coefficients.
#include "apcCellInterpolation.h"
#include "apcLinearSamples.h"
#include "apcOpaqueBins.h"
#include "apcRayClip.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace
{

using apc::CellCorners;
using apc::CellInterpolator;
using apc::CellShape;

apc::TransferTable Table()
{
  // A transparent start, then a ramp, as ParaView's default; the range [-2, 3] lies inside
  // the corner scalars' [-4, 5], so that both ends clamp.
  std::vector<std::array<float, 3>> colours;
  std::vector<double> opacities;
  for (int i = 0; i < 256; ++i)
  {
    const float x = i / 255.0f;
    colours.push_back({ x, 1.0f - x, 0.5f * x });
    opacities.push_back(i < 40 ? 0.0 : 0.99 * x * x);
  }
  return apc::TransferTable(-2.0, 3.0, colours, opacities, 0.2, 0.05);
}

CellCorners DistortedCell(CellShape shape, double distortion, std::mt19937& rng)
{
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> value(-4.0, 5.0);
  CellCorners cell;
  cell.Shape = shape;
  const auto& reference = apc::ReferenceCorners(shape);
  for (int i = 0; i < apc::NumberOfCorners(shape); ++i)
  {
    for (int d = 0; d < 3; ++d)
    {
      cell.X[i][d] = 20.0 + 2.0 * (reference[i][d] + distortion * u(rng));
    }
    cell.S[i] = value(rng);
  }
  return cell;
}

uint64_t Bits(double v)
{
  uint64_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}
uint32_t Bits(float v)
{
  uint32_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

#ifdef APC_HAVE_AVX2_SAMPLES
template <bool Pyramid>
APC_SAMPLES_AVX2 void Quad(const apc::walk::Lattice& grid, int64_t k, double offset,
  const double p0[3], const double dp[3], const apc::walk::LinearScalarForm& form,
  const apc::TransferTable::Layout& table, const apc::walk::SampleBookkeeping& after,
  apc::walk::SampleQuad& out)
{
  apc::walk::LinearSamples4<Pyramid>(grid, k, offset, p0, dp, form, table, after, out);
}
#endif

// Compares 4 samples from k on with the walker's scalar path; returns the lanes compared.
struct Counts
{
  int Visible = 0;
  int Tabled = 0;
  int Opaque = 0; // samples whose quanta saturate
};

// The frame's depth warp (a table from depth 10 to 30) and opaque stop (ln 10^4 of
// absorbance).
struct Frame
{
  apc::LatticeDepthWarp Warp;
  apc::OpaqueBins Bins;
  Frame(double spacing)
    : Warp(apc::LogDepthWarp(10.0, 30.0), spacing)
    , Bins(apc::OpaqueBins::Make(std::log(1e4), 10.0, 30.0, spacing))
  {
  }
};

int CompareQuad(const CellInterpolator& cell, const apc::walk::Lattice& grid, int64_t k,
  double offset, const double p0[3], const double dp[3], double lo, double hi,
  const apc::TransferTable& table, const Frame& frame, Counts& counts)
{
#ifdef APC_HAVE_AVX2_SAMPLES
  apc::walk::LinearScalarForm form;
  std::copy(cell.ScalarCoefficients(), cell.ScalarCoefficients() + 8, form.SC);
  form.Lo = lo;
  form.Hi = hi;
  apc::walk::SampleQuad quad;
  const apc::walk::SampleBookkeeping after{ frame.Warp.GetLayout(),
    frame.Bins.QuantaPerAbsorbance };
  const bool pyramid = cell.Shape() == CellShape::Pyramid;
  if (pyramid)
  {
    Quad<true>(grid, k, offset, p0, dp, form, table.GetLayout(), after, quad);
  }
  else
  {
    Quad<false>(grid, k, offset, p0, dp, form, table.GetLayout(), after, quad);
  }
  for (int lane = 0; lane < 4; ++lane)
  {
    const double t = grid.At(k + lane, offset);
    double q[3];
    for (int d = 0; d < 3; ++d)
    {
      q[d] = p0[d] + t * dp[d];
    }
    const double interpolated = pyramid ? cell.LinearScalarAt(q) : cell.ScalarAt(q);
    const double scalar = std::min(std::max(interpolated, lo), hi);
    const apc::TransferSample s = table.Lookup(scalar);
    EXPECT_EQ(Bits(quad.T[lane]), Bits(t)) << "k " << k + lane;
    EXPECT_EQ(Bits(quad.Scalar[lane]), Bits(scalar)) << "k " << k + lane << " scalar " << scalar;
    EXPECT_EQ(Bits(quad.Absorbance[lane]), Bits(s.Absorbance))
      << "k " << k + lane << " scalar " << scalar;
    // Where Tabled says so, the table's depth is the warp's; elsewhere it is left to the
    // walker, which then warps directly. Lanes on the lattice inside the table are tabled.
    const double z = frame.Warp(k + lane, t);
    const bool onLattice = t == static_cast<double>(k + lane) * grid.Spacing;
    const int64_t i = k + lane - frame.Warp.GetLayout().Base;
    const bool inTable = i >= 0 && i < frame.Warp.GetNumberOfEntries();
    const bool tabled = (quad.Tabled >> lane & 1) != 0;
    EXPECT_EQ(tabled, onLattice && inTable) << "k " << k + lane;
    if (tabled)
    {
      EXPECT_EQ(Bits(quad.Z[lane]), Bits(z)) << "k " << k + lane;
    }
    EXPECT_EQ(quad.Quanta[lane], frame.Bins.Quanta(s.Absorbance)) << "k " << k + lane;
    counts.Visible += s.Absorbance > 0 ? 1 : 0;
    counts.Tabled += tabled ? 1 : 0;
    counts.Opaque += quad.Quanta[lane] == apc::OpaqueBins::kOpaque ? 1 : 0;
  }
  return 4;
#else
  (void)cell, (void)grid, (void)k, (void)offset, (void)p0, (void)dp, (void)lo, (void)hi,
    (void)table, (void)frame, (void)counts;
  return 0;
#endif
}

TEST(LinearSamples, FourAtATimeAreTheScalarPathBitForBit)
{
  if (!apc::walk::HasAvx2())
  {
    GTEST_SKIP() << "no AVX2 on this processor";
  }
  const apc::TransferTable table = Table();
  std::mt19937 rng(26);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int compared = 0;
  Counts counts;
  for (CellShape shape : { CellShape::Hexahedron, CellShape::Wedge, CellShape::Pyramid })
  {
    for (int c = 0; c < 200; ++c)
    {
      const CellCorners corners = DistortedCell(shape, c % 2 ? 0.02 : 0.2, rng);
      CellInterpolator cell;
      cell.Set(corners);
      const double lo = c % 3 == 0 ? -1.0 : -4.0; // a range that clips, or not
      const double hi = c % 3 == 0 ? 2.0 : 5.0;
      const apc::walk::Lattice grid(0.05 + 0.1 * unit(rng));
      const Frame frame(grid.Spacing);
      for (int r = 0; r < 20; ++r)
      {
        const double o[3] = { 20 + 30 * u(rng), 20 + 30 * u(rng), 20 + 30 * u(rng) };
        const double target[3] = { 22 + u(rng), 22 + u(rng), 22 + u(rng) };
        double d[3] = { target[0] - o[0], target[1] - o[1], target[2] - o[2] };
        const double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (double& x : d)
        {
          x /= length;
        }
        double p0[3], dp[3];
        cell.LinearRay(o, d, p0, dp);
        const double offset = r % 2 ? 0.0 : unit(rng);
        // From a few steps before the cell to a few past it.
        const int64_t k0 = static_cast<int64_t>(std::floor((length - 3.0) / grid.Spacing));
        for (int64_t k = k0; k < k0 + static_cast<int64_t>(6.0 / grid.Spacing); k += 3)
        {
          compared += CompareQuad(cell, grid, k, offset, p0, dp, lo, hi, table, frame, counts);
        }
      }
    }
  }
  EXPECT_GT(compared, 100000);
  // The look-ups were not all of transparent samples, nor all of opaque ones; the depths
  // not all in the table, nor all out of it.
  EXPECT_GT(counts.Visible, compared / 4);
  EXPECT_LT(counts.Visible, compared);
  EXPECT_GT(counts.Opaque, 0);
  EXPECT_LT(counts.Opaque, counts.Visible / 2);
  EXPECT_GT(counts.Tabled, compared / 8);
  EXPECT_LT(counts.Tabled, compared * 3 / 4);
}

TEST(LinearSamples, NonFiniteScalarsAreTransparent)
{
  if (!apc::walk::HasAvx2())
  {
    GTEST_SKIP() << "no AVX2 on this processor";
  }
  const apc::TransferTable table = Table();
  std::mt19937 rng(7);
  const apc::walk::Lattice grid(0.1);
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (double bad : { nan, inf, -inf })
  {
    CellCorners corners = DistortedCell(CellShape::Hexahedron, 0.02, rng);
    corners.S[3] = bad;
    CellInterpolator cell;
    cell.Set(corners);
    const double o[3] = { 0, 0, 0 };
    const double d[3] = { 0.6, 0.6, 0.52915026221291805 };
    double p0[3], dp[3];
    cell.LinearRay(o, d, p0, dp);
    const Frame frame(grid.Spacing);
    Counts counts;
    for (int64_t k = 300; k < 500; k += 4)
    {
      // The range may be infinite too (a non-finite corner): no clamp then.
      CompareQuad(cell, grid, k, 0.0, p0, dp, -inf, inf, table, frame, counts);
    }
    EXPECT_EQ(counts.Visible, 0) << bad;
  }
}

} // namespace
