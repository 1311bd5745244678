// Sample End Weights = Boundary (VolumeRayMarcher::EndWeightsMode::Boundary, walk::EndWeightsAt,
// CellMesh::GetBoundaryPlanes): only the ends of (cell, ray) pairs on the mesh's boundary are
// weighted. The mesh finds its boundary faces by their corners' coordinates; a ray's weights
// sum to its exact length along a run of pairs whose outer ends are weighted and inner ones
// plain (but where a sliver's weight is clamped); on a slab of constant absorbance seen at a
// grazing angle pass 1's optical depth is sigma times the exact length where the plain lattice
// is off by up to a sample; and the cells without a boundary face take the plain lattice's
// samples bit for bit.
#include "apcCellMesh.h"
#include "apcCellShapeCheck.h"
#include "apcDepthWarp.h"
#include "apcEndWeights.h"
#include "apcMomentParameters.h"
#include "apcRayCamera.h"
#include "apcTestEndWeights.h"
#include "apcTransferTable.h"
#include "apcVolumeRayMarcher.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <vector>

namespace
{

using apc::walk::EndWeights;
using apc::walk::EndWeightsAt;
using apc::walk::EndWeightsOf;
using apc::walk::Lattice;
using Mode = apc::VolumeRayMarcher::EndWeightsMode;

using apctest::Sum;

bool SameBits(double a, double b)
{
  return std::memcmp(&a, &b, sizeof a) == 0;
}

TEST(BoundaryWeights, RunsOfPairsSumToTheirLength)
{
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double offset = 0.29;
  const Lattice lattice(0.013);
  int exact = 0;
  int clamped = 0;
  int slivers = 0;
  for (int i = 0; i < 20000; ++i)
  {
    // A ray through 1 to 5 cells, some shorter than the spacing: entered and left through the
    // boundary (weighted), plain between cells.
    const int cells = 1 + static_cast<int>(5 * u(rng));
    std::vector<double> t{ 1.0 + 3.0 * u(rng) };
    for (int c = 0; c < cells; ++c)
    {
      t.push_back(t.back() + 0.04 * u(rng) * u(rng));
    }
    if (!(t.front() < t.back()))
    {
      continue;
    }
    double sum = 0;
    bool anyClamped = false;
    for (int c = 0; c < cells; ++c)
    {
      if (!(t[c] < t[c + 1]))
      {
        continue;
      }
      const bool in = c == 0;
      const bool out = c == cells - 1;
      const EndWeights w = EndWeightsAt(lattice, t[c], t[c + 1], offset, in, out);
      const EndWeights all = EndWeightsOf(lattice, t[c], t[c + 1], offset);
      if (in && out)
      {
        // Both ends weighted: EndWeightsOf's lattice points and sum, but a last sample covers
        // at most half a spacing past its point and the rest goes to the end sample, at the
        // pair's end (also for a pair without a lattice point: its only sample).
        EXPECT_EQ(w.First, all.First);
        EXPECT_EQ(w.Last, all.Last);
        EXPECT_EQ(w.Mid, all.Mid);
        EXPECT_NEAR(Sum(w), Sum(all), 1e-9);
        if (w.Mid)
        {
          EXPECT_LT(w.MidT, t[c + 1]);
          EXPECT_GT(w.MidT, t[c + 1] - 1e-12);
        }
        else
        {
          const double past = (t[c + 1] - lattice.At(w.Last, offset)) / lattice.Spacing;
          EXPECT_EQ(w.End, past > 0.5);
          EXPECT_LE(w.LastWeight, (w.Last == w.First ? all.FirstWeight : 1.0) + 1e-12);
          if (w.End)
          {
            EXPECT_LT(w.EndT, t[c + 1]);
            EXPECT_GT(w.EndT, t[c + 1] - 1e-12);
            EXPECT_NEAR(w.EndWeight, past - 0.5, 1e-9);
          }
        }
      }
      else if (!in && !out)
      {
        // Neither: the plain lattice's points, each of weight 1.
        EXPECT_FALSE(w.Mid);
        EXPECT_EQ(w.FirstWeight, 1.0);
        EXPECT_EQ(w.LastWeight, 1.0);
        EXPECT_EQ(w.First, lattice.First(t[c], offset));
        EXPECT_EQ(w.Last, lattice.First(t[c + 1], offset) - 1);
      }
      if ((in || out) && !(in && out) && all.Mid)
      {
        ++slivers;
        // A sliver against a plain face: its exact weight, clamped at 0.
        const double exactWeight = in
          ? (lattice.At(all.First + 1, offset) - t[c]) / lattice.Spacing - 0.5
          : (t[c + 1] - lattice.At(all.First, offset)) / lattice.Spacing - 0.5;
        if (exactWeight <= 0)
        {
          anyClamped = true;
          EXPECT_FALSE(w.Mid);
          EXPECT_LT(w.Last, w.First);
          EXPECT_GE(exactWeight, -0.5 - 1e-9);
        }
        else
        {
          EXPECT_TRUE(w.Mid);
          EXPECT_GT(w.MidT, t[c]);
          EXPECT_LT(w.MidT, t[c + 1]);
          EXPECT_NEAR(w.MidWeight, exactWeight, 1e-9);
        }
      }
      sum += Sum(w);
    }
    const double length = (t.back() - t.front()) / lattice.Spacing;
    if (anyClamped)
    {
      // Each clamped sliver counts up to half a sample more than the ray's length.
      ++clamped;
      EXPECT_GE(sum, length - 1e-9);
      EXPECT_LE(sum, length + 0.5 * cells + 1e-9);
    }
    else
    {
      ++exact;
      EXPECT_NEAR(sum, length, 1e-9);
    }
  }
  EXPECT_GT(slivers, 1000);
  EXPECT_GT(clamped, 100);
  EXPECT_GT(exact, 10000);
}

// A block of nx x ny x nz hexahedra of size h from lo. shared: the cells share their points;
// else every cell has its own 8 (pieces appended without merging their points). scalar: each
// cell's scalar (cell scalars), or null for constant point scalars 0.5.
apc::CellMesh Block(int nx, int ny, int nz, double h, const double lo[3], bool shared,
  const std::function<float(int, int, int)>& scalar,
  const std::function<float(double, double, double)>& pointScalar = nullptr)
{
  apc::CellMesh mesh;
  auto point = [&](int i, int j, int k) -> int64_t
  {
    const double x = lo[0] + i * h;
    const double y = lo[1] + j * h;
    const double z = lo[2] + k * h;
    mesh.Points.push_back({ x, y, z });
    if (!scalar)
    {
      mesh.PointScalars.push_back(pointScalar ? pointScalar(x, y, z) : 0.5f);
    }
    return static_cast<int64_t>(mesh.Points.size()) - 1;
  };
  if (shared)
  {
    for (int k = 0; k <= nz; ++k)
    {
      for (int j = 0; j <= ny; ++j)
      {
        for (int i = 0; i <= nx; ++i)
        {
          point(i, j, k);
        }
      }
    }
  }
  auto id = [&](int i, int j, int k)
  { return shared ? static_cast<int64_t>((k * (ny + 1) + j) * (nx + 1) + i) : point(i, j, k); };
  for (int k = 0; k < nz; ++k)
  {
    for (int j = 0; j < ny; ++j)
    {
      for (int i = 0; i < nx; ++i)
      {
        const int64_t ids[8] = { id(i, j, k), id(i + 1, j, k), id(i + 1, j + 1, k), id(i, j + 1, k),
          id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1) };
        mesh.AddCell(apc::CellShape::Hexahedron, ids);
        if (scalar)
        {
          mesh.CellScalars.push_back(scalar(i, j, k));
        }
      }
    }
  }
  EXPECT_TRUE(mesh.Finalize());
  mesh.FindBoundaryPlanes();
  return mesh;
}

int BoundaryPlaneCount(const apc::CellMesh& mesh)
{
  int count = 0;
  for (int64_t c = 0; c < mesh.GetNumberOfCells(); ++c)
  {
    for (unsigned m = mesh.GetBoundaryPlanes(c); m != 0; m &= m - 1)
    {
      ++count;
    }
  }
  return count;
}

TEST(BoundaryWeights, TheMeshFindsItsBoundaryFacesByTheirCorners)
{
  const double lo[3] = { -1.0, -0.5, -1.0 };
  for (bool shared : { true, false })
  {
    const apc::CellMesh mesh = Block(5, 3, 4, 0.25, lo, shared, nullptr);
    EXPECT_EQ(BoundaryPlaneCount(mesh), 2 * (5 * 3 + 3 * 4 + 5 * 4)) << shared;
    // A corner cell has three boundary faces, a cell inside none.
    auto faces = [&](int i, int j, int k)
    {
      const unsigned m = mesh.GetBoundaryPlanes((k * 3 + j) * 5 + i);
      return __builtin_popcount(m);
    };
    EXPECT_EQ(faces(0, 0, 0), 3);
    EXPECT_EQ(faces(2, 1, 0), 1);
    EXPECT_EQ(faces(2, 1, 2), 0);
  }
}

// The flags by coordinates alone (what FindBoundaryPlanes matched by before it matched faces by
// their points' representative ids): a face's distinct corner coordinates, sorted, counted over
// every face of every cell; a face counted once is on the boundary. Every face of the cells
// below has a plane, so plane n is face n.
std::vector<uint8_t> BoundaryByCoordinates(const apc::CellMesh& mesh)
{
  using Corners = std::vector<std::array<double, 3>>;
  auto cornersOf = [&](int64_t cell, int f)
  {
    const apc::CellFaces& faces = apc::FacesOf(mesh.GetShape(cell));
    Corners corners;
    for (int i = 0; i < faces.Size[f]; ++i)
    {
      corners.push_back(mesh.Points[mesh.GetCellPoints(cell)[faces.Corner[f][i]]]);
    }
    std::sort(corners.begin(), corners.end());
    corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
    return corners;
  };
  std::map<Corners, int> counts;
  for (int64_t c = 0; c < mesh.GetNumberOfCells(); ++c)
  {
    for (int f = 0; f < apc::FacesOf(mesh.GetShape(c)).Count; ++f)
    {
      ++counts[cornersOf(c, f)];
    }
  }
  std::vector<uint8_t> flags;
  for (int64_t c = 0; c < mesh.GetNumberOfCells(); ++c)
  {
    int planes = 0;
    mesh.GetPlanes(c, planes);
    EXPECT_EQ(planes, apc::FacesOf(mesh.GetShape(c)).Count);
    uint8_t mask = 0;
    for (int f = 0; f < planes; ++f)
    {
      mask |= counts[cornersOf(c, f)] == 1 ? static_cast<uint8_t>(1u << f) : 0;
    }
    flags.push_back(mask);
  }
  return flags;
}

TEST(BoundaryWeights, FacesMatchedByPointIdsAsByCoordinates)
{
  // A block of hexahedra whose corners are, at random, the block's shared points or copies of
  // their own (partly unmerged pieces: a face's two cells may name its corners by different
  // ids, or some by the same), some cells left out (holes: inner boundaries), one cell twice
  // (its faces are met three times), and the plane z = 0 reached as -0 by some copies.
  const int n[3] = { 7, 5, 4 };
  const double h = 0.25;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 4; ++trial)
  {
    apc::CellMesh mesh;
    auto coordinates = [&](int i, int j, int k) -> std::array<double, 3> {
      return { -1.0 + i * h, -0.5 + j * h, (k - 2) * h };
    };
    for (int k = 0; k <= n[2]; ++k)
    {
      for (int j = 0; j <= n[1]; ++j)
      {
        for (int i = 0; i <= n[0]; ++i)
        {
          mesh.Points.push_back(coordinates(i, j, k));
        }
      }
    }
    const double unmerged = trial / 3.0; // from none to every corner
    auto corner = [&](int i, int j, int k) -> int64_t
    {
      if (u(rng) < unmerged)
      {
        std::array<double, 3> x = coordinates(i, j, k);
        if (x[2] == 0 && u(rng) < 0.5)
        {
          x[2] = -0.0;
        }
        mesh.Points.push_back(x);
        return static_cast<int64_t>(mesh.Points.size()) - 1;
      }
      return (k * (n[1] + 1) + j) * (n[0] + 1) + i;
    };
    auto addCell = [&](int i, int j, int k)
    {
      const int64_t ids[8] = { corner(i, j, k), corner(i + 1, j, k), corner(i + 1, j + 1, k),
        corner(i, j + 1, k), corner(i, j, k + 1), corner(i + 1, j, k + 1),
        corner(i + 1, j + 1, k + 1), corner(i, j + 1, k + 1) };
      mesh.AddCell(apc::CellShape::Hexahedron, ids);
    };
    for (int k = 0; k < n[2]; ++k)
    {
      for (int j = 0; j < n[1]; ++j)
      {
        for (int i = 0; i < n[0]; ++i)
        {
          if (u(rng) < 0.1)
          {
            continue;
          }
          addCell(i, j, k);
        }
      }
    }
    addCell(3, 2, 1);
    mesh.PointScalars.assign(mesh.Points.size(), 0.5f);
    ASSERT_TRUE(mesh.Finalize());
    mesh.FindBoundaryPlanes();
    const std::vector<uint8_t> expected = BoundaryByCoordinates(mesh);
    int boundary = 0;
    for (int64_t c = 0; c < mesh.GetNumberOfCells(); ++c)
    {
      EXPECT_EQ(mesh.GetBoundaryPlanes(c), expected[c]) << "trial " << trial << " cell " << c;
      boundary += __builtin_popcount(expected[c]);
    }
    // Holes and the block's sides: far from every face, far from none.
    EXPECT_GT(boundary, 2 * (7 * 5 + 5 * 4 + 7 * 4)) << trial;
    EXPECT_LT(boundary, 6 * mesh.GetNumberOfCells() / 2) << trial;
  }
}

// Looking down at a slab's top face (y = 0.5) at about 7 degrees: its rays graze it.
constexpr int kSize = 64;
constexpr double kSpacing = 0.1;
apc::RayCamera Camera()
{
  return apc::RayCamera(
    { 0.2, 0.95, 4.0 }, { 0.0, 0.45, 0.0 }, { 0, 1, 0 }, 40.0, false, 1.0, kSize, kSize, 0.1, 20.0);
}

// Pass 1's moments (5 per pixel) and sample count.
struct Moments
{
  std::vector<double> Values;
  int64_t Samples = 0;
};

// ends: each ray's end (opaque geometry's distances), or null for none.
Moments PassOne(const apc::CellMesh& mesh, const apc::TransferTable& table, Mode mode,
  const float* ends = nullptr)
{
  apc::VolumeRayMarcher marcher;
  marcher.SetMesh(&mesh);
  marcher.SetView(Camera(), ends);
  marcher.SetEndWeightsMode(mode);
  Moments out;
  out.Values.assign(static_cast<size_t>(kSize) * kSize * 5, 0.0);
  marcher.AccumulateMoments<4>(table, apc::LogDepthWarp(2.0, 7.0), out.Values.data());
  out.Samples = marcher.GetLastSampleCount();
  return out;
}

// Where ray enters and leaves the box [lo, hi] (from t = 0): { tin, tout }, tin >= tout if it
// misses.
std::array<double, 2> BoxInterval(const apc::Ray& ray, const double lo[3], const double hi[3])
{
  double tin = 0;
  double tout = std::numeric_limits<double>::infinity();
  for (int d = 0; d < 3; ++d)
  {
    const double a = (lo[d] - ray.Origin[d]) / ray.Direction[d];
    const double b = (hi[d] - ray.Origin[d]) / ray.Direction[d];
    tin = std::max(tin, std::min(a, b));
    tout = std::min(tout, std::max(a, b));
  }
  return { tin, tout };
}

TEST(BoundaryWeights, GrazingSlabHasTheExactOpticalDepth)
{
  // The slab [-1, 1] x [-0.5, 0.5] x [-1, 1] of constant absorbance: every ray's b0 is sigma
  // times its length inside, but where a clamped sliver adds up to half a sample.
  const double lo[3] = { -1.0, -0.5, -1.0 };
  const double hi[3] = { 1.0, 0.5, 1.0 };
  const apc::CellMesh mesh = Block(8, 4, 8, 0.25, lo, true, nullptr);
  const apc::TransferTable table(
    0.0, 1.0, { { 1.f, 1.f, 1.f }, { 1.f, 1.f, 1.f } }, { 0.4, 0.4 }, kSpacing, 1.0);
  const double sample = table.Lookup(0.5).Absorbance;
  const double sigma = sample / kSpacing;
  const apc::RayCamera camera = Camera();
  const Moments boundary = PassOne(mesh, table, Mode::Boundary);
  const Moments plain = PassOne(mesh, table, Mode::Off);
  int inside = 0;
  int exact = 0;
  int plainExact = 0;
  for (int p = 0; p < kSize * kSize; ++p)
  {
    const auto [tin, tout] = BoxInterval(camera.PixelRay(p % kSize, p / kSize), lo, hi);
    const double expected = sigma * std::max(0.0, tout - tin);
    if (expected == 0)
    {
      continue;
    }
    ++inside;
    const double b0 = boundary.Values[5 * p];
    // Each weighted absorbance is rounded to float once: a few 1e-8 of the depth.
    const double rounding = 1e-6 * expected + 1e-12;
    EXPECT_GE(b0, expected - rounding) << "pixel " << p;
    EXPECT_LE(b0, expected + 0.5 * sample + rounding) << "pixel " << p;
    exact += std::abs(b0 - expected) <= rounding ? 1 : 0;
    plainExact += std::abs(plain.Values[5 * p] - expected) <= rounding ? 1 : 0;
  }
  EXPECT_GT(inside, 1000);
  // Most rays exact with the boundary weights (here 1710 of 1797: the others cross a clamped
  // sliver, up to 0.48 of a sample over, 0.14 in the median); the plain lattice's hardly ever.
  EXPECT_GE(exact, inside * 9 / 10) << exact << " of " << inside;
  EXPECT_LT(plainExact, inside / 10) << plainExact << " of " << inside;
  std::cout << "exact: boundary weights " << exact << ", plain " << plainExact << " of " << inside
            << "\n";
}

// Rays that end at an opaque surface (the depth buffer's distances) a float rounding before
// the slab's far face: the pair cut by the ray's end is weighted to it exactly, as one ending
// at the face is, so the optical depth does not jump where a surface meets the mesh's
// boundary (processes composite the depth a rounding apart).
TEST(BoundaryWeights, RaysEndingAtASurfaceCountExactlyToIt)
{
  const double lo[3] = { -1.0, -0.5, -1.0 };
  const double hi[3] = { 1.0, 0.5, 1.0 };
  const apc::CellMesh mesh = Block(8, 4, 8, 0.25, lo, true, nullptr);
  const apc::TransferTable table(
    0.0, 1.0, { { 1.f, 1.f, 1.f }, { 1.f, 1.f, 1.f } }, { 0.4, 0.4 }, kSpacing, 1.0);
  const double sigma = table.Lookup(0.5).Absorbance / kSpacing;
  const double sample = table.Lookup(0.5).Absorbance;
  const apc::RayCamera camera = Camera();
  std::vector<double> tins(kSize * kSize, 0.0);
  std::vector<double> touts(kSize * kSize, 0.0);
  // At the far face: the float just before it.
  std::vector<float> ends(kSize * kSize, std::numeric_limits<float>::infinity());
  for (int p = 0; p < kSize * kSize; ++p)
  {
    const auto [tin, tout] = BoxInterval(camera.PixelRay(p % kSize, p / kSize), lo, hi);
    tins[p] = tin;
    touts[p] = tout;
    if (tout > tin)
    {
      ends[p] = std::nextafter(static_cast<float>(tout), 0.f);
    }
  }
  const Moments moments = PassOne(mesh, table, Mode::Boundary, ends.data());
  int inside = 0;
  int exact = 0;
  for (int p = 0; p < kSize * kSize; ++p)
  {
    if (!(touts[p] > tins[p]))
    {
      continue;
    }
    ++inside;
    const double expected = sigma * (static_cast<double>(ends[p]) - tins[p]);
    const double b0 = moments.Values[5 * p];
    const double rounding = 1e-6 * expected + 1e-12;
    // Never short; over only by a clamped sliver at the entry (GrazingSlab...).
    EXPECT_GE(b0, expected - rounding) << "pixel " << p;
    EXPECT_LE(b0, expected + 0.5 * sample + rounding) << "pixel " << p;
    exact += std::abs(b0 - expected) <= rounding ? 1 : 0;
  }
  EXPECT_GT(inside, 1000);
  EXPECT_GE(exact, inside * 9 / 10) << exact << " of " << inside;
}

// Rays that end a float rounding before or after a face between two cells (an opaque slice
// through the mesh along a layer of faces; processes composite its depth a rounding apart):
// the optical depth is continuous in the ray's end there, whether the cells have a boundary
// face or none (the middle of the block): the ray's end is weighted whichever cell it falls
// in, a pair left through a shared face before the ray's next lattice point counts up to the
// ray's end, and the pair after it adds nothing (rays entering through the block's sides just
// before the face have such pairs without a lattice point).
TEST(BoundaryWeights, RaysEndingAtAnInnerFaceAreContinuousInTheirEnd)
{
  const double lo[3] = { -1.0, -0.5, -1.0 };
  const double hi[3] = { 1.0, 0.5, 1.0 };
  const apc::CellMesh mesh = Block(8, 4, 8, 0.25, lo, true, nullptr);
  const apc::TransferTable table(
    0.0, 1.0, { { 1.f, 1.f, 1.f }, { 1.f, 1.f, 1.f } }, { 0.4, 0.4 }, kSpacing, 1.0);
  const double sigma = table.Lookup(0.5).Absorbance / kSpacing;
  const apc::RayCamera camera = Camera();
  int rays = 0;
  int inner = 0;
  for (double z : { 0.5, 0.25, 0.0, -0.5 })
  {
    std::vector<float> before(kSize * kSize, std::numeric_limits<float>::infinity());
    std::vector<float> after = before;
    for (int p = 0; p < kSize * kSize; ++p)
    {
      const apc::Ray ray = camera.PixelRay(p % kSize, p / kSize);
      const double t = (z - ray.Origin[2]) / ray.Direction[2];
      double x[3];
      for (int d = 0; d < 3; ++d)
      {
        x[d] = ray.Origin[d] + t * ray.Direction[d];
      }
      if (x[0] > lo[0] + 0.01 && x[0] < hi[0] - 0.01 && x[1] > lo[1] + 0.01 && x[1] < hi[1] - 0.01)
      {
        before[p] = std::nextafter(static_cast<float>(t), 0.f);
        after[p] = std::nextafter(static_cast<float>(t), std::numeric_limits<float>::infinity());
      }
    }
    const std::vector<double> a = PassOne(mesh, table, Mode::Boundary, before.data()).Values;
    const std::vector<double> b = PassOne(mesh, table, Mode::Boundary, after.data()).Values;
    for (int p = 0; p < kSize * kSize; ++p)
    {
      if (std::isinf(before[p]))
      {
        continue;
      }
      ++rays;
      const apc::Ray ray = camera.PixelRay(p % kSize, p / kSize);
      const double t = (z - ray.Origin[2]) / ray.Direction[2];
      const double x = ray.Origin[0] + t * ray.Direction[0];
      const double y = ray.Origin[1] + t * ray.Direction[1];
      inner += z > -0.75 && z < 0.75 && x > -0.75 && x < 0.75 && y > -0.25 && y < 0.25 ? 1 : 0;
      // The optical depth grows by sigma over the rounding between the two ends, and no more
      // (the plain lattice's end, or a switch between rules at the face, moves it by up to
      // half a sample).
      const double grows = sigma * (static_cast<double>(after[p]) - before[p]);
      EXPECT_NEAR(b[5 * p], a[5 * p] + grows, 1e-6 * a[5 * p] + 1e-12)
        << "face z = " << z << " pixel " << p;
    }
  }
  EXPECT_GT(rays, 3000);
  EXPECT_GT(inner, 500); // ends in cells with no boundary face
}

// One pair's samples: each weight times f at its point.
template <class F>
double PairIntegral(const EndWeights& w, const Lattice& lattice, double offset, F f)
{
  if (w.Mid)
  {
    return w.MidWeight * f(w.MidT);
  }
  double sum = w.End ? w.EndWeight * f(w.EndT) : 0.0;
  for (int64_t k = w.First; k <= w.Last; ++k)
  {
    sum += w.Of(k) * f(lattice.At(k, offset));
  }
  return sum;
}

// The weighted integral of f along a run of pairs [t0, t1), ..., entered and left through the
// boundary, plain between: each sample's weight times f at its point.
template <class F>
double RunIntegral(const Lattice& lattice, double offset, const std::vector<double>& t, F f)
{
  const size_t cells = t.size() - 1;
  double sum = 0;
  for (size_t c = 0; c < cells; ++c)
  {
    if (!(t[c] < t[c + 1]))
    {
      continue;
    }
    sum += PairIntegral(
      EndWeightsAt(lattice, t[c], t[c + 1], offset, c == 0, c == cells - 1), lattice, offset, f);
  }
  return sum;
}

// A ray that leaves the mesh through its boundary a rounding before and after one of its
// lattice points: in a field linear along the ray the weighted samples' sum moves by the
// rounding's share and no more. (A last sample weighted (tout - t_last) / s + 1/2, the rule
// before the end sample, moves half a spacing from sample k - 1's value to sample k's there.)
TEST(BoundaryWeights, ExitsAtALatticePointAreContinuousInALinearField)
{
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double offset = 0.29;
  const Lattice lattice(0.013);
  const auto f = [](double t) { return 2.0 + 30.0 * t; };
  int runs = 0;
  int jumps = 0;
  for (int i = 0; i < 20000; ++i)
  {
    const int cells = 1 + static_cast<int>(5 * u(rng));
    std::vector<double> t{ 1.0 + 3.0 * u(rng) };
    for (int c = 0; c < cells; ++c)
    {
      t.push_back(t.back() + 0.04 * u(rng) * u(rng));
    }
    // The exit moved onto a lattice point 0-2 spacings past the last inner face.
    const double face = t[cells - 1];
    const double at = lattice.At(lattice.First(face, offset) + i % 3, offset);
    if (!(at > face) || !(at > t.front()))
    {
      continue;
    }
    t.back() = std::nextafter(at, 0.0);
    const double before = RunIntegral(lattice, offset, t, f);
    const double shorter = t.back();
    t.back() = std::nextafter(at, 10.0);
    const double after = RunIntegral(lattice, offset, t, f);
    ++runs;
    const double grows = f(at) * (t.back() - shorter) / lattice.Spacing;
    const bool jumped = std::abs(after - before - grows) > 1e-9 * std::abs(before) + 1e-12;
    jumps += jumped ? 1 : 0;
    EXPECT_FALSE(jumped) << "run " << i << ": " << before << " then " << after;
  }
  EXPECT_GT(runs, 15000);
  EXPECT_EQ(jumps, 0);
}

// The weighted integral of f (and the weights' sum) along a run of cells [t0, t1), ...,
// [t_{n-1}, t_n) of a ray that ends at rayEnd, entered through the boundary at t0, plain
// between, left through the boundary at t_n if exits (else the mesh goes on past rayEnd): the
// weights the walker takes (RayPairWeights, with each cell's exit as the clip finds it).
struct RunValue
{
  double Integral = 0;
  double Weights = 0;
};
template <class F>
RunValue RayRun(const Lattice& lattice, double offset, const std::vector<double>& t, double rayEnd,
  bool exits, F f)
{
  RunValue run;
  const size_t cells = t.size() - 1;
  for (size_t c = 0; c < cells && t[c] < rayEnd; ++c)
  {
    const double end = std::min(t[c + 1], rayEnd);
    if (!(t[c] < end))
    {
      continue;
    }
    const bool exitFace = exits && c + 1 == cells;
    const auto cellExit = [&](double& face, bool& faceOut)
    {
      face = t[c + 1];
      faceOut = exitFace;
    };
    bool plain = false;
    const EndWeights w = apc::walk::RayPairWeights(lattice, t[c], end, offset, c == 0,
      exitFace && end == t[c + 1], lattice.First(t[c], offset), rayEnd, cellExit, plain);
    run.Weights += Sum(w);
    run.Integral += PairIntegral(w, lattice, offset, f);
  }
  return run;
}

// Rays that end (an opaque surface's depth) a rounding before and after each face of a run of
// cells, each of its lattice points and the half spacings before them, its entry and its
// exit: in a field linear along the ray the weighted samples' sum moves by the rounding's
// share and no more, so N processes compositing the depth a few roundings apart weigh what one
// process weighs. The weights sum to the ray's length in the mesh, or up to half a sample more
// where the ray enters within half a spacing before a lattice point from a pair without one
// (a late entry) or leaves through the boundary past a plain face within half a spacing after
// its last lattice point. Before, a late entry in the ray's last spacing before its end
// counted from its entry while the pair holding the end counted from h, so the sum jumped
// by up to half a sample as the end crossed a face between them (PvbatchAPC.pvvolume).
TEST(BoundaryWeights, RaysEndingAnywhereInARunAreContinuousInTheirEnd)
{
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double offset = 0.29;
  const Lattice lattice(0.013);
  const double s = lattice.Spacing;
  const auto f = [](double t) { return 2.0 + 30.0 * t; };
  int ends = 0;
  int jumps = 0;
  int lateEnds = 0; // ends in the last half spacing after a late entry, past a face after it
  int exact = 0;
  for (int i = 0; i < 10000; ++i)
  {
    const int cells = 2 + static_cast<int>(4 * u(rng));
    std::vector<double> t{ 1.0 + 3.0 * u(rng) };
    for (int c = 0; c < cells; ++c)
    {
      t.push_back(t.back() + 0.02 * u(rng) * u(rng));
    }
    if (!(t.front() < t[1]) || !(t.front() < t.back()))
    {
      continue;
    }
    const bool exits = i % 3 == 0;
    std::vector<double> at(t.begin(), t.end() - (exits ? 0 : 1));
    for (int64_t k = lattice.First(t.front(), offset); lattice.At(k, offset) < t.back(); ++k)
    {
      at.push_back(lattice.At(k, offset));
      at.push_back(lattice.At(k, offset) - 0.5 * s);
    }
    const int64_t entryNext = lattice.First(t.front(), offset);
    const bool late = t.front() > lattice.At(entryNext, offset) - 0.5 * s;
    for (const double e : at)
    {
      const double before = std::nextafter(e, 0.0);
      const double after = std::nextafter(e, 10.0);
      if (!(before > t.front()) || (!exits && !(after < t.back())))
      {
        continue;
      }
      const RunValue a = RayRun(lattice, offset, t, before, exits, f);
      const RunValue b = RayRun(lattice, offset, t, after, exits, f);
      ++ends;
      const double grows = after < t.back() || !exits ? f(e) * (after - before) / s : 0.0;
      // A late entry's pair holding the end weighs (e - t0) (t1 - h) / (t1 - t0): continuous,
      // but rising that much faster than the end moves (sliver pairs: a steep slope).
      const double steep = late ? f(e) * (after - before) * 0.5 / (t[1] - t.front()) : 0.0;
      const bool jumped =
        std::abs(b.Integral - a.Integral - grows) > 1e-9 * std::abs(a.Integral) + 1e-12 + steep;
      jumps += jumped ? 1 : 0;
      EXPECT_FALSE(jumped) << "run " << i << " end " << e << ": " << a.Integral << " then "
                           << b.Integral;
      // The sum's bounds: the length in the mesh, up to half a sample more per late entry
      // and per exit sliver.
      const double length = (std::min(before, t.back()) - t.front()) / s;
      EXPECT_GE(a.Weights, length - 1e-9);
      EXPECT_LE(a.Weights, length + 1.0 + 1e-9);
      if (late && before > t[1] && lattice.At(entryNext, offset) >= before)
      {
        ++lateEnds;
      }
      exact += std::abs(a.Weights - length) < 1e-9 ? 1 : 0;
    }
  }
  EXPECT_GT(ends, 40000);
  EXPECT_GT(lateEnds, 1000);
  EXPECT_GT(exact, ends / 2);
  EXPECT_EQ(jumps, 0);
}

// A block whose point scalars are linear in position.
apc::CellMesh LinearBlock(int nz, const double lo[3])
{
  return Block(8, 4, nz, 0.25, lo, true, nullptr,
    [](double x, double y, double z)
    { return static_cast<float>(0.5 + 0.2 * x + 0.3 * y + 0.08 * z); });
}

// Its transfer function: absorbance rising with the scalar, so that neighbouring samples
// differ.
apc::TransferTable Ramp()
{
  return apc::TransferTable(
    0.0, 1.0, { { 1.f, 1.f, 1.f }, { 1.f, 1.f, 1.f } }, { 0.02, 0.9 }, kSpacing, 1.0);
}

// Pass 1's moments of two frames agree pixel by pixel up to what the ends' rounding adds:
// the number of pixels (of those in check) where they jump.
int Jumps(const std::vector<double>& a, const std::vector<double>& b, const std::vector<int>& check,
  double rounding, double sigma)
{
  int jumps = 0;
  for (int p : check)
  {
    const double tolerance = 1e-6 * a[5 * p] + 4.0 * sigma * rounding + 1e-12;
    bool jumped = false;
    for (int m = 0; m < 5; ++m)
    {
      jumped = jumped || !(std::abs(b[5 * p + m] - a[5 * p + m]) <= tolerance);
    }
    jumps += jumped ? 1 : 0;
  }
  return jumps;
}

// Rays that end at an opaque surface a float rounding before and after one of their lattice
// points (processes composite the depth a few roundings apart), in a field linear in
// position, at several depths of the block (inner cells, cells with a boundary face, the last
// lattice point before the far face): pass 1's moments are continuous in the ray's end. The
// rule before (the pair holding the end's last lattice point counted up to the end, up to
// 3/2 spacings) moved half a spacing from sample k - 1 to sample k as the end crossed t_k.
TEST(BoundaryWeights, RaysEndingAtALatticePointAreContinuousInTheirEnd)
{
  const double lo[3] = { -1.0, -0.5, -1.0 };
  const apc::CellMesh mesh = LinearBlock(8, lo);
  const double hi[3] = { 1.0, 0.5, 1.0 };
  const apc::TransferTable table = Ramp();
  const double sigma = table.Lookup(1.0).Absorbance / kSpacing;
  const apc::RayCamera camera = Camera();
  const Lattice lattice(kSpacing);
  int rays = 0;
  int jumps = 0;
  for (double share : { 0.15, 0.5, 0.85, 1.0 })
  {
    std::vector<float> before(kSize * kSize, std::numeric_limits<float>::infinity());
    std::vector<float> after = before;
    std::vector<int> check;
    double rounding = 0;
    for (int p = 0; p < kSize * kSize; ++p)
    {
      const auto [tin, tout] = BoxInterval(camera.PixelRay(p % kSize, p / kSize), lo, hi);
      if (!(tout - tin > 2.0 * kSpacing))
      {
        continue;
      }
      // The lattice point at that share of the way through (1.0: the last before the exit).
      const int64_t k =
        share < 1.0 ? lattice.First(tin + share * (tout - tin), 0.0) : lattice.First(tout, 0.0) - 1;
      const double at = lattice.At(k, 0.0);
      const float f = static_cast<float>(at);
      const float a = f < at ? f : std::nextafter(f, 0.f);
      const float b = f > at ? f : std::nextafter(f, std::numeric_limits<float>::infinity());
      if (!(a > tin && b < tout))
      {
        continue;
      }
      before[p] = a;
      after[p] = b;
      rounding = std::max(rounding, static_cast<double>(b) - a);
      check.push_back(p);
    }
    const std::vector<double> m0 = PassOne(mesh, table, Mode::Boundary, before.data()).Values;
    const std::vector<double> m1 = PassOne(mesh, table, Mode::Boundary, after.data()).Values;
    const int j = Jumps(m0, m1, check, rounding, sigma);
    EXPECT_EQ(j, 0) << "ends at share " << share << " of the way, " << check.size() << " rays";
    rays += static_cast<int>(check.size());
    jumps += j;
  }
  EXPECT_GT(rays, 4000);
  std::cout << "rays ending at a lattice point: " << rays << ", jumping " << jumps << "\n";
}

// Rays that leave the mesh through its far face a rounding before and after one of their
// lattice points (a parallel camera looking straight at that face: every ray leaves at the same
// t; the block moved by a rounding between the two frames): pass 1's moments are continuous.
TEST(BoundaryWeights, RaysLeavingAtALatticePointAreContinuousInTheirExit)
{
  const apc::RayCamera camera(
    { 0.1, 0.05, 4.0 }, { 0.1, 0.05, 0.0 }, { 0, 1, 0 }, 40.0, true, 1.2, kSize, kSize, 0.1, 20.0);
  const apc::Ray centre = camera.PixelRay(kSize / 2, kSize / 2);
  ASSERT_EQ(centre.Direction[2], -1.0);
  const Lattice lattice(kSpacing);
  // The far face at lattice point k's depth, give or take delta; 7 layers of 0.25 deep, so
  // the entry lies half way between two lattice points.
  const int64_t k = std::llround((centre.Origin[2] + 1.0) / kSpacing);
  const double at = lattice.At(k, 0.0);
  const double delta = 1e-9;
  const apc::TransferTable table = Ramp();
  const double sigma = table.Lookup(1.0).Absorbance / kSpacing;
  std::vector<double> moments[2];
  std::vector<int> check;
  for (int side = 0; side < 2; ++side)
  {
    const double lo[3] = { -1.0, -0.5, centre.Origin[2] - at + (side ? -delta : delta) };
    const double hi[3] = { 1.0, 0.5, lo[2] + 7 * 0.25 };
    const apc::CellMesh mesh = LinearBlock(7, lo);
    apc::VolumeRayMarcher marcher;
    marcher.SetMesh(&mesh);
    marcher.SetView(camera, nullptr);
    marcher.SetEndWeightsMode(Mode::Boundary);
    moments[side].assign(static_cast<size_t>(kSize) * kSize * 5, 0.0);
    marcher.AccumulateMoments<4>(table, apc::LogDepthWarp(2.0, 7.0), moments[side].data());
    for (int p = 0; side == 1 && p < kSize * kSize; ++p)
    {
      const auto [tin, tout] = BoxInterval(camera.PixelRay(p % kSize, p / kSize), lo, hi);
      // Inside the block's sides, leaving past t_k (the other frame left before it).
      if (tout > tin && tout > at && tout - at < 10.0 * delta)
      {
        check.push_back(p);
      }
    }
  }
  EXPECT_GT(check.size(), 1000u);
  EXPECT_EQ(Jumps(moments[0], moments[1], check, 2.0 * delta, sigma), 0);
}

TEST(BoundaryWeights, InnerCellsTakeThePlainLatticesSamples)
{
  // The cells with a boundary face transparent (a NaN scalar), the others of varied
  // opacity: only cells without a boundary face have samples, and with Boundary they are the
  // plain lattice's, bit for bit (All weights their ends, and differs).
  const double lo[3] = { -1.0, -0.5, -1.0 };
  const apc::CellMesh mesh = Block(8, 4, 8, 0.25, lo, true,
    [](int i, int j, int k)
    {
      const bool skin = i == 0 || i == 7 || j == 0 || j == 3 || k == 0 || k == 7;
      return skin ? std::numeric_limits<float>::quiet_NaN()
                  : 0.3f + 0.1f * static_cast<float>((i + 2 * j + 3 * k) % 7);
    });
  const apc::TransferTable table(
    0.0, 1.0, { { 1.f, 1.f, 1.f }, { 1.f, 1.f, 1.f } }, { 0.0, 0.8 }, kSpacing, 1.0);
  const Moments boundary = PassOne(mesh, table, Mode::Boundary);
  const Moments plain = PassOne(mesh, table, Mode::Off);
  const Moments all = PassOne(mesh, table, Mode::All);
  EXPECT_GT(plain.Samples, 1000);
  EXPECT_EQ(boundary.Samples, plain.Samples);
  int same = 0;
  int allSame = 0;
  for (size_t v = 0; v < plain.Values.size(); ++v)
  {
    same += SameBits(boundary.Values[v], plain.Values[v]) ? 1 : 0;
    allSame += SameBits(all.Values[v], plain.Values[v]) ? 1 : 0;
  }
  EXPECT_EQ(same, static_cast<int>(plain.Values.size()));
  EXPECT_LT(allSame, static_cast<int>(plain.Values.size()));
}

TEST(BoundaryWeights, PassTwoReplaysWhatItWouldMarch)
{
  // The cache keeps a weight for every sample once any is weighted: 1 for the samples of the
  // cells without a boundary face, which take the plain path and weigh nothing themselves.
  // Pass 2 from the cache takes what a pass 2 marching again takes.
  const double lo[3] = { -1.0, -0.5, -1.0 };
  const apc::CellMesh mesh = Block(8, 4, 8, 0.25, lo, true, nullptr);
  const apc::TransferTable table(
    0.0, 1.0, { { 1.f, 1.f, 1.f }, { 1.f, 1.f, 1.f } }, { 0.4, 0.4 }, kSpacing, 1.0);
  const apc::LogDepthWarp warp(2.0, 7.0);
  const size_t pixels = static_cast<size_t>(kSize) * kSize;
  std::vector<double> colour[2];
  for (int cache = 0; cache < 2; ++cache)
  {
    apc::VolumeRayMarcher marcher;
    marcher.SetMesh(&mesh);
    marcher.SetView(Camera(), nullptr);
    marcher.SetEndWeightsMode(Mode::Boundary);
    marcher.SetMaxSampleCacheBytes(cache ? size_t(1) << 30 : 0);
    std::vector<double> moments(pixels * 5, 0.0);
    marcher.AccumulateMoments<4>(table, warp, moments.data());
    colour[cache].assign(pixels * 4, 0.0);
    marcher.AccumulateColour<4>(
      table, warp, moments.data(), apc::MomentSettings<4>(), colour[cache].data());
    EXPECT_EQ(marcher.GetLastColourCacheShare(), cache ? 1.0 : 0.0);
  }
  for (size_t v = 0; v < colour[0].size(); ++v)
  {
    EXPECT_NEAR(colour[1][v], colour[0][v], 1e-9 + 1e-6 * colour[0][v]) << "value " << v;
  }
}

} // namespace
