// What empty-space skipping rests on: a cell's scalar range (CellMesh) and the transfer
// table's answer to "can any scalar of this range be seen?", checked against looking every
// scalar up, the test that tells a wrong Newton root from a point in the cell, and the marcher
// that drops the hidden cells from its tiles' lists once per march.
#include "apcTestBlock.h"

#include "apcCellInterpolation.h"
#include "apcCellMesh.h"
#include "apcTransferTable.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace
{
// Opacity zero except on a few islands, some one entry wide: the edges are where an
// off-by-one in the index range would show.
apc::TransferTable IslandTable(int entries)
{
  std::vector<std::array<float, 3>> colours(entries, { 1.f, 0.5f, 0.25f });
  std::vector<double> opacities(entries, 0.0);
  for (int i : { 3, 17, 18, 40, entries - 1 })
  {
    opacities[i] = 0.5;
  }
  return apc::TransferTable(-2.0, 3.0, colours, opacities, 0.1, 1.0);
}

bool AnyVisibleByLookup(const apc::TransferTable& table, double lo, double hi)
{
  // Both ends, their neighbours in double and a dense sweep in between.
  const double ends[] = { lo, hi, std::nextafter(lo, hi), std::nextafter(hi, lo) };
  for (double s : ends)
  {
    if (s >= lo && s <= hi && table.Lookup(s).Absorbance > 0)
    {
      return true;
    }
  }
  for (int k = 0; k <= 4000; ++k)
  {
    if (table.Lookup(lo + (hi - lo) * k / 4000.0).Absorbance > 0)
    {
      return true;
    }
  }
  return false;
}
}

TEST(EmptySpaceSkipping, TableNeverHidesAVisibleScalar)
{
  const apc::TransferTable table = IslandTable(64);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-3.0, 4.0);
  int hidden = 0;
  for (int trial = 0; trial < 20000; ++trial)
  {
    double lo = u(rng);
    double hi = trial % 3 == 0 ? lo : u(rng);
    if (lo > hi)
    {
      std::swap(lo, hi);
    }
    const bool visible = AnyVisibleByLookup(table, lo, hi);
    if (visible)
    {
      ASSERT_TRUE(table.MayBeVisible(lo, hi)) << "[" << lo << ", " << hi << "]";
    }
    else
    {
      hidden += table.MayBeVisible(lo, hi) ? 0 : 1;
    }
  }
  // And it does skip: most ranges that lie between the islands are found invisible.
  EXPECT_GT(hidden, 2000);
}

TEST(EmptySpaceSkipping, TableEdgesAndSpecialRanges)
{
  const apc::TransferTable table = IslandTable(64);
  const double step = 5.0 / 63; // scalar per entry
  // Between the islands at entries 3 and 17 nothing is visible, up to the entry before 17
  // (which interpolates towards 17).
  EXPECT_FALSE(table.MayBeVisible(-2.0 + 4.5 * step, -2.0 + 15.5 * step));
  EXPECT_TRUE(table.MayBeVisible(-2.0 + 4.5 * step, -2.0 + 16.5 * step));
  // Beyond the range the end entries apply (VTK's clamping); the last entry is visible.
  EXPECT_TRUE(table.MayBeVisible(10.0, 20.0));
  EXPECT_FALSE(table.MayBeVisible(-20.0, -19.0));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(table.MayBeVisible(nan, nan));
  EXPECT_FALSE(table.MayBeVisible(1.0, 0.0)); // an empty range
  EXPECT_TRUE(table.MayBeVisible(-inf, inf));

  const apc::TransferTable transparent(0.0, 1.0, { { 1.f, 1.f, 1.f } }, { 0.0 }, 0.1, 1.0);
  EXPECT_TRUE(transparent.IsTransparent());
  EXPECT_FALSE(transparent.MayBeVisible(-inf, inf));
}

TEST(EmptySpaceSkipping, MarkVisibleIsMayBeVisible)
{
  // The march's marking of every cell against the one range's test: random ranges, ranges
  // ending on and one float either side of the entries' edges, out of the table, NaN, empty
  // and infinite ones, and a table that hides everything.
  const apc::TransferTable table = IslandTable(64);
  const apc::TransferTable transparent(
    0.0, 1.0, { { 1.f, 1.f, 1.f }, { 1.f, 1.f, 1.f } }, { 0.0, 0.0 }, 0.1, 1.0);
  std::mt19937 rng(29);
  std::uniform_real_distribution<float> u(-3.f, 4.f);
  const float step = 5.f / 64.f;
  std::vector<std::array<float, 2>> ranges;
  for (int trial = 0; trial < 20000; ++trial)
  {
    const float a = u(rng);
    const float b = trial % 3 == 0 ? a + 0.2f * step * u(rng) : u(rng);
    ranges.push_back({ std::min(a, b), std::max(a, b) });
  }
  for (int i = -2; i <= 66; ++i)
  {
    const float edge = -2.f + static_cast<float>(i) * step;
    for (float lo : { std::nextafter(edge, -10.f), edge, std::nextafter(edge, 10.f) })
    {
      for (int j = 0; j < 3; ++j)
      {
        ranges.push_back({ lo, lo + static_cast<float>(j) * step });
      }
    }
  }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  for (const std::array<float, 2> special :
    std::vector<std::array<float, 2>>{ { nan, nan }, { nan, 1.f }, { 1.f, nan }, { 1.f, 0.f },
      { -inf, inf }, { -inf, -inf }, { inf, inf }, { -20.f, -19.f }, { 10.f, 20.f } })
  {
    ranges.push_back(special);
  }
  int visible = 0;
  for (const apc::TransferTable* t : { &table, &transparent })
  {
    std::vector<uint8_t> marks(ranges.size(), 7);
    t->MarkVisible(ranges.data(), static_cast<int64_t>(ranges.size()), marks.data());
    for (size_t r = 0; r < ranges.size(); ++r)
    {
      const bool expected = t->MayBeVisible(ranges[r][0], ranges[r][1]);
      ASSERT_EQ(marks[r], expected ? 1 : 0) << "[" << ranges[r][0] << ", " << ranges[r][1] << "]";
      visible += expected ? 1 : 0;
    }
  }
  // Both answers, many times.
  EXPECT_GT(visible, 2000);
  EXPECT_LT(visible, static_cast<int>(ranges.size()) - 2000);
}

TEST(EmptySpaceSkipping, CellScalarRanges)
{
  apc::CellMesh mesh;
  mesh.Points = { { 0, 0, 0 }, { 1, 0, 0 }, { 0, 1, 0 }, { 0, 0, 1 }, { 1, 1, 1 } };
  mesh.PointScalars = { 2.f, -1.f, 5.f, 0.5f, std::numeric_limits<float>::quiet_NaN() };
  const int64_t a[] = { 0, 1, 2, 3 };
  const int64_t b[] = { 1, 2, 3, 4 };
  mesh.AddCell(apc::CellShape::Tetra, a);
  mesh.AddCell(apc::CellShape::Tetra, b);
  ASSERT_TRUE(mesh.Finalize());
  EXPECT_EQ(mesh.GetScalarRange(0)[0], -1.f);
  EXPECT_EQ(mesh.GetScalarRange(0)[1], 5.f);
  // A NaN corner makes every sample NaN (transparent): the range says so.
  EXPECT_TRUE(std::isnan(mesh.GetScalarRange(1)[0]));
  EXPECT_TRUE(std::isnan(mesh.GetScalarRange(1)[1]));

  mesh.PointScalars.clear();
  mesh.CellScalars = { 7.f, 3.f };
  ASSERT_TRUE(mesh.Finalize());
  EXPECT_EQ(mesh.GetScalarRange(1)[0], 3.f);
  EXPECT_EQ(mesh.GetScalarRange(1)[1], 3.f);
}

TEST(EmptySpaceSkipping, InsideReferenceCell)
{
  using apc::CellShape;
  const double centre[3] = { 0.2, 0.2, 0.2 };
  for (CellShape shape :
    { CellShape::Tetra, CellShape::Pyramid, CellShape::Wedge, CellShape::Hexahedron })
  {
    EXPECT_TRUE(apc::InsideReferenceCell(shape, centre, 0.0));
    for (const auto& corner : apc::ReferenceCorners(shape))
    {
      EXPECT_TRUE(apc::InsideReferenceCell(shape, corner.data(), 1e-12));
    }
    const double below[3] = { 0.2, -0.01, 0.2 };
    EXPECT_FALSE(apc::InsideReferenceCell(shape, below, 1e-3));
    EXPECT_TRUE(apc::InsideReferenceCell(shape, below, 0.02));
    const double nan[3] = { std::nan(""), 0.2, 0.2 };
    EXPECT_FALSE(apc::InsideReferenceCell(shape, nan, 1.0));
  }
  const double offDiagonal[3] = { 0.6, 0.6, 0.0 }; // outside the triangle r + s <= 1
  EXPECT_FALSE(apc::InsideReferenceCell(CellShape::Tetra, offDiagonal, 1e-3));
  EXPECT_FALSE(apc::InsideReferenceCell(CellShape::Wedge, offDiagonal, 1e-3));
  EXPECT_TRUE(apc::InsideReferenceCell(CellShape::Hexahedron, offDiagonal, 1e-3));
  EXPECT_TRUE(apc::InsideReferenceCell(CellShape::Pyramid, offDiagonal, 1e-3));
}

namespace
{
template <class T>
bool SameBits(const std::vector<T>& a, const std::vector<T>& b)
{
  // An empty vector's data() may be null, which memcmp must not be given even for no bytes.
  return a.size() == b.size() &&
    (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}
}

TEST(EmptySpaceSkipping, MarcherDropsClearCellsWithTheSameSamples)
{
  // Pass 1 and pass 2 with the hidden cells left out of each tile's list once per march
  // against each (cell, tile) entry tested as it comes: the same samples, moments, profile
  // and colour, bit for bit, with the lanes and the scalar loops, with and without the stop
  // and the boundary's end weights. The tables hide whole cells (the lower 60 % clear, the
  // upper four fifths clear, clear but for islands), and leave others straddling
  // a clear edge.
  std::mt19937 rng(17);
  const std::vector<std::array<float, 3>> colours(10, { 0.8f, 0.5f, 0.2f });
  std::vector<double> lower60(10, 0.0);
  std::vector<double> islands(10, 0.0);
  for (int i = 6; i < 10; ++i)
  {
    lower60[i] = 0.3 + 0.07 * i;
  }
  islands[2] = 0.9;
  islands[7] = 0.6;
  std::vector<double> lowest(10, 0.0); // only the lowest fifth seen
  lowest[0] = 0.5;
  lowest[1] = 0.8;
  const apc::RayCamera camera(
    { 0.3, 0.9, 4.0 }, { 0.0, 0.4, 0.0 }, { 0, 1, 0 }, 40.0, false, 1.0, 48, 48, 0.1, 20.0);
  int hiddenCells = 0;
  int cells = 0;
  int compared = 0;
  for (int mesh = 0; mesh < 2; ++mesh)
  {
    const apc::CellMesh block = apctest::DistortedBlock(rng);
    for (const std::vector<double>* opacities : { &lower60, &islands, &lowest })
    {
      const apc::TransferTable table(0.0, 1.0, colours, *opacities, 0.08, 1.0);
      for (int64_t c = 0; c < block.GetNumberOfCells(); ++c)
      {
        const auto& range = block.GetScalarRange(c);
        hiddenCells += table.MayBeVisible(range[0], range[1]) ? 0 : 1;
        ++cells;
      }
      for (bool lanes : { true, false })
      {
        for (bool stop : { false, true })
        {
          for (apc::VolumeRayMarcher::EndWeightsMode mode :
            { apc::VolumeRayMarcher::EndWeightsMode::Off,
              apc::VolumeRayMarcher::EndWeightsMode::Boundary })
          {
            const auto render = [&](bool drop)
            {
              return apctest::RenderBlockFrame(block, table, camera, 48 * 48, stop,
                [&](apc::VolumeRayMarcher& marcher)
                {
                  marcher.SetSampleLanes(lanes);
                  marcher.SetEndWeightsMode(mode);
                  marcher.SetDropClearCells(drop);
                });
            };
            const apctest::BlockFrame dropped = render(true);
            const apctest::BlockFrame tested = render(false);
            EXPECT_GT(dropped.Pass1Samples, 200);
            EXPECT_EQ(dropped.Pass1Samples, tested.Pass1Samples);
            EXPECT_EQ(dropped.Pass2Samples, tested.Pass2Samples);
            EXPECT_TRUE(SameBits(dropped.Moments, tested.Moments))
              << "mesh " << mesh << " lanes " << lanes << " stop " << stop;
            EXPECT_TRUE(SameBits(dropped.Profile, tested.Profile));
            EXPECT_TRUE(SameBits(dropped.Colour, tested.Colour));
            ++compared;
          }
        }
      }
    }
  }
  EXPECT_EQ(compared, 48);
  // Both kinds of cell, in numbers.
  EXPECT_GT(hiddenCells, cells / 20);
  EXPECT_LT(hiddenCells, cells * 4 / 5);
}
