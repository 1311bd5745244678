// SPDX-License-Identifier: BSD-3-Clause
#include "apcDualGraph.h"

#include <algorithm>
#include <numeric>

namespace apc
{

void Facets::Add(std::int64_t cell, const std::int64_t* keys, std::size_t n)
{
  this->Cell.push_back(cell);
  this->Points.insert(this->Points.end(), keys, keys + n);
  this->Offsets.push_back(static_cast<std::int64_t>(this->Points.size()));
}

void Facets::Append(const Facets& other, std::int64_t cellOffset)
{
  const std::int64_t base = this->Offsets.back();
  for (const std::int64_t c : other.Cell)
  {
    this->Cell.push_back(c + cellOffset);
  }
  for (std::size_t f = 1; f < other.Offsets.size(); ++f)
  {
    this->Offsets.push_back(base + other.Offsets[f]);
  }
  this->Points.insert(this->Points.end(), other.Points.begin(), other.Points.end());
}

namespace
{
std::uint64_t Mix(std::uint64_t h, std::uint64_t v)
{
  // splitmix64 finaliser on the running value: point ids are small and clustered, so a plain
  // sum or xor would collide constantly.
  h ^= v + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ULL;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebULL;
  h ^= h >> 31;
  return h;
}

struct HashedFacet
{
  std::uint64_t Hash;
  std::int64_t Facet;
  bool operator<(const HashedFacet& o) const
  {
    return this->Hash < o.Hash || (this->Hash == o.Hash && this->Facet < o.Facet);
  }
};

// Each facet's keys sorted (a facet's orientation and starting point differ between its
// cells) into `sorted`, and the facets ordered by the hash of their sorted keys.
std::vector<HashedFacet> SortKeysAndHash(const Facets& facets, std::vector<std::int64_t>& sorted)
{
  const std::size_t n = facets.Size();
  sorted = facets.Points;
  std::vector<HashedFacet> order(n);
  for (std::size_t f = 0; f < n; ++f)
  {
    auto first = sorted.begin() + facets.Offsets[f];
    auto last = sorted.begin() + facets.Offsets[f + 1];
    // Facets have 2-4 keys (rarely more): insertion sort beats std::sort's set-up there.
    for (auto it = first + (first != last); it < last; ++it)
    {
      const std::int64_t v = *it;
      auto hole = it;
      for (; hole != first && *(hole - 1) > v; --hole)
      {
        *hole = *(hole - 1);
      }
      *hole = v;
    }
    std::uint64_t h = static_cast<std::uint64_t>(last - first);
    for (auto it = first; it != last; ++it)
    {
      h = Mix(h, static_cast<std::uint64_t>(*it));
    }
    order[f] = { h, static_cast<std::int64_t>(f) };
  }
  std::sort(order.begin(), order.end());
  return order;
}

// Matches the facets of one run of equal hashes. A run is almost always one facet seen from
// its two cells; anything longer (a hash collision or a non-manifold facet) is split by exact
// comparison, and a facet shared by more than two cells links each of them to the first.
class RunMatcher
{
public:
  RunMatcher(const Facets& facets, const std::vector<std::int64_t>& sorted)
    : Input(facets)
    , Sorted(sorted)
  {
  }

  void Match(const std::vector<std::int64_t>& run, FacetMatches& result)
  {
    this->Grouped.assign(run.size(), 0);
    for (std::size_t i = 0; i < run.size(); ++i)
    {
      if (this->Grouped[i])
      {
        continue;
      }
      this->Grouped[i] = 1;
      bool matched = false;
      const std::int64_t cellA = this->Input.Cell[run[i]];
      for (std::size_t j = i + 1; j < run.size(); ++j)
      {
        if (!this->Grouped[j] && this->Same(run[i], run[j]))
        {
          this->Grouped[j] = 1;
          matched = true;
          const std::int64_t cellB = this->Input.Cell[run[j]];
          if (cellA != cellB)
          {
            result.Pairs.emplace_back(std::min(cellA, cellB), std::max(cellA, cellB));
          }
        }
      }
      if (!matched)
      {
        result.Unmatched.push_back(run[i]);
      }
    }
  }

private:
  bool Same(std::int64_t a, std::int64_t b) const
  {
    const std::vector<std::int64_t>& offsets = this->Input.Offsets;
    return offsets[a + 1] - offsets[a] == offsets[b + 1] - offsets[b] &&
      std::equal(this->Sorted.begin() + offsets[a], this->Sorted.begin() + offsets[a + 1],
        this->Sorted.begin() + offsets[b]);
  }

  const Facets& Input;
  const std::vector<std::int64_t>& Sorted;
  std::vector<char> Grouped;
};
} // namespace

FacetMatches MatchFacets(const Facets& facets)
{
  const std::size_t n = facets.Size();
  std::vector<std::int64_t> sorted;
  const std::vector<HashedFacet> order = SortKeysAndHash(facets, sorted);
  RunMatcher matcher(facets, sorted);
  FacetMatches result;
  result.Pairs.reserve(n / 2);
  std::vector<std::int64_t> run;
  for (std::size_t begin = 0; begin < n;)
  {
    std::size_t end = begin + 1;
    while (end < n && order[end].Hash == order[begin].Hash)
    {
      ++end;
    }
    run.clear();
    for (std::size_t i = begin; i < end; ++i)
    {
      run.push_back(order[i].Facet);
    }
    matcher.Match(run, result);
    begin = end;
  }
  std::sort(result.Unmatched.begin(), result.Unmatched.end());
  return result;
}

CellGraph BuildCellGraph(
  std::int64_t numberOfCells, const std::vector<std::pair<std::int64_t, std::int64_t>>& pairs)
{
  CellGraph graph;
  graph.Offsets.assign(static_cast<std::size_t>(numberOfCells) + 1, 0);
  for (const auto& p : pairs)
  {
    if (p.first != p.second)
    {
      ++graph.Offsets[p.first + 1];
      ++graph.Offsets[p.second + 1];
    }
  }
  std::partial_sum(graph.Offsets.begin(), graph.Offsets.end(), graph.Offsets.begin());
  std::vector<std::int64_t> adjacency(static_cast<std::size_t>(graph.Offsets.back()));
  std::vector<std::int64_t> fill(graph.Offsets.begin(), graph.Offsets.end() - 1);
  for (const auto& p : pairs)
  {
    if (p.first != p.second)
    {
      adjacency[fill[p.first]++] = p.second;
      adjacency[fill[p.second]++] = p.first;
    }
  }
  // Sort and drop repeats per row, compacting in place.
  std::int64_t write = 0;
  for (std::int64_t c = 0; c < numberOfCells; ++c)
  {
    auto first = adjacency.begin() + graph.Offsets[c];
    auto last = adjacency.begin() + graph.Offsets[c + 1];
    std::sort(first, last);
    last = std::unique(first, last);
    graph.Offsets[c] = write;
    for (auto it = first; it != last; ++it)
    {
      adjacency[write++] = *it;
    }
  }
  graph.Offsets[numberOfCells] = write;
  adjacency.resize(static_cast<std::size_t>(write));
  graph.Adjacency = std::move(adjacency);
  return graph;
}

CellGraph BuildDualGraph(std::int64_t numberOfCells, const Facets& facets)
{
  return BuildCellGraph(numberOfCells, MatchFacets(facets).Pairs);
}

} // namespace apc
