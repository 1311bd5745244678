// Run under mpirun -np N. Stop Where Opaque on the first frame of several processes, which
// has no predicted bound: the processes combine a 2-byte summary of each pixel's opaque
// profile first (apcOpaqueSummary.h) and sum each pixel's bins only up to the earliest cut a
// process found on its own, none where their totals stay below the threshold. A faint view
// must then send 2 bytes a composited pixel more than the stop off (not the whole profile's
// 32), an opaque one less than half the whole profile, and both must give one process's image.
// The first frame's probe for a bound (TestOpaqueProbeMPI) is off here: it is what a frame
// without any bound sends.
#include "apcCompositePassRenders.h"
#include "apcMPITest.h"
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

struct Frame
{
  std::vector<float> RGBA; // the display rank's float image
  double Bytes = 0;        // this rank's bytes on the wire
  double Composited = 0;   // the pixels of the agreed tiles
  double Skipped = 0;      // bands rendered without the stop
  double ProfileBytes = 0; // of Bytes, the opaque summaries' and profiles'
};

// The first frame of a fresh pass over each rank's piece, with the stop on or off.
Frame RenderFirst(vtkMPIController* controller, const apctest::Scene& scene,
  vtkUnstructuredGrid* piece, const double bounds[6], bool stop)
{
  vtkNew<vtkAPCCompositePass> pass;
  pass->SetOpaqueProbeStep(0);
  Frame frame;
  frame.RGBA = apctest::RenderDistributed(controller, scene, piece, bounds, 96, false, pass, true,
    vtkAPCVolumeMapper::RENORMALISED, nullptr, stop);
  frame.Bytes = pass->GetLastBytesSent();
  frame.Composited = static_cast<double>(pass->GetLastCompositedPixels());
  frame.Skipped = pass->GetLastTimings().OpaqueStopSkipped;
  frame.ProfileBytes = pass->GetLastTimings().ProfileBytes;
  return frame;
}

void CheckView(vtkMPIController* controller, const char* name, apctest::Scene scene,
  vtkUnstructuredGrid* piece, const double bounds[6], double maxProfileBytes)
{
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  const Frame on = RenderFirst(controller, scene, piece, bounds, true);
  const Frame off = RenderFirst(controller, scene, piece, bounds, false);
  Check(on.Skipped == 0, rank, std::string(name) + ": the first frame keeps the stop");
  const double profileBytes = (on.Bytes - off.Bytes) / on.Composited;
  if (ranks > 1)
  {
    Check(on.Composited > 0 && on.Composited == off.Composited, rank,
      std::string(name) + ": the same tiles composited");
    Check(profileBytes <= maxProfileBytes, rank,
      std::string(name) + ": the profiles' bytes a composited pixel");
    // The timing profile_bytes is what the stop adds to the wire (the rest is the same).
    Check(on.ProfileBytes == on.Bytes - off.Bytes && off.ProfileBytes == 0, rank,
      std::string(name) + ": profile_bytes counts the profiles' bytes");
  }
  if (rank == 0)
  {
    const std::vector<float> whole = apctest::RenderWhole(scene, 96, false);
    const double difference = apctest::MaxAbsDifference(on.RGBA, whole);
    Check(difference <= 1e-5, rank, std::string(name) + ": one process's image");
    std::printf("%s: largest difference from one process %g\n", name, difference);
  }
  std::printf("rank %d, %s: %g profile bytes a composited pixel (%g pixels)\n", rank, name,
    profileBytes, on.Composited);
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
  return apctest::FinishMPITest(controller);
}
