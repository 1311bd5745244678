// SPDX-License-Identifier: BSD-3-Clause
// Sample End Weights = Boundary on several processes: the faces between the processes' pieces
// are inner, as they are for one process holding the whole mesh. Once per data change, every
// process's faces left on its piece's boundary travel to an owner process (MPI_Alltoallv of
// their corners, 96 bytes a face), the owner marks those two processes sent as inner, and one
// byte a face comes back (apcBoundaryFaces.h is the part without MPI). Internal to APC's
// rendering module.
#ifndef apcBoundaryExchange_h
#define apcBoundaryExchange_h

#include "APCRenderingModule.h" // for export macro
#include "apcCompositeFrame.h"

#include <cstdint>
#include <string>

namespace apc
{

// What the last exchange on this process cost (for tests and measurements).
struct BoundaryExchangeRecord
{
  int64_t FacesSent = 0; // this process's faces on its piece's boundary
  double BytesSent = 0;  // this process's, both exchanges
  double Seconds = 0;    // wall, from the local matching to the flags taken back
  // Of Seconds, this piece's own matching (CellMesh::FindBoundaryPlanes and GetBoundaryFaces):
  // wall, and the process's CPU (all its threads) over it.
  double LocalSeconds = 0;
  double LocalCPUSeconds = 0;
};

// Step 3a of the frame, before PrepareEngines: for every volume of the frame (by its position
// among each process's visible APC volumes, as the moments are summed) that some process renders
// with Sample End Weights = Boundary and whose mesh has not been matched since its data
// changed, every process matches its piece's faces with the others' (a process without the
// volume, or without cells, joins with none). Collective: every process calls it. One process
// finds its own boundary in its engine's Prepare and needs nothing here. A failure on any
// process (an exception, too many faces for MPI's counts, a controller that is not MPI's) is
// agreed: every process keeps its own piece's boundary for this frame, the next frame tries
// again, and problem says why (false).
APCRENDERING_EXPORT bool ShareBoundaryFaces(
  const ProcessGroup& group, const CompositeFrame& frame, std::string& problem);

APCRENDERING_EXPORT const BoundaryExchangeRecord& GetLastBoundaryExchange();

} // namespace apc

#endif
