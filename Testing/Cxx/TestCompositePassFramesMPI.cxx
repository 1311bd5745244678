// Run under mpirun -np N. What a sequence of frames through one vtkAPCCompositePass keeps
// from frame to frame must not change its images: Stop Where Opaque left out after a frame
// without a pixel near its threshold, pass 1 bounded by the last frame's cut on several
// processes, the window without a kept float image; and the wire cut into bands or small
// messages carries the same bytes and gives the image of the whole frame.

#include "apcCompositePassRenders.h"
#include "apcMPITest.h"
#include "vtkAPCCompositePass.h"
#include "vtkAPCVolumeMapper.h"

#include "vtkMPIController.h"
#include "vtkNew.h"
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

  // Stop Where Opaque is left out of a frame after one without a pixel near its threshold:
  // the image is the stop's, bit for bit; a frame that turns opaque is marched again with it.
  {
    apctest::Scene faint = puzzle;
    faint.TF = apctest::BlueToRedTF(0.0, 1.0, 20.0); // absorbance along a ray below 0.2
    apctest::Scene opaque = puzzle;
    opaque.TF = apctest::BlueToRedTF(0.0, 1.0, 0.01); // most rays opaque
    vtkNew<vtkAPCCompositePass> pass;
    const std::vector<float> stopped =
      RenderDistributed(controller, faint, piece, bounds, 48, false, pass);
    const vtkAPCCompositePass::Timings first = pass->GetLastTimings();
    const std::vector<float> skipped =
      RenderDistributed(controller, faint, piece, bounds, 48, false, pass);
    const vtkAPCCompositePass::Timings second = pass->GetLastTimings();
    const std::vector<float> redone =
      RenderDistributed(controller, opaque, piece, bounds, 48, false, pass);
    const vtkAPCCompositePass::Timings third = pass->GetLastTimings();
    // A band redone with the stop has no bound (no previous cut, no probe): nor has this
    // reference, since a bound may move moments by float rounding (docs/sampler.md).
    vtkNew<vtkAPCCompositePass> fresh;
    fresh->SetOpaqueProbeStep(0);
    const std::vector<float> dense =
      RenderDistributed(controller, opaque, piece, bounds, 48, false, fresh);
    const vtkAPCCompositePass::Timings reference = fresh->GetLastTimings();
    vtkNew<vtkAPCCompositePass> off; // the stop off: what the frame would be without the redo
    const std::vector<float> unstopped = RenderDistributed(controller, opaque, piece, bounds, 48,
      false, off, true, vtkAPCVolumeMapper::RENORMALISED, nullptr, false);
    // The first frame has no last frame to ask: on several processes its probe finds no ray
    // near opaque and it skips the stop too; one process keeps it (and its tiles without it).
    Check(first.OpaqueStopSkipped == (ranks > 1 ? 1 : 0) && first.OpaqueStopRedone == 0 &&
        second.OpaqueStopSkipped == 1 && second.OpaqueStopRedone == 0,
      rank, "a faint frame after a faint one skips the stop");
    Check(third.OpaqueStopSkipped == 0 && third.OpaqueStopRedone == 1 &&
        reference.OpaqueStopRedone == 0,
      rank, "an opaque frame after a faint one is redone");
    if (rank == 0)
    {
      Check(!stopped.empty() && skipped == stopped, rank, "without the stop: the stop's image");
      Check(!dense.empty() && redone == dense, rank, "redone with the stop: the stop's image");
      Check(unstopped != dense, rank, "the stop changes the opaque frame's image");
    }
  }

  // Several processes bound pass 1 by the last frame's cut: the same frame again (nothing
  // left unresolved, no more samples) and a more transparent one after an opaque one (the
  // bound too shallow: its pixels are marched again) give a fresh pass's images.
  if (ranks > 1)
  {
    apctest::Scene opaque = puzzle;
    opaque.TF = apctest::BlueToRedTF(0.0, 1.0, 0.01);
    apctest::Scene lighter = puzzle;
    lighter.TF = apctest::BlueToRedTF(0.0, 1.0, 0.05);
    vtkNew<vtkAPCCompositePass> pass;
    RenderDistributed(controller, opaque, piece, bounds, 48, false, pass);
    const std::vector<float> again =
      RenderDistributed(controller, opaque, piece, bounds, 48, false, pass);
    const vtkAPCCompositePass::Timings predicted = pass->GetLastTimings();
    const std::vector<float> shallow =
      RenderDistributed(controller, lighter, piece, bounds, 48, false, pass);
    const vtkAPCCompositePass::Timings fallback = pass->GetLastTimings();
    vtkNew<vtkAPCCompositePass> fresh;
    const std::vector<float> opaqueFresh =
      RenderDistributed(controller, opaque, piece, bounds, 48, false, fresh);
    const vtkAPCCompositePass::Timings unbounded = fresh->GetLastTimings();
    vtkNew<vtkAPCCompositePass> freshLighter;
    const std::vector<float> lighterFresh =
      RenderDistributed(controller, lighter, piece, bounds, 48, false, freshLighter);
    Check(predicted.OpaquePredictedUnresolved == 0 && unbounded.OpaquePredictedUnresolved == 0 &&
        predicted.Pass1Samples <= unbounded.Pass1Samples,
      rank, "the same frame again: its cut predicted, no more samples");
    Check(fallback.OpaquePredictedUnresolved > 0 && fallback.OpaquePredictedRedone > 0, rank,
      "a lighter frame after an opaque one: pixels unresolved and marched again");
    if (rank == 0)
    {
      auto near = [](const std::vector<float>& a, const std::vector<float>& b)
      { return apctest::MaxAbsDifference(a, b) <= 1e-5; };
      Check(near(again, opaqueFresh), rank, "predicted cut: a fresh pass's image");
      Check(near(shallow, lighterFresh), rank, "too shallow a prediction: a fresh pass's image");
    }
  }

  // Without KeepLastImage the display process resolves into the colour sums' memory (and
  // keeps no float image): the window must show exactly what it shows with the image kept.
  {
    std::vector<unsigned char> kept;
    std::vector<unsigned char> lean;
    vtkNew<vtkAPCCompositePass> keeping;
    keeping->KeepLastImageOn();
    RenderDistributed(controller, puzzle, piece, bounds, 48, true, keeping, true,
      vtkAPCVolumeMapper::RENORMALISED, &kept);
    vtkNew<vtkAPCCompositePass> pass;
    const std::vector<float> none = RenderDistributed(controller, puzzle, piece, bounds, 48, true,
      pass, true, vtkAPCVolumeMapper::RENORMALISED, &lean);
    Check(none.empty(), rank, "no float image kept without KeepLastImage");
    if (rank == 0)
    {
      size_t shownPixels = 0;
      for (size_t v = 0; v < kept.size(); ++v)
      {
        shownPixels += kept[v] > 0 ? 1 : 0;
      }
      Check(shownPixels > 100, rank, "the kept frame shows the volume");
      Check(kept == lean, rank, "the lean frame shows the same window as the kept one");
    }
  }

  // A frame composited band by band (bands of 16 rows; only rank 0 asks, so the smallest
  // setting must be agreed) is the frame composited whole: the same samples, the same sums,
  // the same bytes on the wire; only the messages multiply. The moments' integer sums are
  // exact; MPI may add the float colour sums in another order for other message sizes
  // (measured on 4 ranks), which moves the image by float rounding alone.
  for (int resolve : { vtkAPCVolumeMapper::RENORMALISED, vtkAPCVolumeMapper::HYBRID })
  {
    vtkNew<vtkAPCCompositePass> whole;
    whole->SetMaxBandPixels(VTK_ID_MAX); // one band, however large the setting
    const std::vector<float> one =
      RenderDistributed(controller, puzzle, piece, bounds, 64, true, whole, true, resolve);
    vtkNew<vtkAPCCompositePass> banded;
    if (rank == 0)
    {
      banded->SetMaxBandPixels(1);
    }
    const std::vector<float> bands =
      RenderDistributed(controller, puzzle, piece, bounds, 64, true, banded, true, resolve);
    Check(!banded->GetLastFrameFailed(), rank, "bands: frame rendered");
    if (rank == 0)
    {
      const double maxDiff = apctest::MaxAbsDifference(bands, one);
      std::printf("bands (%s) on %d ranks: max |bands - whole| = %.3g, messages %lld vs %lld\n",
        resolve == vtkAPCVolumeMapper::HYBRID ? "Hybrid" : "Renormalised", ranks, maxDiff,
        static_cast<long long>(banded->GetLastMessagesSent()),
        static_cast<long long>(whole->GetLastMessagesSent()));
      Check(!one.empty() && maxDiff <= (ranks <= 2 ? 0.0 : 1e-6), rank,
        "bands: the image of the whole frame");
      Check(banded->GetLastBytesSent() == whole->GetLastBytesSent(), rank,
        "bands: the same bytes on the wire");
      Check(banded->GetLastCompositedPixels() == whole->GetLastCompositedPixels() &&
          banded->GetLastCoveredPixels() == whole->GetLastCoveredPixels(),
        rank, "bands: the same pixels");
      // Counted, not inferred from the messages: a first frame's opaque probe sends its
      // messages once a frame, not once a band.
      Check(
        ranks == 1 || (banded->GetLastTimings().Bands >= 3 && whole->GetLastTimings().Bands == 1),
        rank, "bands: a frame of at least three bands");
    }
  }

  // The wire in small messages (64 bytes; only rank 0 asks, so the smallest setting must be
  // agreed) is the wire in one message each: the same bytes, summed in the same exact integers
  // for the moments and profiles; MPI may add the float colour sums in another order for
  // other message sizes, which moves the image by float rounding alone. With the stop on and
  // off (the profile's messages) and in double (the double wire's).
  for (int variant = 0; variant < 3 && ranks > 1; ++variant)
  {
    vtkNew<vtkAPCCompositePass> whole;
    vtkNew<vtkAPCCompositePass> split;
    whole->SetCompositeInDouble(variant == 2);
    split->SetCompositeInDouble(variant == 2);
    if (rank == 0)
    {
      split->SetMaxMessageBytes(64);
    }
    const bool stop = variant != 1;
    const std::vector<float> one = RenderDistributed(controller, puzzle, piece, bounds, 64, true,
      whole, true, vtkAPCVolumeMapper::RENORMALISED, nullptr, stop);
    const std::vector<float> many = RenderDistributed(controller, puzzle, piece, bounds, 64, true,
      split, true, vtkAPCVolumeMapper::RENORMALISED, nullptr, stop);
    Check(!split->GetLastFrameFailed(), rank, "messages: frame rendered");
    if (rank == 0)
    {
      const double maxDiff = apctest::MaxAbsDifference(many, one);
      std::printf("messages (variant %d) on %d ranks: max |64-byte messages - one each| = %.3g, "
                  "messages %lld vs %lld\n",
        variant, ranks, maxDiff, static_cast<long long>(split->GetLastMessagesSent()),
        static_cast<long long>(whole->GetLastMessagesSent()));
      Check(!one.empty() && maxDiff <= 1e-6, rank, "messages: the image of one message each");
      Check(split->GetLastBytesSent() == whole->GetLastBytesSent(), rank,
        "messages: the same bytes on the wire");
      Check(split->GetLastMessagesSent() >= 10 * whole->GetLastMessagesSent(), rank,
        "messages: the wire cut into many messages");
    }
  }

  return apctest::FinishMPITest(controller);
}
