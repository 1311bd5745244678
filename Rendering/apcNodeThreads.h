// SPDX-License-Identifier: BSD-3-Clause
// How many threads a process renders with when the user has not said: its share of the
// node's cores. TBB alone follows the affinity mask, which is right for a bound process but
// lets every unbound process of a node (oversubscribed runs, --bind-to none, many launchers)
// start a thread per core: 64 ranks on a 64-core node would run 4,096 threads. The sample
// cache's default budget is shared among a node's processes the same way.
#ifndef apcNodeThreads_h
#define apcNodeThreads_h

#include "APCRenderingModule.h" // for export macro

#include <cstddef>

class vtkMultiProcessController;

namespace apc
{

/**
 * Sets this process's defaults from its share of the node, counting the processes of
 * controller on the node once (MPI_Comm_split_type with MPI_COMM_TYPE_SHARED; without MPI, a
 * single process or another kind of controller, the process is alone on its node):
 * - the thread count (apc::SetDefaultThreads, used wherever a thread count of 0 reaches
 *   apc::ParallelFor) by apc::NodeShareOfThreads: an unbound process gets twice its share of
 *   the node's cores (cores / processes, at least one), at most the node's cores, so that ranks
 *   still rendering take the cores of ranks that wait; a bound process keeps its affinity mask.
 *   A thread count set on the mapper still overrides it;
 * - the sample cache budget (DefaultSampleCacheBytes) by apc::NodeShareOfMemory: a quarter of
 *   the node's physical memory divided among the node's processes.
 * A collective over controller's MPI communicator: every process calls it.
 */
APCRENDERING_EXPORT void ShareNode(vtkMultiProcessController* controller);

/// The processes of controller on this process's node (1 without MPI). A collective.
APCRENDERING_EXPORT int ProcessesOnThisNode(vtkMultiProcessController* controller);

/// The sample cache budget of a volume whose Sample Cache (MB) is automatic (-1): the one
/// ShareNode set, or, before any, the node's share for a process alone on it.
APCRENDERING_EXPORT size_t DefaultSampleCacheBytes();

}

#endif
