// Run under mpirun -np N (N >= 2). vtkAPCCompositePass splits each stage with collectives into
// the wait for the last rank to arrive and the transfer after it: on the display rank the two
// must add up to the stage, less the rank's own work in it (packing, marking tiles), which
// is bounded by kSlack; and a deliberately slow rank's lateness must appear as the display
// rank's wait, not as transfer:
// - a rank that sleeps before the frame's agreement: the display rank's "agree_wait" holds
//   the sleep; when the display rank itself sleeps, its wait is short and "wait_max" (another
//   rank's) holds it;
// - a rank that renders its piece several times (as many volumes): it is the slowest rank, the
//   imbalance shows it, and the display rank waits for it in the tiles' and colours' stages.
// Both compositing modes (APC, SEGMENTS).

#include "apcMPITest.h"
#include "apcTestCompositePass.h"
#include "apcTestPuzzles.h"
#include "apcTestScenes.h"
#include "apcTestTransferFunctions.h"
#include "vtkAPCCompositePass.h"
#include "vtkAPCPuzzleSource.h"
#include "vtkAPCVolumeMapper.h"

#include "vtkCallbackCommand.h"
#include "vtkMPIController.h"
#include "vtkNew.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <thread>
#include <vector>

namespace
{
using apctest::Check;

// What a stage may hold besides its collectives' wait and transfer: the rank's own packing
// and tile marking of a 96^2 frame (well under a millisecond unloaded; 50 ms seen at load ~23
// on 2 cores, where a rank is descheduled mid-stage), with room for that.
constexpr double kSlack = 0.15;
// The slow rank's lateness, seconds. A waiting rank sees less of it by its own work between
// its frame's start and its agreement (VTK's opaque render, the volumes' set-up: up to ~1 s
// on 3 ranks at load ~23 on 2 cores), hence the halves and quarters below.
constexpr double kSleep = 2.0;

const char* const kStages[] = { "agree", "depth", "tiles", "profile", "allreduce", "reduce",
  "exchange", "gather", "statistics", "auto", "ranks" };

std::map<std::string, double> TimingsOf(const vtkAPCCompositePass* pass)
{
  std::map<std::string, double> timings;
  const vtkAPCCompositePass::Timings t = pass->GetLastTimings();
  vtkAPCCompositePass::ForEachTiming(
    t, [&](const char* name, double value) { timings[name] = value; });
  return timings;
}

void Sleep(vtkObject*, unsigned long, void* clientData, void*)
{
  const double seconds = *static_cast<const double*>(clientData);
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
}

struct Frame
{
  std::map<std::string, double> Timings;
  std::vector<double> Render; // per rank, on the display rank
};

// Renders twice (the first frame converts the data) with this rank's piece shown `copies`
// times, sleeping `sleep` seconds before the second frame's agreement; the second frame's
// timings.
Frame RenderFrame(
  vtkMPIController* controller, vtkUnstructuredGrid* piece, int copies, double sleep, int mode)
{
  vtkNew<vtkRenderWindow> window;
  vtkNew<vtkRenderer> renderer;
  vtkNew<vtkAPCCompositePass> pass;
  apctest::SetUpCompositeWindow(window, renderer, 96, pass, controller);
  pass->SetCompositeMode(mode);
  const apctest::TransferFunction tf = apctest::BlueToRedTF(0.0, 1.0, 0.2);
  std::vector<vtkSmartPointer<vtkVolume>> volumes;
  for (int c = 0; c < copies; ++c)
  {
    vtkNew<vtkAPCVolumeMapper> mapper;
    mapper->SetInputData(piece);
    mapper->SetSampleDistance(0.01);
    auto volume = vtkSmartPointer<vtkVolume>::New();
    volume->SetMapper(mapper);
    volume->SetProperty(apctest::MakeVolumeProperty(tf));
    pass->AddVolume(volume);
    volumes.push_back(volume);
  }
  apctest::View view;
  view.Parallel = false;
  view.Position = { 2.5, 1.7, 3.1 };
  apctest::ApplyView(renderer, view);
  renderer->ResetCameraClippingRange(-1, 1, -1, 1, -1, 1);
  window->Render();
  vtkNew<vtkCallbackCommand> sleeper;
  sleeper->SetCallback(Sleep);
  sleeper->SetClientData(&sleep);
  if (sleep > 0)
  {
    pass->AddObserver(vtkAPCCompositePass::DelegateRenderedEvent, sleeper);
  }
  window->Render();
  return { TimingsOf(pass), pass->GetLastRankRenderSeconds() };
}

// Every stage's wait and transfer add up to the stage, within kSlack.
void CheckStagesAddUp(const Frame& frame, int rank, const std::string& what)
{
  const std::map<std::string, double>& t = frame.Timings;
  double wait = 0;
  double transfer = 0;
  for (const char* stage : kStages)
  {
    const double seconds = t.at(stage);
    const double parts =
      t.at(std::string(stage) + "_wait") + t.at(std::string(stage) + "_transfer");
    wait += t.at(std::string(stage) + "_wait");
    transfer += t.at(std::string(stage) + "_transfer");
    std::printf("%s: %-10s %.4f s = wait %.4f + transfer %.4f + own %.4f\n", what.c_str(), stage,
      seconds, t.at(std::string(stage) + "_wait"), t.at(std::string(stage) + "_transfer"),
      seconds - parts);
    Check(parts <= seconds + 1e-9 && seconds - parts <= kSlack, rank,
      what + ": " + stage + " = wait + transfer within the slack");
  }
  Check(std::abs(wait - t.at("wait")) < 1e-9 && std::abs(transfer - t.at("transfer")) < 1e-9, rank,
    what + ": wait and transfer are the sums over the stages");
  Check(frame.Render.size() ==
      static_cast<size_t>(vtkMultiProcessController::GetGlobalController()->GetNumberOfProcesses()),
    rank, what + ": a render time per rank");
}

void CheckMode(vtkMPIController* controller, int mode, const char* name)
{
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  const int slow = ranks - 1;
  auto piece = apctest::PuzzlePiece(vtkAPCPuzzleSource::SANDWICH, ranks, 4, 12, rank);

  // A late rank other than the display rank: the display rank waits for it in the agreement.
  // (The loaded rank's volumes below combine their transfer functions' checksums, so the pass
  // warns that they differ: expected.)
  {
    const Frame frame = RenderFrame(controller, piece, 1, rank == slow ? kSleep : 0.0, mode);
    if (rank == 0)
    {
      const std::string what = std::string(name) + " late rank";
      CheckStagesAddUp(frame, rank, what);
      const auto& t = frame.Timings;
      Check(t.at("agree_wait") >= 0.5 * kSleep && t.at("agree_transfer") < 0.25 * kSleep, rank,
        what + ": the lateness is the display rank's wait, not transfer");
    }
  }
  // The display rank late: it waits for nobody; the others wait for it.
  {
    const Frame frame = RenderFrame(controller, piece, 1, rank == 0 ? kSleep : 0.0, mode);
    if (rank == 0)
    {
      const std::string what = std::string(name) + " late display rank";
      CheckStagesAddUp(frame, rank, what);
      const auto& t = frame.Timings;
      std::printf("%s: agree_wait %.4f s, wait_max %.4f s\n", what.c_str(), t.at("agree_wait"),
        t.at("wait_max"));
      Check(t.at("agree_wait") < 0.25 * kSleep && t.at("wait_max") >= 0.5 * kSleep, rank,
        what + ": the others waited, the display rank did not");
    }
  }
  // A rank with several times the work: the slowest, and the display rank waits for its
  // renders.
  {
    const Frame frame = RenderFrame(controller, piece, rank == slow ? 6 : 1, 0.0, mode);
    if (rank == 0)
    {
      const std::string what = std::string(name) + " loaded rank";
      CheckStagesAddUp(frame, rank, what);
      const auto& t = frame.Timings;
      std::printf("%s: render per rank", what.c_str());
      for (const double seconds : frame.Render)
      {
        std::printf(" %.4f", seconds);
      }
      std::printf(" s; imbalance %.2f, slowest rank %.0f, display wait %.4f s\n",
        t.at("render_imbalance"), t.at("slowest_rank"), t.at("wait"));
      Check(t.at("slowest_rank") == slow && t.at("render_imbalance") > 1.3, rank,
        what + ": the loaded rank is the slowest");
      Check(t.at("wait") >= 0.5 * (t.at("render_max") - t.at("render")), rank,
        what + ": the display rank's wait holds the loaded rank's extra render");
    }
  }
}
}

int main(int argc, char* argv[])
{
  vtkSmartPointer<vtkMPIController> controller = apctest::StartMPI(&argc, &argv);
  if (controller->GetNumberOfProcesses() < 2)
  {
    std::fprintf(stderr, "FAILED: run on 2 or more ranks\n");
    controller->Finalize();
    return 1;
  }
  CheckMode(controller, vtkAPCCompositePass::APC, "APC");
  CheckMode(controller, vtkAPCCompositePass::SEGMENTS, "SEGMENTS");
  return apctest::FinishMPITest(controller);
}
