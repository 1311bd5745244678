// The flat-cell check (apcCellShapeCheck.h) and what CellMesh::Finalize makes of flat cells
// and non-finite values: flat cells of every shape are found, real cells (thin ones, needles,
// cells with a collapsed edge) are not, the measure does not depend on the cell's size or
// position, and a non-finite scalar (NaN or +-inf) makes its cell transparent.
#include "apcCellMesh.h"
#include "apcCellShapeCheck.h"
#include "apcTestCells.h"
#include "apcTransferTable.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iostream>
#include <limits>
#include <vector>

namespace
{
using apc::CellShape;
using Corners = std::array<std::array<double, 3>, 8>;

Corners Make(std::initializer_list<std::array<double, 3>> points)
{
  Corners c{};
  int i = 0;
  for (const auto& p : points)
  {
    c[i++] = p;
  }
  return c;
}

// The unit reference cells in VTK's corner order.
Corners Reference(CellShape shape)
{
  switch (shape)
  {
    case CellShape::Tetra:
      return Make({ { 0, 0, 0 }, { 1, 0, 0 }, { 0, 1, 0 }, { 0, 0, 1 } });
    case CellShape::Pyramid:
      return Make({ { 0, 0, 0 }, { 1, 0, 0 }, { 1, 1, 0 }, { 0, 1, 0 }, { 0.5, 0.5, 1 } });
    case CellShape::Wedge:
      return Make({ { 0, 0, 0 }, { 1, 0, 0 }, { 0, 1, 0 }, { 0, 0, 1 }, { 1, 0, 1 }, { 0, 1, 1 } });
    default:
      return Make({ { 0, 0, 0 }, { 1, 0, 0 }, { 1, 1, 0 }, { 0, 1, 0 }, { 0, 0, 1 }, { 1, 0, 1 },
        { 1, 1, 1 }, { 0, 1, 1 } });
  }
}

// z scaled by `thickness` (0: every corner in the plane z = 0), then x shifted by `shear` * z
// before scaling, so that the flattened corners stay distinct.
Corners Squash(CellShape shape, double thickness, double shear = 0.3)
{
  Corners c = Reference(shape);
  for (int i = 0; i < apc::NumberOfCorners(shape); ++i)
  {
    c[i][0] += shear * c[i][2];
    c[i][2] *= thickness;
  }
  return c;
}

Corners Transform(CellShape shape, Corners c, double scale, double offset)
{
  for (int i = 0; i < apc::NumberOfCorners(shape); ++i)
  {
    for (int d = 0; d < 3; ++d)
    {
      c[i][d] = c[i][d] * scale + offset * (d + 1);
    }
  }
  return c;
}

} // namespace

using apctest::kSolidShapes;
using apctest::ShapeName;

TEST(CellShapeCheck, ReferenceCellsHaveTheirExactThickness)
{
  // |V| / (A_max * D): these pin the volume (consistent face orientation) and the areas.
  const double r3 = std::sqrt(3.0);
  const double r2 = std::sqrt(2.0);
  EXPECT_NEAR(apc::RelativeThickness(CellShape::Tetra, Reference(CellShape::Tetra)),
    (1.0 / 6) / (r3 / 2 * r3), 1e-15);
  EXPECT_NEAR(apc::RelativeThickness(CellShape::Pyramid, Reference(CellShape::Pyramid)),
    (1.0 / 3) / (1.0 * r3), 1e-15);
  EXPECT_NEAR(
    apc::RelativeThickness(CellShape::Wedge, Reference(CellShape::Wedge)), 0.5 / (r2 * r3), 1e-15);
  EXPECT_NEAR(
    apc::RelativeThickness(CellShape::Hexahedron, Reference(CellShape::Hexahedron)), 1 / r3, 1e-15);
  for (CellShape shape : kSolidShapes)
  {
    EXPECT_FALSE(apc::IsFlat(shape, Reference(shape))) << ShapeName(shape);
    // Inverted corner order (a mirror image) is not flat either: the check takes |V|.
    Corners mirrored = Reference(shape);
    for (int i = 0; i < apc::NumberOfCorners(shape); ++i)
    {
      mirrored[i][0] = -mirrored[i][0];
    }
    EXPECT_FALSE(apc::IsFlat(shape, mirrored)) << ShapeName(shape) << " mirrored";
  }
}

TEST(CellShapeCheck, FlatCellsOfEveryShape)
{
  for (CellShape shape : kSolidShapes)
  {
    // Distinct corners, all in one plane: the "four distinct coplanar corners".
    const Corners flat = Squash(shape, 0.0);
    EXPECT_TRUE(apc::IsFlat(shape, flat)) << ShapeName(shape);
    EXPECT_LE(apc::RelativeThickness(shape, flat), 1e-16) << ShapeName(shape);
    // Nearly flat, in a tilted plane far from the origin: still flat.
    const Corners nearly = Transform(shape, Squash(shape, 1e-9), 3.0, 1e3);
    EXPECT_TRUE(apc::IsFlat(shape, nearly))
      << ShapeName(shape) << " " << apc::RelativeThickness(shape, nearly);
    // Thin but real (1e-4 of its size): rendered.
    const Corners thin = Transform(shape, Squash(shape, 1e-4), 3.0, 1e3);
    EXPECT_FALSE(apc::IsFlat(shape, thin))
      << ShapeName(shape) << " " << apc::RelativeThickness(shape, thin);
    // Every corner at one point, and no extent at all.
    Corners point{};
    EXPECT_TRUE(apc::IsFlat(shape, point)) << ShapeName(shape);
    std::cout << ShapeName(shape) << ": reference "
              << apc::RelativeThickness(shape, Reference(shape)) << ", thickness 1e-4 "
              << apc::RelativeThickness(shape, thin) << ", 1e-9 "
              << apc::RelativeThickness(shape, nearly) << ", flat "
              << apc::RelativeThickness(shape, flat) << "\n";
  }
  // Collapsed cells: a hexahedron whose top face lies on its bottom face (other points, the
  // same place), a pyramid with its apex on the base, a wedge on its bottom triangle.
  Corners hex = Reference(CellShape::Hexahedron);
  for (int i = 4; i < 8; ++i)
  {
    hex[i] = hex[i - 4];
  }
  EXPECT_TRUE(apc::IsFlat(CellShape::Hexahedron, hex));
  Corners pyramid = Reference(CellShape::Pyramid);
  pyramid[4] = { 0.2, 0.7, 0.0 };
  EXPECT_TRUE(apc::IsFlat(CellShape::Pyramid, pyramid));
  Corners wedge = Reference(CellShape::Wedge);
  for (int i = 3; i < 6; ++i)
  {
    wedge[i] = wedge[i - 3];
  }
  EXPECT_TRUE(apc::IsFlat(CellShape::Wedge, wedge));
  // Corners on one line.
  const Corners line =
    Make({ { 0, 0, 0 }, { 1, 1, 1 }, { 2, 2, 2 }, { 3, 3, 3 }, { 4, 4, 4 }, { 5, 5, 5 } });
  EXPECT_TRUE(apc::IsFlat(CellShape::Wedge, line));
  // A NaN corner.
  Corners nan = Reference(CellShape::Tetra);
  nan[2][1] = std::nan("");
  EXPECT_TRUE(apc::IsFlat(CellShape::Tetra, nan));
}

TEST(CellShapeCheck, RealCellsAreNotFlat)
{
  // A needle 1000 x 1 x 1: its volume is 1e-6 of its longest edge cubed, but it is a
  // perfectly good cell (its thickness is 1e-3 of its size).
  Corners needle = Reference(CellShape::Hexahedron);
  for (int i = 0; i < 8; ++i)
  {
    needle[i][0] *= 1000;
  }
  EXPECT_FALSE(apc::IsFlat(CellShape::Hexahedron, needle));
  EXPECT_NEAR(apc::RelativeThickness(CellShape::Hexahedron, needle), 1e-3, 1e-5);
  // A hexahedron with a collapsed edge (corners 5 and 6 on 4 and 7: a wedge written as a
  // hexahedron, common in CFD meshes) keeps its volume.
  Corners collapsed = Reference(CellShape::Hexahedron);
  collapsed[5] = collapsed[4];
  collapsed[6] = collapsed[7];
  EXPECT_FALSE(apc::IsFlat(CellShape::Hexahedron, collapsed));
  // A pyramid with a collapsed base edge (a tetrahedron written as a pyramid).
  Corners pyramid = Reference(CellShape::Pyramid);
  pyramid[2] = pyramid[1];
  EXPECT_FALSE(apc::IsFlat(CellShape::Pyramid, pyramid));
}

TEST(CellShapeCheck, ScaleAndPositionFree)
{
  for (CellShape shape : kSolidShapes)
  {
    for (double thickness : { 1.0, 1e-3, 1e-5 })
    {
      const Corners c = Squash(shape, thickness);
      const double t = apc::RelativeThickness(shape, c);
      for (double scale : { 1e-9, 1e-3, 1e4, 1e9 })
      {
        // Offsets up to 1e3 cell sizes: the digits left for the cell's own shape still
        // resolve a thickness of 1e-5 to 1e-3 relative.
        for (double offset : { 0.0, 1.0, 1e3 })
        {
          const double moved =
            apc::RelativeThickness(shape, Transform(shape, c, scale, offset * scale));
          EXPECT_NEAR(moved / t, 1.0, 1e-3) << ShapeName(shape) << " thickness " << thickness
                                            << " scale " << scale << " offset " << offset;
        }
      }
    }
  }
}

TEST(CellShapeCheck, MeshSkipsFlatCellsAndCountsThem)
{
  // A unit hexahedron and a flat tetrahedron on its bottom face (distinct corners 0, 1, 2, 3).
  apc::CellMesh mesh;
  const Corners hex = Reference(CellShape::Hexahedron);
  for (int i = 0; i < 8; ++i)
  {
    mesh.Points.push_back(hex[i]);
    mesh.PointScalars.push_back(0.5f);
  }
  const int64_t hexIds[8] = { 0, 1, 2, 3, 4, 5, 6, 7 };
  const int64_t flatIds[4] = { 0, 1, 2, 3 };
  mesh.AddCell(CellShape::Hexahedron, hexIds);
  mesh.AddCell(CellShape::Tetra, flatIds);
  // A tetrahedron with a NaN corner.
  mesh.Points.push_back({ std::nan(""), 0, 0 });
  mesh.PointScalars.push_back(0.5f);
  const int64_t nanIds[4] = { 4, 5, 6, 8 };
  mesh.AddCell(CellShape::Tetra, nanIds);
  ASSERT_TRUE(mesh.Finalize());
  EXPECT_EQ(mesh.GetNumberOfSkippedCells(), 2);
  EXPECT_EQ(mesh.GetNumberOfFlatCells(), 1);
  EXPECT_EQ(mesh.GetNumberOfNonFiniteCornerCells(), 1);
  int planes = 0;
  mesh.GetPlanes(0, planes);
  EXPECT_EQ(planes, 6);
  mesh.GetPlanes(1, planes);
  EXPECT_EQ(planes, 0);
  const auto& b = mesh.GetBounds();
  EXPECT_EQ(b[0], 0.0);
  EXPECT_EQ(b[1], 1.0);
}

TEST(CellShapeCheck, NonFiniteScalarsMakeTheirCellTransparent)
{
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (float bad : { nan, inf, -inf })
  {
    apc::CellMesh mesh;
    const Corners tet = Reference(CellShape::Tetra);
    for (int i = 0; i < 4; ++i)
    {
      mesh.Points.push_back(tet[i]);
    }
    mesh.Points.push_back({ 1, 1, 1 });
    mesh.PointScalars = { 0.1f, 0.2f, bad, 0.4f, 0.5f };
    const int64_t a[4] = { 0, 1, 2, 3 }; // has the bad corner
    const int64_t b[4] = { 1, 4, 3, 0 }; // does not
    mesh.AddCell(CellShape::Tetra, a);
    mesh.AddCell(CellShape::Tetra, b);
    ASSERT_TRUE(mesh.Finalize());
    EXPECT_TRUE(std::isnan(mesh.GetScalarRange(0)[0]) && std::isnan(mesh.GetScalarRange(0)[1]))
      << bad;
    EXPECT_EQ(mesh.GetScalarRange(1)[0], 0.1f);
    EXPECT_EQ(mesh.GetScalarRange(1)[1], 0.5f);
    EXPECT_EQ(mesh.GetNumberOfNonFiniteScalarCells(), 1) << bad;
    EXPECT_EQ(mesh.GetNumberOfSkippedCells(), 0) << bad;

    // Cell scalars: the same rule.
    apc::CellMesh cells;
    cells.Points = mesh.Points;
    cells.AddCell(CellShape::Tetra, a);
    cells.AddCell(CellShape::Tetra, b);
    cells.CellScalars = { bad, 0.3f };
    ASSERT_TRUE(cells.Finalize());
    EXPECT_TRUE(std::isnan(cells.GetScalarRange(0)[0])) << bad;
    EXPECT_EQ(cells.GetScalarRange(1)[0], 0.3f);
    EXPECT_EQ(cells.GetNumberOfNonFiniteScalarCells(), 1) << bad;
  }
  // The table: an opaque end entry stays unreachable for +-inf, as for NaN.
  const apc::TransferTable table(
    0.0, 1.0, { { 1.f, 1.f, 1.f }, { 1.f, 0.f, 0.f } }, { 0.9, 0.9 }, 0.1, 1.0);
  for (double bad : { std::nan(""), std::numeric_limits<double>::infinity(),
         -std::numeric_limits<double>::infinity() })
  {
    EXPECT_EQ(table.Lookup(bad).Absorbance, 0.f) << bad;
    EXPECT_EQ(table.Lookup(bad).Colour[0], 0.f) << bad;
  }
  EXPECT_GT(table.Lookup(1e30).Absorbance, 0.f) << "finite values beyond the range still clamp";
  EXPECT_FALSE(table.MayBeVisible(std::nan(""), std::nan("")));
}

namespace
{
// The measure as it was first written (a square root per face, the centroid and bounds summed
// here): what CellMesh::Finalize's inputs and results must stay bit for bit.
apc::CellMeasure ReferenceMeasure(CellShape shape, const Corners& corners)
{
  using Vec = std::array<double, 3>;
  auto sub = [](const Vec& a, const Vec& b) -> Vec {
    return { a[0] - b[0], a[1] - b[1], a[2] - b[2] };
  };
  auto cross = [](const Vec& a, const Vec& b) -> Vec {
    return { a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0] };
  };
  auto dot = [](const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  const int n = apc::NumberOfCorners(shape);
  Vec centroid = { 0, 0, 0 };
  Vec lo = corners[0];
  Vec hi = corners[0];
  for (int i = 0; i < n; ++i)
  {
    for (int d = 0; d < 3; ++d)
    {
      centroid[d] += corners[i][d] / n;
      lo[d] = std::min(lo[d], corners[i][d]);
      hi[d] = std::max(hi[d], corners[i][d]);
    }
  }
  std::array<Vec, 8> x;
  for (int i = 0; i < n; ++i)
  {
    x[i] = sub(corners[i], centroid);
  }
  const Vec extent = sub(hi, lo);
  const double diagonal = std::sqrt(dot(extent, extent));
  double volume6 = 0;
  double maxArea2 = 0;
  const apc::CellFaces& faces = apc::FacesOf(shape);
  for (int f = 0; f < faces.Count; ++f)
  {
    const int* c = faces.Corner[f];
    Vec area2 = { 0, 0, 0 };
    for (int k = 1; k + 1 < faces.Size[f]; ++k)
    {
      const Vec t = cross(sub(x[c[k]], x[c[0]]), sub(x[c[k + 1]], x[c[0]]));
      for (int i = 0; i < 3; ++i)
      {
        area2[i] += t[i];
      }
      volume6 += dot(x[c[0]], cross(x[c[k]], x[c[k + 1]]));
    }
    maxArea2 = std::max(maxArea2, std::sqrt(dot(area2, area2)));
  }
  apc::CellMeasure measure;
  measure.Volume = std::abs(volume6) / 6.0;
  if (std::isnan(volume6) || std::isnan(maxArea2) || std::isnan(diagonal))
  {
    measure.RelativeThickness = volume6 + maxArea2 + diagonal;
    return measure;
  }
  const double denominator = 0.5 * maxArea2 * diagonal;
  measure.RelativeThickness =
    denominator > 0 && std::isfinite(denominator) ? measure.Volume / denominator : 0;
  return measure;
}

bool SameBits(double a, double b)
{
  return std::memcmp(&a, &b, sizeof a) == 0;
}
}

// The measure takes one square root for the largest face and (from Finalize) the centroid and
// bounds Finalize summed already: the same volumes and thicknesses, bit for bit, as the per-face
// roots it replaced, on jittered cells of every shape far from and near the origin, collapsed and
// flat ones, and cells with a NaN or infinite corner.
TEST(CellShapeCheck, MeasureIsTheReferenceBitForBit)
{
  uint64_t state = 12345;
  auto uniform = [&state]
  {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) * 0x1.0p-53;
  };
  int compared = 0;
  for (CellShape shape : kSolidShapes)
  {
    const int n = apc::NumberOfCorners(shape);
    for (int trial = 0; trial < 4000; ++trial)
    {
      Corners c = Reference(shape);
      const double scale = std::pow(10.0, -6 + 12 * uniform());
      const double offset = trial % 3 == 0 ? 0.0 : std::pow(10.0, 7 * uniform()) * scale;
      for (int i = 0; i < n; ++i)
      {
        for (int d = 0; d < 3; ++d)
        {
          c[i][d] = (c[i][d] + 0.4 * (uniform() - 0.5)) * scale + offset * (d + 1);
        }
      }
      switch (trial % 11)
      {
        case 1: // two corners on one point
          c[n - 1] = c[0];
          break;
        case 2: // flat
          c = Transform(shape, Squash(shape, trial % 2 ? 0.0 : 1e-9), scale, offset);
          break;
        case 3: // a non-finite corner
          c[trial % n][trial % 3] = trial % 2 ? std::nan("") : -HUGE_VAL;
          break;
        case 4: // signed zeros
          c[0] = { -0.0, 0.0, -0.0 };
          c[1][0] = 0.0;
          break;
        default:
          break;
      }
      const apc::CellMeasure expected = ReferenceMeasure(shape, c);
      const apc::CellMeasure measured = apc::MeasureCell(shape, c);
      ASSERT_TRUE(SameBits(measured.Volume, expected.Volume) &&
        SameBits(measured.RelativeThickness, expected.RelativeThickness))
        << ShapeName(shape) << " trial " << trial << ": " << measured.Volume << " "
        << measured.RelativeThickness << " against " << expected.Volume << " "
        << expected.RelativeThickness;
      ++compared;
    }
  }
  EXPECT_EQ(compared, 4 * 4000);
}
