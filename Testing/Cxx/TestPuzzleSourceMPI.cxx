// SPDX-License-Identifier: BSD-3-Clause
// Run under mpirun -np N: every rank generates only its own puzzle piece(s) of
// vtkAPCPuzzleSource through the pipeline's piece request, and the pieces are the paper's
// worst case: the expected cell counts, no cell generated twice, and every pair of
// non-empty rank bounds overlapping.

#include "apcMPITest.h"
#include "vtkAPCPuzzleSource.h"
#include "vtkCellData.h"
#include "vtkDataArray.h"
#include "vtkMPIController.h"
#include "vtkMeshQuality.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkUnstructuredGrid.h"

#include <cmath>
#include <cstdio>
#include <vector>

namespace
{
using apctest::Check;

bool Overlap(const double* a, const double* b)
{
  for (int d = 0; d < 3; ++d)
  {
    // Strict: slabs that merely touch at a face do not count as overlapping in depth.
    if (a[2 * d + 1] <= b[2 * d] || b[2 * d + 1] <= a[2 * d])
    {
      return false;
    }
  }
  return true;
}

// One configuration: all ranks build it, rank 0 checks the gathered results.
void RunCase(vtkMPIController* controller, int puzzlePieces, int slabs, int resolution, int axis)
{
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();

  vtkNew<vtkAPCPuzzleSource> source;
  source->SetNumberOfPuzzlePieces(puzzlePieces);
  source->SetSlabsPerPiece(slabs);
  source->SetResolution(resolution);
  source->SetAxis(axis);
  source->UpdatePiece(rank, ranks, 0);
  vtkUnstructuredGrid* grid = source->GetOutput();

  const int piecesTotal = puzzlePieces > 0 ? puzzlePieces : ranks;
  const int myPieces = (rank + 1) * piecesTotal / ranks - rank * piecesTotal / ranks;
  const vtkIdType expectedCells =
    static_cast<vtkIdType>(myPieces) * source->GetNumberOfCellsPerPuzzlePiece();
  Check(grid->GetNumberOfCells() == expectedCells, rank, "local cell count");
  Check(source->GetNumberOfCellsPerPuzzlePiece() ==
      static_cast<vtkIdType>(slabs) * resolution * resolution * 2,
    rank, "cells per puzzle piece");
  Check(grid->GetPointData()->GetScalars() != nullptr, rank, "point scalars present");
  if (grid->GetNumberOfCells() > 0)
  {
    Check(grid->IsHomogeneous() && grid->GetCellType(0) == VTK_HEXAHEDRON, rank, "all hexahedra");
    double range[2];
    grid->GetCellData()->GetArray("PuzzlePiece")->GetRange(range);
    Check(
      range[0] == rank * piecesTotal / ranks && range[1] == (rank + 1) * piecesTotal / ranks - 1,
      rank, "PuzzlePiece ids are this rank's");
  }

  // Right-handed hexahedra that tile the box: every volume positive, the sum over all ranks 8.
  double volume = 0;
  bool allPositive = true;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    const double v = vtkMeshQuality::HexVolume(grid->GetCell(c));
    allPositive = allPositive && v > 0;
    volume += v;
  }
  Check(allPositive, rank, "every hexahedron has positive volume");
  double totalVolume = 0;
  controller->AllReduce(&volume, &totalVolume, 1, vtkCommunicator::SUM_OP);
  Check(std::abs(totalVolume - 8.0) < 1e-5, rank, "the pieces tile [-1,1]^3 (total volume 8)");

  // Gather counts and bounds: [cells, xmin..zmax] per rank.
  double local[7] = { static_cast<double>(grid->GetNumberOfCells()) };
  grid->GetBounds(local + 1);
  std::vector<double> all(7 * ranks);
  controller->Gather(local, all.data(), 7, 0);
  if (rank == 0)
  {
    double total = 0;
    for (int r = 0; r < ranks; ++r)
    {
      const double* b = &all[7 * r + 1];
      std::printf("P=%d K=%d R=%d axis=%d rank %d: %.0f cells, bounds [%g %g] [%g %g] [%g %g]\n",
        piecesTotal, slabs, resolution, axis, r, all[7 * r], b[0], b[1], b[2], b[3], b[4], b[5]);
      total += all[7 * r];
    }
    Check(total == static_cast<double>(piecesTotal) * source->GetNumberOfCellsPerPuzzlePiece(), 0,
      "total cells = pieces x cells per piece (none missing, none twice)");
    for (int r = 0; r < ranks; ++r)
    {
      for (int s = r + 1; s < ranks; ++s)
      {
        if (all[7 * r] > 0 && all[7 * s] > 0 && slabs > 1)
        {
          Check(Overlap(&all[7 * r + 1], &all[7 * s + 1]), 0, "bounds of two ranks overlap");
        }
      }
    }
  }
}
}

int main(int argc, char* argv[])
{
  vtkSmartPointer<vtkMPIController> controller = apctest::StartMPI(&argc, &argv);
  const int ranks = controller->GetNumberOfProcesses();

  RunCase(controller, 0, 4, 8, 2);         // one puzzle piece per rank, the paper's 4 slabs
  RunCase(controller, 0, 3, 5, 0);         // another axis and slab count
  RunCase(controller, 2 * ranks, 2, 4, 1); // several puzzle pieces per rank
  RunCase(
    controller, ranks > 1 ? ranks - 1 : 1, 4, 4, 2); // fewer pieces than ranks: one rank empty

  return apctest::FinishMPITest(controller);
}
