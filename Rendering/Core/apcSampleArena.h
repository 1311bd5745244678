// The memory of the sample cache's records: address space reserved once for the whole budget
// and committed page by page as pass 1 first writes it. Tiles take their records from it in
// any order (an atomic bump), so nothing is reallocated, copied or grown while pass 1
// records; a later frame refills pages already mapped (no page faults) as long as it needs no
// more than the largest frame before it; and where the system offers huge pages the first
// frame takes one page fault per 2 MiB instead of one per 4 KiB.
#ifndef apcSampleArena_h
#define apcSampleArena_h

#include <atomic>
#include <cstddef>

namespace apc
{

class SampleArena
{
public:
  SampleArena() = default;
  SampleArena(const SampleArena&) = delete;
  SampleArena& operator=(const SampleArena&) = delete;
  ~SampleArena() { this->Release(); }

  // Room for bytes (what is held is lost if the reservation must grow). Where the system
  // refuses that much address space, as much as it grants: Capacity() says.
  void Reserve(size_t bytes);
  void Release();
  size_t Capacity() const { return this->Size; }
  // The next frame's records overwrite the last's, in the pages the last touched.
  void Reset() { this->Used = 0; }
  // bytes (a multiple of 8) for one tile, or null beyond the reservation. Thread-safe.
  void* Take(size_t bytes)
  {
    const size_t at = this->Used.fetch_add(bytes, std::memory_order_relaxed);
    if (at + bytes > this->Size)
    {
      return nullptr;
    }
    return this->Base + at;
  }

private:
  char* Base = nullptr;
  size_t Size = 0;
  std::atomic<size_t> Used{ 0 };
};

} // namespace apc

#endif
