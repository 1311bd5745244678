#include "apcBoundaryFaces.h"

#include <algorithm>
#include <cstring>
#include <numeric>

namespace apc
{

//------------------------------------------------------------------------------
int FaceOwner(const CellMesh::FaceCorners& face, int processes)
{
  uint64_t h = 1469598103934665603ull;
  for (double x : face)
  {
    uint64_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    h = (h ^ bits) * 1099511628211ull;
    h ^= h >> 29;
  }
  return processes > 0 ? static_cast<int>(h % static_cast<uint64_t>(processes)) : 0;
}

//------------------------------------------------------------------------------
std::vector<uint8_t> MatchBoundaryFaces(
  const std::vector<CellMesh::FaceCorners>& received, const std::vector<int64_t>& counts)
{
  // Sorted by corners, equal faces sit side by side; the sender of each tells whether two
  // processes hold it (the same process never sends a face twice, but a bad input might: such
  // a pair alone does not make a face inner).
  const size_t n = received.size();
  std::vector<int> sender(n, 0);
  size_t at = 0;
  for (size_t p = 0; p < counts.size(); ++p)
  {
    for (int64_t i = 0; i < counts[p] && at < n; ++i)
    {
      sender[at++] = static_cast<int>(p);
    }
  }
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t(0));
  std::sort(order.begin(), order.end(),
    [&](size_t a, size_t b)
    { return received[a] != received[b] ? received[a] < received[b] : sender[a] < sender[b]; });
  std::vector<uint8_t> inner(n, 0);
  for (size_t first = 0; first < n;)
  {
    size_t last = first + 1;
    while (last < n && received[order[last]] == received[order[first]])
    {
      ++last;
    }
    // Senders ascend within the run: two processes if the first and last differ.
    if (sender[order[first]] != sender[order[last - 1]])
    {
      for (size_t i = first; i < last; ++i)
      {
        inner[order[i]] = 1;
      }
    }
    first = last;
  }
  return inner;
}

} // namespace apc
