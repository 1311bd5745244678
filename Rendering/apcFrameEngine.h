// SPDX-License-Identifier: BSD-3-Clause
// One process's frame of one APC volume, stage by stage: what vtkAPCVolumeMapper::Render runs
// in one go, and what vtkAPCCompositePass runs with its collectives between the stages.
// Internal to APC's rendering module (not installed, not for applications).
//
// Buffers are W x H pixels of the prepared crop of the image (GetWidth/GetHeight: the
// data's screen rectangle, so that memory follows the data's footprint on screen, not the
// view's size), row 0 at the bottom; moments hold MomentParameters::Moments + 1 doubles per pixel,
// colour sums 4, images 4 floats (premultiplied RGBA). Moment, colour and image buffers are
// accumulated into (+=), so several volumes sum into one. Stages before a successful Prepare do
// nothing, so a process with nothing to render still takes part in the sums with zeros.
#ifndef apcFrameEngine_h
#define apcFrameEngine_h

#include "APCRenderingModule.h" // for export macro
#include "apcCellMesh.h"
#include "apcInputReport.h"
#include "apcMomentParameters.h"
#include "apcScreenRect.h"
#include "apcStageClock.h"
#include "apcVolumeRayMarcher.h"
#include "apcVolumeSettings.h"

#include "vtkType.h"

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

class vtkObject;
class vtkRenderer;
class vtkUnstructuredGridBase;
class vtkVolumeProperty;

namespace apc
{
class LogDepthWarp;
class RayCamera;
class TransferTable;

// The image a frame renders: W x H pixels covering the viewport at (X0, Y0) of the window,
// whose aspect (width / height) fixes the frustum, and the factor on the sample distance.
// Full quality is one ray per viewport pixel at the volume's sample distance; an interactive
// frame of vtkAPCCompositePass renders fewer, larger pixels and/or a coarser lattice.
// Of that image only the pixels of Crop are rendered (all if unset): every buffer is its size.
struct APCRENDERING_EXPORT ImageSetup
{
  int Width = 0;
  int Height = 0;
  int X0 = 0;
  int Y0 = 0;
  double Aspect = 1.0;
  double SampleFactor = 1.0;
  // The frame blends the plain lattice exactly (vtkAPCCompositePass::SamplesPlainLattice
  // decides it from the composite mode): a sample distance of 0 is then the plain lattice's
  // default, as for the mapper's EXACT mode (apcDefaultSpacing.h).
  bool PlainLattice = false;
  std::optional<ScreenRect> Crop;

  // ren's viewport (the tile of a large screenshot) at full quality, all of it.
  static ImageSetup FullQuality(vtkRenderer* ren);
};

class APCRENDERING_EXPORT FrameEngine
{
public:
  FrameEngine();
  ~FrameEngine();

  /**
   * Starts a frame with the volume's settings (read once from its mapper at the VTK boundary,
   * vtkAPCVolumeMapper::GetVolumeSettings): the stage clock and a not-yet-prepared state.
   */
  void BeginFrame(const VolumeSettings& settings);

  /**
   * After BeginFrame, copies input for the ray marcher if it or the settings' scalar selection
   * changed. When only the scalars changed (a new time step of the same mesh: the same points,
   * cells and ghost flags, by content, even in new arrays), only they and the per-cell scalar
   * ranges are refreshed: no cell conversion, shape checks or face planes again. False, with an
   * error on reporter (the mapper), if the input is unusable (cells but no scalars, a broken mesh);
   * an empty or missing input is usable and renders nothing.
   */
  bool UpdateInput(vtkUnstructuredGridBase* input, vtkObject* reporter);

  /**
   * What the conversion of the current input found (skipped or transparent cells, see
   * apcInputReport.h), and whether that is news: true once after a data change whose report
   * is not empty. The mapper alone says its report then; vtkAPCCompositePass, when any
   * process has news, says the sum of every process's current report, once.
   */
  const InputReport& GetInputReport() const { return this->Report; }
  bool TakeNewInputReport();

  /// How often UpdateInput converted the whole input, and how often it refreshed only the
  /// scalars of the mesh it had (a new step of the same mesh).
  int64_t GetNumberOfMeshConversions() const { return this->MeshConversions; }
  int64_t GetNumberOfScalarRefreshes() const { return this->ScalarRefreshes; }

  /// Bounds of the renderable cells as of the last UpdateInput; false if there are none.
  bool GetLocalBounds(double bounds[6]) const;
  int64_t GetNumberOfCells() const { return this->Mesh.GetNumberOfCells(); }
  /// The threads this volume's passes run on (its setting, or this process's default).
  int GetThreads() const;
  /// Sample End Weights = Boundary (after BeginFrame): this frame weights the ends on the
  /// mesh's boundary; on several processes its faces are not yet matched with the other
  /// processes' pieces since its data changed (apcBoundaryExchange.h), which matches them in
  /// the mesh GetMeshForSharing gives.
  bool RendersBoundaryWeights() const;
  /// The ends the marcher weights: the volume's Sample End Weights, but none for Hybrid.
  VolumeRayMarcher::EndWeightsMode EndWeightsMode() const;
  /// This volume samples with weighted ends (MBOIT, not Hybrid, Sample End Weights not Off):
  /// its default sample distance is the coarser one those allow (apcDefaultSpacing.h), unless
  /// the frame blends the plain lattice (ImageSetup::PlainLattice).
  bool WeightsEnds() const;
  bool NeedsSharedBoundary() const
  {
    return this->RendersBoundaryWeights() && !this->Mesh.SharesBoundary();
  }
  CellMesh& GetMeshForSharing() { return this->Mesh; }
  /// The renderable cells' total volume, summed exactly (the default sample distance's input).
  const ExactSum& GetCellVolume() const { return this->Mesh.GetCellVolume(); }

  /**
   * After UpdateInput (once per frame), samples property's transfer functions and sets up the rays
   * of ren's viewport. globalBounds (xmin..zmax of all processes' cells), globalCells (their
   * number, summed over the processes) and globalVolume (their volume, GetCellVolume summed
   * exactly over the processes) fix the depth warp and the default sample spacing
   * (apcDefaultSpacing.h) so that every process uses the same ones; null (and 0, 0) use this
   * process's cells. depthBuffer (W*H OpenGL depth values, e.g. the composited opaque scene) stops
   * the rays; null reads ren's window. image is what to render (ImageSetup::FullQuality(ren) by the
   * mapper; the pass's agreed image). False if there is nothing this process can render.
   */
  bool Prepare(vtkRenderer* ren, vtkVolumeProperty* property, const double* globalBounds,
    double globalCells, double globalVolume, const float* depthBuffer, const ImageSetup& image);

  int GetWidth() const { return this->Crop.Pixels() > 0 ? this->Crop.Width() : 0; }
  int GetHeight() const { return this->Crop.Pixels() > 0 ? this->Crop.Height() : 0; }
  size_t GetPixels() const { return this->Crop.Pixels(); }
  /// The viewport's origin in the window (tiles of a large screenshot are offset).
  int GetX0() const { return this->X0; }
  int GetY0() const { return this->Y0; }
  /// The rendered pixels in the image (GetWidth x GetHeight of them).
  const ScreenRect& GetCrop() const { return this->Crop; }
  double GetSampleDistance() const { return this->Spacing; }
  /**
   * The most samples a ray takes through the data (along its bounding-box diagonal; the
   * default sample distance takes 128, more on meshes of over ~10^6 cells): a finer sample
   * distance, set or default, is raised to diagonal / this,
   * so that a mistyped setting cannot freeze a render for minutes. Prepare then leaves a note
   * saying what to change, once per setting and data extent: TakeSpacingNote hands it over
   * (empty if none) for the caller to say (the pass: on the display process only).
   */
  static constexpr double kMaxSamplesPerRay = 4096;
  std::string TakeSpacingNote();
  /// Lattice samples taken since Prepare by pass 1 (all its bands), or by the exact or
  /// segment stage.
  int64_t GetSampleCount() const { return this->Samples; }
  /// Pass 2's samples since Prepare (all its bands), those of them replayed from the sample
  /// cache and those skipped as hidden.
  int64_t GetColourSampleCount() const { return this->ColourSamples; }
  int64_t GetReplayedSampleCount() const { return this->ReplayedSamples; }
  int64_t GetHiddenSampleCount() const { return this->HiddenSamples; }
  StageClock& GetClock() { return this->Clock; }
  const StageClock& GetClock() const { return this->Clock; }

  /// MBOIT's passes over the rows of band (all by default; see RowBand): the buffers hold
  /// those rows alone.
  /// bound: with Stop Where Opaque, a predicted last bin per pixel of band that pass 1 passes
  /// on no ray (VolumeRayMarcher::SetOpaqueBound), or null.
  void RenderMoments(const MomentParameters& parameters, double* moments, const RowBand& band = {},
    const uint8_t* bound = nullptr);
  void RenderColour(const MomentParameters& parameters, const double* moments, double* colourSums,
    const RowBand& band = {});
  /// True if this volume's pass 1 stops where opaque (the same on every process), and after
  /// RenderMoments its opaque profile (VolumeRayMarcher::GetOpaqueProfile; empty if none).
  bool StopsWhereOpaque(const MomentParameters& parameters) const;
  /// Whether the next RenderMoments applies the volume's Stop Where Opaque (on from
  /// BeginFrame): the pass leaves it out of a frame where it would cut nothing (an agreed
  /// choice, the same on every process).
  void SetOpaqueStopActive(bool active);
  /// True where this volume's own opaque profile is the one the cut takes (one process, one
  /// volume): pass 1 then keeps tiles marched without the stop where no ray came near it
  /// (VolumeRayMarcher::SetOpaqueStopAlone).
  void SetOpaqueStopAlone(bool alone) { this->Marcher.SetOpaqueStopAlone(alone); }
  VolumeRayMarcher::OpaqueProfile GetOpaqueProfile() const;
  /// The opaque profile of values values to sum the processes' profiles into in place
  /// (VolumeRayMarcher::GetOpaqueProfileToSum), or null if it has not that size.
  uint16_t* GetOpaqueProfileToSum(size_t values);
  /// Memory for pass 1's opaque profile until withdrawn with null
  /// (VolumeRayMarcher::LendOpaqueProfileMemory).
  void LendOpaqueProfileMemory(unsigned char* bytes, size_t size)
  {
    this->Marcher.LendOpaqueProfileMemory(bytes, size);
  }
  /// The cut agreed from the profiles of every volume and process (ApplyOpaqueCut): moments
  /// holds this volume's own pass-1 moments of band, which lose the samples past it.
  void ApplyOpaqueCut(const MomentParameters& parameters, const uint16_t* profile, double* moments,
    const RowBand& band);
  /// After a bounded RenderMoments of band: marches again, without the bound, the tiles holding
  /// a pixel with unresolved[pixel] set (VolumeRayMarcher::RedoOpaqueTiles), whose moments
  /// (this volume's own) and profile are replaced. Its samples count as pass 1's.
  void RedoOpaqueTiles(const MomentParameters& parameters, const uint8_t* unresolved,
    double* moments, const RowBand& band);
  /// Stop Where Opaque's probe of a first frame on several processes (apcOpaquePrediction.h):
  /// marches the rays of every step-th pixel of the crop in each direction (the crop's pixel
  /// (i * step + offset, j * step + offset) is probe pixel (i, j); apc::ProbeSize gives the
  /// probe image's size) with this volume's own stop and no sample cache, and adds their
  /// opaque profile (OpaqueBins::kBins per probe pixel) into profile. Returns the samples
  /// taken (0 if the volume does not stop where opaque or is not prepared).
  int64_t ProbeOpaqueProfile(
    const MomentParameters& parameters, int step, int offset, uint16_t* profile);
  /// Samples marched again by the cuts since Prepare (tiles the sample cache did not hold).
  int64_t GetCutSampleCount() const { return this->CutSamples; }
  /// Marcher tiles pass 1 kept as marched without the stop since Prepare (alone only).
  int64_t GetUnstoppedTileCount() const { return this->UnstoppedTiles; }
  void RenderExact(float* rgba);
  void CountSegments(int* counts);
  /// This process's sort-last segments of every pixel, replacing segments' content.
  void RenderSegments(SegmentImage& segments);

private:
  FrameEngine(const FrameEngine&) = delete;
  // Raises Spacing to the limit of kMaxSamplesPerRay (distance: the setting; 0 the default).
  void CapSpacing(double distance, double diagonal);
  FrameEngine& operator=(const FrameEngine&) = delete;

  VolumeSettings Settings; // this frame's
  bool OpaqueStopActive = true;
  CellMesh Mesh;
  bool MeshValid = false;
  std::string MeshKey;            // what the mesh was made of (data arrays, scalar selection)
  const void* MeshData = nullptr; // the data set last seen (compared, never dereferenced)
  vtkMTimeType MeshDataTime = 0;
  std::string MeshSelectionKey;           // the scalar selection without the array's identity
  unsigned long long MeshGeometryKey = 0; // a hash of points, cells and ghost flags; 0 if none
  std::vector<long long> MeshSources;     // the input cell of every mesh cell
  int64_t MeshConversions = 0;
  int64_t ScalarRefreshes = 0;
  InputReport Report;
  bool ReportPending = false;
  VolumeRayMarcher Marcher;

  bool Ready = false;
  int X0 = 0;
  int Y0 = 0;
  ScreenRect Crop;
  double Spacing = 0.0;
  bool DefaultWeighted = true; // this frame's default distance: the weighted ends' (Prepare)
  std::string SpacingNote;
  double CappedDistance = -1; // the setting and extent last capped (said once)
  double CappedDiagonal = -1;
  std::unique_ptr<TransferTable> Table;
  std::unique_ptr<RayCamera> Camera;
  std::unique_ptr<LogDepthWarp> Warp;
  int64_t Samples = 0;
  int64_t ColourSamples = 0;
  int64_t ReplayedSamples = 0;
  int64_t HiddenSamples = 0;
  int64_t CutSamples = 0;
  int64_t UnstoppedTiles = 0;
  StageClock Clock;
};

} // namespace apc

#endif
