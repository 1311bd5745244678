// SPDX-License-Identifier: BSD-3-Clause
#include "apcGraphPartitioner.h"

#include <metis.h>

#include <algorithm>
#include <limits>

namespace apc
{

GraphPartition PartitionCellGraph(const CellGraph& graph, int parts, int seed)
{
  GraphPartition result;
  const std::int64_t n = graph.NumberOfCells();
  if (n <= 0)
  {
    result.Error = "no cells to partition";
    return result;
  }
  if (parts < 1)
  {
    result.Error = "the number of parts must be at least 1, not " + std::to_string(parts);
    return result;
  }
  result.Part.assign(static_cast<std::size_t>(n), 0);
  result.Ok = true;
  if (parts == 1)
  {
    result.Method = "single";
    return result;
  }
  if (parts >= n)
  {
    // METIS misbehaves with fewer vertices than parts; one cell per part is the best balance.
    for (std::int64_t c = 0; c < n; ++c)
    {
      result.Part[c] = static_cast<int>(c);
    }
    result.Method = "one-cell-per-part";
    return result;
  }
  if (graph.Adjacency.empty())
  {
    // Nothing is connected (e.g. vertex cells): any balanced split cuts no edge.
    for (std::int64_t c = 0; c < n; ++c)
    {
      result.Part[c] = static_cast<int>(c * parts / n);
    }
    result.Method = "blocks";
    return result;
  }
  if (n > std::numeric_limits<idx_t>::max() ||
    static_cast<std::int64_t>(graph.Adjacency.size()) > std::numeric_limits<idx_t>::max())
  {
    result.Ok = false;
    result.Error = "graph of " + std::to_string(n) + " cells and " +
      std::to_string(graph.Adjacency.size()) + " adjacency entries exceeds METIS's 32-bit ids";
    return result;
  }

  std::vector<idx_t> xadj(graph.Offsets.begin(), graph.Offsets.end());
  std::vector<idx_t> adjncy(graph.Adjacency.begin(), graph.Adjacency.end());
  std::vector<idx_t> part(static_cast<std::size_t>(n), 0);
  idx_t nvtxs = static_cast<idx_t>(n);
  idx_t ncon = 1;
  idx_t nparts = parts;
  idx_t objval = 0;
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_SEED] = seed;
  options[METIS_OPTION_NUMBERING] = 0;
  const int status = METIS_PartGraphKway(&nvtxs, &ncon, xadj.data(), adjncy.data(), nullptr,
    nullptr, nullptr, &nparts, nullptr, nullptr, options, &objval, part.data());
  if (status != METIS_OK)
  {
    result.Ok = false;
    result.Error = std::string("METIS_PartGraphKway failed (") +
      (status == METIS_ERROR_MEMORY ? "out of memory"
                                    : (status == METIS_ERROR_INPUT ? "input error" : "error")) +
      ")";
    result.Part.clear();
    return result;
  }
  std::copy(part.begin(), part.end(), result.Part.begin());
  result.EdgeCut = objval;
  result.Method = "metis-kway";
  return result;
}

double PartitionImbalance(const std::vector<int>& part, int parts)
{
  if (part.empty() || parts < 1)
  {
    return 0;
  }
  std::vector<std::int64_t> sizes(static_cast<std::size_t>(parts), 0);
  for (const int p : part)
  {
    if (p >= 0 && p < parts)
    {
      ++sizes[p];
    }
  }
  const double mean = static_cast<double>(part.size()) / parts;
  return static_cast<double>(*std::max_element(sizes.begin(), sizes.end())) / mean;
}

} // namespace apc
