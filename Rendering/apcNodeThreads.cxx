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
#include <vector>

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

// This process's affinity mask in CoreMask's words; every online core if it cannot be read
// (as if unbound).
CoreMask AffinityMask(int nodeCores)
{
  CoreMask mask(CPU_SETSIZE / 64, 0);
  cpu_set_t set;
  CPU_ZERO(&set);
  const bool known = sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0;
  for (int core = 0; core < CPU_SETSIZE; ++core)
  {
    if (known ? CPU_ISSET(core, &set) : core < nodeCores)
    {
      mask[core / 64] |= uint64_t(1) << (core % 64);
    }
  }
  return mask;
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
namespace
{
// controller's processes on this process's node (MPI_COMM_TYPE_SHARED), or false without MPI
// or another kind of controller (the process is then alone on its node). A collective.
bool SplitNode(vtkMultiProcessController* controller, MPI_Comm* node)
{
  auto* communicator =
    controller ? vtkMPICommunicator::SafeDownCast(controller->GetCommunicator()) : nullptr;
  MPI_Comm* comm =
    communicator && communicator->GetMPIComm() ? communicator->GetMPIComm()->GetHandle() : nullptr;
  int initialized = 0;
  int finalized = 0;
  MPI_Initialized(&initialized);
  MPI_Finalized(&finalized);
  return comm && initialized && !finalized &&
    MPI_Comm_split_type(*comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, node) == MPI_SUCCESS;
}
}

//------------------------------------------------------------------------------
int ProcessesOnThisNode(vtkMultiProcessController* controller)
{
  MPI_Comm node;
  if (!SplitNode(controller, &node))
  {
    return 1;
  }
  int processes = 1;
  MPI_Comm_size(node, &processes);
  MPI_Comm_free(&node);
  return processes > 0 ? processes : 1;
}

//------------------------------------------------------------------------------
// The affinity masks of the processes on this node, and this process's index among them
// (its own mask alone without MPI). A collective.
static std::vector<CoreMask> AffinityMasksOnThisNode(
  vtkMultiProcessController* controller, int* self)
{
  const CoreMask mine = AffinityMask(CoresOfNode());
  *self = 0;
  MPI_Comm node;
  if (!SplitNode(controller, &node))
  {
    return { mine };
  }
  int processes = 1;
  MPI_Comm_size(node, &processes);
  MPI_Comm_rank(node, self);
  const int words = static_cast<int>(mine.size());
  std::vector<uint64_t> all(static_cast<size_t>(processes) * mine.size());
  const bool gathered = MPI_Allgather(mine.data(), words, MPI_UINT64_T, all.data(), words,
                          MPI_UINT64_T, node) == MPI_SUCCESS;
  MPI_Comm_free(&node);
  if (!gathered)
  {
    *self = 0;
    return { mine };
  }
  std::vector<CoreMask> masks(static_cast<size_t>(processes));
  for (int p = 0; p < processes; ++p)
  {
    masks[p].assign(all.begin() + p * words, all.begin() + (p + 1) * words);
  }
  return masks;
}

//------------------------------------------------------------------------------
void ShareNode(vtkMultiProcessController* controller)
{
  int self = 0;
  const std::vector<CoreMask> masks = AffinityMasksOnThisNode(controller, &self);
  SetDefaultThreads(NodeShareOfThreads(masks, static_cast<size_t>(self)));
  NodeCacheBytes.store(NodeShareOfMemory(MemoryOfNode(), static_cast<int>(masks.size())));
}

//------------------------------------------------------------------------------
size_t DefaultSampleCacheBytes()
{
  const size_t shared = NodeCacheBytes.load();
  return shared > 0 ? shared : NodeShareOfMemory(MemoryOfNode(), 1);
}

}
