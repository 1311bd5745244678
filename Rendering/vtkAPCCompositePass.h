// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkAPCCompositePass
 * @brief   Approximate Puzzlepiece Compositing: distributed volume rendering of
 *          unstructured pieces that stay on their process, by summing moment images.
 *
 * Replaces sort-last compositing for the volumes added with AddVolume() (whose mappers must
 * be vtkAPCVolumeMapper; the volumes must NOT also be props of the renderer). Every process
 * runs Render() in lockstep; per frame it does, whatever the partition:
 *
 * 1. the delegate pass, if any (the opaque scene; in ParaView, IceT's composited result);
 * 2. one small allreduce: the union of all processes' data bounds (depth warp, sample
 *    spacing, screen rectangle) and a failure flag, so that a process whose input is
 *    unusable makes every process skip the frame instead of waiting in a collective;
 * 3. a broadcast of the display process's depth where it has opaque geometry, so that
 *    every process stops its rays at the composited opaque geometry (or, when no delegate
 *    composited depth, see DisplayDepthComposited, a MIN allreduce of all processes' own);
 * 4. pass 1 on the local cells: the moment image; a small allreduce (bytewise max) of which
 *    8x8 tiles each process covers, then the covered tiles' moments are summed onto every
 *    process (allreduce);
 * 5. pass 2 with the global moments: the colour-sum image; one reduce (sum) of the same
 *    tiles to the display process;
 * 6. on the display process: resolve, and blend over the opaque image in the render window.
 *
 * A screen rectangle of more than MaxBandPixels pixels runs steps 4-6 band by band (rows of
 * the rectangle), so that the per-pixel buffers are one band's size whatever the view.
 *
 * Only the tiles of the data's screen rectangle that some process covers are sent (depth:
 * the tiles where the display process has opaque geometry). Processes sum their own samples
 * in double. Unless CompositeInDouble is on, the moments travel as 32-bit fixed point with a
 * per-pixel scale the processes agree on first (one byte per pixel, MAX allreduce): integer
 * sums are exact, so every process gets the same global moments whatever order MPI adds them
 * in, with more bits than float sums up to ~64 processes; the colour sums travel in float
 * (the paper's format). That is 1 + 20 + 16 bytes per covered pixel at 4 moments (the paper:
 * 36), and the distributed image equals the one-process MBOIT image to ~1e-6 (up to 6e-5 on
 * slab-like data, whose moment solve amplifies any rounding; CompositeInDouble: ~1e-7).
 *
 * Volumes share one moment image, so several APC volumes are composited order-independently
 * together; they must then use the same NumberOfMoments, and the first volume's
 * Overestimation, MomentBias and ResolveMode apply to all.
 *
 * CompositeMode SEGMENTS replaces steps 4-6 by the paper's exact sort-last baseline, for
 * comparison: every process renders its ray segments, sends them directly to the process
 * owning their strip of the screen rectangle (first every process's count per owner, in one
 * allgather, then one message per pair of processes that has segments to exchange, pairs
 * scheduled in rounds so that blocking sends cannot deadlock), each owner sorts and blends
 * its pixels' segments front to back, and a gather brings the strips to the display
 * process, which blends them over the opaque image. Segments travel as 24 bytes (pixel,
 * first lattice index, float premultiplied colour and transmittance). The exact modes blend one
 * volume's samples at a time and cannot interleave overlapping volumes: a frame with two or more
 * visible APC volumes runs APC instead (one warning while it lasts), and AUTO chooses APC.
 *
 * Works with any vtkMultiProcessController (vtkMPIController for real runs; none or a
 * single process renders locally). In ParaView it is installed as the view's image
 * processing pass, after IceT.
 *
 * @par Reference:
 * X. Huang, W. Usher, et al., "Approximate Puzzlepiece Compositing", arXiv 2501.12581.
 */
#ifndef vtkAPCCompositePass_h
#define vtkAPCCompositePass_h

#include "APCRenderingModule.h" // for export macro
#include "vtkCommand.h"         // for vtkCommand::UserEvent
#include "vtkImageProcessingPass.h"

#include <memory> // for std::unique_ptr
#include <vector> // for GetLastRankRenderSeconds

namespace apc
{
struct CompositeFrame;
struct FrameResult;
struct ProcessGroup;
}
class vtkFloatArray;
class vtkImageData;
class vtkMultiProcessController;
class vtkRenderer;
class vtkVolume;

class APCRENDERING_EXPORT vtkAPCCompositePass : public vtkImageProcessingPass
{
public:
  static vtkAPCCompositePass* New();
  vtkTypeMacro(vtkAPCCompositePass, vtkImageProcessingPass);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void Render(const vtkRenderState* s) override;

  ///@{
  /**
   * The processes that render together. Default: the global controller at construction.
   */
  void SetController(vtkMultiProcessController* controller);
  vtkGetObjectMacro(Controller, vtkMultiProcessController);
  ///@}

  ///@{
  /**
   * The volumes this pass renders (vtkAPCVolumeMapper volumes, not props of the renderer).
   */
  void AddVolume(vtkVolume* volume);
  void RemoveVolume(vtkVolume* volume);
  void RemoveAllVolumes();
  int GetNumberOfVolumes() const;
  ///@}

  ///@{
  /**
   * The process that shows the image (IceT's root). Default 0.
   */
  void SetDisplayProcess(int process);
  vtkGetMacro(DisplayProcess, int);
  ///@}

  /**
   * Invoked on every process right after the delegate pass has rendered (call data: the
   * vtkRenderer), before the pass reads any depth: where a caller can hand over the
   * delegate's own depth (SetDelegateDepth) or finish what the delegate left in the
   * framebuffer (apcPassInstaller does both for IceT). The offset spells "APC", clear of the
   * small offsets other code adds to UserEvent.
   */
  static constexpr unsigned long DelegateRenderedEvent = vtkCommand::UserEvent + 0x41504300;

  /**
   * For the current frame only (call it from a DelegateRenderedEvent observer): the depth the
   * delegate composited, one float per pixel of the renderer's viewport, row by row from the
   * bottom, read on the display process instead of its framebuffer's depth (which may have
   * gone through a conversion on its way back). Ignored elsewhere; forgotten after the frame.
   */
  void SetDelegateDepth(vtkFloatArray* depth);

  ///@{
  /**
   * Whether the display process's depth buffer holds every process's opaque geometry when
   * the delegate pass is done (IceT's z-composite, pasted back; default on). Off when each
   * process's depth buffer holds only its own (IceT's ordered compositing blends colours
   * alone, a delegate without compositing): the pass then takes the nearest of all
   * processes' depths itself (one MIN allreduce of the screen rectangle). Must be the same
   * on every process; apcPassInstaller sets it before every ParaView render.
   */
  void SetDisplayDepthComposited(bool composited);
  bool GetDisplayDepthComposited() const;
  vtkBooleanMacro(DisplayDepthComposited, bool);
  ///@}

  ///@{
  /**
   * Stop Where Opaque on several processes: the first frame of a view (no previous frame's
   * cut to bound pass 1 with) first marches the rays of every OpaqueProbeStep-th pixel in each
   * direction with each process's own stop, agrees their cut and bounds pass 1 with it as a
   * later frame does with the previous cut (docs/sampler.md). The image is the same either
   * way; 0 switches the probe off. Default 8 (1/64 of the rays). Must be the same on
   * every process.
   */
  void SetOpaqueProbeStep(int step);
  int GetOpaqueProbeStep() const;
  ///@}

  ///@{
  /**
   * Ship the moment and colour sums in double instead of the compact wire (default off:
   * fixed-point moments and float colour sums, half the bytes; each process still sums its
   * own samples in double).
   */
  void SetCompositeInDouble(bool inDouble);
  bool GetCompositeInDouble() const;
  vtkBooleanMacro(CompositeInDouble, bool);
  ///@}

  ///@{
  /**
   * APC mode renders and composites a screen rectangle of more pixels than this band by band:
   * pass 1, the moments' allreduce, pass 2 and the colour sums' reduce of one band of rows,
   * then the next (default 2,097,152 >= 1448^2; at least one 16-pixel row of tiles). The
   * moment and colour buffers (72 bytes per pixel at 4 moments, ~150 MB by default) then hold
   * one band, and the sample cache one band's samples, whatever the view size; each band
   * costs every process a wait for the slowest one. The image does not depend on it (up to
   * the order in which MPI adds float colour sums). The smallest setting of any process
   * applies.
   */
  void SetMaxBandPixels(vtkIdType pixels);
  vtkIdType GetMaxBandPixels() const;
  ///@}

  ///@{
  /**
   * APC mode sends its wire (the opaque profiles, the moments, the colour sums) in MPI
   * messages of at most this many bytes (default 8 MiB, at least 64). Open MPI's allreduce of
   * a message of 32 MiB or more allocates a temporary of its size on every call, which the
   * system pages in afresh each time: on the machine measured that cost 0.3-1 s per 32 MiB,
   * against 0.06 s in 1-16 MiB messages. The image does not depend on it (up to the order in
   * which MPI adds float colour sums). The smallest setting of any process applies.
   */
  void SetMaxMessageBytes(vtkIdType bytes);
  vtkIdType GetMaxMessageBytes() const;
  ///@}

  enum CompositeModeType
  {
    /// Approximate Puzzlepiece Compositing: moment allreduce and colour reduce (default).
    APC = 0,
    /// The exact sort-last baseline: each process's ray segments (runs of consecutive lattice
    /// samples in its cells, pre-blended) are sent directly to the owner of their pixel
    /// (the data's screen rectangle cut into one strip of rows per process), sorted by depth
    /// and blended there, and the strips are gathered on the display process. Equal to the
    /// one-process EXACT image to rounding on any partition; bytes grow with the number of
    /// segments per pixel.
    SEGMENTS = 1,
    /// The volumes' EXACT mode without compositing: each process blends only its own cells
    /// (a local reference; in parallel the display process shows its own piece only).
    LOCAL_EXACT = 2,
    /// Per frame, SEGMENTS where it moves fewer bytes than APC (few segments per pixel: the
    /// exact picture for free) and APC where segments would cost more, estimated from the
    /// previous frames' measured coverage and segment counts, the same on every process
    /// (apcAutoMode.h). The first frame composites segments. GetLastCompositeMode() says
    /// which ran.
    AUTO = 3
  };

  ///@{
  /**
   * How the processes' volumes are combined: APC (default), SEGMENTS, LOCAL_EXACT or AUTO.
   */
  void SetCompositeMode(int mode);
  int GetCompositeMode() const;
  ///@}

  ///@{
  /**
   * Interactive frames (while the camera moves: the render window's DesiredUpdateRate is at
   * least 1, as ParaView's interactive renders (5) and VTK's interactor (15) set it; still
   * renders set it far below 1) are rendered at reduced cost: the sample distance times
   * InteractiveSampleDistanceFactor, and an image InteractiveImageReduction times smaller in
   * each direction, stretched over the viewport. 1 switches either off. Every process takes
   * the same decision: the flag and the factors are part of the frame's agreement (interactive
   * if any process's window is; the largest factors). Still frames are never reduced.
   */
  void SetInteractiveSampleDistanceFactor(double factor);
  double GetInteractiveSampleDistanceFactor() const;
  void SetInteractiveImageReduction(int reduction);
  int GetInteractiveImageReduction() const;
  ///@}

  /**
   * The image reduction the last frame ran with: 1 for a still frame (or interactive with
   * both settings off), InteractiveImageReduction for an interactive one; 0 if skipped.
   */
  int GetLastImageReduction() const;

  /**
   * Whether the last frame was an interactive one (see InteractiveImageReduction).
   */
  bool GetLastFrameInteractive() const;

  /**
   * The mode the last frame ran: APC, SEGMENTS or LOCAL_EXACT (AUTO's choice); -1 before
   * the first frame or if it was skipped.
   */
  int GetLastCompositeMode() const;

  ///@{
  /**
   * 0: silent; 1: the display process prints the stage timings and bytes of every frame
   * (every mode).
   */
  void SetVerbosity(int verbosity);
  vtkGetMacro(Verbosity, int);
  ///@}

  ///@{
  /**
   * The last frame, per process: wall-clock seconds of a stage (null for the total), bytes
   * this process sent into the collectives and point-to-point messages, the number of those
   * (a collective this process contributes data to counts as one, as does each non-empty
   * direct send), and the screen pixels composited (APC: the pixels of the covered tiles;
   * SEGMENTS: the screen rectangle). Stages: "agree", "depth", then for APC "pass1",
   * "tiles" (agreeing on the covered tiles: where a process waits for the slowest pass 1),
   * "allreduce", "pass2", "reduce", "resolve"; for SEGMENTS "segments" (rendering
   * them), "exchange" (counts and direct send to the strip owners), "blend_segments" (sort
   * and blend of the own strip), "gather" (strips to the display process), "statistics"
   * (the segment counts below; not counted in bytes or messages); for LOCAL_EXACT "exact";
   * "auto" (AUTO's covered pixels), "ranks" (every process's render and wait times to the
   * display process) and "blend" (into the window, display process).
   */
  double GetLastStageSeconds(const char* stage) const;
  double GetLastBytesSent() const;
  vtkIdType GetLastMessagesSent() const;
  vtkIdType GetLastCompositedPixels() const;
  ///@}

  /**
   * APC mode, the last frame: the pixels where some process's volume has absorbance (the
   * global moment b0 > 0), the same on every process; for bytes per covered pixel.
   */
  vtkIdType GetLastCoveredPixels() const;

  ///@{
  /**
   * SEGMENTS mode, the last frame, the same on every process: segments over all processes,
   * the pixels that have at least one, and the average and maximum number of segments per
   * such pixel (what every strip owner received, sorted and blended). Zero in other modes.
   */
  vtkIdType GetLastSegmentCount() const;
  vtkIdType GetLastNonEmptyPixels() const;
  double GetLastAverageSegmentsPerPixel() const;
  vtkIdType GetLastMaxSegmentsPerPixel() const;
  ///@}

  /**
   * The last frame's render seconds of every process (pass 1 + pass 2, or segments + their
   * sort and blend, or the local exact image), by rank, on the display process; elsewhere
   * this process's alone. Empty if the frame was skipped.
   */
  std::vector<double> GetLastRankRenderSeconds() const;

  /**
   * Everything the GetLast*() methods above say about the last frame on this process, as named
   * fields: seconds of each stage (zero for the stages the mode did not run) and of the whole
   * frame, the counts, the mode that ran and the image reduction. What vtkAPCVolumeRepresentation
   * publishes to ParaView, by these names (ForEachTiming), and apcparaview.last_timings()
   * returns as a dict. Counts are doubles so that the fields travel as one array.
   *
   * Every collective of a stage starts with the processes meeting in a barrier: "<stage>_wait"
   * is this process's time there (waiting for the last process to arrive: the slowest
   * render), "<stage>_transfer" the collectives' time after it (moving and summing the bytes).
   * The rest of the stage is this process's own work (packing, marking tiles). "wait" and
   * "transfer" sum them over stages. "render" is this process's render seconds (see
   * GetLastRankRenderSeconds); on the display process "render_mean", "render_max",
   * "render_imbalance" (max / mean), "slowest_rank" and "wait_max" (the longest wait of any
   * process in the frame) are over all processes.
   */
  struct Timings
  {
    double Agree = 0;
    double Depth = 0;
    // Sample End Weights = Boundary on several processes, after a data change: matching the
    // piece's faces and exchanging those on its boundary (apcBoundaryExchange.h).
    double Boundary = 0;
    double Pass1 = 0;
    double Tiles = 0;   // where a process waits for the slowest pass 1
    double Profile = 0; // Stop Where Opaque: the opaque profiles' allreduce
    double Cut = 0;     // and the cut applied to pass 1
    double Allreduce = 0;
    double Pass2 = 0;
    double Reduce = 0;
    double Resolve = 0;
    double Segments = 0;
    double Exchange = 0;
    double BlendSegments = 0;
    double Gather = 0;
    double Statistics = 0;
    double Exact = 0;
    double Auto = 0;
    double Ranks = 0;
    double Blend = 0;
    double Total = 0; // all the stages above
    double BytesSent = 0;
    double MessagesSent = 0;
    double CompositedPixels = 0;
    double CoveredPixels = 0;
    double Mode = -1; // GetLastCompositeMode: what ran (AUTO's choice); -1 if skipped
    double ImageReduction = 0;
    double AverageSegmentsPerPixel = 0;
    double MaxSegmentsPerPixel = 0;
    // This process's APC samples in pass 1, and the shares of pass 2's samples replayed from
    // the sample cache and skipped as hidden (0 to 1): with "pass1" and "pass2", the cost of
    // a sample.
    double Pass1Samples = 0;
    double Pass2CachedShare = 0;
    double Pass2HiddenShare = 0;
    // Pass 2's samples (replayed or marched): pass 1's samples with an opacity, less the cut.
    double Pass2Samples = 0;
    // Bands of rows rendered without Stop Where Opaque (it was on, but the last frame had no
    // pixel near its threshold), and bands marched again with it (tried without, a pixel
    // reached the threshold after all).
    double OpaqueStopSkipped = 0;
    double OpaqueStopRedone = 0;
    // On one process with one volume: marcher tiles pass 1 kept as marched without the stop
    // (no ray of theirs came near its threshold).
    double OpaqueUnstoppedTiles = 0;
    // Stop Where Opaque: the bytes of the profiles' summaries and sums this process sent
    // (part of BytesSent).
    double ProfileBytes = 0;
    // On several processes, pass 1 also stops each ray at a cut predicted from the last
    // frame's: the pixels whose cut that left unknown, and the 16x16 tiles marched again
    // without it for them.
    double OpaquePredictedUnresolved = 0;
    double OpaquePredictedRedone = 0;
    // A first frame's bound on several processes (SetOpaqueProbeStep): the probe's seconds
    // (its march and its profiles' allreduce) and this process's samples in it.
    double OpaquePrepass = 0;
    double OpaquePrepassSamples = 0;
    // APC mode: the bands of rows the frame was rendered in (one process takes small ones).
    double Bands = 0;
    // Each stage's wait for the last process and transfer after it (see above).
    double AgreeWait = 0, AgreeTransfer = 0;
    double DepthWait = 0, DepthTransfer = 0;
    double BoundaryWait = 0, BoundaryTransfer = 0;
    double TilesWait = 0, TilesTransfer = 0;
    double ProfileWait = 0, ProfileTransfer = 0;
    double AllreduceWait = 0, AllreduceTransfer = 0;
    double ReduceWait = 0, ReduceTransfer = 0;
    double ExchangeWait = 0, ExchangeTransfer = 0;
    double GatherWait = 0, GatherTransfer = 0;
    double StatisticsWait = 0, StatisticsTransfer = 0;
    double AutoWait = 0, AutoTransfer = 0;
    double RanksWait = 0, RanksTransfer = 0;
    double Wait = 0;
    double Transfer = 0;
    double Render = 0;
    double RenderMean = 0;
    double RenderMax = 0;
    double RenderImbalance = 0;
    double SlowestRank = 0;
    double WaitMax = 0;
  };
  Timings GetLastTimings() const;

  /**
   * Calls f(name, field) for every field of timings, in declaration order; the names of the
   * stages are GetLastStageSeconds' ("blend_segments"), the others in the same style
   * ("bytes_sent", "image_reduction", ...).
   */
  template <class T, class F>
  static void ForEachTiming(T& timings, F&& f) // T: Timings or const Timings
  {
    f("agree", timings.Agree);
    f("depth", timings.Depth);
    f("boundary", timings.Boundary);
    f("pass1", timings.Pass1);
    f("tiles", timings.Tiles);
    f("profile", timings.Profile);
    f("cut", timings.Cut);
    f("allreduce", timings.Allreduce);
    f("pass2", timings.Pass2);
    f("reduce", timings.Reduce);
    f("resolve", timings.Resolve);
    f("segments", timings.Segments);
    f("exchange", timings.Exchange);
    f("blend_segments", timings.BlendSegments);
    f("gather", timings.Gather);
    f("statistics", timings.Statistics);
    f("exact", timings.Exact);
    f("auto", timings.Auto);
    f("ranks", timings.Ranks);
    f("blend", timings.Blend);
    f("total", timings.Total);
    f("bytes_sent", timings.BytesSent);
    f("messages_sent", timings.MessagesSent);
    f("composited_pixels", timings.CompositedPixels);
    f("covered_pixels", timings.CoveredPixels);
    f("mode", timings.Mode);
    f("image_reduction", timings.ImageReduction);
    f("average_segments_per_pixel", timings.AverageSegmentsPerPixel);
    f("max_segments_per_pixel", timings.MaxSegmentsPerPixel);
    f("pass1_samples", timings.Pass1Samples);
    f("pass2_cached_share", timings.Pass2CachedShare);
    f("pass2_hidden_share", timings.Pass2HiddenShare);
    f("pass2_samples", timings.Pass2Samples);
    f("opaque_stop_skipped", timings.OpaqueStopSkipped);
    f("opaque_stop_redone", timings.OpaqueStopRedone);
    f("opaque_unstopped_tiles", timings.OpaqueUnstoppedTiles);
    f("profile_bytes", timings.ProfileBytes);
    f("opaque_predicted_unresolved", timings.OpaquePredictedUnresolved);
    f("opaque_predicted_redone", timings.OpaquePredictedRedone);
    f("opaque_prepass", timings.OpaquePrepass);
    f("opaque_prepass_samples", timings.OpaquePrepassSamples);
    f("bands", timings.Bands);
    f("agree_wait", timings.AgreeWait);
    f("agree_transfer", timings.AgreeTransfer);
    f("depth_wait", timings.DepthWait);
    f("depth_transfer", timings.DepthTransfer);
    f("boundary_wait", timings.BoundaryWait);
    f("boundary_transfer", timings.BoundaryTransfer);
    f("tiles_wait", timings.TilesWait);
    f("tiles_transfer", timings.TilesTransfer);
    f("profile_wait", timings.ProfileWait);
    f("profile_transfer", timings.ProfileTransfer);
    f("allreduce_wait", timings.AllreduceWait);
    f("allreduce_transfer", timings.AllreduceTransfer);
    f("reduce_wait", timings.ReduceWait);
    f("reduce_transfer", timings.ReduceTransfer);
    f("exchange_wait", timings.ExchangeWait);
    f("exchange_transfer", timings.ExchangeTransfer);
    f("gather_wait", timings.GatherWait);
    f("gather_transfer", timings.GatherTransfer);
    f("statistics_wait", timings.StatisticsWait);
    f("statistics_transfer", timings.StatisticsTransfer);
    f("auto_wait", timings.AutoWait);
    f("auto_transfer", timings.AutoTransfer);
    f("ranks_wait", timings.RanksWait);
    f("ranks_transfer", timings.RanksTransfer);
    f("wait", timings.Wait);
    f("transfer", timings.Transfer);
    f("render", timings.Render);
    f("render_mean", timings.RenderMean);
    f("render_max", timings.RenderMax);
    f("render_imbalance", timings.RenderImbalance);
    f("slowest_rank", timings.SlowestRank);
    f("wait_max", timings.WaitMax);
  }
  static constexpr int NumberOfTimings = 74;

  ///@{
  /**
   * If set, the display process writes every frame's final float image (premultiplied RGBA
   * of the volumes and the global moments) to this file: OpenEXR for ".exr", VTK XML image
   * data (binary, readable everywhere) for ".vti".
   */
  vtkSetFilePathMacro(ImageFileName);
  vtkGetFilePathMacro(ImageFileName);
  ///@}

  /**
   * Whether the last frame was skipped because a process could not render (message on the
   * display process).
   */
  bool GetLastFrameFailed() const;

  ///@{
  /**
   * Keep each frame's final float image for GetLastImage(). Off by default: the image holds
   * ~72 bytes per view pixel (RGBA, moments, colour sums) on the display process, which a
   * frame does not otherwise need once blended (an ImageFileName is written either way).
   */
  vtkSetMacro(KeepLastImage, bool);
  vtkGetMacro(KeepLastImage, bool);
  vtkBooleanMacro(KeepLastImage, bool);
  ///@}

  /**
   * With KeepLastImage, the last final float image on the display process (premultiplied
   * RGBA of the volumes, before blending, zero outside the data's screen rectangle) and the
   * global moments and colour sums, as point arrays "RGBA", "Moments" and "ColourSums";
   * empty otherwise.
   */
  vtkImageData* GetLastImage();

  /**
   * The pixels [rectangle[0], rectangle[2]) x [rectangle[1], rectangle[3]) of a width x height
   * viewport whose rays can meet the box bounds (its projected corners and one pixel of
   * margin): what the pass composites, and splits into the SEGMENTS strips. The whole viewport
   * if a corner lies behind the eye. For tools that model the pass's traffic.
   */
  static void GetScreenRectangle(
    vtkRenderer* ren, const double bounds[6], int width, int height, int rectangle[4]);

  /**
   * Whether compositeMode's frames sample the plain lattice's default distance (SEGMENTS and
   * LOCAL_EXACT blend exactly, as the mapper's EXACT mode; apcDefaultSpacing.h). AUTO keeps
   * the volumes' own default, one lattice whichever mode it picks. The one place that decides
   * it: the pass's frames and the tools that model them (apcSegmentAnalysis) ask here.
   */
  static bool SamplesPlainLattice(int compositeMode);

protected:
  vtkAPCCompositePass();
  ~vtkAPCCompositePass() override;

  // The settings every process must agree on (CompositeMode, CompositeInDouble,
  // DisplayDepthComposited, MaxBandPixels, the interactive ones) live in one value,
  // apc::FrameSettings, in Internal; these are the display process's own.
  vtkMultiProcessController* Controller = nullptr;
  int DisplayProcess = 0;
  bool KeepLastImage = false;
  int Verbosity = 0;
  char* ImageFileName = nullptr;

private:
  vtkAPCCompositePass(const vtkAPCCompositePass&) = delete;
  void operator=(const vtkAPCCompositePass&) = delete;

  void WriteImage();
  // The mode this frame runs: the setting, AUTO's choice, or APC for several volumes (the
  // exact modes cannot interleave them; said once while it lasts).
  int ChooseMode(const apc::ProcessGroup& group, const apc::CompositeFrame& frame);
  // AUTO: what this frame measured, summed over processes, into the history of the choice;
  // seconds: this process's compositing of a still frame (< 0: not timed).
  void RecordForAuto(const apc::ProcessGroup& group, double seconds);
  // Stores, blends and writes the display process's image, and reports the frame.
  void FinishFrame(const apc::ProcessGroup& group, const apc::CompositeFrame& frame,
    const apc::FrameResult& result);

  struct Internals;
  std::unique_ptr<Internals> Internal;
};

#endif
