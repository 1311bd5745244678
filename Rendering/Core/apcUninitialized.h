// A vector whose resize leaves new elements of trivial types unwritten (default-initialised):
// the large per-cell arrays of a mesh are then first written, and their memory pages first
// touched, by the parallel loops that fill them, instead of by one thread zeroing them first
// (on the meshes at hand that zeroing and its page faults cost more than filling them).
// Large arrays take huge pages (apcHugePages.h): one page fault per 2 MiB instead of 512.
#ifndef apcUninitialized_h
#define apcUninitialized_h

#include "apcHugePages.h"

#include <memory>
#include <new>
#include <utility>
#include <vector>

namespace apc
{

template <class T>
struct UninitializedAllocator : std::allocator<T>
{
  template <class U>
  struct rebind
  {
    using other = UninitializedAllocator<U>;
  };
  UninitializedAllocator() = default;
  template <class U>
  UninitializedAllocator(const UninitializedAllocator<U>&) noexcept
  {
  }
  T* allocate(size_t n)
  {
    T* memory = std::allocator<T>::allocate(n);
    if (n * sizeof(T) >= kMinHugeBlockBytes)
    {
      // From the heap as any vector (its reuse of freed memory stays the allocator's), but
      // in huge pages where the block has whole ones.
      AdviseHugePages(memory, n * sizeof(T));
    }
    return memory;
  }
  // resize() and the size constructor: default-initialised, i.e. nothing written for trivial T.
  template <class U>
  void construct(U* p) noexcept
  {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args)
  {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

template <class T>
using UninitializedVector = std::vector<T, UninitializedAllocator<T>>;

} // namespace apc

#endif
