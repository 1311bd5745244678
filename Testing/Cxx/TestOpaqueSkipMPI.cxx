// Run under mpirun -np N. Stop Where Opaque on a first frame (no last frame to say whether it
// cuts anything): on one process with one volume, pass 1 keeps the tiles no ray of which comes
// near the threshold as marched without the stop. A faint first frame must give the image of
// the stop off, bit for bit, with its tiles marched without the stop on one process (none on
// several, where a process's own absorbance is not the global one); an opaque first frame
// must still be cut (fewer pass-1 samples than with the stop off).
#include "apcCompositePassRenders.h"
#include "apcMPITest.h"
#include "apcTestCompositePass.h"
#include "apcTestPuzzles.h"
#include "apcTestScenes.h"
#include "vtkAPCCompositePass.h"
#include "vtkAPCPuzzleSource.h"
#include "vtkAPCVolumeMapper.h"

#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkMPIController.h"
#include "vtkNew.h"
#include "vtkPointData.h"
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

// The first frame of a fresh pass over each rank's piece, with the stop on or off.
Frame RenderFirst(vtkMPIController* controller, const apctest::Scene& scene,
  vtkUnstructuredGrid* piece, const double bounds[6], bool stop)
{
  constexpr int size = 128; // 64 tiles, for one thread (kTilesPerThreadWithoutStop)
  vtkNew<vtkAPCCompositePass> pass;
  vtkNew<vtkRenderWindow> window;
  vtkNew<vtkRenderer> renderer;
  apctest::SetUpCompositeWindow(window, renderer, size, pass, controller);
  vtkNew<vtkAPCVolumeMapper> mapper;
  mapper->SetInputData(piece);
  mapper->SetStopWhereOpaque(stop);
  mapper->SetNumberOfThreads(1);
  vtkNew<vtkVolume> volume;
  apctest::ConfigureVolume(volume, mapper, scene);
  pass->KeepLastImageOn();
  pass->AddVolume(volume);
  apctest::SetCamera(renderer, scene, bounds);
  window->Render();
  Frame frame;
  frame.Timings = pass->GetLastTimings();
  frame.RGBA = apctest::ImageRGBA(pass->GetLastImage());
  return frame;
}
}

int main(int argc, char* argv[])
{
  vtkSmartPointer<vtkMPIController> controller = apctest::StartMPI(&argc, &argv);
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();

  apctest::Scene scene;
  scene.Camera.Parallel = false;
  scene.Camera.Position = { 2.5, 1.7, 3.1 };
  scene.SampleDistance = 0.02;
  vtkSmartPointer<vtkUnstructuredGrid> piece =
    apctest::PuzzlePiece(vtkAPCPuzzleSource::SPHERES, ranks, 4, 12, rank, 2, ranks);
  double bounds[6];
  apctest::GlobalBounds(controller, piece, bounds);

  {
    scene.TF = apctest::BlueToRedTF(0.0, 1.0, 20.0); // absorbance along a ray below 0.2
    const Frame on = RenderFirst(controller, scene, piece, bounds, true);
    const Frame off = RenderFirst(controller, scene, piece, bounds, false);
    Check(on.Timings.OpaqueStopSkipped == 0, rank, "faint first frame: the stop is on");
    Check(ranks == 1 ? on.Timings.OpaqueUnstoppedTiles > 0 : on.Timings.OpaqueUnstoppedTiles == 0,
      rank, "faint first frame: tiles marched without the stop on one process only");
    Check(on.Timings.Pass1Samples == off.Timings.Pass1Samples, rank,
      "faint first frame: the samples of the stop off");
    if (rank == 0)
    {
      Check(!on.RGBA.empty() && on.RGBA == off.RGBA, rank, "faint first frame: stop off's image");
    }
    std::printf("rank %d: faint first frame, tiles without the stop %g, pass-1 samples %g\n", rank,
      on.Timings.OpaqueUnstoppedTiles, on.Timings.Pass1Samples);
  }
  {
    scene.TF = apctest::BlueToRedTF(0.0, 1.0, 0.01); // most rays opaque
    const Frame on = RenderFirst(controller, scene, piece, bounds, true);
    const Frame off = RenderFirst(controller, scene, piece, bounds, false);
    double mine[2] = { on.Timings.Pass1Samples, off.Timings.Pass1Samples };
    double all[2];
    controller->AllReduce(mine, all, 2, vtkCommunicator::SUM_OP);
    Check(all[0] < 0.9 * all[1], rank, "opaque first frame: the stop still cuts");
    if (rank == 0)
    {
      Check(!on.RGBA.empty() && on.RGBA != off.RGBA, rank, "opaque first frame: stop's image");
    }
    std::printf("rank %d: opaque first frame, tiles without the stop %g, pass-1 samples %g of %g\n",
      rank, on.Timings.OpaqueUnstoppedTiles, all[0], all[1]);
  }
  return apctest::FinishMPITest(controller);
}
