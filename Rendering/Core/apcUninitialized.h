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
  static bool Huge(size_t n)
  {
    return n <= size_t(-1) / sizeof(T) && n * sizeof(T) >= kMinHugeBlockBytes;
  }
  T* allocate(size_t n)
  {
    if (!Huge(n))
    {
      return std::allocator<T>::allocate(n);
    }
    void* block = AllocateHugeBlock(n * sizeof(T));
    if (!block)
    {
      throw std::bad_alloc(); // not from the heap: deallocate must know where a block lives
    }
    return static_cast<T*>(block);
  }
  void deallocate(T* p, size_t n)
  {
    if (Huge(n))
    {
      FreeHugeBlock(p, n * sizeof(T));
      return;
    }
    std::allocator<T>::deallocate(p, n);
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
