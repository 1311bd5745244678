#include "apcHugePages.h"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>

#if defined(__unix__) || defined(__APPLE__)
#include <sys/mman.h>
#include <time.h>
#define APC_HUGE_MMAP 1
#endif

namespace apc
{

namespace
{
std::atomic<int> ForcedHugePages{ -1 };

size_t WholeHugePages(size_t bytes)
{
  return (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
}

#ifdef APC_HUGE_MMAP
// size bytes (whole huge pages) of address space at a 2 MiB-aligned start, or null. Mapped
// with a huge page of slack, then trimmed: mmap itself only aligns to 4 KiB, and a huge page
// can only back a 2 MiB-aligned range.
void* MapAligned(size_t size)
{
  void* mapped = mmap(nullptr, size + kHugePageBytes, PROT_READ | PROT_WRITE,
    MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (mapped == MAP_FAILED)
  {
    return nullptr;
  }
  const uintptr_t start = reinterpret_cast<uintptr_t>(mapped);
  const uintptr_t aligned = (start + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
  if (aligned > start)
  {
    munmap(mapped, aligned - start);
  }
  if (start + kHugePageBytes > aligned)
  {
    munmap(reinterpret_cast<void*>(aligned + size), start + kHugePageBytes - aligned);
  }
  return reinterpret_cast<void*>(aligned);
}

double ThreadSeconds()
{
  timespec t{};
#ifdef CLOCK_THREAD_CPUTIME_ID
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
#else
  clock_gettime(CLOCK_MONOTONIC, &t);
#endif
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// This thread's CPU seconds (the faults' kernel time is the thread's) to first write every
// 4 KiB page of a fresh mapping of size bytes given advice; -1 if it cannot be mapped.
double FirstTouchSeconds(size_t size, int advice)
{
  void* block = MapAligned(size);
  if (!block)
  {
    return -1;
  }
  if (advice >= 0)
  {
    madvise(block, size, advice);
  }
  volatile unsigned char* bytes = static_cast<unsigned char*>(block);
  const double start = ThreadSeconds();
  for (size_t i = 0; i < size; i += 4096)
  {
    bytes[i] = 1;
  }
  const double seconds = ThreadSeconds() - start;
  munmap(block, size);
  return seconds;
}
#endif

// APC_HUGE_PAGES as set: 0 or 1, else -1 (not set, or another value).
int FromEnvironment()
{
  const char* value = std::getenv("APC_HUGE_PAGES");
  if (value && (std::strcmp(value, "0") == 0 || std::strcmp(value, "1") == 0))
  {
    return value[0] == '1' ? 1 : 0;
  }
  return -1;
}

bool FromEnvironmentOrProbe()
{
  const int forced = FromEnvironment();
  if (forced >= 0)
  {
    return forced == 1;
  }
  const PageTouchCost cost = MeasurePageTouch(kPageProbeBytes, kCheap4KiBSecondsPerMB);
  return ChooseHugePages(cost, kPageProbeBytes);
}
}

bool ChooseHugePages(const PageTouchCost& cost, size_t bytes)
{
  const double megabytes = static_cast<double>(WholeHugePages(bytes)) / (1 << 20);
  if (cost.Small < kCheap4KiBSecondsPerMB * megabytes)
  {
    return false;
  }
  // Huge pages on a tie: fewer TLB entries for the same bytes.
  return !(cost.Small < cost.Huge);
}

PageTouchCost MeasurePageTouch(size_t bytes, double cheapSmallSecondsPerMB)
{
  PageTouchCost cost;
#if defined(APC_HUGE_MMAP) && defined(MADV_HUGEPAGE) && defined(MADV_NOHUGEPAGE)
  const size_t size = WholeHugePages(bytes);
  // 4 KiB pages first: memory the huge pages' probe freed is not handed to it. In 1 MB rounds,
  // the cheapest taken for all: an interrupt or a profiler's sample in one round (a share of a
  // millisecond) would otherwise count as the faults' cost.
  constexpr size_t kRound = size_t(1) << 20;
  double small = -1;
  for (size_t done = 0; done < size; done += kRound)
  {
    const double round = FirstTouchSeconds(kRound, MADV_NOHUGEPAGE);
    if (round < 0)
    {
      return cost;
    }
    small = small < 0 ? round : std::min(small, round);
  }
  small *= static_cast<double>(size) / kRound;
  cost.Small = small;
  cost.Huge = small;
  if (small >= cheapSmallSecondsPerMB * static_cast<double>(size) / (1 << 20))
  {
    const double huge = FirstTouchSeconds(size, MADV_HUGEPAGE);
    cost.Huge = huge >= 0 ? huge : small;
  }
#else
  (void)bytes;
  (void)cheapSmallSecondsPerMB;
#endif
  return cost;
}

bool HugePagesWanted()
{
  const int forced = ForcedHugePages.load(std::memory_order_relaxed);
  if (forced >= 0)
  {
    return forced == 1;
  }
  static const bool chosen = FromEnvironmentOrProbe();
  return chosen;
}

void SetHugePagesWantedForTesting(int wanted)
{
  ForcedHugePages.store(wanted < 0 ? -1 : (wanted > 0 ? 1 : 0), std::memory_order_relaxed);
}

void* AllocateHugeBlock(size_t bytes)
{
  if (bytes == 0)
  {
    return nullptr;
  }
#ifdef APC_HUGE_MMAP
  const size_t size = WholeHugePages(bytes);
  void* block = MapAligned(size);
  if (!block)
  {
    return nullptr;
  }
#if defined(MADV_HUGEPAGE) && defined(MADV_NOHUGEPAGE)
  // A hint either way: 4 KiB pages also where the system gives huge pages unasked.
  madvise(block, size, HugePagesWanted() ? MADV_HUGEPAGE : MADV_NOHUGEPAGE);
#endif
  return block;
#else
  return ::operator new(bytes, std::nothrow);
#endif
}

void AdviseHugePages(void* memory, size_t bytes)
{
#if defined(APC_HUGE_MMAP) && defined(MADV_HUGEPAGE)
  const uintptr_t start = reinterpret_cast<uintptr_t>(memory);
  const uintptr_t first = (start + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
  const uintptr_t last = (start + bytes) / kHugePageBytes * kHugePageBytes;
  if (memory && last > first && FromEnvironment() != 0)
  {
    madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
  }
#else
  (void)memory;
  (void)bytes;
#endif
}

void AdviseFrameHugePages(void* memory, size_t bytes)
{
  if (HugePagesWanted())
  {
    AdviseHugePages(memory, bytes);
  }
}

void FreeHugeBlock(void* block, size_t bytes)
{
  if (!block)
  {
    return;
  }
#ifdef APC_HUGE_MMAP
  munmap(block, WholeHugePages(bytes));
#else
  (void)bytes;
  ::operator delete(block);
#endif
}

} // namespace apc
