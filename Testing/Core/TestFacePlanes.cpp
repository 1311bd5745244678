// The face planes CellMesh derives: two cells sharing a face must hold that face's plane bit
// for bit (up to the sign), however each numbers the face's points (cells on different ranks,
// or in pieces appended without merging points, have their own ids for it), and a plane must
// pass through its face to rounding of the cell's size, wherever the mesh sits.
#include "apcCellMesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <random>
#include <vector>

namespace
{
using Point = std::array<double, 3>;

// The plane among a cell's planes that all the given points lie on (to tol), or nullptr.
const apc::FacePlane* PlaneThrough(
  const apc::CellMesh& mesh, int64_t cell, const std::vector<Point>& points, double tol)
{
  int count = 0;
  const apc::FacePlane* planes = mesh.GetPlanes(cell, count);
  for (int p = 0; p < count; ++p)
  {
    bool all = true;
    for (const Point& x : points)
    {
      const double d = planes[p].Normal[0] * x[0] + planes[p].Normal[1] * x[1] +
        planes[p].Normal[2] * x[2] - planes[p].Offset;
      all = all && std::abs(d) <= tol;
    }
    if (all)
    {
      return planes + p;
    }
  }
  return nullptr;
}

// A mesh of one tetrahedron: the shared face's three points in the given order of ids, then
// the apex. Ids follow `order`: point i of the face gets id order[i].
apc::CellMesh OneTet(const std::array<Point, 3>& face, const Point& apex, std::array<int, 3> order)
{
  apc::CellMesh mesh;
  mesh.Points.resize(4);
  for (int i = 0; i < 3; ++i)
  {
    mesh.Points[order[i]] = face[i];
  }
  mesh.Points[3] = apex;
  mesh.PointScalars.assign(4, 1.0f);
  const int64_t ids[4] = { order[0], order[1], order[2], 3 };
  mesh.AddCell(apc::CellShape::Tetra, ids);
  EXPECT_TRUE(mesh.Finalize());
  return mesh;
}
}

TEST(FacePlanes, SharedFaceIsBitIdenticalWhateverTheNumbering)
{
  // Two tetrahedra on either side of one triangle, each in its own mesh (two ranks), with every
  // pair of numberings of the triangle's points: the two planes must be exact negatives.
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-3.0, 3.0);
  const std::array<std::array<int, 3>, 6> orders = { { { 0, 1, 2 }, { 0, 2, 1 }, { 1, 0, 2 },
    { 1, 2, 0 }, { 2, 0, 1 }, { 2, 1, 0 } } };
  int compared = 0;
  for (int trial = 0; trial < 200; ++trial)
  {
    std::array<Point, 3> face;
    for (Point& p : face)
    {
      p = { 100 + coordinate(random), 50 + coordinate(random), 20 + coordinate(random) };
    }
    // Apexes on either side of the triangle.
    Point centre{ 0, 0, 0 };
    for (const Point& p : face)
    {
      for (int d = 0; d < 3; ++d)
      {
        centre[d] += p[d] / 3;
      }
    }
    const Point u{ face[1][0] - face[0][0], face[1][1] - face[0][1], face[1][2] - face[0][2] };
    const Point v{ face[2][0] - face[0][0], face[2][1] - face[0][1], face[2][2] - face[0][2] };
    const Point n{ u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
      u[0] * v[1] - u[1] * v[0] };
    const Point front{ centre[0] + n[0], centre[1] + n[1], centre[2] + n[2] };
    const Point back{ centre[0] - n[0], centre[1] - n[1], centre[2] - n[2] };
    const std::vector<Point> facePoints(face.begin(), face.end());
    for (const auto& a : orders)
    {
      for (const auto& b : orders)
      {
        const apc::CellMesh left = OneTet(face, front, a);
        const apc::CellMesh right = OneTet(face, back, b);
        const apc::FacePlane* p = PlaneThrough(left, 0, facePoints, 1e-4);
        const apc::FacePlane* q = PlaneThrough(right, 0, facePoints, 1e-4);
        ASSERT_TRUE(p && q);
        for (int d = 0; d < 3; ++d)
        {
          ASSERT_EQ(p->Normal[d], -q->Normal[d]) << "trial " << trial;
        }
        ASSERT_EQ(p->Offset, -q->Offset) << "trial " << trial;
        // Exactly one of the two cells keeps a ray running inside the face, as its normal
        // says (the flag is stored at conversion and read by the clip).
        ASSERT_EQ(p->KeepsParallelRays, apc::InPositiveHalf(p->Normal) ? 1.0f : 0.0f);
        ASSERT_EQ(q->KeepsParallelRays, apc::InPositiveHalf(q->Normal) ? 1.0f : 0.0f);
        ASSERT_EQ(p->KeepsParallelRays + q->KeepsParallelRays, 1.0f) << "trial " << trial;
        ++compared;
      }
    }
  }
  EXPECT_EQ(compared, 200 * 36);
}

TEST(FacePlanes, PassThroughTheirFacesFarFromTheOrigin)
{
  // A hexahedron of ~3 m cells far from the origin, and its copy scaled down to ~3e-6: every
  // face's corners lie on its plane to a millionth of the cell's size.
  for (const double scale : { 1.0, 1e-6 })
  {
    for (const double shift : { 0.0, 1e4, 1e7 })
    {
      apc::CellMesh mesh;
      const double s = 3.0;
      const Point corners[8] = { { 0, 0, 0 }, { s, 0, 0 }, { s, s, 0 }, { 0, s, 0 }, { 0, 0, s },
        { s, 0, s }, { s, s, s }, { 0, s, s } };
      for (const Point& c : corners)
      {
        mesh.Points.push_back(
          { scale * (shift + c[0]), scale * (shift + 0.5 * c[1]), scale * (shift + c[2]) });
      }
      mesh.PointScalars.assign(8, 1.0f);
      const int64_t ids[8] = { 0, 1, 2, 3, 4, 5, 6, 7 };
      mesh.AddCell(apc::CellShape::Hexahedron, ids);
      ASSERT_TRUE(mesh.Finalize());
      const int faces[6][4] = { { 0, 3, 2, 1 }, { 4, 5, 6, 7 }, { 0, 1, 5, 4 }, { 3, 7, 6, 2 },
        { 0, 4, 7, 3 }, { 1, 2, 6, 5 } };
      int count = 0;
      mesh.GetPlanes(0, count);
      ASSERT_EQ(count, 6);
      for (const auto& face : faces)
      {
        std::vector<Point> points;
        for (int i : face)
        {
          points.push_back(mesh.Points[i]);
        }
        EXPECT_NE(PlaneThrough(mesh, 0, points, 1e-6 * s * scale), nullptr)
          << "scale " << scale << ", shift " << shift;
      }
    }
  }
}

TEST(FacePlanes, TiltedFacesPassThroughTheirCornersFarFromTheOrigin)
{
  // Faces in no axis direction, so that their float normals are rounded: each plane's offset
  // must be the rounded normal's, or the plane misses its face by the rounding (6e-8) times
  // the distance from the origin, a tenth of a metre at 1e7.
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double size = 3.0;
  for (const double shift : { 0.0, 1e4, 1e7 })
  {
    double worst = 0;
    for (int trial = 0; trial < 50; ++trial)
    {
      apc::CellMesh mesh;
      for (int i = 0; i < 4; ++i)
      {
        mesh.Points.push_back({ shift + size * unit(random), shift + size * unit(random),
          shift + size * unit(random) });
      }
      mesh.PointScalars.assign(4, 1.0f);
      const int64_t ids[4] = { 0, 1, 2, 3 };
      mesh.AddCell(apc::CellShape::Tetra, ids);
      ASSERT_TRUE(mesh.Finalize());
      int count = 0;
      const apc::FacePlane* planes = mesh.GetPlanes(0, count);
      if (count != 4)
      {
        continue; // a flat draw
      }
      for (int p = 0; p < count; ++p)
      {
        // A face's three corners lie on its plane, the opposite corner off it.
        std::vector<double> distances;
        for (const Point& x : mesh.Points)
        {
          distances.push_back(std::abs(planes[p].Normal[0] * (x[0] - shift) +
            planes[p].Normal[1] * (x[1] - shift) + planes[p].Normal[2] * (x[2] - shift) -
            (planes[p].Offset -
              shift * (double(planes[p].Normal[0]) + planes[p].Normal[1] + planes[p].Normal[2]))));
        }
        std::sort(distances.begin(), distances.end());
        worst = std::max(worst, distances[2]);
      }
    }
    std::cout << "shift " << shift << ": largest distance of a face's corner from its plane "
              << worst << "\n";
    EXPECT_LE(worst, 1e-6 * size) << "shift " << shift;
  }
}
