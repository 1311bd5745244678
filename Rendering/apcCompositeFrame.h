// SPDX-License-Identifier: BSD-3-Clause
// What vtkAPCCompositePass's compositing modes share for one frame: the processes (derived
// once from the controller), the agreed frame (viewport, screen rectangle, moment
// parameters, the visible volumes' engines), what the frame records (stage times, bytes,
// messages), and the display process's result. Internal to APC's rendering module.
#ifndef apcCompositeFrame_h
#define apcCompositeFrame_h

#include "apcCollectiveTimes.h"
#include "apcCoveredTiles.h"
#include "apcFrameSettings.h"
#include "apcMomentParameters.h"
#include "apcOpaquePrediction.h"
#include "apcRaySegments.h"
#include "apcScreenRect.h"
#include "apcStageClock.h"
#include "apcVolumeRayMarcher.h"

#include "vtkType.h"

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

class vtkFloatArray;
class vtkMultiProcessController;
class vtkRenderer;
class vtkVolume;

namespace apc
{
class FrameEngine;

// The processes rendering together, as this process sees them.
struct ProcessGroup
{
  vtkMultiProcessController* Controller = nullptr;
  bool Parallel = false; // more than one process: the collectives run
  int Processes = 1;
  int Rank = 0;
  int Display = 0; // the process that shows the image

  // Where Collective records its times (none if null).
  CollectiveTimes* Times = nullptr;

  ProcessGroup(
    vtkMultiProcessController* controller, int displayProcess, CollectiveTimes* times = nullptr);
  bool IsDisplay() const { return this->Rank == this->Display; }

  // Runs collective (a call every process makes, in the same order) after every process has
  // arrived (WaitForAll: no busy wait), and adds the two times to stage's in Times. Every
  // collective of a frame goes through here, so that its stage's time splits into the wait
  // for the slowest process, the transfer, and this process's own work around them.
  template <class F>
  void Collective(const char* stage, F&& collective) const
  {
    using Clock = std::chrono::steady_clock;
    const Clock::time_point start = Clock::now();
    if (this->Parallel)
    {
      WaitForAll(this->Controller);
    }
    const Clock::time_point arrived = Clock::now();
    collective();
    if (this->Times)
    {
      this->Times->Add(stage, std::chrono::duration<double>(arrived - start).count(),
        std::chrono::duration<double>(Clock::now() - arrived).count());
    }
  }
};

// One agreed frame: the same on every process except Engines (this process's volumes).
struct CompositeFrame
{
  vtkRenderer* Renderer = nullptr;
  // The image rendered and composited: the viewport (a tile of a large screenshot), or in an
  // interactive frame with image reduction r, ceil(viewport / r) pixels covering it.
  int Width = 0;
  int Height = 0;
  int ViewWidth = 0; // the viewport, where the image is blended
  int ViewHeight = 0;
  int X0 = 0;
  int Y0 = 0;
  bool Interactive = false;
  FrameSettings Settings;                  // as agreed (apcFrameAgreement.h)
  double Bounds[6] = { 0, 0, 0, 0, 0, 0 }; // all processes' cells
  double Cells = 0;                        // their number
  double CellVolume = 0; // their total volume (summed exactly: the same on every process)
  // The pixels whose rays can meet Bounds: the only ones rendered. Every per-pixel buffer of
  // the frame (depth, moments, colour sums, the result) holds Rect's pixels alone, row by
  // row (RectWidth() long), so memory follows the data's footprint, not the view.
  ScreenRect Rect;
  TileGrid Tiles; // Rect in tiles, in Rect's own pixel indices: what the depth share ships
  MomentParameters Moments;
  int Volumes = 0; // visible APC volumes, the most on any process
  // Some process's volume stops where opaque (agreed): every process joins the profile's
  // allreduce, a process without volumes too.
  bool StopsWhereOpaque = false;
  // Some process's volume weights the boundary's ends and has not matched its faces with the
  // other processes' since its data changed (agreed): every process joins ShareBoundaryFaces.
  bool ShareBoundary = false;
  // ... but no pixel of the last frame reached the stop's threshold (agreed): pass 1 marches
  // without the stop's bookkeeping, and a band where some pixel reaches it after all is
  // marched again with the stop, so the image is the one the stop gives.
  bool TryWithoutOpaqueStop = false;
  std::vector<FrameEngine*> Engines;
  // The frame's float image is kept (KeepLastImage, or the display process's image file): the
  // display process then keeps the moments and colour sums in the result; otherwise they go
  // as soon as the image is resolved.
  bool KeepFloatImages = false;

  // Viewport pixels per image pixel in each direction, and the factor on the sample distance
  // (1 and 1 for still frames).
  int Reduction() const { return this->Interactive ? this->Settings.InteractiveImageReduction : 1; }
  double SampleFactor() const
  {
    return this->Interactive ? this->Settings.InteractiveSampleDistanceFactor : 1.0;
  }
  size_t Pixels() const { return static_cast<size_t>(this->Width) * this->Height; }
  size_t RectPixels() const { return this->Rect.Pixels(); }
  int RectWidth() const { return this->Rect.Pixels() > 0 ? this->Rect.Width() : 0; }
  int RectHeight() const { return this->Rect.Pixels() > 0 ? this->Rect.Height() : 0; }
  double Aspect() const { return static_cast<double>(this->ViewWidth) / this->ViewHeight; }
};

// What the last frame cost, for GetLast*() and the verbose report.
struct FrameRecord
{
  StageClock Clock;
  CollectiveTimes Collectives; // the wait and transfer inside Clock's stages
  // Every process's render and wait seconds, by rank, on the display process (this process's
  // alone elsewhere): apcFrameTimings.h's GatherRankTimes.
  std::vector<double> RankRender;
  std::vector<double> RankWait;
  double BytesSent = 0;
  double ProfileBytes = 0; // of BytesSent, Stop Where Opaque's summaries and profiles
  vtkIdType MessagesSent = 0;
  vtkIdType Pixels = 0;           // pixels whose values travel (APC: the covered tiles')
  vtkIdType CoveredPixels = 0;    // pixels some process's volume covers (APC)
  vtkIdType OwnCoveredPixels = 0; // pixels this process's volumes cover (APC, SEGMENTS)
  // This process's APC samples: pass 1's, pass 2's, and of pass 2's those replayed from the
  // sample cache and those skipped as hidden.
  int64_t Pass1Samples = 0;
  int64_t Pass2Samples = 0;
  int64_t Pass2Replayed = 0;
  int64_t Pass2Hidden = 0;
  // APC: pixels whose global absorbance reached the opaque stop's threshold (the next frame
  // keeps the stop), bands rendered without the stop and bands marched again with it.
  vtkIdType OpaquePixels = 0;
  int OpaqueStopSkipped = 0;
  int OpaqueStopRedone = 0;
  // APC on one process with one volume: tiles pass 1 kept as marched without the stop.
  vtkIdType OpaqueUnstoppedTiles = 0;
  // APC on several processes: pixels whose cut pass 1's predicted bound left unknown, and the
  // marcher tiles marched again for them (docs/sampler.md).
  vtkIdType OpaquePredictedUnresolved = 0;
  vtkIdType OpaquePredictedRedone = 0;
  vtkIdType OpaquePrepassSamples = 0;
  int Bands = 0; // APC mode: bands of rows rendered
  SegmentStatistics Segments;
  bool Failed = false;
  std::string Problem; // why a frame failed after the agreement (Failed), for the error message
};

// The display process's final image of the volumes (the frame's Rect, premultiplied RGBA)
// and, in APC mode with KeepFloatImages, the global moments and colour sums it was resolved
// from.
struct FrameResult
{
  std::vector<float> RGBA;
  std::vector<double> Moments;
  std::vector<double> ColourSums;
};

// APC mode's band-sized buffers, which the pass keeps from frame to frame and which only ever
// grow. Memory allocated afresh is paged in afresh on first touch: 3.5 ms of CPU per MB on
// the virtual machine measured (a 32 MB buffer 0.11 s), and a 1024^2 frame on 2 processes
// touched ~280 MB of new buffers in its exchanges, more than their transfer cost. Kept, they
// cost a memset. (Each process's peak memory is unchanged; it is no longer returned between
// frames.)
struct MomentBuffers
{
  std::vector<double> Moments; // the band's moments, then the global ones
  // The band's colour sums (double), and before pass 2 one volume's opaque profile (uint16,
  // VolumeRayMarcher::LendOpaqueProfileMemory: the same 32 bytes a pixel, idle until then).
  std::vector<unsigned char> ColourSums;
  // The wire's two buffers, send and received, shared by every sum of the band in turn: the
  // opaque profiles' bins (uint16, Stop Where Opaque on several processes), the moments in
  // fixed point (int32), then the colour sums (float), or both in double
  // (CompositeInDouble). Each sum makes its values in them (bytes: any type may live there), so
  // a first frame pages in the largest sum's, not each one's (at 1024^2 the colour sums' 32 MB
  // a process fit in the moments' 40 MB).
  std::vector<unsigned char> WireSend;
  std::vector<unsigned char> WireReceived;
  std::vector<unsigned char> Exponents; // each pixel's exponent byte, and the agreed one
  std::vector<unsigned char> Agreed;
  std::vector<uint16_t> Profile;     // several volumes: the opaque profiles summed, over the band
  std::vector<uint16_t> SummarySend; // without a bound: each covered pixel's OpaqueSummary
  std::vector<uint16_t> SummarySum;
  std::vector<uint16_t> ProfileLocal; // several volumes' profiles summed
  // The opaque cut agreed over the last frame's rectangle and the one this frame agrees
  // (several processes only), pass 1's bound predicted from it, and the pixels it leaves
  // unresolved (apcOpaquePrediction.h).
  OpaqueCutMemory PreviousCuts;
  OpaqueCutMemory Cuts;
  std::vector<uint8_t> Bound;
  std::vector<uint8_t> Unresolved;
};

// Rect's rows cut into bands of at most maxPixels pixels (at least one marcher tile row each),
// bottom to top: the same on every process for the same rectangle.
std::vector<RowBand> MomentBands(int width, int height, size_t maxPixels);

// Step 2 of vtkAPCCompositePass's frame: the display process's (composited) depth over the
// screen rectangle, where every ray must stop, on every process: only the tiles where it has
// opaque geometry travel. If no delegate composited depth (DisplayDepthComposited off), the
// nearest of every process's own depth. delegateDepth: the delegate's, or null.
std::vector<float> ShareDepth(const ProcessGroup& group, const CompositeFrame& frame,
  vtkFloatArray* delegateDepth, FrameRecord& record);

// Step 3: every engine of the frame (this process's volumes, in order) prepares its rays over
// the agreed image, stopping at depth (ShareDepth's). A sample distance capped to the limit of
// samples per ray is the same on every process: the display process says it, on the mapper.
// The same agreed stage reserves result's images for the rectangle (the float images only on
// the display process, if kept), so that no mode allocates them between two collectives.
// False if some process's set-up failed (agreed: record.Failed and record.Problem set).
bool PrepareEngines(const ProcessGroup& group, const CompositeFrame& frame,
  const std::vector<vtkVolume*>& volumes, const std::vector<float>& depth, FrameRecord& record,
  FrameResult& result);

// The modes: each runs the frame's stages and collectives on every process and fills
// result on the display process.
// APC mode renders and composites a rectangle of more than Settings.MaxBandPixels pixels band by
// band (see MomentBands), so that its buffers are a band's size, not the rectangle's.
void RunMomentCompositing(const ProcessGroup& group, const CompositeFrame& frame,
  FrameRecord& record, FrameResult& result, MomentBuffers& buffers);
// APC mode with Stop Where Opaque (apcOpaqueCompositing.cxx). On several processes, the
// band's predicted last bins into buffers.Bound, from the last frame's agreed cut; false if
// there is none (another image, the first frame).
bool PredictOpaqueBand(
  const CompositeFrame& frame, const RowBand& band, size_t pixels, MomentBuffers& buffers);
// On several processes, before the bands of a frame that has no previous cut for its image
// (buffers.Cuts.Image): every process probes the rays of every OpaqueProbeStep-th pixel with
// its own stop, their profiles are summed, and their agreed cuts spread over the rectangle
// into buffers.PreviousCuts, for PredictOpaqueBand. Every process makes the same calls.
// Bounded: some probe ray turned opaque and buffers.PreviousCuts holds the spread cuts.
// NoneOpaque: no probe ray did (nothing is bounded). Failed: some process's probe threw (agreed:
// every process returns Failed, record.Failed and record.Problem set), before any profile was
// summed.
enum class ProbeResult
{
  Bounded,
  NoneOpaque,
  Failed
};
ProbeResult ProbeOpaqueCuts(const ProcessGroup& group, const CompositeFrame& frame,
  MomentBuffers& buffers, FrameRecord& record);
// After pass 1 of band (pixels of it): every volume's opaque profile summed over the covered
// tiles of every process, then each volume's own moments (own[e], or moments with one volume)
// cut where the sum is opaque and summed into moments. bounded: pass 1 took buffers.Bound,
// whose unresolved pixels are marched again first (their tiles join covered). The agreed cut
// goes to buffers.Cuts. Every process makes the same calls. False if some process's own work
// in it (the tiles marched again, the cut applied) failed: agreed, record.Failed set, and every
// process leaves the band before its next collective.
bool CutWhereOpaque(const ProcessGroup& group, const CompositeFrame& frame, const RowBand& band,
  const TileGrid& tiles, std::vector<unsigned char>& covered, std::vector<std::vector<double>>& own,
  double* moments, size_t pixels, bool bounded, MomentBuffers& buffers, FrameRecord& record);
void RunSegmentCompositing(
  const ProcessGroup& group, const CompositeFrame& frame, FrameRecord& record, FrameResult& result);

} // namespace apc

#endif
