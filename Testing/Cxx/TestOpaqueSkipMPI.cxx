// Run under mpirun -np N. Stop Where Opaque on a first frame (no last frame to say whether it
// cuts anything): on one process with one volume, pass 1 keeps the tiles no ray of which comes
// near the threshold as marched without the stop; on several, a probe of every
// OpaqueProbeStep-th ray that finds none near opaque lets pass 1 march the whole frame without
// the stop, marching a band again with it if some pixel's global absorbance reaches the
// threshold after all. A faint first frame must give the image of the stop off, bit for bit,
// with its tiles (one process) or its band (several) marched without the stop; an opaque first
// frame must still be cut (fewer pass-1 samples than with the stop off); and a first frame
// whose few opaque rays the probe misses must be marched again with the stop and give the
// stop's image.
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

// A transfer function under which some rays of the spheres reach the threshold but not the
// probe's at a step of 64 (at 128^2 on 2 ranks: 0.02-0.08 do; 0.15 leaves every ray open).
constexpr double kBarelyOpaqueUnit = 0.05;

using Frame = apctest::PassFrame;

// The first frame of a fresh pass over each rank's piece, with the stop on or off, and the
// probe's step (0: no probe).
Frame RenderFirst(vtkMPIController* controller, const apctest::Scene& scene,
  vtkUnstructuredGrid* piece, const double bounds[6], bool stop, int probeStep = 8,
  vtkIdType maxMessageBytes = 0)
{
  apctest::PassFrameOptions options;
  options.Size = 128; // 64 tiles, for one thread (kTilesPerThreadWithoutStop)
  options.Stop = stop;
  options.ProbeStep = probeStep;
  options.MaxMessageBytes = maxMessageBytes;
  return apctest::RenderPassFrames(controller, scene, piece, bounds, { scene.Camera }, options)[0];
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
    // One process keeps its tiles without the stop; several, whose probe finds no ray near
    // opaque, march the whole band without it.
    Check(ranks == 1 ? on.Timings.OpaqueStopSkipped == 0 : on.Timings.OpaqueStopSkipped > 0, rank,
      "faint first frame: several processes march the band without the stop");
    Check(on.Timings.OpaqueStopRedone == 0, rank, "faint first frame: nothing marched again");
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
    Check(on.Timings.OpaqueStopSkipped == 0 && on.Timings.OpaqueStopRedone == 0, rank,
      "opaque first frame: the probe keeps the stop");
    if (rank == 0)
    {
      Check(!on.RGBA.empty() && on.RGBA != off.RGBA, rank, "opaque first frame: stop's image");
    }
    std::printf("rank %d: opaque first frame, tiles without the stop %g, pass-1 samples %g of %g\n",
      rank, on.Timings.OpaqueUnstoppedTiles, all[0], all[1]);

    // The profiles' bins, the moments' codes and the colour sums in messages of 70 bytes (35
    // bins: pixels' bins and codes cut between messages), each packed and taken back in a
    // message-sized buffer: the same cut as one message each (the profiles and moments are
    // exact integer sums), so the same samples in pass 2; the float colour sums may be added
    // in another order for another message size, which moves the image by rounding alone.
    const Frame split = RenderFirst(controller, scene, piece, bounds, true, 8, 70);
    Check(split.Timings.Pass2Samples == on.Timings.Pass2Samples &&
        split.Timings.Pass1Samples == on.Timings.Pass1Samples,
      rank, "opaque first frame in small messages: the same cut");
    if (rank == 0)
    {
      const double diff = apctest::MaxAbsDifference(split.RGBA, on.RGBA);
      std::printf(
        "opaque first frame in 70-byte messages: max |difference| %g, pass-2 samples %g\n", diff,
        split.Timings.Pass2Samples);
      Check(!split.RGBA.empty() && diff <= 1e-6, rank,
        "opaque first frame in small messages: the image of one message each");
    }
  }
  if (ranks > 1)
  {
    // Rays near opaque only where the spheres are thickest, and a probe of one ray in 64 in
    // each direction that meets none of them: the band is marched without the stop, then
    // again with it, and gives the stop's image (that of a frame without the probe).
    scene.TF = apctest::BlueToRedTF(0.0, 1.0, kBarelyOpaqueUnit);
    const Frame missed = RenderFirst(controller, scene, piece, bounds, true, 64);
    const Frame plain = RenderFirst(controller, scene, piece, bounds, true, 0);
    std::printf("rank %d: probe of one ray in 64: skipped %g, marched again %g, probe samples %g\n",
      rank, missed.Timings.OpaqueStopSkipped, missed.Timings.OpaqueStopRedone,
      missed.Timings.OpaquePrepassSamples);
    Check(missed.Timings.OpaqueStopSkipped == 0 && missed.Timings.OpaqueStopRedone > 0 &&
        missed.Timings.OpaquePrepassSamples > 0,
      rank, "opaque rays the probe missed: the band marched again with the stop");
    Check(plain.Timings.OpaqueStopSkipped == 0 && plain.Timings.OpaqueStopRedone == 0, rank,
      "without the probe: the stop throughout");
    if (rank == 0)
    {
      // The band marched again with the stop and no bound takes the samples of the frame
      // without the probe: the same image, bit for bit.
      Check(!missed.RGBA.empty() && missed.RGBA == plain.RGBA, rank,
        "opaque rays the probe missed: the stop's image");
    }
  }
  return apctest::FinishMPITest(controller);
}
