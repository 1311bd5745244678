// Run under mpirun -np N. One process renders APC mode in small bands whatever the Band Size
// setting (apcAloneBands.h), so that its sample cache holds a band's samples; several
// processes keep the agreed setting (one band here). Either way the picture is the one of the
// whole data on one process (the mapper rendering alone), and one process's small bands give
// bit for bit the image of bands of one tile row.
#include "apcAloneBands.h"
#include "apcCompositePassRenders.h"
#include "apcMPITest.h"
#include "apcParallel.h"
#include "vtkAPCCompositePass.h"

#include "vtkMPIController.h"
#include "vtkNew.h"
#include "vtkSmartPointer.h"
#include "vtkUnstructuredGrid.h"

#include <cstdio>
#include <vector>

int main(int argc, char* argv[])
{
  vtkSmartPointer<vtkMPIController> controller = apctest::StartMPI(&argc, &argv);
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  using apctest::Check;

  constexpr int size = 512; // 2 bands of 2^17 pixels on one process with up to 2 threads
  const apctest::Scene puzzle = apctest::PuzzleScene(ranks);
  vtkSmartPointer<vtkUnstructuredGrid> piece = apctest::PuzzleShare(rank, ranks, ranks);
  double bounds[6];
  apctest::GlobalBounds(controller, piece, bounds);

  vtkNew<vtkAPCCompositePass> pass; // Band Size at its default, 2 megapixels
  const std::vector<float> image =
    apctest::RenderDistributed(controller, puzzle, piece, bounds, size, false, pass);
  Check(!pass->GetLastFrameFailed(), rank, "default bands: frame rendered");
  const double bands = pass->GetLastTimings().Bands;
  vtkNew<vtkAPCCompositePass> rows;
  rows->SetMaxBandPixels(1); // a band per tile row
  const std::vector<float> rowImage =
    apctest::RenderDistributed(controller, puzzle, piece, bounds, size, false, rows);
  if (rank == 0)
  {
    // The threads the frame ran on: the process's default, as the engine resolved it.
    const size_t band = apc::AloneBandPixels(pass->GetMaxBandPixels(), apc::ConcurrencyFor(0), 16);
    const size_t rowsPerBand = band / (size * 16) * 16;
    const double expected =
      ranks == 1 ? static_cast<double>((size + rowsPerBand - 1) / rowsPerBand) : 1.0;
    std::printf("%d rank(s): %g bands (%g expected), %g with a band per tile row\n", ranks, bands,
      expected, rows->GetLastTimings().Bands);
    Check(bands == expected, 0, "default bands: one process's small bands, else the setting's");
    Check(ranks > 1 || bands >= 2, 0, "default bands: more than one band on one process");
    Check(rows->GetLastTimings().Bands == size / 16, 0, "a band per tile row");
    const std::vector<float> whole = apctest::RenderWhole(puzzle, size, false);
    const double maxDiff = apctest::MaxAbsDifference(image, whole);
    std::printf("max |image - one-process mapper| = %.3g, |image - tile-row bands| = %.3g\n",
      maxDiff, apctest::MaxAbsDifference(image, rowImage));
    // As CompositePassMPI: 32-bit fixed-point moments and float colour sums, rounded once.
    Check(maxDiff <= 1e-5, 0, "default bands: the whole data's image on one process");
    Check(ranks > 2 || apctest::MaxAbsDifference(image, rowImage) == 0.0, 0,
      "default bands: the image of bands of one tile row, bit for bit");
  }
  return apctest::FinishMPITest(controller);
}
