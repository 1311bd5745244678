// The cell facet table (apcCellFacets.h), held to the geometry of VTK's reference cells rather
// than to a second copy of the table: the faces of every 3D cell close its surface with every
// edge used once in each direction (consistent orientation), enclose the cell's volume with the
// documented sign, and each lie in one plane; 2D cells' edges walk around the cell once; the
// renderer's shape check uses this very table.
#include "apcCellFacets.h"
#include "apcCellShapeCheck.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <set>
#include <utility>
#include <vector>

namespace
{
using Point = std::array<double, 3>;

struct Reference
{
  const char* Name;
  int Type;
  std::vector<Point> Corners; // VTK's parametric corner coordinates
  double SignedVolume;        // what the faces enclose (negative: inward faces)
};

// VTK's reference cells (vtkCell::GetParametricCoords) and their volumes.
std::vector<Reference> Solids()
{
  using apc::CellType::Hexahedron;
  using apc::CellType::Pyramid;
  using apc::CellType::Tetra;
  using apc::CellType::Voxel;
  using apc::CellType::Wedge;
  return {
    { "tetra", Tetra, { { 0, 0, 0 }, { 1, 0, 0 }, { 0, 1, 0 }, { 0, 0, 1 } }, 1.0 / 6 },
    { "pyramid", Pyramid, { { 0, 0, 0 }, { 1, 0, 0 }, { 1, 1, 0 }, { 0, 1, 0 }, { 0, 0, 1 } },
      1.0 / 3 },
    { "wedge", Wedge,
      { { 0, 0, 0 }, { 1, 0, 0 }, { 0, 1, 0 }, { 0, 0, 1 }, { 1, 0, 1 }, { 0, 1, 1 } }, -0.5 },
    { "hexahedron", Hexahedron,
      { { 0, 0, 0 }, { 1, 0, 0 }, { 1, 1, 0 }, { 0, 1, 0 }, { 0, 0, 1 }, { 1, 0, 1 }, { 1, 1, 1 },
        { 0, 1, 1 } },
      1.0 },
    { "voxel", Voxel,
      { { 0, 0, 0 }, { 1, 0, 0 }, { 0, 1, 0 }, { 1, 1, 0 }, { 0, 0, 1 }, { 1, 0, 1 }, { 0, 1, 1 },
        { 1, 1, 1 } },
      1.0 },
  };
}

Point Sub(const Point& a, const Point& b)
{
  return { a[0] - b[0], a[1] - b[1], a[2] - b[2] };
}

Point Cross(const Point& a, const Point& b)
{
  return { a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0] };
}

double Dot(const Point& a, const Point& b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// Signed volume by the divergence theorem, each face fanned from its first corner.
double EnclosedVolume(const apc::CellFacets& facets, const std::vector<Point>& x)
{
  double volume6 = 0;
  for (int f = 0; f < facets.Count; ++f)
  {
    const int* c = facets.Corner[f];
    for (int k = 1; k + 1 < facets.Size[f]; ++k)
    {
      volume6 += Dot(x[c[0]], Cross(x[c[k]], x[c[k + 1]]));
    }
  }
  return volume6 / 6;
}

// Every corner index valid and distinct within its facet.
void ExpectValidCorners(const apc::CellFacets& facets, int corners, const char* name)
{
  for (int f = 0; f < facets.Count; ++f)
  {
    std::set<int> seen;
    for (int k = 0; k < facets.Size[f]; ++k)
    {
      const int c = facets.Corner[f][k];
      EXPECT_TRUE(c >= 0 && c < corners) << name << " facet " << f;
      EXPECT_TRUE(seen.insert(c).second) << name << " facet " << f << " repeats corner " << c;
    }
  }
}
} // namespace

TEST(CellFacets, SolidFacesCloseTheSurfaceWithOneOrientation)
{
  for (const Reference& cell : Solids())
  {
    const apc::CellFacets* facets = apc::FacetsOfCellType(cell.Type);
    ASSERT_NE(facets, nullptr) << cell.Name;
    const int corners = static_cast<int>(cell.Corners.size());
    ExpectValidCorners(*facets, corners, cell.Name);
    // Each directed edge once, and its reverse once: a closed, consistently oriented surface.
    std::map<std::pair<int, int>, int> directed;
    for (int f = 0; f < facets->Count; ++f)
    {
      ASSERT_GE(facets->Size[f], 3) << cell.Name;
      for (int k = 0; k < facets->Size[f]; ++k)
      {
        ++directed[{ facets->Corner[f][k], facets->Corner[f][(k + 1) % facets->Size[f]] }];
      }
    }
    for (const auto& [edge, count] : directed)
    {
      EXPECT_EQ(count, 1) << cell.Name << " edge " << edge.first << "-" << edge.second;
      EXPECT_EQ(directed.count({ edge.second, edge.first }), 1u)
        << cell.Name << " edge " << edge.first << "-" << edge.second << " has no twin";
    }
    // Euler: V - E + F = 2, with every corner on the surface.
    const int edges = static_cast<int>(directed.size()) / 2;
    EXPECT_EQ(corners - edges + facets->Count, 2) << cell.Name;
    EXPECT_NEAR(EnclosedVolume(*facets, cell.Corners), cell.SignedVolume, 1e-15) << cell.Name;
  }
}

TEST(CellFacets, QuadrilateralFacesArePlanar)
{
  for (const Reference& cell : Solids())
  {
    const apc::CellFacets& facets = *apc::FacetsOfCellType(cell.Type);
    for (int f = 0; f < facets.Count; ++f)
    {
      if (facets.Size[f] == 4)
      {
        const auto& x = cell.Corners;
        const int* c = facets.Corner[f];
        const Point normal = Cross(Sub(x[c[1]], x[c[0]]), Sub(x[c[2]], x[c[0]]));
        EXPECT_EQ(Dot(normal, Sub(x[c[3]], x[c[0]])), 0.0) << cell.Name << " face " << f;
      }
    }
  }
}

TEST(CellFacets, PolygonEdgesWalkAroundTheCellOnce)
{
  struct Polygon
  {
    const char* Name;
    int Type;
    std::vector<Point> Corners;
    double SignedArea;
  };
  const std::vector<Polygon> polygons = {
    { "triangle", apc::CellType::Triangle, { { 0, 0, 0 }, { 1, 0, 0 }, { 0, 1, 0 } }, 0.5 },
    { "quad", apc::CellType::Quad, { { 0, 0, 0 }, { 1, 0, 0 }, { 1, 1, 0 }, { 0, 1, 0 } }, 1 },
    { "pixel", apc::CellType::Pixel, { { 0, 0, 0 }, { 1, 0, 0 }, { 0, 1, 0 }, { 1, 1, 0 } }, 1 },
  };
  for (const Polygon& cell : polygons)
  {
    const apc::CellFacets* facets = apc::FacetsOfCellType(cell.Type);
    ASSERT_NE(facets, nullptr) << cell.Name;
    const int corners = static_cast<int>(cell.Corners.size());
    ASSERT_EQ(facets->Count, corners) << cell.Name;
    ExpectValidCorners(*facets, corners, cell.Name);
    // Edge f ends where edge f + 1 starts, and the walk visits every corner: a cycle.
    std::set<int> visited;
    double area2 = 0;
    for (int f = 0; f < facets->Count; ++f)
    {
      ASSERT_EQ(facets->Size[f], 2) << cell.Name;
      const int from = facets->Corner[f][0];
      const int to = facets->Corner[f][1];
      EXPECT_EQ(to, facets->Corner[(f + 1) % facets->Count][0]) << cell.Name;
      visited.insert(from);
      area2 +=
        cell.Corners[from][0] * cell.Corners[to][1] - cell.Corners[to][0] * cell.Corners[from][1];
    }
    EXPECT_EQ(static_cast<int>(visited.size()), corners) << cell.Name;
    EXPECT_EQ(area2 / 2, cell.SignedArea) << cell.Name;
  }
}

TEST(CellFacets, LineFacetsAreItsEndPoints)
{
  const apc::CellFacets* line = apc::FacetsOfCellType(apc::CellType::Line);
  ASSERT_NE(line, nullptr);
  ASSERT_EQ(line->Count, 2);
  EXPECT_EQ(line->Size[0], 1);
  EXPECT_EQ(line->Size[1], 1);
  EXPECT_EQ(line->Corner[0][0], 0);
  EXPECT_EQ(line->Corner[1][0], 1);
}

TEST(CellFacets, TypesWithoutAFixedTableHaveNone)
{
  // VTK_EMPTY_CELL, VTK_VERTEX, VTK_POLY_VERTEX, VTK_POLY_LINE, VTK_TRIANGLE_STRIP,
  // VTK_POLYGON, VTK_QUADRATIC_TETRA, VTK_POLYHEDRON, VTK_LAGRANGE_HEXAHEDRON, and nonsense.
  for (const int type : { 0, 1, 2, 4, 6, 7, 24, 42, 72, -1, 1000 })
  {
    EXPECT_EQ(apc::FacetsOfCellType(type), nullptr) << type;
  }
}

TEST(CellFacets, TheShapeCheckUsesThisTable)
{
  EXPECT_EQ(&apc::FacesOf(apc::CellShape::Tetra), apc::FacetsOfCellType(apc::CellType::Tetra));
  EXPECT_EQ(&apc::FacesOf(apc::CellShape::Pyramid), apc::FacetsOfCellType(apc::CellType::Pyramid));
  EXPECT_EQ(&apc::FacesOf(apc::CellShape::Wedge), apc::FacetsOfCellType(apc::CellType::Wedge));
  EXPECT_EQ(
    &apc::FacesOf(apc::CellShape::Hexahedron), apc::FacetsOfCellType(apc::CellType::Hexahedron));
}
