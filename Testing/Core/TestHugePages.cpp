// Large blocks for the sample arena and the mesh's per-cell arrays: aligned to a huge page,
// usable to their last byte, and where the system offers transparent huge pages, filled with
// far fewer page faults than 4 KiB pages would take.
#include "apcHugePages.h"
#include "apcUninitialized.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#if defined(__linux__)
#include <sys/resource.h>
#endif

namespace
{
long MinorFaults()
{
#if defined(__linux__)
  rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_minflt;
#else
  return 0;
#endif
}

// True where madvise(MADV_HUGEPAGE) regions get huge pages ("always" or "madvise").
bool HugePagesOffered()
{
  std::ifstream file("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  std::getline(file, line);
  return line.find("[always]") != std::string::npos || line.find("[madvise]") != std::string::npos;
}

// The page size forced for one test (the process's own choice is measured and may be either).
class PageSizeForced
{
public:
  explicit PageSizeForced(bool huge) { apc::SetHugePagesWantedForTesting(huge ? 1 : 0); }
  ~PageSizeForced() { apc::SetHugePagesWantedForTesting(-1); }
  PageSizeForced(const PageSizeForced&) = delete;
  PageSizeForced& operator=(const PageSizeForced&) = delete;
};
}

TEST(HugePages, BlocksAreAlignedAndUsable)
{
  for (size_t bytes : { size_t(1), apc::kHugePageBytes - 8, apc::kMinHugeBlockBytes + 12345 })
  {
    auto* block = static_cast<unsigned char*>(apc::AllocateHugeBlock(bytes));
    ASSERT_NE(block, nullptr);
#if defined(__unix__) || defined(__APPLE__)
    EXPECT_EQ(reinterpret_cast<uintptr_t>(block) % apc::kHugePageBytes, 0u) << bytes;
#endif
    std::memset(block, 0x5a, bytes);
    EXPECT_EQ(block[bytes - 1], 0x5a);
    apc::FreeHugeBlock(block, bytes);
  }
  apc::FreeHugeBlock(nullptr, 0); // nothing to free
}

TEST(HugePages, LargeUninitializedVectorsWork)
{
  apc::UninitializedVector<double> values;
  values.resize(apc::kMinHugeBlockBytes / sizeof(double) + 3); // advised huge pages
  for (size_t i = 0; i < values.size(); ++i)
  {
    values[i] = static_cast<double>(i);
  }
  values.push_back(-1.0); // grows into a new block
  EXPECT_EQ(values[values.size() - 2], static_cast<double>(values.size() - 2));
  EXPECT_EQ(values.back(), -1.0);
  apc::UninitializedVector<double> small(16, 2.0); // from the heap
  EXPECT_EQ(small[15], 2.0);
  values = apc::UninitializedVector<double>();
  EXPECT_TRUE(values.empty());
}

// The faults of first writing every 4 KiB page of bytes at memory.
long FaultsToFill(unsigned char* memory, size_t bytes)
{
  const long before = MinorFaults();
  for (size_t i = 0; i < bytes; i += 4096)
  {
    memory[i] = 1;
  }
  return MinorFaults() - before;
}

TEST(HugePages, FillingABlockTakesFewPageFaults)
{
#if !defined(__linux__)
  GTEST_SKIP() << "page faults are counted on Linux only";
#else
  if (!HugePagesOffered())
  {
    GTEST_SKIP() << "the system offers no transparent huge pages";
  }
  const PageSizeForced huge(true);
  const size_t bytes = 8 * apc::kHugePageBytes; // 4096 pages of 4 KiB
  auto* block = static_cast<unsigned char*>(apc::AllocateHugeBlock(bytes));
  ASSERT_NE(block, nullptr);
  // 8 with huge pages; 4096 in 4 KiB pages. A few huge pages may be refused (fragmented
  // memory), not most of them.
  EXPECT_LT(FaultsToFill(block, bytes), 1024);
  apc::FreeHugeBlock(block, bytes);

  // A heap block advised: its whole huge pages (at least 7 of the 9 it spans) in one fault.
  const size_t heapBytes = bytes + apc::kHugePageBytes;
  apc::UninitializedVector<unsigned char> heap(heapBytes);
  EXPECT_LT(FaultsToFill(heap.data(), heapBytes), 2048);
#endif
}

// A frame's buffers (plain vectors) grown in huge pages: contents kept, and a large buffer
// filled with few page faults where the system offers huge pages.
TEST(HugePages, ReservedVectorsKeepTheirValuesAndTakeFewFaults)
{
  std::vector<double> values = { 1.0, 2.0, 3.0 };
  apc::ReserveInHugePages(values, 5);
  ASSERT_GE(values.capacity(), 5u);
  EXPECT_EQ(values, (std::vector<double>{ 1.0, 2.0, 3.0 }));
  const double* memory = values.data();
  apc::ReserveInHugePages(values, 4); // room enough: nothing moves
  EXPECT_EQ(values.data(), memory);
#if defined(__linux__)
  if (!HugePagesOffered())
  {
    GTEST_SKIP() << "the system offers no transparent huge pages";
  }
  const PageSizeForced huge(true);
  const size_t bytes = 9 * apc::kHugePageBytes; // 4608 pages of 4 KiB, at least 8 huge ones
  std::vector<unsigned char> buffer;
  apc::ReserveInHugePages(buffer, bytes);
  const long before = MinorFaults();
  buffer.assign(bytes, 1); // what a frame does with its buffers
  EXPECT_LT(MinorFaults() - before, 2048);
#endif
}

// Where 4 KiB pages are chosen (cheaper to first touch on the host), a block APC maps takes them
// even where the system would give huge pages unasked, and advised heap blocks are left alone.
TEST(HugePages, BlocksIn4KiBPagesWhenChosen)
{
#if !defined(__linux__)
  GTEST_SKIP() << "page faults are counted on Linux only";
#else
  const PageSizeForced small(false);
  EXPECT_FALSE(apc::HugePagesWanted());
  const size_t bytes = 8 * apc::kHugePageBytes; // 4096 pages of 4 KiB
  auto* block = static_cast<unsigned char*>(apc::AllocateHugeBlock(bytes));
  ASSERT_NE(block, nullptr);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(block) % apc::kHugePageBytes, 0u);
  EXPECT_GE(FaultsToFill(block, bytes), 4000);
  EXPECT_EQ(block[bytes - 4096], 1);
  apc::FreeHugeBlock(block, bytes);
#endif
}

TEST(HugePages, ForcedChoiceIsUndone)
{
  {
    const PageSizeForced huge(true);
    EXPECT_TRUE(apc::HugePagesWanted());
  }
  {
    const PageSizeForced small(false);
    EXPECT_FALSE(apc::HugePagesWanted());
  }
  const bool chosen = apc::HugePagesWanted(); // the process's own, measured once
  EXPECT_EQ(apc::HugePagesWanted(), chosen);
}

// The probe behind the choice: both page sizes' first touch timed, in the thread's CPU time.
TEST(HugePages, FirstTouchIsMeasuredInBothPageSizes)
{
  const apc::PageTouchCost cost = apc::MeasurePageTouch(apc::kPageProbeBytes);
  EXPECT_GE(cost.Huge, 0.0);
  EXPECT_GE(cost.Small, 0.0);
#if defined(__linux__)
  // 1024 faults of 4 KiB take measurable time anywhere; each probe well under a second.
  EXPECT_GT(cost.Small, 0.0);
  EXPECT_LT(cost.Small, 1.0);
  EXPECT_LT(cost.Huge, 1.0);
#endif
}

// The rule behind the choice: 4 KiB pages where their first touch is cheap whatever huge pages
// cost in the probe (a few freed huge pages are cheap, a frame's hundreds of MB are not), else
// the cheaper of the two, huge pages on a tie.
TEST(HugePages, ChoiceFollowsThe4KiBPagesPrice)
{
  const size_t bytes = apc::kPageProbeBytes; // 4 MB
  const double cheap = 0.9 * apc::kCheap4KiBSecondsPerMB * 4;
  const double dear = 2.0 * apc::kCheap4KiBSecondsPerMB * 4;
  EXPECT_FALSE(apc::ChooseHugePages({ cheap / 10, cheap }, bytes)); // huge cheaper: still 4 KiB
  EXPECT_FALSE(apc::ChooseHugePages({ 2 * cheap, cheap }, bytes));
  EXPECT_TRUE(apc::ChooseHugePages({ dear / 2, dear }, bytes));
  EXPECT_TRUE(apc::ChooseHugePages({ dear, dear }, bytes));
  EXPECT_FALSE(apc::ChooseHugePages({ 2 * dear, dear }, bytes));
}
