#include "apcSampleArena.h"

#include "apcHugePages.h"

namespace apc
{

void SampleArena::Reserve(size_t bytes)
{
  if (bytes <= this->Size)
  {
    return;
  }
  this->Release();
  // The budget rounded up to whole huge pages; address space that is never written costs
  // nothing but its page-table entry.
  size_t size = (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
  while (size >= kHugePageBytes)
  {
    this->Base = static_cast<char*>(AllocateHugeBlock(size));
    if (this->Base)
    {
      this->Size = size;
      break;
    }
    size /= 2; // a system that grants less address space (ulimit -v, strict overcommit)
  }
  this->Used = 0;
}

void SampleArena::Release()
{
  FreeHugeBlock(this->Base, this->Size);
  this->Base = nullptr;
  this->Size = 0;
  this->Used = 0;
}

} // namespace apc
