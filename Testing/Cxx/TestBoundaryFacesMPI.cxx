// Run under mpirun -np N. Sample End Weights = Boundary on N processes renders what one
// process renders: the faces between the ranks' pieces of the wind data (Scotch pieces) are
// matched over MPI (apcBoundaryExchange.h) and left plain, as inner faces of the whole mesh
// are. Hybrid keeps the plain lattice, so that on one rank it is the exact image. A failure
// injected on one rank's exchange is agreed: every rank finishes the frame with its own piece's
// boundary, and the next exchange matches the faces again.
#include "apcBoundaryExchange.h"
#include "apcCompositePassRenders.h"
#include "apcMPITest.h"
#include "apcTestFailures.h"
#include "apcTestScenes.h"
#include "vtkAPCCompositePass.h"
#include "vtkAPCVolumeMapper.h"

#include "vtkMPIController.h"
#include "vtkNew.h"
#include "vtkUnstructuredGrid.h"

#include <cstdio>
#include <string>
#include <vector>

namespace
{
using apctest::Check;

// Every rank's faces, bytes and seconds of its last exchange, in rank order on rank 0.
void Report(vtkMPIController* controller, const char* name)
{
  const apc::BoundaryExchangeRecord& record = apc::GetLastBoundaryExchange();
  double mine[5] = { static_cast<double>(record.FacesSent), record.BytesSent, record.Seconds,
    record.LocalSeconds, record.LocalCPUSeconds };
  std::vector<double> all(5 * static_cast<size_t>(controller->GetNumberOfProcesses()));
  controller->Gather(mine, all.data(), 5, 0);
  if (controller->GetLocalProcessId() == 0)
  {
    for (int r = 0; r < controller->GetNumberOfProcesses(); ++r)
    {
      std::printf("%s, rank %d: %.0f boundary faces sent, %.0f bytes, %.4f s wall (of which its "
                  "own piece's matching %.4f s wall, %.4f s CPU)\n",
        name, r, all[5 * r], all[5 * r + 1], all[5 * r + 2], all[5 * r + 3], all[5 * r + 4]);
    }
  }
}
}

int main(int argc, char* argv[])
{
  vtkSmartPointer<vtkMPIController> controller = apctest::StartMPI(&argc, &argv);
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();

  apctest::View windView;
  windView.Parallel = false;
  windView.Position = { -120, -260, 420 };
  windView.FocalPoint = { 155, 90, 40 };
  windView.ViewUp = { 0, 0, 1 };
  apctest::Scene wind = apctest::MakeScene(
    apctest::WindPieces(0, 1), apctest::BlueToRedTF(0.0, 20.0, 20.0), 2.0, windView);
  wind.SampleEndWeights = vtkAPCVolumeMapper::END_WEIGHTS_BOUNDARY;
  vtkSmartPointer<vtkUnstructuredGrid> piece = apctest::WindPieces(rank, ranks);
  double bounds[6];
  apctest::GlobalBounds(controller, piece, bounds);
  const int size = 96;

  std::vector<float> whole;
  if (rank == 0)
  {
    whole = apctest::RenderWhole(wind, size, false);
    apctest::Scene plain = wind;
    plain.SampleEndWeights = vtkAPCVolumeMapper::END_WEIGHTS_OFF;
    // The weights change this view: the check below is not one of the plain lattice.
    const double weighted =
      apctest::MaxAbsDifference(whole, apctest::RenderWhole(plain, size, false));
    Check(weighted > 1e-3, rank, "the boundary's weights change the one-process image");
    std::printf("one process, Boundary against Off: %g\n", weighted);
  }

  {
    vtkNew<vtkAPCCompositePass> pass;
    const std::vector<float> distributed =
      apctest::RenderDistributed(controller, wind, piece, bounds, size, false, pass);
    Check(!pass->GetLastFrameFailed(), rank, "the frame renders");
    Report(controller, "matched");
    // The matching and exchange are a stage of the frame's timings of their own ("boundary",
    // its collectives' waits and transfers inside it), so a first frame's cost shows there.
    const vtkAPCCompositePass::Timings timings = pass->GetLastTimings();
    if (ranks > 1)
    {
      std::printf("rank %d: boundary stage %.4f s (wait %.4f, transfer %.4f)\n", rank,
        timings.Boundary, timings.BoundaryWait, timings.BoundaryTransfer);
      Check(timings.Boundary > 0 && timings.BoundaryWait > 0 &&
          timings.BoundaryWait + timings.BoundaryTransfer <= timings.Boundary,
        rank, "the boundary exchange is timed as its own stage");
    }
    if (rank == 0)
    {
      // The compact wire's criterion of every N-ranks-against-one test (TestCompositePassMPI).
      const double difference = apctest::MaxAbsDifference(distributed, whole);
      std::printf(
        "Boundary on %d ranks: max |distributed - one process| = %g\n", ranks, difference);
      Check(difference <= 1e-5, rank, "Boundary on N ranks equals one process");
    }
  }

  {
    // Hybrid keeps the plain lattice (the exact modes do): on one rank it is the exact blend,
    // the one-process EXACT image (TestCompositePassMPI's criterion), with Boundary set too.
    vtkNew<vtkAPCCompositePass> pass;
    const std::vector<float> hybrid = apctest::RenderDistributed(
      controller, wind, piece, bounds, size, false, pass, true, vtkAPCVolumeMapper::HYBRID);
    if (rank == 0 && ranks == 1)
    {
      const double difference = apctest::MaxAbsDifference(
        hybrid, apctest::RenderWhole(wind, size, false, vtkAPCVolumeMapper::EXACT));
      std::printf("Hybrid with Boundary on one rank: max |Hybrid - EXACT| = %g\n", difference);
      Check(difference <= 1e-6, rank, "Hybrid with Boundary on one rank equals EXACT");
    }
  }

  if (ranks > 1)
  {
    // The last rank alone fails once (hook: the failure to inject), then renders with target.
    auto renderFailingOnLastRank = [&](apc::FailurePoint point, vtkAPCCompositePass* target)
    {
      if (rank == ranks - 1)
      {
        apc::FailForTesting(point, 1);
      }
      return apctest::RenderDistributed(controller, wind, piece, bounds, size, false, target);
    };
    // The last rank fails before it sends anything: every rank must leave the exchange (none
    // waits in an Alltoallv), render the frame with its own piece's boundary and say why.
    vtkNew<vtkAPCCompositePass> pass;
    const std::vector<float> fallback =
      renderFailingOnLastRank(apc::FailurePoint::BoundaryExchange, pass);
    Check(!pass->GetLastFrameFailed(), rank, "a failed exchange: the frame still renders");
    if (rank == 0)
    {
      const double difference = apctest::MaxAbsDifference(fallback, whole);
      std::printf("Boundary on %d ranks, exchange failed: max |distributed - one process| = %g\n",
        ranks, difference);
      Check(!fallback.empty(), rank, "a failed exchange: an image");
      // Each piece's own boundary: the faces between the pieces are weighted.
      Check(difference > 1e-5, rank, "a failed exchange: each rank weights its own piece");
    }
    // The failure is not kept: the next exchange matches the faces again.
    vtkNew<vtkAPCCompositePass> again;
    const std::vector<float> matched =
      apctest::RenderDistributed(controller, wind, piece, bounds, size, false, again);
    if (rank == 0)
    {
      Check(apctest::MaxAbsDifference(matched, whole) <= 1e-5, rank,
        "after a failed exchange, a new frame matches the faces again");
    }

    // The last rank fails while it sets the exchange up, before its first collective: every
    // rank must leave the exchange as from a failed one (the same image), and the next frame
    // of the same pass matches the faces.
    vtkNew<vtkAPCCompositePass> setUp;
    const std::vector<float> unmatched =
      renderFailingOnLastRank(apc::FailurePoint::BoundarySetUp, setUp);
    Check(!setUp->GetLastFrameFailed(), rank, "a failed set-up: the frame still renders");
    const std::vector<float> rematched =
      apctest::RenderDistributed(controller, wind, piece, bounds, size, false, setUp);
    if (rank == 0)
    {
      Check(apctest::MaxAbsDifference(unmatched, fallback) == 0, rank,
        "a failed set-up: the image of a failed exchange");
      Check(apctest::MaxAbsDifference(rematched, whole) <= 1e-5, rank,
        "after a failed set-up, the next frame matches the faces");
    }
  }
  return apctest::FinishMPITest(controller);
}
