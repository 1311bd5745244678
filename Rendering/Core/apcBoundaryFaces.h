// Sample End Weights = Boundary on several processes, the part without MPI: the faces each
// process's piece leaves on its boundary (CellMesh::GetBoundaryFaces) are sent to an owner
// process chosen by their corners (FaceOwner), and the owner marks every face that arrived from
// more than one process as inner (MatchBoundaryFaces); each process takes the flags of its own
// faces back (CellMesh::ClearBoundaryFaces). Then N processes weight the faces one process
// weights: those of the whole mesh's boundary. The exchange itself is apcBoundaryExchange.h.
#ifndef apcBoundaryFaces_h
#define apcBoundaryFaces_h

#include "apcCellMesh.h"

#include <cstdint>
#include <vector>

namespace apc
{

// The process in [0, processes) that matches a face: a hash of its corners' bits, the same on
// every process that holds the face.
int FaceOwner(const CellMesh::FaceCorners& face, int processes);

// The owner's side. received: the faces from every process, process by process, counts[p] of
// them from process p (a process sends a face at most once: it is on its piece's boundary).
// Returns one flag per received face, in the same order: 1 if the same corners came from
// another process too (the face lies between two pieces), else 0.
std::vector<uint8_t> MatchBoundaryFaces(
  const std::vector<CellMesh::FaceCorners>& received, const std::vector<int64_t>& counts);

} // namespace apc

#endif
