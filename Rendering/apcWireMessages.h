// SPDX-License-Identifier: BSD-3-Clause
// What the APC mode's collectives share (apcMomentCompositing.cxx, apcOpaqueCompositing.cxx):
// buffers that only grow, and messages of a bounded size. Internal to APC's rendering module.
#ifndef apcWireMessages_h
#define apcWireMessages_h

#include "apcHugePages.h"

#include "vtkType.h"

#include <algorithm>
#include <cstddef>
#include <type_traits>
#include <vector>

namespace apc
{
namespace wire
{
// v's first n values (v grows if it must and never shrinks: see MomentBuffers).
template <class T>
T* Hold(std::vector<T>& v, size_t n)
{
  if (v.size() < n)
  {
    ReserveInHugePages(v, n);
    v.resize(n);
  }
  return v.data();
}

// Room for n values of T at the start of bytes (see Hold), for a buffer the band's sums share
// in turn (MomentBuffers::WireSend): the values are made there by whoever writes them first.
// T is an arithmetic type (implicit-lifetime, so writing it creates it), and the vector's
// storage comes from operator new, aligned for any of them.
template <class T>
T* HoldAs(std::vector<unsigned char>& bytes, size_t n)
{
  static_assert(std::is_arithmetic<T>::value && alignof(T) <= alignof(std::max_align_t),
    "a wire value made in place in a byte buffer");
  return reinterpret_cast<T*>(Hold(bytes, n * sizeof(T)));
}

// The most values of T one message holds (see InMessages).
template <class T>
size_t MessageValues(size_t maxBytes)
{
  return std::max<size_t>(1, maxBytes / sizeof(T));
}

// Calls message(offset, count) over [0, total) values of T, at most maxBytes at a time
// (Settings.MaxMessageBytes: Open MPI maps a fresh temporary for an allreduce of 32 MB or
// more on every call, see vtkAPCCompositePass.h). Every process cuts the same total the same
// way, so the messages pair up.
template <class T, class Message>
void InMessages(size_t total, size_t maxBytes, Message message)
{
  const size_t step = MessageValues<T>(maxBytes);
  for (size_t offset = 0; offset < total; offset += step)
  {
    message(offset, static_cast<vtkIdType>(std::min(step, total - offset)));
  }
}

} // namespace wire
} // namespace apc

#endif
