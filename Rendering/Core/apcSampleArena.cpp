#include "apcSampleArena.h"

#include <new>

#if defined(__unix__) || defined(__APPLE__)
#include <sys/mman.h>
#define APC_ARENA_MMAP 1
#endif

namespace apc
{

void SampleArena::Reserve(size_t bytes)
{
  if (bytes <= this->Size)
  {
    return;
  }
  this->Release();
  // The budget rounded up to whole 2 MiB pages; address space that is never written costs
  // nothing but its page-table entry.
  constexpr size_t kHugePage = size_t(2) << 20;
  size_t size = (bytes + kHugePage - 1) / kHugePage * kHugePage;
  while (size >= kHugePage)
  {
#ifdef APC_ARENA_MMAP
    void* base = mmap(
      nullptr, size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    if (base != MAP_FAILED)
    {
#ifdef MADV_HUGEPAGE
      madvise(base, size, MADV_HUGEPAGE); // a hint: without it, 4 KiB pages
#endif
      this->Base = static_cast<char*>(base);
      this->Size = size;
      break;
    }
#else
    this->Base = static_cast<char*>(::operator new(size, std::nothrow));
    if (this->Base)
    {
      this->Size = size;
      break;
    }
#endif
    size /= 2; // a system that grants less address space (ulimit -v, strict overcommit)
  }
  this->Used = 0;
}

void SampleArena::Release()
{
  if (this->Base)
  {
#ifdef APC_ARENA_MMAP
    munmap(this->Base, this->Size);
#else
    ::operator delete(this->Base);
#endif
  }
  this->Base = nullptr;
  this->Size = 0;
  this->Used = 0;
}

} // namespace apc
