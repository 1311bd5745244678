// Run under mpirun -np N. Stop Where Opaque on the first frame of several processes, which
// has no predicted bound: the processes combine a 2-byte summary of each pixel's opaque
// profile first (apcOpaqueSummary.h) and sum each pixel's bins only up to the earliest cut a
// process found on its own, none where their totals stay below the threshold. A faint view
// must then send 2 bytes a composited pixel more than the stop off (not the whole profile's
// 32), an opaque one less than half the whole profile, and both must give one process's image.
// On an image large enough, pass 1 keeps the tiles no ray of which comes near the threshold on
// a process's own samples as marched without the stop, and marches again for their profiles
// only those where the processes' summaries together may reach it: still one process's image.
#include "apcCompositePassRenders.h"
#include "apcMPITest.h"
#include "apcTestScenes.h"
#include "vtkAPCCompositePass.h"
#include "vtkAPCVolumeMapper.h"

#include "vtkCommunicator.h"
#include "vtkMPIController.h"
#include "vtkNew.h"
#include "vtkUnstructuredGrid.h"

#include <cstdio>
#include <string>
#include <vector>

namespace
{
using apctest::Check;

struct Frame
{
  std::vector<float> RGBA; // the display rank's float image
  double Bytes = 0;        // this rank's bytes on the wire
  double Composited = 0;   // the pixels of the agreed tiles
  double Skipped = 0;      // bands rendered without the stop
  double Unstopped = 0;    // tiles pass 1 kept as marched without the stop
  double Profiled = 0;     // of those, tiles marched again for their profiles
};

// The first frame of a fresh pass over each rank's piece, with the stop on or off.
Frame RenderFirst(vtkMPIController* controller, const apctest::Scene& scene,
  vtkUnstructuredGrid* piece, const double bounds[6], bool stop, int size)
{
  vtkNew<vtkAPCCompositePass> pass;
  Frame frame;
  frame.RGBA = apctest::RenderDistributed(controller, scene, piece, bounds, size, false, pass, true,
    vtkAPCVolumeMapper::RENORMALISED, nullptr, stop);
  frame.Bytes = pass->GetLastBytesSent();
  frame.Composited = static_cast<double>(pass->GetLastCompositedPixels());
  frame.Skipped = pass->GetLastTimings().OpaqueStopSkipped;
  frame.Unstopped = pass->GetLastTimings().OpaqueUnstoppedTiles;
  frame.Profiled = pass->GetLastTimings().OpaqueUnstoppedProfiled;
  return frame;
}

// What a first frame on several processes must show of pass 1's march without the stop.
enum class Unstopped
{
  Any,     // (a small image: too few tiles a thread to try it)
  Kept,    // tiles kept as marched without the stop
  Profiled // ... and some of them marched again for their profiles
};

void CheckView(vtkMPIController* controller, const char* name, apctest::Scene scene,
  vtkUnstructuredGrid* piece, const double bounds[6], double maxProfileBytes, int size = 96,
  Unstopped unstopped = Unstopped::Any)
{
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  const Frame on = RenderFirst(controller, scene, piece, bounds, true, size);
  const Frame off = RenderFirst(controller, scene, piece, bounds, false, size);
  double counts[2] = { on.Unstopped, on.Profiled };
  double all[2];
  controller->AllReduce(counts, all, 2, vtkCommunicator::SUM_OP);
  if (ranks > 1 && unstopped != Unstopped::Any)
  {
    Check(all[0] > 0, rank, std::string(name) + ": tiles kept as marched without the stop");
    Check(unstopped == Unstopped::Profiled ? all[1] > 0 : all[1] == 0, rank,
      std::string(name) + ": tiles marched again for their profiles where the sums need them");
  }
  Check(on.Skipped == 0, rank, std::string(name) + ": the first frame keeps the stop");
  const double profileBytes = (on.Bytes - off.Bytes) / on.Composited;
  if (ranks > 1)
  {
    Check(on.Composited > 0 && on.Composited == off.Composited, rank,
      std::string(name) + ": the same tiles composited");
    Check(profileBytes <= maxProfileBytes, rank,
      std::string(name) + ": the profiles' bytes a composited pixel");
  }
  if (rank == 0)
  {
    const std::vector<float> whole = apctest::RenderWhole(scene, size, false);
    const double difference = apctest::MaxAbsDifference(on.RGBA, whole);
    Check(difference <= 1e-5, rank, std::string(name) + ": one process's image");
    std::printf("%s: largest difference from one process %g\n", name, difference);
  }
  std::printf("rank %d, %s: %g profile bytes a composited pixel (%g pixels), tiles without the "
              "stop %g, of them profiled %g (all ranks)\n",
    rank, name, profileBytes, on.Composited, all[0], all[1]);
}
}

int main(int argc, char* argv[])
{
  vtkSmartPointer<vtkMPIController> controller = apctest::StartMPI(&argc, &argv);
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  apctest::Scene scene = apctest::PuzzleScene(ranks);
  vtkSmartPointer<vtkUnstructuredGrid> piece = apctest::PuzzleShare(rank, ranks, ranks);
  double bounds[6];
  apctest::GlobalBounds(controller, piece, bounds);

  // Faint: absorbance along a ray below 0.2, nothing near the threshold; the summaries alone.
  scene.TF = apctest::BlueToRedTF(0.0, 1.0, 20.0);
  CheckView(controller, "faint", scene, piece, bounds, 2.0);
  // Opaque: most rays turn opaque early, many on one process's own samples.
  scene.TF = apctest::BlueToRedTF(0.0, 1.0, 0.01);
  CheckView(controller, "opaque", scene, piece, bounds, 16.0);
  // At 256^2 (enough tiles a thread for pass 1 to try tiles without the stop on several
  // processes): faint, every tile kept so; summed, no process's own absorbance comes near the
  // threshold in many tiles, but the processes' together do in some of them, which are
  // marched again for their profiles.
  scene.TF = apctest::BlueToRedTF(0.0, 1.0, 20.0);
  CheckView(controller, "faint 256", scene, piece, bounds, 2.0, 256, Unstopped::Kept);
  scene.TF = apctest::BlueToRedTF(0.0, 1.0, 0.04);
  CheckView(controller, "summed 256", scene, piece, bounds, 16.0, 256, Unstopped::Profiled);
  return apctest::FinishMPITest(controller);
}
