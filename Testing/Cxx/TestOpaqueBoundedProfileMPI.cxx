// Run under mpirun -np N. Stop Where Opaque on several processes: a later frame's pass 1 stops
// every ray at its predicted last bin, so past that bin every process's opaque profile is
// zero and the profiles' allreduce carries each pixel's bins up to its bound alone. A later
// frame after a small camera move must give the image of a fresh pass's first frame of the
// same view (no prediction), and on several processes send fewer profile bytes than the whole
// profiles (32 a pixel): many of the opaque view's cuts lie in front of the last bin.
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

using Frame = apctest::PassFrame;

// Renders each of views in turn through one pass over each rank's piece (the first frame
// has no prediction, the later ones predict from the frame before); returns every frame.
std::vector<Frame> RenderFrames(vtkMPIController* controller, const apctest::Scene& scene,
  vtkUnstructuredGrid* piece, const double bounds[6], const std::vector<apctest::View>& views,
  bool stop = true)
{
  apctest::PassFrameOptions options;
  options.Stop = stop;
  return apctest::RenderPassFrames(controller, scene, piece, bounds, views, options);
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
  scene.TF = apctest::BlueToRedTF(0.0, 1.0, 0.01); // most rays opaque, early
  vtkSmartPointer<vtkUnstructuredGrid> piece =
    apctest::PuzzlePiece(vtkAPCPuzzleSource::SPHERES, ranks, 4, 12, rank, 2, ranks);
  double bounds[6];
  apctest::GlobalBounds(controller, piece, bounds);

  apctest::View moved = scene.Camera;
  moved.Position = { 2.51, 1.7, 3.09 }; // a small move: the last frame's cut still predicts
  const std::vector<Frame> later =
    RenderFrames(controller, scene, piece, bounds, { scene.Camera, moved });
  const std::vector<Frame> fresh = RenderFrames(controller, scene, piece, bounds, { moved });
  const std::vector<Frame> off = RenderFrames(controller, scene, piece, bounds, { moved }, false);
  const vtkAPCCompositePass::Timings& bounded = later.back().Timings;
  const vtkAPCCompositePass::Timings& first = fresh.back().Timings;
  if (rank == 0)
  {
    const double difference = apctest::MaxAbsDifference(later.back().RGBA, fresh.back().RGBA);
    Check(difference <= 1e-5, rank, "a later frame gives the fresh frame's image");
    std::printf("largest difference from a fresh frame: %g\n", difference);
  }
  Check(bounded.CoveredPixels == first.CoveredPixels, rank, "the same pixels covered");
  if (ranks > 1)
  {
    // The whole profile is 32 bytes a composited pixel, on top of what the stop off sends;
    // here the bounds leave out about 3 of a pixel's 16 bins on average (6.7 bytes; rays that
    // turn opaque nowhere keep all 16). Without the bound, every bin would be sent.
    const double whole = off.back().Timings.BytesSent + 32 * bounded.CompositedPixels;
    Check(bounded.BytesSent < whole - 4 * bounded.CompositedPixels, rank,
      "a bounded frame sends each pixel's bins up to its bound alone");
  }
  std::printf("rank %d: bytes sent %g bounded, %g fresh, %g stop off; covered pixels %g; "
              "unresolved %g\n",
    rank, bounded.BytesSent, first.BytesSent, off.back().Timings.BytesSent, first.CoveredPixels,
    bounded.OpaquePredictedUnresolved);
  return apctest::FinishMPITest(controller);
}
