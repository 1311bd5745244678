// SPDX-License-Identifier: BSD-3-Clause
// The VTK-free half of vtkAPCGraphPartition: the dual graph from facets (matched whatever the
// point order, never by hash alone, assembled across processes exactly as the filter does)
// and the METIS call (balance, determinism, the cases answered without METIS, errors).
#include "apcDualGraph.h"
#include "apcGraphPartitioner.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <set>

namespace
{
// Facets of an n x n x n block of hexahedra with point ids as keys; the face point order is
// rotated and reversed from cell to cell, as neighbouring cells see a shared face.
apc::Facets HexBlockFacets(int n, int firstCell = 0, int lastCell = -1)
{
  const int np = n + 1;
  auto pid = [np](int i, int j, int k) { return static_cast<std::int64_t>((k * np + j) * np + i); };
  apc::Facets facets;
  const int cells = n * n * n;
  lastCell = lastCell < 0 ? cells : lastCell;
  for (int c = firstCell; c < lastCell; ++c)
  {
    const int i = c % n, j = (c / n) % n, k = c / (n * n);
    const std::array<std::array<std::int64_t, 4>, 6> faces = { {
      { pid(i, j, k), pid(i, j + 1, k), pid(i, j + 1, k + 1), pid(i, j, k + 1) },
      { pid(i + 1, j, k), pid(i + 1, j + 1, k), pid(i + 1, j + 1, k + 1), pid(i + 1, j, k + 1) },
      { pid(i, j, k), pid(i + 1, j, k), pid(i + 1, j, k + 1), pid(i, j, k + 1) },
      { pid(i, j + 1, k), pid(i + 1, j + 1, k), pid(i + 1, j + 1, k + 1), pid(i, j + 1, k + 1) },
      { pid(i, j, k), pid(i + 1, j, k), pid(i + 1, j + 1, k), pid(i, j + 1, k) },
      { pid(i, j, k + 1), pid(i + 1, j, k + 1), pid(i + 1, j + 1, k + 1), pid(i, j + 1, k + 1) },
    } };
    for (std::size_t f = 0; f < faces.size(); ++f)
    {
      std::array<std::int64_t, 4> face = faces[f];
      std::rotate(face.begin(), face.begin() + (c + f) % 4, face.end());
      if (c % 2)
      {
        std::reverse(face.begin(), face.end());
      }
      facets.Add(c - firstCell, face.data(), face.size());
    }
  }
  return facets;
}

std::set<std::pair<std::int64_t, std::int64_t>> Edges(const apc::CellGraph& g)
{
  std::set<std::pair<std::int64_t, std::int64_t>> edges;
  for (std::int64_t c = 0; c < g.NumberOfCells(); ++c)
  {
    for (std::int64_t e = g.Offsets[c]; e < g.Offsets[c + 1]; ++e)
    {
      edges.emplace(c, g.Adjacency[e]);
    }
  }
  return edges;
}
} // namespace

TEST(DualGraph, HexBlockHasTheGridsNeighbours)
{
  const int n = 7;
  const apc::Facets facets = HexBlockFacets(n);
  const apc::FacetMatches matches = apc::MatchFacets(facets);
  EXPECT_EQ(matches.Pairs.size(), static_cast<std::size_t>(3 * n * n * (n - 1)));
  EXPECT_EQ(matches.Unmatched.size(), static_cast<std::size_t>(6 * n * n)); // the block's skin
  const apc::CellGraph g = apc::BuildDualGraph(n * n * n, facets);
  EXPECT_EQ(g.NumberOfEdges(), 3 * n * n * (n - 1));
  for (int c = 0; c < n * n * n; ++c)
  {
    const int i = c % n, j = (c / n) % n, k = c / (n * n);
    const int expected = (i > 0) + (i < n - 1) + (j > 0) + (j < n - 1) + (k > 0) + (k < n - 1);
    ASSERT_EQ(g.Offsets[c + 1] - g.Offsets[c], expected) << "cell " << c;
    for (std::int64_t e = g.Offsets[c]; e < g.Offsets[c + 1]; ++e)
    {
      const std::int64_t d = std::abs(g.Adjacency[e] - c);
      ASSERT_TRUE(d == 1 || d == n || d == n * n) << "cell " << c << " -> " << g.Adjacency[e];
    }
  }
  EXPECT_EQ(Edges(g).size(), g.Adjacency.size()) << "no repeated neighbours";
}

TEST(DualGraph, FacetsOfDifferentSizesOrPointsNeverMatch)
{
  apc::Facets facets;
  const std::int64_t tri[3] = { 1, 2, 3 };
  const std::int64_t quad[4] = { 1, 2, 3, 4 };
  const std::int64_t tri2[3] = { 1, 2, 4 };
  const std::int64_t triSame[3] = { 3, 1, 2 };
  facets.Add(0, tri, 3);
  facets.Add(1, quad, 4);
  facets.Add(2, tri2, 3);
  facets.Add(3, triSame, 3);
  const apc::FacetMatches m = apc::MatchFacets(facets);
  ASSERT_EQ(m.Pairs.size(), 1u);
  EXPECT_EQ(m.Pairs[0], std::make_pair(std::int64_t(0), std::int64_t(3)));
  EXPECT_EQ(m.Unmatched, (std::vector<std::int64_t>{ 1, 2 }));
}

TEST(DualGraph, NonManifoldFacetLinksEveryCellToTheFirst)
{
  apc::Facets facets;
  const std::int64_t tri[3] = { 5, 6, 7 };
  for (int c = 0; c < 3; ++c)
  {
    facets.Add(c, tri, 3);
  }
  const apc::CellGraph g = apc::BuildDualGraph(3, facets);
  EXPECT_EQ(g.NumberOfEdges(), 2);
  EXPECT_EQ(g.Offsets[1] - g.Offsets[0], 2); // cell 0 sees both
}

TEST(DualGraph, RepeatsAndSelfPairsAreDropped)
{
  const apc::CellGraph g = apc::BuildCellGraph(3, { { 0, 1 }, { 1, 0 }, { 0, 1 }, { 2, 2 } });
  EXPECT_EQ(g.Offsets, (std::vector<std::int64_t>{ 0, 1, 2, 2 }));
  EXPECT_EQ(g.Adjacency, (std::vector<std::int64_t>{ 1, 0 }));
}

// What the filter does on several processes: each matches its own cells' facets, and the
// unmatched ones are matched again together. The result must be the one-process graph.
TEST(DualGraph, SplitThenMatchedAgainEqualsTheWholeGraph)
{
  const int n = 6, cells = n * n * n;
  const apc::CellGraph whole = apc::BuildDualGraph(cells, HexBlockFacets(n));
  const int cuts[] = { 0, 50, 51, 130, cells };
  std::vector<std::pair<std::int64_t, std::int64_t>> pairs;
  apc::Facets boundary;
  for (int r = 0; r + 1 < 5; ++r)
  {
    const apc::Facets local = HexBlockFacets(n, cuts[r], cuts[r + 1]);
    const apc::FacetMatches m = apc::MatchFacets(local);
    for (const auto& p : m.Pairs)
    {
      pairs.emplace_back(p.first + cuts[r], p.second + cuts[r]);
    }
    apc::Facets unmatched;
    for (const std::int64_t f : m.Unmatched)
    {
      unmatched.Add(local.Cell[f], &local.Points[local.Offsets[f]],
        static_cast<std::size_t>(local.Offsets[f + 1] - local.Offsets[f]));
    }
    boundary.Append(unmatched, cuts[r]);
  }
  const apc::FacetMatches across = apc::MatchFacets(boundary);
  pairs.insert(pairs.end(), across.Pairs.begin(), across.Pairs.end());
  const apc::CellGraph assembled = apc::BuildCellGraph(cells, pairs);
  EXPECT_EQ(assembled.Offsets, whole.Offsets);
  EXPECT_EQ(assembled.Adjacency, whole.Adjacency);
}

TEST(GraphPartitioner, BalancedDeterministicAndEveryPartUsed)
{
  const int n = 20, cells = n * n * n;
  const apc::CellGraph g = apc::BuildDualGraph(cells, HexBlockFacets(n));
  for (const int parts : { 2, 4, 7, 16, 64 })
  {
    const apc::GraphPartition a = apc::PartitionCellGraph(g, parts, 3);
    ASSERT_TRUE(a.Ok) << a.Error;
    EXPECT_EQ(a.Method, "metis-kway");
    ASSERT_EQ(a.Part.size(), static_cast<std::size_t>(cells));
    std::vector<int> sizes(parts, 0);
    for (const int p : a.Part)
    {
      ASSERT_TRUE(p >= 0 && p < parts);
      ++sizes[p];
    }
    const double mean = static_cast<double>(cells) / parts;
    EXPECT_LE(*std::max_element(sizes.begin(), sizes.end()), 1.03 * mean + 1) << parts;
    EXPECT_GT(*std::min_element(sizes.begin(), sizes.end()), 0) << parts;
    EXPECT_NEAR(apc::PartitionImbalance(a.Part, parts),
      *std::max_element(sizes.begin(), sizes.end()) / mean, 1e-12);
    // The cut is a cut: counted from the parts it is what METIS reports, and far below the
    // 3 n^2 (n-1) edges.
    std::int64_t cut = 0;
    for (std::int64_t c = 0; c < g.NumberOfCells(); ++c)
    {
      for (std::int64_t e = g.Offsets[c]; e < g.Offsets[c + 1]; ++e)
      {
        cut += a.Part[c] != a.Part[g.Adjacency[e]];
      }
    }
    EXPECT_EQ(cut / 2, a.EdgeCut);
    EXPECT_LT(a.EdgeCut, g.NumberOfEdges() / 4);
    const apc::GraphPartition b = apc::PartitionCellGraph(g, parts, 3);
    EXPECT_EQ(a.Part, b.Part) << "same seed, same parts";
  }
}

TEST(GraphPartitioner, CasesWithoutMetisAndErrors)
{
  const apc::CellGraph g = apc::BuildDualGraph(27, HexBlockFacets(3));
  const apc::GraphPartition one = apc::PartitionCellGraph(g, 1, 0);
  ASSERT_TRUE(one.Ok);
  EXPECT_EQ(one.Method, "single");
  EXPECT_EQ(one.Part, std::vector<int>(27, 0));

  const apc::GraphPartition many = apc::PartitionCellGraph(g, 40, 0);
  ASSERT_TRUE(many.Ok);
  EXPECT_EQ(many.Method, "one-cell-per-part");
  EXPECT_EQ(std::set<int>(many.Part.begin(), many.Part.end()).size(), 27u);

  const apc::GraphPartition loose = apc::PartitionCellGraph(apc::BuildCellGraph(10, {}), 3, 0);
  ASSERT_TRUE(loose.Ok);
  EXPECT_EQ(loose.Method, "blocks");
  EXPECT_EQ(loose.Part, (std::vector<int>{ 0, 0, 0, 0, 1, 1, 1, 2, 2, 2 }));

  EXPECT_FALSE(apc::PartitionCellGraph(g, 0, 0).Ok);
  EXPECT_FALSE(apc::PartitionCellGraph(g, -3, 0).Ok);
  const apc::GraphPartition none = apc::PartitionCellGraph(apc::CellGraph{}, 4, 0);
  EXPECT_FALSE(none.Ok);
  EXPECT_NE(none.Error.find("no cells"), std::string::npos);
}
