// SPDX-License-Identifier: BSD-3-Clause
#include "apcStageAgreement.h"

#include "vtkCommunicator.h"
#include "vtkMultiProcessController.h"

#include <algorithm>
#include <array>

namespace apc
{
namespace
{
// A failure's message travels with at most this many characters.
constexpr int kMaxMessage = 1000;
}

std::string AgreeOnFailure(
  const ProcessGroup& group, const char* stage, const char* what, const std::string& failure)
{
  // The success path is one int allreduce: 0 everywhere. A failing process sends the number
  // of processes less its rank, so the maximum names the lowest failing rank.
  int failing = failure.empty() ? -1 : group.Rank;
  std::string message = failure;
  if (group.Parallel)
  {
    int mine = failure.empty() ? 0 : group.Processes - group.Rank;
    int worst = mine;
    group.Collective(
      stage, [&] { group.Controller->AllReduce(&mine, &worst, 1, vtkCommunicator::MAX_OP); });
    if (worst == 0)
    {
      return std::string();
    }
    failing = group.Processes - worst;
    // Only after a failure: the failing process's message, to every process (on the stack: a
    // process whose memory ran out must still take part).
    std::array<char, kMaxMessage + 1> text{};
    if (group.Rank == failing)
    {
      std::copy_n(failure.begin(), std::min<size_t>(failure.size(), kMaxMessage), text.begin());
    }
    group.Collective(
      stage, [&] { group.Controller->Broadcast(text.data(), kMaxMessage + 1, failing); });
    message = text.data();
  }
  else if (failure.empty())
  {
    return std::string();
  }
  return std::string(what) + " failed on process " + std::to_string(failing) + ": " + message;
}

} // namespace apc
