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

// The rule for the default (pure, so it is tested alone): a process bound to fewer cores than
// the node has (affinityCores < nodeCores) keeps its mask, i.e. TBB's choice (0); an unbound
// one takes twice its share of the node, 2 * (nodeCores / processesOnNode, at least one), at
// most nodeCores. Twice, because a view's work is rarely even over the ranks: a rank that
// finished waits in a barrier that sleeps (apcCollectiveTimes.h), and the ranks still
// rendering take the cores it left with their second share; one share each left those cores
// idle (4 ranks on 2 cores, wind 1024²: later frames about 20 % faster, docs/performance.md).
// Bounded, not every core per rank: 64 ranks on 64 cores run 128 threads, not 4,096.
inline int NodeShareOfThreads(int nodeCores, int affinityCores, int processesOnNode)
{
  if (nodeCores < 1 || processesOnNode < 1 || (affinityCores > 0 && affinityCores < nodeCores))
  {
    return 0;
  }
  const int share = std::max(1, nodeCores / processesOnNode);
  return std::min(nodeCores, 2 * share);
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
