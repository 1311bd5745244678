#include "apcHugePages.h"

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>

#if defined(__unix__) || defined(__APPLE__)
#include <sys/mman.h>
#define APC_HUGE_MMAP 1
#endif

namespace apc
{

bool HugePagesWanted()
{
  static const bool wanted = []
  {
    const char* value = std::getenv("APC_HUGE_PAGES");
    return !(value && std::strcmp(value, "0") == 0);
  }();
  return wanted;
}

void* AllocateHugeBlock(size_t bytes)
{
  if (bytes == 0)
  {
    return nullptr;
  }
#ifdef APC_HUGE_MMAP
  // Mapped with a huge page of slack, then trimmed to a 2 MiB-aligned start: mmap itself only
  // aligns to 4 KiB, and a huge page can only back a 2 MiB-aligned range.
  const size_t size = (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
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
  void* block = reinterpret_cast<void*>(aligned);
#ifdef MADV_HUGEPAGE
  if (HugePagesWanted())
  {
    madvise(block, size, MADV_HUGEPAGE); // a hint: without it, 4 KiB pages
  }
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
  if (memory && last > first && HugePagesWanted())
  {
    madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
  }
#else
  (void)memory;
  (void)bytes;
#endif
}

void FreeHugeBlock(void* block, size_t bytes)
{
  if (!block)
  {
    return;
  }
#ifdef APC_HUGE_MMAP
  munmap(block, (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes);
#else
  (void)bytes;
  ::operator delete(block);
#endif
}

} // namespace apc
