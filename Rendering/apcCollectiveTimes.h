// SPDX-License-Identifier: BSD-3-Clause
// The wait and the transfer of a frame's collectives, per stage. Every collective of
// vtkAPCCompositePass's frame enters through ProcessGroup::Collective (apcCompositeFrame.h):
// the processes first meet in a non-blocking barrier (WaitForAll), then run the collective.
// The barrier's time on a process is its wait for the last one to arrive (the slowest
// process's render, or its own late start); the collective's time after it is the transfer,
// which no longer includes anyone's render. Internal to APC's rendering module.
#ifndef apcCollectiveTimes_h
#define apcCollectiveTimes_h

#include <string>
#include <vector>

class vtkMultiProcessController;

namespace apc
{

class CollectiveTimes
{
public:
  struct Entry
  {
    std::string Stage;
    double Wait = 0;     // seconds in the barrier
    double Transfer = 0; // seconds in the collective after it
    int Calls = 0;
  };

  void Add(const char* stage, double wait, double transfer);
  // The stage's seconds; null gives the sum over all stages.
  double Wait(const char* stage) const;
  double Transfer(const char* stage) const;
  const std::vector<Entry>& Entries() const { return this->Stages; }

private:
  std::vector<Entry> Stages;
};

// Returns once every process of the controller has called it, without keeping a core busy:
// MPI's blocking collectives poll in a loop, so a process that arrives early would take a
// core from one still rendering (the ranks of a node share its cores). Here an MPI_Ibarrier
// is tested 100 times with a yield, then with sleeps that grow from 20 us to 1 ms: a process
// that waited long leaves ~1 ms after the last arrival (plus the time the system takes to
// give it a core back). False (and no wait) if the controller is not MPI's or has one process.
bool WaitForAll(vtkMultiProcessController* controller);

} // namespace apc

#endif
