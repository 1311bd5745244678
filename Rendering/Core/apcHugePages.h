// Large blocks of memory in transparent huge pages where the system offers them and where
// they are the cheaper to first touch. The first write to a fresh page faults; in 4 KiB pages
// that is one fault per 4 KiB, which on some virtual machines costs about as much as the
// set-up's computing (each fault exits to the hypervisor), while a 2 MiB page takes one fault
// for 512 of them. On others a 4 KiB fault is cheap and a fresh huge page dear (the host backs
// it anew after the guest reported it free): there the same bytes cost several times more in
// huge pages. Which holds is measured once per process (HugePagesWanted), for the blocks a
// frame writes and reads in order; arrays read in no order every frame keep huge pages (TLB
// misses). A block is aligned to 2 MiB so that every whole 2 MiB of it can be a huge page.
#ifndef apcHugePages_h
#define apcHugePages_h

#include <cstddef>
#include <utility>

namespace apc
{

// Blocks of at least this many bytes are worth huge pages (smaller ones come from the heap):
// a block's last huge page is committed whole, so the waste stays under half the block.
constexpr size_t kHugePageBytes = size_t(2) << 20;
constexpr size_t kMinHugeBlockBytes = 2 * kHugePageBytes;

// Whether large blocks are asked for in huge pages. APC_HUGE_PAGES=0 or 1 in the environment
// decides; otherwise the first call measures the first touch of a few MB (MeasurePageTouch)
// and decides once for the process (ChooseHugePages).
bool HugePagesWanted();

// Overrides HugePagesWanted (tests): 1 huge pages, 0 4 KiB pages, -1 back to its own choice.
void SetHugePagesWantedForTesting(int wanted);

// The CPU seconds (this thread's, kernel time included) of writing one byte in each 4 KiB page
// of bytes of fresh memory, in 4 KiB pages (Small) and advised huge pages (Huge: measured only
// where Small is at least cheapSmallSecondsPerMB a MB, Small's value otherwise; where the
// system has no transparent huge pages, Small's cost again). Both 0 where APC maps no memory.
struct PageTouchCost
{
  double Huge = 0;
  double Small = 0;
};
PageTouchCost MeasurePageTouch(size_t bytes, double cheapSmallSecondsPerMB = 0);

// 4 KiB pages where a 4 KiB page costs less than this a MB to first touch (a cheap fault: the
// guest's own page tables), else whichever page size the probe found cheaper. A small probe
// cannot price huge pages: it gets the few 2 MiB blocks freed last, still backed by the host
// (0.08-0.1 ms per MB on a KVM guest with free page reporting), while a frame's hundreds of MB
// take blocks the guest reported free, which the host backs anew (2.7-3.1 ms per MB there, and
// 2.7 on a guest whose 4 KiB fault costs 15 us, 3.7 ms per MB). Under half that price a 4 KiB
// page is the safe choice: at most 0.5 ms per MB dearer than a huge page backed already, and
// 2 ms per MB cheaper than one the host must back.
constexpr double kCheap4KiBSecondsPerMB = 1.5e-3;
bool ChooseHugePages(const PageTouchCost& cost, size_t bytes);

// The bytes MeasurePageTouch touches for HugePagesWanted's choice: 1,024 pages of 4 KiB (about
// 2 ms on a KVM guest), and where those are dear, two huge pages.
constexpr size_t kPageProbeBytes = 2 * kHugePageBytes;

// bytes of address space (committed page by page as it is first written), or null if the
// system refuses them. Free with FreeHugeBlock and the same bytes.
void* AllocateHugeBlock(size_t bytes);
void FreeHugeBlock(void* block, size_t bytes);

// Asks for huge pages in the whole 2 MiB pages inside [memory, memory + bytes) (a heap
// block: the allocator keeps owning it, so that its own reuse of freed memory is unchanged).
// For arrays read in no order every frame (the mesh's, the bins'): huge pages whatever
// HugePagesWanted says (only APC_HUGE_PAGES=0 leaves them out), since 4 KiB pages would cost
// every later frame its TLB misses.
void AdviseHugePages(void* memory, size_t bytes);

// AdviseHugePages where HugePagesWanted: for buffers a frame writes and reads in order (its
// moments, sums, wire buffers, image), whose first touch is their cost.
void AdviseFrameHugePages(void* memory, size_t bytes);

// Room for n elements in v, its contents kept: a block it must allocate afresh is advised huge
// pages before anything touches it. For the large buffers a frame fills (moments, colour
// sums, opaque profiles, wire buffers, its image): a first frame pages them all in, and in
// 4 KiB pages that costs more than filling them. A block grows by a quarter more than asked
// (address space only, untouched until used), so that buffers sized by what a frame covers
// are not allocated, and paged in, afresh whenever a frame covers a little more.
template <class Vector>
void ReserveInHugePages(Vector& v, size_t n)
{
  if (v.capacity() >= n)
  {
    return;
  }
  const size_t room = n + n / 4;
  Vector fresh;
  fresh.reserve(room);
  if (room * sizeof(typename Vector::value_type) >= kMinHugeBlockBytes)
  {
    AdviseFrameHugePages(fresh.data(), room * sizeof(typename Vector::value_type));
  }
  fresh.assign(v.begin(), v.end());
  v.swap(fresh);
}

} // namespace apc

#endif
