// The puzzle source (the paper's worst case: every piece overlaps every other in depth) as
// the tests and benchmarks configure it.
#ifndef apcTestPuzzles_h
#define apcTestPuzzles_h

#include "vtkAPCPuzzleSource.h"
#include "vtkNew.h"
#include "vtkSmartPointer.h"
#include "vtkUnstructuredGrid.h"

namespace apctest
{

inline vtkSmartPointer<vtkAPCPuzzleSource> PuzzleSource(
  int field, int pieces, int slabs, int resolution, int axis)
{
  vtkNew<vtkAPCPuzzleSource> source;
  source->SetField(field);
  source->SetNumberOfPuzzlePieces(pieces);
  source->SetSlabsPerPiece(slabs);
  source->SetResolution(resolution);
  source->SetAxis(axis);
  return source;
}

// The puzzle source's whole output (all puzzle pieces in one grid).
inline vtkSmartPointer<vtkUnstructuredGrid> PuzzleGrid(
  int field, int pieces, int slabs, int resolution, int axis = 2)
{
  auto source = PuzzleSource(field, pieces, slabs, resolution, axis);
  source->Update();
  return source->GetOutput();
}

// Piece `piece` of `requests` (default: one per puzzle piece) as a rank would generate it:
// the source's pipeline piece request.
inline vtkSmartPointer<vtkUnstructuredGrid> PuzzlePiece(
  int field, int pieces, int slabs, int resolution, int piece, int axis = 2, int requests = -1)
{
  auto source = PuzzleSource(field, pieces, slabs, resolution, axis);
  source->UpdatePiece(piece, requests < 0 ? pieces : requests, 0);
  return source->GetOutput();
}

} // namespace apctest

#endif
