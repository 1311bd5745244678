// The one way the core runs work in parallel: TBB tasks in an arena of the requested size, so
// that a thread count set on a mapper limits APC alone and leaves VTK's SMP backend alone.
#ifndef apcParallel_h
#define apcParallel_h

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <vector>

namespace apc
{

// The threads used where none are requested (0): this process's share of its node's cores,
// set once by whoever knows how many processes share the node (apcNodeThreads.h); 0 leaves
// it to TBB, which follows the process's affinity mask.
inline std::atomic<int> DefaultThreadsValue{ 0 };

inline void SetDefaultThreads(int threads)
{
  DefaultThreadsValue.store(threads > 0 ? threads : 0);
}

inline int GetDefaultThreads()
{
  return DefaultThreadsValue.load();
}

// The arena size for a request: the request itself, else the default above, else TBB's.
inline int ThreadsFor(int requested)
{
  const int threads = requested > 0 ? requested : GetDefaultThreads();
  return threads > 0 ? threads : tbb::task_arena::automatic;
}

// The threads an arena for this request runs: ThreadsFor's, or TBB's own number.
inline int ConcurrencyFor(int requested)
{
  const int threads = ThreadsFor(requested);
  return threads > 0 ? threads : tbb::this_task_arena::max_concurrency();
}

// One process's affinity mask: bit c of word c / 64 set if it may run on core c.
using CoreMask = std::vector<uint64_t>;

// The rule for the default (pure, so it is tested alone). masks holds the affinity mask of
// every process on the node, self is this process's index. Each core of this process's mask
// is shared among the processes whose masks hold it; the sum over its cores of
// 1 / (processes sharing the core) is its share of the node (cores / processes when nobody is
// bound, 1 when bound alone to a core, 1 for each of 32 ranks bound to a 32-core socket). The
// process takes twice its share, rounded down and at least one, at most its mask's cores.
// Twice, because a view's work is rarely even over the ranks: a rank that finished waits in a
// barrier that sleeps (apcCollectiveTimes.h), and the ranks still rendering take the cores it
// left with their second share; one share each left those cores idle (4 ranks on 2 cores,
// wind 1024²: later frames about 20 % faster, docs/performance.md). Bounded, not every core of
// the mask: 64 ranks on 64 cores run 128 threads, not 4,096, whether they are unbound or bound
// to a socket of 32 cores each (mpirun's default above 2 ranks). 0 (TBB's choice) if self has
// no mask or no core.
inline int NodeShareOfThreads(const std::vector<CoreMask>& masks, size_t self)
{
  if (self >= masks.size())
  {
    return 0;
  }
  const CoreMask& mine = masks[self];
  int cores = 0;
  double share = 0;
  for (size_t word = 0; word < mine.size(); ++word)
  {
    for (int bit = 0; bit < 64; ++bit)
    {
      const uint64_t core = uint64_t(1) << bit;
      if (!(mine[word] & core))
      {
        continue;
      }
      int sharing = 0;
      for (const CoreMask& other : masks)
      {
        sharing += word < other.size() && (other[word] & core) ? 1 : 0;
      }
      ++cores;
      share += 1.0 / sharing;
    }
  }
  if (cores == 0)
  {
    return 0;
  }
  // The share is a sum of fractions: a little slack so that 3 x 1/3 counts as one core.
  const int whole = std::max(1, static_cast<int>(share + 1e-9));
  return std::min(cores, 2 * whole);
}

// Calls body(begin, end) on disjoint chunks of [0, count) of at least grain items, on up to
// threads threads (0 = the default above).
template <class Body>
void ParallelFor(int threads, int64_t count, int64_t grain, Body&& body)
{
  if (count <= 0)
  {
    return;
  }
  tbb::task_arena arena(ThreadsFor(threads));
  arena.execute(
    [&]
    {
      tbb::parallel_for(tbb::blocked_range<int64_t>(0, count, grain),
        [&](const tbb::blocked_range<int64_t>& range) { body(range.begin(), range.end()); });
    });
}

} // namespace apc

#endif
