// SPDX-License-Identifier: BSD-3-Clause
// How many threads a process renders with when the user has not said: its share of the
// node's cores. TBB alone follows the affinity mask, which is right for a bound process but
// lets every unbound process of a node (oversubscribed runs, --bind-to none, many launchers)
// start a thread per core: 64 ranks on a 64-core node would run 4,096 threads.
#ifndef apcNodeThreads_h
#define apcNodeThreads_h

#include "APCRenderingModule.h" // for export macro

#include <cstddef>

class vtkMultiProcessController;

namespace apc
{

/**
 * Sets this process's default thread count (apc::SetDefaultThreads, used wherever a thread
 * count of 0 reaches apc::ParallelFor) by apc::NodeShareOfThreads: an unbound process gets
 * the node's cores divided by the processes of controller on its node (MPI_Comm_split_type
 * with MPI_COMM_TYPE_SHARED), at least one; a bound process keeps its affinity mask. A
 * collective over controller's MPI communicator (every process calls it); without one (a
 * single process, another kind of controller) the process is alone on its node. A thread
 * count set on the mapper still overrides the default. Returns the default set (0 = TBB's).
 */
APCRENDERING_EXPORT int ShareNodeCores(vtkMultiProcessController* controller);

/// The processes of controller on this process's node (1 without MPI). A collective.
APCRENDERING_EXPORT int ProcessesOnThisNode(vtkMultiProcessController* controller);

/**
 * Sets this process's default sample cache budget (DefaultSampleCacheBytes) by
 * apc::NodeShareOfMemory: a quarter of the node's physical memory divided among the processes
 * of controller on its node. A collective, as ShareNodeCores. Returns the budget set.
 */
APCRENDERING_EXPORT size_t ShareNodeMemory(vtkMultiProcessController* controller);

/// The sample cache budget of a volume whose Sample Cache (MB) is automatic (-1): the one
/// ShareNodeMemory set, or, before any, the node's share for a process alone on it.
APCRENDERING_EXPORT size_t DefaultSampleCacheBytes();

}

#endif
