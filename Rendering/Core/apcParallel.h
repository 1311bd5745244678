// The one way the core runs work in parallel: TBB tasks in an arena of the requested size, so
// that a thread count set on a mapper limits APC alone and leaves VTK's SMP backend alone.
#ifndef apcParallel_h
#define apcParallel_h

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cstdint>

namespace apc
{

// Calls body(begin, end) on disjoint chunks of [0, count) of at least grain items, on up to
// threads threads (0 = as many as TBB offers).
template <class Body>
void ParallelFor(int threads, int64_t count, int64_t grain, Body&& body)
{
  if (count <= 0)
  {
    return;
  }
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute(
    [&]
    {
      tbb::parallel_for(tbb::blocked_range<int64_t>(0, count, grain),
        [&](const tbb::blocked_range<int64_t>& range) { body(range.begin(), range.end()); });
    });
}

} // namespace apc

#endif
