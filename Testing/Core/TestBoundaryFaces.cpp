// Sample End Weights = Boundary on several processes without MPI (apcBoundaryFaces.h): the
// pieces' boundary faces routed to their owners, matched there and taken back give every
// piece the flags of the whole mesh, whatever the split; without the matching the faces
// between pieces stay flagged.
#include "apcBoundaryFaces.h"
#include "apcCellMesh.h"
#include "apcDepthWarp.h"
#include "apcRayCamera.h"
#include "apcTransferTable.h"
#include "apcVolumeRayMarcher.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

namespace
{

// The hexahedra (i, j, k) of an nx x ny x nz block of size h for which keep(i, j, k), each
// piece with its own points (a rank's piece), cell (0, 0, 0) copies times; cells[c]: cell c's
// (i, j, k).
apc::CellMesh Piece(const int n[3], double h, const std::function<bool(int, int, int)>& keep,
  std::vector<std::array<int, 3>>& cells, int copies = 1)
{
  apc::CellMesh mesh;
  auto point = [&](int i, int j, int k) -> int64_t
  {
    mesh.Points.push_back({ -1.0 + i * h, -0.5 + j * h, (k - 2) * h });
    return static_cast<int64_t>(mesh.Points.size()) - 1;
  };
  for (int k = 0; k < n[2]; ++k)
  {
    for (int j = 0; j < n[1]; ++j)
    {
      for (int i = 0; i < n[0]; ++i)
      {
        if (!keep(i, j, k))
        {
          continue;
        }
        const int64_t ids[8] = { point(i, j, k), point(i + 1, j, k), point(i + 1, j + 1, k),
          point(i, j + 1, k), point(i, j, k + 1), point(i + 1, j, k + 1),
          point(i + 1, j + 1, k + 1), point(i, j + 1, k + 1) };
        for (int copy = 0; copy < (i == 0 && j == 0 && k == 0 ? copies : 1); ++copy)
        {
          mesh.AddCell(apc::CellShape::Hexahedron, ids);
          cells.push_back({ i, j, k });
        }
      }
    }
  }
  mesh.PointScalars.assign(mesh.Points.size(), 0.5f);
  EXPECT_TRUE(mesh.Finalize());
  mesh.FindBoundaryPlanes();
  return mesh;
}

// What the exchange does between processes, in one: every piece's boundary faces to their
// owners, each owner's flags back to the pieces.
void MatchPieces(std::vector<apc::CellMesh>& pieces)
{
  const int processes = static_cast<int>(pieces.size());
  std::vector<std::vector<apc::CellMesh::FaceCorners>> faces(processes);
  std::vector<std::vector<int>> owners(processes);
  // received[o]: owner o's faces, sender by sender; from[o][s]: how many from sender s.
  std::vector<std::vector<apc::CellMesh::FaceCorners>> received(processes);
  std::vector<std::vector<int64_t>> from(processes, std::vector<int64_t>(processes, 0));
  for (int s = 0; s < processes; ++s)
  {
    faces[s] = pieces[s].GetBoundaryFaces();
    for (const auto& face : faces[s])
    {
      owners[s].push_back(apc::FaceOwner(face, processes));
    }
  }
  for (int o = 0; o < processes; ++o)
  {
    for (int s = 0; s < processes; ++s)
    {
      for (size_t f = 0; f < faces[s].size(); ++f)
      {
        if (owners[s][f] == o)
        {
          received[o].push_back(faces[s][f]);
          ++from[o][s];
        }
      }
    }
  }
  std::vector<std::vector<uint8_t>> inner(processes);
  for (int o = 0; o < processes; ++o)
  {
    inner[o] = apc::MatchBoundaryFaces(received[o], from[o]);
  }
  // Back in each sender's order: owner by owner, its faces in the order sent.
  for (int s = 0; s < processes; ++s)
  {
    std::vector<uint8_t> flags(faces[s].size(), 0);
    for (int o = 0; o < processes; ++o)
    {
      size_t at = 0;
      for (int earlier = 0; earlier < s; ++earlier)
      {
        at += static_cast<size_t>(from[o][earlier]);
      }
      for (size_t f = 0; f < faces[s].size(); ++f)
      {
        if (owners[s][f] == o)
        {
          flags[f] = inner[o][at++];
        }
      }
    }
    pieces[s].ClearBoundaryFaces(flags);
  }
}

TEST(BoundaryFaces, PiecesMatchedAcrossProcessesFlagWhatTheWholeMeshFlags)
{
  const int n[3] = { 6, 5, 4 };
  const double h = 0.25;
  std::vector<std::array<int, 3>> wholeCells;
  const apc::CellMesh whole = Piece(
    n, h, [](int, int, int) { return true; }, wholeCells);
  std::mt19937 rng(3);
  for (int processes : { 1, 2, 3, 4 })
  {
    for (bool slabs : { true, false })
    {
      // Slabs along x, or every cell dealt at random (pieces of many small parts).
      std::vector<int> owner(static_cast<size_t>(n[0] * n[1] * n[2]));
      for (size_t c = 0; c < owner.size(); ++c)
      {
        owner[c] = slabs ? static_cast<int>(c % n[0]) * processes / n[0]
                         : static_cast<int>(rng() % static_cast<unsigned>(processes));
      }
      auto index = [&](int i, int j, int k) { return (k * n[1] + j) * n[0] + i; };
      std::vector<apc::CellMesh> pieces;
      std::vector<std::vector<std::array<int, 3>>> cells(processes);
      for (int p = 0; p < processes; ++p)
      {
        pieces.push_back(Piece(
          n, h, [&](int i, int j, int k) { return owner[index(i, j, k)] == p; }, cells[p]));
      }
      int differ = 0;
      for (int p = 0; p < processes; ++p)
      {
        for (size_t c = 0; c < cells[p].size(); ++c)
        {
          const auto& ijk = cells[p][c];
          differ += pieces[p].GetBoundaryPlanes(static_cast<int64_t>(c)) !=
            whole.GetBoundaryPlanes(index(ijk[0], ijk[1], ijk[2]));
        }
      }
      // Each piece alone flags the faces between pieces.
      EXPECT_EQ(differ > 0, processes > 1) << processes << " " << slabs;
      MatchPieces(pieces);
      for (int p = 0; p < processes; ++p)
      {
        EXPECT_TRUE(pieces[p].SharesBoundary());
        for (size_t c = 0; c < cells[p].size(); ++c)
        {
          const auto& ijk = cells[p][c];
          EXPECT_EQ(pieces[p].GetBoundaryPlanes(static_cast<int64_t>(c)),
            whole.GetBoundaryPlanes(index(ijk[0], ijk[1], ijk[2])))
            << processes << " processes, slabs " << slabs << ", piece " << p << " cell " << c;
        }
      }
    }
  }
}

// A face that four cells hold (the wind data has 102: cells of its polyhedra meeting on a
// triangle), split three to one: inner in one process, so the piece holding one copy must
// learn of the three the other matched among themselves.
TEST(BoundaryFaces, AFaceThreeCellsOfAPieceHoldIsInnerForTheOtherPiece)
{
  const int n[3] = { 2, 1, 1 };
  std::vector<std::array<int, 3>> cells;
  const apc::CellMesh whole = Piece(
    n, 0.5, [](int, int, int) { return true; }, cells, 3);
  ASSERT_EQ(whole.GetNumberOfCells(), 4);
  // Plane order of a hexahedron: the face x = 0.5 between the cells is inner in one process.
  const uint8_t wholeLast = whole.GetBoundaryPlanes(3);
  std::vector<apc::CellMesh> pieces;
  std::vector<std::vector<std::array<int, 3>>> pieceCells(2);
  pieces.push_back(Piece(
    n, 0.5, [](int i, int, int) { return i == 0; }, pieceCells[0], 3));
  pieces.push_back(Piece(
    n, 0.5, [](int i, int, int) { return i == 1; }, pieceCells[1]));
  ASSERT_NE(pieces[1].GetBoundaryPlanes(0), wholeLast) << "alone, the shared face is boundary";
  MatchPieces(pieces);
  EXPECT_EQ(pieces[1].GetBoundaryPlanes(0), wholeLast);
  for (int64_t c = 0; c < 3; ++c)
  {
    EXPECT_EQ(pieces[0].GetBoundaryPlanes(c), whole.GetBoundaryPlanes(c)) << c;
  }
}

TEST(BoundaryFaces, AFaceIsInnerOnlyWhenTwoProcessesSendIt)
{
  apc::CellMesh::FaceCorners a;
  a.fill(1.0);
  apc::CellMesh::FaceCorners b = a;
  b[0] = 2.0;
  // a from processes 0 and 2, b from process 1 alone, and from process 1 twice (a bad input).
  const std::vector<apc::CellMesh::FaceCorners> received = { a, b, b, a };
  const std::vector<int64_t> counts = { 1, 2, 1 };
  const std::vector<uint8_t> inner = apc::MatchBoundaryFaces(received, counts);
  EXPECT_EQ(inner, (std::vector<uint8_t>{ 1, 0, 0, 1 }));
  EXPECT_EQ(apc::FaceOwner(a, 3), apc::FaceOwner(a, 3));
  EXPECT_LT(apc::FaceOwner(b, 3), 3);
}

// Pass 1 with Boundary on pieces matched as the exchange matches them sums to the whole mesh's
// moments: every weight depends on the pair and the ray, never on the piece, also at a spacing
// close to the cells' size where a ray's last lattice point lies far before the piece's own
// far bound (each piece's far bound differs; a weight taken from it would differ too).
TEST(BoundaryFaces, PiecesMatchedSumToTheWholeMeshsMoments)
{
  const int n[3] = { 6, 5, 4 };
  const double h = 0.25;
  constexpr int kSize = 48;
  const apc::RayCamera camera({ 0.3, 1.2, 3.0 }, { -0.25, 0.125, 0.0 }, { 0, 1, 0 }, 40.0, false,
    1.0, kSize, kSize, 0.1, 20.0);
  auto passOne = [&](const apc::CellMesh& mesh, double spacing)
  {
    const apc::TransferTable table(
      0.0, 1.0, { { 1.f, 1.f, 1.f }, { 1.f, 1.f, 1.f } }, { 0.4, 0.4 }, spacing, 1.0);
    apc::VolumeRayMarcher marcher;
    marcher.SetMesh(&mesh);
    marcher.SetView(camera, nullptr);
    marcher.SetEndWeightsMode(apc::VolumeRayMarcher::EndWeightsMode::Boundary);
    std::vector<double> moments(static_cast<size_t>(kSize) * kSize * 5, 0.0);
    marcher.AccumulateMoments<4>(table, apc::LogDepthWarp(1.5, 6.0), moments.data());
    return moments;
  };
  std::vector<std::array<int, 3>> wholeCells;
  const apc::CellMesh whole = Piece(
    n, h, [](int, int, int) { return true; }, wholeCells);
  for (int processes : { 2, 4 })
  {
    // Slabs along the depth (k), so that the pieces' far bounds differ.
    std::vector<apc::CellMesh> pieces;
    std::vector<std::vector<std::array<int, 3>>> cells(processes);
    for (int p = 0; p < processes; ++p)
    {
      pieces.push_back(Piece(
        n, h, [&](int, int, int k) { return k * processes / n[2] == p; }, cells[p]));
    }
    MatchPieces(pieces);
    for (double spacing : { 0.05, 0.2 })
    {
      const std::vector<double> expected = passOne(whole, spacing);
      std::vector<double> sum(expected.size(), 0.0);
      for (const apc::CellMesh& piece : pieces)
      {
        const std::vector<double> own = passOne(piece, spacing);
        for (size_t i = 0; i < sum.size(); ++i)
        {
          sum[i] += own[i];
        }
      }
      int covered = 0;
      for (int p = 0; p < kSize * kSize; ++p)
      {
        covered += expected[5 * p] > 0 ? 1 : 0;
        EXPECT_NEAR(sum[5 * p], expected[5 * p], 1e-9 * (1.0 + expected[5 * p]))
          << processes << " pieces, spacing " << spacing << ", pixel " << p;
      }
      EXPECT_GT(covered, kSize * kSize / 4) << processes << " pieces, spacing " << spacing;
    }
  }
}

} // namespace
