// Run under mpirun -np N. Stop Where Opaque on the first frame of several processes: with no
// previous cut to bound pass 1 with, each process would march every ray up to where its OWN
// absorbance turns opaque, far behind the cut when its cells lie behind another's. The first
// frame therefore probes every 4th ray in each direction first, agrees their cut and bounds
// pass 1 with it as a later frame does with the previous cut (unresolved pixels marched
// again). The processes must then take far fewer pass-1 samples (the probe's included) than
// without the probe, and give the same image as without it and as one process.
#include "apcCompositePassRenders.h"
#include "apcMPITest.h"
#include "apcTestCompositePass.h"
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

struct Frame
{
  std::vector<float> RGBA; // the display rank's float image
  vtkAPCCompositePass::Timings Timings;
};

constexpr int kSize = 96;

// The first frame of a fresh pass over each rank's piece, with the probe's step (0: none).
Frame RenderFirst(vtkMPIController* controller, const apctest::Scene& scene,
  vtkUnstructuredGrid* piece, const double bounds[6], int probeStep)
{
  vtkNew<vtkAPCCompositePass> pass;
  pass->SetOpaqueProbeStep(probeStep);
  vtkNew<vtkRenderWindow> window;
  vtkNew<vtkRenderer> renderer;
  apctest::SetUpCompositeWindow(window, renderer, kSize, pass, controller);
  vtkNew<vtkAPCVolumeMapper> mapper;
  mapper->SetInputData(piece);
  mapper->SetNumberOfThreads(1);
  vtkNew<vtkVolume> volume;
  apctest::ConfigureVolume(volume, mapper, scene);
  pass->KeepLastImageOn();
  pass->AddVolume(volume);
  apctest::ApplyView(renderer, scene.Camera);
  renderer->ResetCameraClippingRange(bounds);
  window->Render();
  Frame frame;
  frame.Timings = pass->GetLastTimings();
  frame.RGBA = apctest::ImageRGBA(pass->GetLastImage());
  return frame;
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

  // Spheres split among the processes, most rays opaque early (TestOpaqueBoundedProfileMPI's).
  apctest::Scene scene;
  scene.Camera.Parallel = false;
  scene.Camera.Position = { 2.5, 1.7, 3.1 };
  scene.SampleDistance = 0.02;
  scene.TF = apctest::BlueToRedTF(0.0, 1.0, 0.01);
  vtkSmartPointer<vtkUnstructuredGrid> piece =
    apctest::PuzzlePiece(vtkAPCPuzzleSource::SPHERES, ranks, 1, 12, rank, 2, ranks);
  double bounds[6];
  apctest::GlobalBounds(controller, piece, bounds);

  const Frame probed = RenderFirst(controller, scene, piece, bounds, 4);
  const Frame plain = RenderFirst(controller, scene, piece, bounds, 0);
  const vtkAPCCompositePass::Timings& p = probed.Timings;
  const vtkAPCCompositePass::Timings& q = plain.Timings;
  Check(q.OpaquePrepassSamples == 0 && q.OpaquePredictedUnresolved == 0, rank,
    "no probe, no bound: nothing probed, nothing unresolved");
  const double with = Summed(controller, p.Pass1Samples + p.OpaquePrepassSamples);
  const double without = Summed(controller, q.Pass1Samples);
  if (ranks > 1)
  {
    Check(p.OpaquePrepassSamples > 0 || p.Pass1Samples == 0, rank, "the first frame probes");
    // Here the processes together take 1.25 (2 ranks) and 1.64 (3) times one process's
    // samples without the probe, 1.06 and 1.15 with it (the probe's 1/16 of the rays
    // included; no pixel unresolved).
    Check(with < 0.9 * without, rank, "the probe's bound saves pass-1 samples");
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
  std::printf("rank %d: pass-1 samples %g with the probe (its own %g), %g without; all ranks "
              "%g and %g; unresolved %g, tiles marched again %g\n",
    rank, p.Pass1Samples, p.OpaquePrepassSamples, q.Pass1Samples, with, without,
    p.OpaquePredictedUnresolved, p.OpaquePredictedRedone);
  return apctest::FinishMPITest(controller);
}
