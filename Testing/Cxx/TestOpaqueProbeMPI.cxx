// Run under mpirun -np N. Stop Where Opaque on the first frame of several processes: with no
// previous cut to bound pass 1 with, each process would march every ray up to where its OWN
// absorbance turns opaque, far behind the cut when its cells lie behind another's. The first
// frame therefore probes every 8th ray in each direction first, agrees their cut and bounds
// pass 1 with it as a later frame does with the previous cut (unresolved pixels marched
// again). The processes must then take far fewer pass-1 samples (the probe's included) than
// without the probe, and give the same image as without it and as one process.
#include "apcCompositePassRenders.h"
#include "apcMPITest.h"
#include "apcTestCompositePass.h"
#include "apcTestFailures.h"
#include "apcTestPuzzles.h"
#include "apcTestScenes.h"
#include "vtkAPCCompositePass.h"
#include "vtkAPCPuzzleSource.h"
#include "vtkAPCVolumeMapper.h"

#include "vtkCommunicator.h"
#include "vtkImageData.h"
#include "vtkMPIController.h"
#include "vtkNew.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"

#include <cstdio>
#include <vector>

namespace
{
using apctest::Check;

using Frame = apctest::PassFrame;

// The first frame of a fresh pass over each rank's piece, with the probe (its default step) or
// without it.
Frame RenderFirst(vtkMPIController* controller, const apctest::Scene& scene,
  vtkUnstructuredGrid* piece, const double bounds[6], bool probe)
{
  apctest::PassFrameOptions options;
  options.ProbeStep = probe ? -1 : 0;
  return apctest::RenderPassFrames(controller, scene, piece, bounds, { scene.Camera }, options)[0];
}

// Every process's value summed.
double Summed(vtkMPIController* controller, double mine)
{
  double sum = 0;
  controller->AllReduce(&mine, &sum, 1, vtkCommunicator::SUM_OP);
  return sum;
}
}

int main(int argc, char* argv[])
{
  vtkSmartPointer<vtkMPIController> controller = apctest::StartMPI(&argc, &argv);
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();

  // Spheres split among the processes in slabs along the depth (the front one's cells hide
  // the others'), most rays opaque early.
  apctest::Scene scene;
  scene.Camera.Parallel = false;
  scene.Camera.Position = { 2.5, 1.7, 3.1 };
  scene.SampleDistance = 0.02;
  scene.TF = apctest::BlueToRedTF(0.0, 1.0, 0.003);
  vtkSmartPointer<vtkUnstructuredGrid> piece =
    apctest::PuzzlePiece(vtkAPCPuzzleSource::SPHERES, ranks, 1, 12, rank, 2, ranks);
  double bounds[6];
  apctest::GlobalBounds(controller, piece, bounds);

  const Frame probed = RenderFirst(controller, scene, piece, bounds, true);
  const Frame plain = RenderFirst(controller, scene, piece, bounds, false);
  const vtkAPCCompositePass::Timings& p = probed.Timings;
  const vtkAPCCompositePass::Timings& q = plain.Timings;
  Check(q.OpaquePrepassSamples == 0 && q.OpaquePredictedUnresolved == 0, rank,
    "no probe, no bound: nothing probed, nothing unresolved");
  const double with = Summed(controller, p.Pass1Samples + p.OpaquePrepassSamples);
  const double without = Summed(controller, q.Pass1Samples);
  // The samples of the process the probe's bound spares most, against its own without.
  const double mine =
    q.Pass1Samples > 0 ? (p.Pass1Samples + p.OpaquePrepassSamples) / q.Pass1Samples : 1.0;
  double least = 1.0;
  controller->AllReduce(&mine, &least, 1, vtkCommunicator::MIN_OP);
  if (ranks > 1)
  {
    Check(p.OpaquePrepassSamples > 0 || p.Pass1Samples == 0, rank, "the first frame probes");
    // The front process's rays turn opaque on its own cells: it takes as many samples either
    // way, plus the probe's (1/64 of its rays) and a few tiles marched again. The processes
    // behind stop near the cut: here all ranks together take 0.95 (2 ranks) and 0.86 (3) of
    // the samples without the probe, the rank behind 0.74 and 0.63 of its own (3 pixels
    // unresolved, 2 tiles marched again).
    Check(with < 0.97 * without, rank, "the probe's bound saves pass-1 samples");
    Check(least < 0.8, rank, "the probe's bound spares the processes behind");
  }
  else
  {
    Check(p.OpaquePrepassSamples == 0 && with == without, rank,
      "one process never probes (its own stop is the cut)");
  }
  if (rank == 0)
  {
    const double difference = apctest::MaxAbsDifference(probed.RGBA, plain.RGBA);
    Check(difference <= 1e-5, rank, "the probe's frame gives the frame without it");
    std::printf("largest difference from the frame without the probe: %g\n", difference);
  }
  // The predicted cut's replay (the unresolved pixels' tiles marched again) or the cut applied
  // to the moments, throwing on the last process (its memory ran out): every process gives the
  // frame up (no image on the display process, which only learns of it by the agreement)
  // instead of waiting in the profiles' or the moments' sum, and the next first frame is the
  // undisturbed one.
  if (ranks > 1)
  {
    Check(p.OpaquePredictedUnresolved > 0, rank, "the probe leaves pixels to march again");
    for (apc::FailurePoint point : { apc::FailurePoint::OpaqueRedo, apc::FailurePoint::OpaqueCut })
    {
      if (rank == ranks - 1)
      {
        apc::FailForTesting(point, 1);
      }
      const Frame failed = RenderFirst(controller, scene, piece, bounds, true);
      const Frame next = RenderFirst(controller, scene, piece, bounds, true);
      if (rank == 0)
      {
        Check(failed.RGBA.empty(), rank, "a replay or cut that throws: no image");
        Check(apctest::MaxAbsDifference(next.RGBA, probed.RGBA) == 0, rank,
          "after a failed replay or cut: the next first frame is the undisturbed one");
      }
    }
  }
  std::printf("rank %d: pass-1 samples %g with the probe (its own %g), %g without; all ranks "
              "%g and %g, the most spared rank %g; unresolved %g, tiles marched again %g\n",
    rank, p.Pass1Samples, p.OpaquePrepassSamples, q.Pass1Samples, with, without, least,
    p.OpaquePredictedUnresolved, p.OpaquePredictedRedone);
  return apctest::FinishMPITest(controller);
}
