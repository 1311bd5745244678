// Run under mpirun -np N. A frame that some process cannot render, or that the processes set
// up differently (a misconfigured in-situ code: a rank without the scalar array or without any
// APC volume, viewports of different sizes, different compositing modes or wire precisions)
// is skipped on every process instead of leaving one waiting in a collective; settings one
// process alone changes that can be agreed (Stop Where Opaque) still render, and so does a
// 1x1 window. A process whose own work between two collectives throws (Stop Where Opaque's
// probe, a band's buffers, pass 1, pass 2, the exact segments, their packing or blend, the
// local exact image) makes every process skip the frame, and the next frame renders.

#include "apcCompositePassRenders.h"
#include "apcFrameEngine.h"
#include "apcMPITest.h"
#include "apcTestFailures.h"
#include "vtkAPCCompositePass.h"
#include "vtkAPCVolumeMapper.h"

#include "vtkMPIController.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkSmartPointer.h"
#include "vtkUnstructuredGrid.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

using apctest::Check;
using apctest::GlobalBounds;
using apctest::PuzzleShare;
using apctest::RenderDistributed;

int main(int argc, char* argv[])
{
  vtkSmartPointer<vtkMPIController> controller = apctest::StartMPI(&argc, &argv);
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  const apctest::Scene puzzle = apctest::PuzzleScene(ranks);
  // Each rank's share of the puzzle (no render changes it) and the bounds of all of them.
  const vtkSmartPointer<vtkUnstructuredGrid> piece = PuzzleShare(rank, ranks, ranks);
  double bounds[6];
  GlobalBounds(controller, piece, bounds);

  // A rank without the scalar array: every rank must skip the frame, none may hang.
  {
    auto stripped =
      PuzzleShare(rank, ranks, ranks); // a grid of its own: the shared one stays whole
    if (rank == ranks - 1)
    {
      stripped->GetPointData()->RemoveArray("Spheres");
    }
    vtkNew<vtkAPCCompositePass> pass;
    RenderDistributed(controller, puzzle, stripped, bounds, 32, false, pass);
    Check(pass->GetLastFrameFailed(), rank, "missing scalars: the frame is skipped everywhere");
  }

  // Stop Where Opaque's probe of a first frame throwing on one process (its memory ran out):
  // every process must give the frame up with an error instead of waiting in the probe's
  // allreduce, and the next first frame renders.
  if (ranks > 1)
  {
    if (rank == ranks - 1)
    {
      apc::FailForTesting(apc::FailurePoint::Probe, 1);
    }
    vtkNew<vtkAPCCompositePass> pass;
    pass->KeepLastImageOn();
    RenderDistributed(controller, puzzle, piece, bounds, 32, false, pass);
    Check(pass->GetLastFrameFailed(), rank, "a probe that throws: frame skipped everywhere");
    Check(
      pass->GetLastTimings().OpaquePrepassSamples == 0 || pass->GetLastTimings().Pass1Samples == 0,
      rank, "a probe that throws: no pass 1 after it");
    vtkNew<vtkAPCCompositePass> again;
    RenderDistributed(controller, puzzle, piece, bounds, 32, false, again);
    Check(!again->GetLastFrameFailed() && again->GetLastTimings().OpaquePrepassSamples > 0, rank,
      "after a probe that threw: the next first frame probes and renders");
  }

  // A process's own work between two collectives throwing on one process (its memory ran
  // out): pass 1, pass 2, a band's buffers (held before pass 1, for every later sum of the
  // band), the exact segments mode's segments, their packing for the exchange and an owner's
  // blend of its strip, and the local exact image. Every process gives the frame up with the
  // same error instead of waiting in the next collective (the tiles' allreduce after pass 1,
  // the colour sums' reduce after pass 2, the exchange, the gather) or aborting on the
  // exception, and the next frame of the same pass is the undisturbed image.
  if (ranks > 1)
  {
    struct Failing
    {
      int Mode;
      apc::FailurePoint Point;
      const char* What;
    };
    const Failing failings[] = {
      { vtkAPCCompositePass::APC, apc::FailurePoint::PassOne, "pass 1" },
      { vtkAPCCompositePass::APC, apc::FailurePoint::PassTwo, "pass 2" },
      { vtkAPCCompositePass::APC, apc::FailurePoint::BandBuffers, "a band's buffers" },
      { vtkAPCCompositePass::SEGMENTS, apc::FailurePoint::Segments, "the exact segments" },
      { vtkAPCCompositePass::SEGMENTS, apc::FailurePoint::SegmentPacking, "the segments' packing" },
      { vtkAPCCompositePass::SEGMENTS, apc::FailurePoint::SegmentBlend, "a strip's blend" },
      { vtkAPCCompositePass::LOCAL_EXACT, apc::FailurePoint::LocalExact, "the local exact image" },
    };
    for (const Failing& failing : failings)
    {
      vtkNew<vtkAPCCompositePass> undisturbed;
      undisturbed->SetCompositeMode(failing.Mode);
      const std::vector<float> reference =
        RenderDistributed(controller, puzzle, piece, bounds, 32, false, undisturbed);
      Check(!undisturbed->GetLastFrameFailed(), rank, failing.What);
      if (rank == ranks - 1)
      {
        apc::FailForTesting(failing.Point, 1);
      }
      vtkNew<vtkAPCCompositePass> pass;
      pass->SetCompositeMode(failing.Mode);
      const std::vector<float> failed =
        RenderDistributed(controller, puzzle, piece, bounds, 32, false, pass);
      Check(pass->GetLastFrameFailed(), rank, failing.What);
      Check(failed.empty(), rank, "a failed frame leaves no image");
      if (failing.Point == apc::FailurePoint::PassOne)
      {
        Check(pass->GetLastTimings().Pass1Samples == 0, rank, "no pass 1 counted after it");
      }
      const std::vector<float> next =
        RenderDistributed(controller, puzzle, piece, bounds, 32, false, pass);
      Check(!pass->GetLastFrameFailed(), rank, "after a failed stage: the next frame renders");
      if (rank == 0)
      {
        Check(!next.empty() && apctest::MaxAbsDifference(next, reference) == 0, rank,
          "after a failed stage: the next frame is the undisturbed image");
      }
    }
  }

  // A process without any APC volume (a misconfigured in-situ code): every process must skip
  // the frame instead of waiting for it in a collective.
  if (ranks > 1)
  {
    vtkNew<vtkAPCCompositePass> pass;
    RenderDistributed(controller, puzzle, piece, bounds, 32, false, pass, rank != ranks - 1);
    Check(pass->GetLastFrameFailed(), rank, "a process without a volume: frame skipped everywhere");
  }

  // Stop Where Opaque on one process only (a script that sets it on some ranks): the profile's
  // allreduce is agreed, so every process joins it and the frame ends everywhere.
  if (ranks > 1)
  {
    vtkNew<vtkAPCCompositePass> pass;
    RenderDistributed(controller, puzzle, piece, bounds, 32, false, pass, true,
      vtkAPCVolumeMapper::RENORMALISED, nullptr, rank == 0);
    Check(!pass->GetLastFrameFailed(), rank, "Stop Where Opaque on one process: frame rendered");
  }

  // Viewports of different sizes (a misconfigured in-situ code): the image buffers would
  // differ in length, so every process must skip the frame, in both modes.
  if (ranks > 1)
  {
    for (int mode : { vtkAPCCompositePass::APC, vtkAPCCompositePass::SEGMENTS })
    {
      vtkNew<vtkAPCCompositePass> pass;
      pass->SetCompositeMode(mode);
      RenderDistributed(controller, puzzle, piece, bounds, rank == 0 ? 32 : 40, false, pass);
      Check(pass->GetLastFrameFailed(), rank, "viewports differ: frame skipped everywhere");
    }
  }

  // Processes set to different compositing modes or wire precisions (a misconfigured in-situ
  // code) would run different collectives: every process must skip the frame.
  if (ranks > 1)
  {
    for (int odd : { 0, 1 })
    {
      vtkNew<vtkAPCCompositePass> pass;
      if (rank == ranks - 1)
      {
        if (odd == 0)
        {
          pass->SetCompositeMode(vtkAPCCompositePass::SEGMENTS);
        }
        else
        {
          pass->SetCompositeInDouble(true);
        }
      }
      RenderDistributed(controller, puzzle, piece, bounds, 32, false, pass);
      Check(pass->GetLastFrameFailed(), rank,
        odd == 0 ? "modes differ: frame skipped everywhere"
                 : "wire precisions differ: frame skipped everywhere");
    }
  }

  // A 1x1 window, in both modes.
  for (int mode : { vtkAPCCompositePass::APC, vtkAPCCompositePass::SEGMENTS })
  {
    vtkNew<vtkAPCCompositePass> pass;
    pass->SetCompositeMode(mode);
    RenderDistributed(controller, puzzle, piece, bounds, 1, false, pass);
    Check(!pass->GetLastFrameFailed(), rank, "1x1 window renders");
  }

  return apctest::FinishMPITest(controller);
}
