// SPDX-License-Identifier: BSD-3-Clause
#include "apcNodeThreads.h"

#include "apcParallel.h"
#include "apcSampleCache.h"

#include "vtkMPI.h"
#include "vtkMPICommunicator.h"
#include "vtkMultiProcessController.h"

#include <atomic>
#include <cstdint>
#include <sched.h>
#include <thread>
#include <unistd.h>

namespace apc
{
namespace
{
int CoresOfNode()
{
  const long online = sysconf(_SC_NPROCESSORS_ONLN);
  return online > 0 ? static_cast<int>(online)
                    : static_cast<int>(std::thread::hardware_concurrency());
}

// The cores this process may run on (0 if unknown).
int CoresInAffinityMask()
{
  cpu_set_t set;
  CPU_ZERO(&set);
  return sched_getaffinity(0, sizeof set, &set) == 0 ? CPU_COUNT(&set) : 0;
}

// The node's physical memory in bytes (0 if unknown).
uint64_t MemoryOfNode()
{
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long pageSize = sysconf(_SC_PAGESIZE);
  return pages > 0 && pageSize > 0 ? static_cast<uint64_t>(pages) * static_cast<uint64_t>(pageSize)
                                   : 0;
}

// ShareNode's budget; 0 until it runs.
std::atomic<size_t> NodeCacheBytes{ 0 };
}

//------------------------------------------------------------------------------
int ProcessesOnThisNode(vtkMultiProcessController* controller)
{
  auto* communicator =
    controller ? vtkMPICommunicator::SafeDownCast(controller->GetCommunicator()) : nullptr;
  MPI_Comm* comm =
    communicator && communicator->GetMPIComm() ? communicator->GetMPIComm()->GetHandle() : nullptr;
  int initialized = 0;
  int finalized = 0;
  MPI_Initialized(&initialized);
  MPI_Finalized(&finalized);
  if (!comm || !initialized || finalized)
  {
    return 1;
  }
  MPI_Comm node;
  if (MPI_Comm_split_type(*comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node) != MPI_SUCCESS)
  {
    return 1;
  }
  int processes = 1;
  MPI_Comm_size(node, &processes);
  MPI_Comm_free(&node);
  return processes > 0 ? processes : 1;
}

//------------------------------------------------------------------------------
void ShareNode(vtkMultiProcessController* controller)
{
  const int processes = ProcessesOnThisNode(controller);
  SetDefaultThreads(NodeShareOfThreads(CoresOfNode(), CoresInAffinityMask(), processes));
  NodeCacheBytes.store(NodeShareOfMemory(MemoryOfNode(), processes));
}

//------------------------------------------------------------------------------
size_t DefaultSampleCacheBytes()
{
  const size_t shared = NodeCacheBytes.load();
  return shared > 0 ? shared : NodeShareOfMemory(MemoryOfNode(), 1);
}

}
