// SPDX-License-Identifier: BSD-3-Clause
// How many threads a process renders with when the user has not said: its share of the
// node's cores. TBB alone follows the affinity mask, which is right for a process bound alone
// to its cores but lets every process of a node whose mask it shares with others (unbound:
// oversubscribed runs, --bind-to none, many launchers; bound to a socket: mpirun's default
// above 2 ranks) start a thread per core of its mask: 64 ranks on a 64-core node would run
// 4,096 threads unbound, 2,048 bound to two sockets. The sample
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
 *   apc::ParallelFor) by apc::NodeShareOfThreads over the affinity masks of the node's
 *   processes (gathered once): twice the process's share of the cores of its mask (each core
 *   divided among the processes that may run on it), at least one, at most its mask, so that
 *   ranks still rendering take the cores of ranks that wait, and a node's ranks never start a
 *   thread per core each, bound to a socket or not. A thread count set on the mapper still
 *   overrides it;
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
