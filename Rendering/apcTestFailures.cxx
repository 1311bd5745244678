// SPDX-License-Identifier: BSD-3-Clause
#include "apcTestFailures.h"

#include <array>
#include <cstddef>
#include <new>

namespace apc
{
namespace
{
// Calls left to fail, per point (a render thread's, set between frames by the test).
std::array<int, static_cast<size_t>(FailurePoint::Count)> Failures{};
}

void FailForTesting(FailurePoint point, int count)
{
  Failures[static_cast<size_t>(point)] = count;
}

void ThrowIfFailingForTesting(FailurePoint point)
{
  int& left = Failures[static_cast<size_t>(point)];
  if (left > 0)
  {
    --left;
    throw std::bad_alloc();
  }
}

} // namespace apc
