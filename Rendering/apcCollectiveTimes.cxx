// SPDX-License-Identifier: BSD-3-Clause
#include "apcCollectiveTimes.h"

#include "vtkMPI.h"
#include "vtkMPICommunicator.h"
#include "vtkMultiProcessController.h"

#include <algorithm>
#include <chrono>
#include <thread>

namespace apc
{

void CollectiveTimes::Add(const char* stage, double wait, double transfer)
{
  for (Entry& entry : this->Stages)
  {
    if (entry.Stage == stage)
    {
      entry.Wait += wait;
      entry.Transfer += transfer;
      ++entry.Calls;
      return;
    }
  }
  this->Stages.push_back({ stage, wait, transfer, 1 });
}

double CollectiveTimes::Wait(const char* stage) const
{
  double seconds = 0;
  for (const Entry& entry : this->Stages)
  {
    seconds += !stage || entry.Stage == stage ? entry.Wait : 0.0;
  }
  return seconds;
}

double CollectiveTimes::Transfer(const char* stage) const
{
  double seconds = 0;
  for (const Entry& entry : this->Stages)
  {
    seconds += !stage || entry.Stage == stage ? entry.Transfer : 0.0;
  }
  return seconds;
}

bool WaitForAll(vtkMultiProcessController* controller)
{
  auto* communicator =
    controller ? vtkMPICommunicator::SafeDownCast(controller->GetCommunicator()) : nullptr;
  if (!communicator || !communicator->GetMPIComm() || !communicator->GetMPIComm()->GetHandle() ||
    communicator->GetNumberOfProcesses() < 2)
  {
    return false;
  }
  MPI_Request request;
  MPI_Ibarrier(*communicator->GetMPIComm()->GetHandle(), &request);
  // A barrier of processes that are already together completes in microseconds, and on
  // oversubscribed cores only once each of them has had the core to test it: the first
  // kYields tests yield the core (to whoever is runnable, so on a busy node they span the
  // others' time slices), then the tests sleep.
  constexpr int kYields = 100;
  auto sleep = std::chrono::microseconds(20);
  for (int tests = 0;; ++tests)
  {
    int done = 0;
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    if (done)
    {
      return true;
    }
    if (tests < kYields)
    {
      std::this_thread::yield();
    }
    else
    {
      std::this_thread::sleep_for(sleep);
      sleep = std::min(2 * sleep, std::chrono::microseconds(1000));
    }
  }
}

} // namespace apc
