// Ray marching of one rank's unstructured cells on the global sample lattice, in the ways
// APC needs: exact front-to-back blending (the ground truth), MBOIT pass 1 (absorbance
// moments) and MBOIT pass 2 (colour weighted by the transmittance reconstructed from the
// global moments), plus the per-pixel count of disjoint ray segments through the cells and
// the segments themselves, pre-blended, for exact sort-last compositing across ranks.
//
// Cells are binned to screen tiles once per view (apcTileBins.h); each tile (one TBB task)
// intersects its pixels' rays with its cells' face planes and takes the lattice samples
// t_k = k * spacing that fall in [t_in, t_out), handing them to a visitor (apcRayVisitors.h).
// The moment and colour passes are sums, so the order in which cells and samples arrive does
// not matter and nothing is sorted; only the exact and segment modes sort each pixel's
// samples by k.
//
// Images are W x H, row 0 at the bottom, pixel (i, j) at index j * W + i. Output buffers are
// accumulated into (+=), so the caller zeroes them once and may sum several meshes or passes.
#ifndef apcVolumeRayMarcher_h
#define apcVolumeRayMarcher_h

#include "apcCellMesh.h"
#include "apcDepthWarp.h"
#include "apcMomentTransmittance.h"
#include "apcOpaqueBins.h"
#include "apcRayCamera.h"
#include "apcRaySegments.h"
#include "apcTransferTable.h"

#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

namespace apc
{

struct SampleCache;
struct TileBins;
struct TileRect;
namespace walk
{
struct RaySetup;
}
namespace visitors
{
template <int N>
struct Moments;
}

// Image rows [J0, J1): a band the moment and colour passes can be limited to, so that a large
// image is rendered and composited band by band with band-sized buffers (the buffers then
// hold the band's rows alone, row J0 first). J0 must be a multiple of
// VolumeRayMarcher::kTileSize, and J1 too unless it is past the last row.
struct RowBand
{
  int J0 = 0;
  int J1 = 1 << 30;
};

class VolumeRayMarcher
{
public:
  VolumeRayMarcher();
  ~VolumeRayMarcher();
  VolumeRayMarcher(const VolumeRayMarcher&) = delete;
  VolumeRayMarcher& operator=(const VolumeRayMarcher&) = delete;

  // The cells to march (kept by pointer: the mesh must outlive the marcher's use of it).
  void SetMesh(const CellMesh* mesh);

  // Per frame. rayEnds: W*H distances at which each ray stops (opaque geometry), or null for
  // none. Bins the cells into tiles; call again whenever the camera or the mesh changes.
  void SetView(const RayCamera& camera, const float* rayEnds);
  // The same, taking over the W*H ray ends (none: no ray stops), so that they are not held
  // twice while the view is set up.
  void SetView(const RayCamera& camera, std::vector<float>&& rayEnds);
  // The view of frame's camera decimated (RayCamera::Decimated(step, offset)), for a marcher
  // of frame's mesh after frame's SetView: its bins are derived from frame's (DecimateBins)
  // instead of binning every cell again, the same bins. rayEnds: as for SetView, per
  // decimated pixel.
  void SetDecimatedView(
    const VolumeRayMarcher& frame, int step, int offset, std::vector<float>&& rayEnds);

  // The distances at which the current view's rays stop (W*H; +inf where nothing stops them).
  const std::vector<float>& GetRayEnds() const { return this->RayEnds; }

  // 0 = as many as TBB offers.
  void SetNumberOfThreads(int threads) { this->Threads = threads; }

  // Shift each pixel's sample lattice by its apcLatticeJitter offset (banding becomes noise).
  // Set it before a frame's passes: pass 2 replays pass 1's samples.
  void SetLatticeJitter(bool jitter) { this->LatticeJitter = jitter; }

  // Weight the end samples of each (cell, ray) pair so that a pair's samples sum to its exact
  // length, and sample a pair without a lattice point once at its middle (apcEndWeights.h):
  // no lattice staircase along grazing silhouettes. Both MBOIT passes and the opaque stop take
  // the same weighted samples, on every partition; the sample cache keeps each one's weight
  // for pass 2. The exact blend and the segments keep the plain lattice
  // (visitors::PixelSampleLists says why). Off by default. Set it before a frame's passes.
  void SetSampleEndWeights(bool weights)
  {
    this->SampleEndWeights = weights ? EndWeightsMode::All : EndWeightsMode::Off;
  }
  bool GetSampleEndWeights() const { return this->SampleEndWeights != EndWeightsMode::Off; }
  // Which ends SetSampleEndWeights weights: every (cell, ray) pair's (All), or only those on
  // the mesh's boundary (Boundary, CellMesh::GetBoundaryPlanes; apcEndWeights.h EndWeightsAt):
  // there the staircase is, while at an inner face the plain lattice already covers the ray
  // exactly, so the cells without a boundary face keep the plain lattice's samples and cost.
  enum class EndWeightsMode : uint8_t
  {
    Off = 0,
    All = 1,
    Boundary = 2
  };
  void SetEndWeightsMode(EndWeightsMode mode) { this->SampleEndWeights = mode; }
  EndWeightsMode GetEndWeightsMode() const { return this->SampleEndWeights; }

  // Take nearly affine cells' and twisted pyramids' samples four rays at a time where the
  // processor has AVX2 (on by default); off, every pair goes through the scalar loop, with
  // the same samples (tests compare the two).
  void SetSampleLanes(bool lanes) { this->SampleLanes = lanes; }
  bool GetSampleLanes() const { return this->SampleLanes; }
  // Whether a march that skips the cells its transfer table hides finds them once per march
  // and leaves them out of each tile's list (on, the default), or tests each (cell, tile)
  // entry as it comes (off: the form the tests compare it with). The same samples either way.
  void SetDropClearCells(bool drop) { this->DropClearCells = drop; }
  bool GetDropClearCells() const { return this->DropClearCells; }

  // The MBOIT passes may stop a ray once the absorbance of its samples on this mesh reaches
  // this (the tiles' cells are visited nearest first, so that happens early): a later sample
  // behind all the samples summed so far has a transmittance below exp(-absorbance) whatever
  // other meshes or ranks add in front of it, so leaving it out changes a pixel's opacity by
  // less than that. Pass 1 stops at the end of one of the ray's fixed bins (apcOpaqueBins.h)
  // and records each pixel's absorbance per bin (GetOpaqueProfile); ApplyOpaqueCut, given
  // the profiles summed over every mesh and process, keeps only the samples up to the cut
  // complete data gives, so N processes sum the samples one process sums. Without
  // ApplyOpaqueCut, pass 2 takes exactly pass 1's samples, which depend on how the cells are
  // split. +inf (every sample) by default. Exact and segment renders never stop, nor does a
  // pass 1 that keeps its own moments for Hybrid, whose own transmittance is exact.
  void SetOpaqueAbsorbance(double absorbance) { this->OpaqueAbsorbance = absorbance; }
  double GetOpaqueAbsorbance() const { return this->OpaqueAbsorbance; }
  // True if this mesh's own absorbance is all the cut will sum (one process, one mesh): pass 1
  // then marches each tile without the stop first and keeps it where no ray came near the
  // threshold, which is then exactly what the stop gives (on a band of at least
  // kTilesPerThreadWithoutStop tiles per thread). False by default.
  void SetOpaqueStopAlone(bool alone) { this->OpaqueStopAlone = alone; }
  static constexpr int kTilesPerThreadWithoutStop = 64;
  // Tiles the last pass 1 kept as marched without the stop (alone only).
  int64_t GetLastUnstoppedTileCount() const { return this->LastUnstoppedTiles; }
  // ln 10^3: what a ray leaves unsampled is hidden behind a transmittance of at most 1e-3,
  // a quarter of one step of an 8-bit colour (1/255). Chosen by measurement against the exact
  // blend on the bundled data (docs/sampler.md, "The opaque stop's threshold, measured").
  static constexpr double kRecommendedOpaqueAbsorbance = 6.907755278982137;

  // A band's opaque profile where it lies: Count values, OpaqueBins::kBins per pixel.
  struct OpaqueProfile
  {
    uint16_t* Values = nullptr;
    size_t Count = 0;
    const uint16_t* data() const { return this->Values; }
    size_t size() const { return this->Count; }
  };
  // After pass 1 with a stop: this mesh's profile, OpaqueBins::kBins saturating quanta per
  // pixel of the pass's rows (empty without a stop), to be summed (AddProfiles) over every
  // mesh and process into the profile ApplyOpaqueCut takes.
  OpaqueProfile GetOpaqueProfile() const { return { this->Profile, this->ProfileValues }; }
  // The same, for the processes' profiles to be summed into in place: after pass 1 the marcher
  // reads it no more (ApplyOpaqueCut is given the profile to cut at; RedoOpaqueTiles zeroes and
  // rewrites the tiles it marches), so no second band-sized profile need be paged in.
  uint16_t* GetOpaqueProfileToSum() { return this->Profile; }
  // Lends pass 1 bytes (size of them, from operator new) to make its profile in instead of
  // the marcher's own memory, if they hold it, until lent again or withdrawn (null; the profile
  // in them is then forgotten). For a caller whose buffer is idle from pass 1 to the cut, so
  // that a first frame pages in one buffer less (vtkAPCCompositePass: the colour sums').
  void LendOpaqueProfileMemory(unsigned char* bytes, size_t size);
  // Cuts every pixel's samples at the end of the first bin where the summed profile reaches
  // the threshold (CutBin): the moments of this pass 1 (moments: this mesh's alone, as pass 1
  // wrote them) lose the samples past it, and pass 2 takes none of them. Nothing without a
  // stop. Samples marched again for tiles beyond the cache: GetLastCutSampleCount.
  template <int N>
  void ApplyOpaqueCut(const TransferTable& table, const LogDepthWarp& warp, const uint16_t* profile,
    double* moments, const RowBand& rows = {});
  int64_t GetLastCutSampleCount() const { return this->LastCutSamples; }
  // A last bin per pixel of the next pass 1's rows (W*rows bytes, kept by pointer until
  // reset) that no ray of it passes, besides its own stop: a cut predicted alike on every
  // process (apcOpaquePrediction.h). Null: none. The profile is then complete only up to the
  // nearer of the two; pixels whose summed profile does not reach the threshold by their
  // bound must be marched again (RedoOpaqueTiles) before ApplyOpaqueCut.
  void SetOpaqueBound(const uint8_t* bound) { this->Bound = bound; }
  // After a bounded pass 1: marches again, without the bound, every tile holding a pixel with
  // unresolved[pixel] set (W*rows bytes), replacing those tiles' moments (this mesh's, as
  // pass 1 wrote them), profile and cached samples. Samples: GetLastRedoSampleCount.
  template <int N>
  void RedoOpaqueTiles(const TransferTable& table, const LogDepthWarp& warp,
    const uint8_t* unresolved, double* moments, const RowBand& rows = {});
  int64_t GetLastRedoSampleCount() const { return this->LastRedoSamples; }

  // Nearly affine cells take their parametric coordinates linearly along a ray (the inverse
  // of the map's affine part about the cell's centre) where that moves no sample's scalar by
  // more than this many transfer-table bins (CellInterpolator::GetLinearScalarError); the
  // others by Newton. 0: only exactly affine cells. The choice is the cell's own, so every
  // rank makes the same one.
  void SetLinearTolerance(double bins) { this->LinearTolerance = bins; }
  double GetLinearTolerance() const { return this->LinearTolerance; }
  static constexpr double kDefaultLinearTolerance = 0.25;
  // Pass 2 skips a pixel's samples behind the depth from which the transmittance
  // reconstructed from the global moments, times the pixel's total absorbance b0, stays at or
  // below this weight (apc::MomentTransmittance::HiddenDepth): the alphas of a pixel's samples
  // sum to at most b0, so what is skipped weighs at most this much together, and the depth
  // depends on the global moments alone, so N processes skip exactly what one would. 0 weights
  // every sample. Hybrid pass 2 never skips. Default kDefaultHiddenSampleWeight.
  void SetHiddenSampleWeight(double weight) { this->HiddenSampleWeight = weight; }
  double GetHiddenSampleWeight() const { return this->HiddenSampleWeight; }
  // 1e-4: far below one step of an 8-bit colour (1/255) in the Paper Sum resolve's weights,
  // and below it in Renormalised's (which divides by the weights' sum W) unless W < 0.026.
  static constexpr double kDefaultHiddenSampleWeight = 1e-4;
  // The share of the last AccumulateColour's samples skipped as hidden (0 to 1), and their
  // number.
  double GetLastHiddenShare() const { return this->LastHiddenShare; }
  int64_t GetLastHiddenCount() const { return this->LastHidden; }

  // Pass 1 keeps its samples (scalar and depth, 6 bytes each in the compact form, else 8, 10
  // with the lattice bits, 4 more with end weights) for pass 2 up to this many bytes, so that
  // pass 2 only re-weights them instead of clipping and interpolating again; the tiles beyond
  // the budget are marched again. 0 disables. Default 1 GiB (the frame engine sets the node's
  // share, apc::NodeShareOfMemory). Lowering it frees the memory the cache holds.
  void SetMaxSampleCacheBytes(size_t bytes);
  // The cache keeps a sample's depth as the index of its entry in the frame's depth table
  // where it can (apcSampleCache.h's CompactSpan: fewer bytes of memory written and read);
  // off, every sample whole (for tests and measurements). The same images bit for bit.
  void SetCompactSampleCache(bool compact);
  // The share of the last AccumulateColour's samples replayed from the cache (0 to 1), and
  // their number.
  double GetLastColourCacheShare() const { return this->LastColourCacheShare; }
  int64_t GetLastReplayedCount() const { return this->LastReplayed; }

  // Exact ordered blending: premultiplied RGBA, W*H*4.
  void RenderExact(const TransferTable& table, float* rgba);

  // MBOIT pass 1: unnormalised power moments b0..bN per pixel of rows, W*rows*(N+1). keepOwn:
  // the marcher also keeps this mesh's moments (as many, held only while asked for) for a
  // Hybrid pass 2. The sample cache then holds these rows' samples alone.
  template <int N>
  void AccumulateMoments(const TransferTable& table, const LogDepthWarp& warp, double* moments,
    bool keepOwn = false, const RowBand& rows = {});

  // MBOIT pass 2: (sum w r, sum w g, sum w b, sum w) per pixel, W*H*4, w = alpha * T(z) with
  // T reconstructed from the (global) moments. hybrid (apcHybridTransmittance.h): T is the
  // exact ordered transmittance of this mesh's own samples times the one reconstructed from
  // the moments of everything else (global - own); it needs the own moments of a pass 1 with
  // keepOwn on the same view, N, table and warp, and without them weights as without hybrid.
  // rows: as in the pass 1 just run (moments and colourSums hold those rows alone).
  template <int N>
  void AccumulateColour(const TransferTable& table, const LogDepthWarp& warp, const double* moments,
    const MomentSettings<N>& settings, double* colourSums, bool hybrid = false,
    const RowBand& rows = {});

  // This mesh's segments of every pixel (see RaySegment), replacing segments' content.
  void RenderSegments(const TransferTable& table, SegmentImage& segments);

  // Number of disjoint intervals of each ray inside the cells (before the ray end), W*H.
  void CountSegments(int32_t* counts);

  // Square tiles of this many pixels a side: small enough to balance the TBB tasks and keep a
  // tile's pixel index in the sample cache's 16 bits. Bands of rows are cut on tile rows.
  static constexpr int kTileSize = 16;

  // Samples taken (lattice points inside cells) by the last pass, for benchmarks.
  int64_t GetLastSampleCount() const { return this->LastSamples; }

private:
  // SetView's and SetDecimatedView's camera, ray ends (infinite where absent) and an empty cache;
  // the bins are theirs.
  void SetCamera(const RayCamera& camera, std::vector<float>&& rayEnds);
  struct Walker;
  // Marches the tiles of rows (all by default); visitors see them shifted by rows.J0, so that
  // they write into band-sized buffers. skipTiles: tiles t with (*skipTiles)[t] set are left out.
  template <class Visitor>
  void March(Visitor& prototype, const TransferTable& table,
    const std::vector<uint8_t>* skipTiles = nullptr, const RowBand& rows = {});
  // The rays of a tile's pixels.
  void SetUpRays(const TileRect& tile, std::vector<walk::RaySetup>& rays) const;
  // After a tile of pass 1 marched without the stop (alone): true to keep it, else its
  // moments and cached samples are undone for a march with the stop.
  template <class Visitor>
  bool KeepUnstoppedTile(Visitor& visitor, const TileRect& inBand, int64_t tile);
  template <int N>
  bool KeepUnstoppedTile(visitors::Moments<N>& visitor, const TileRect& inBand, int64_t tile);
  // Replays the cached tiles into copies of prototype; returns the samples replayed.
  template <class Visitor>
  int64_t ReplayColour(const TransferTable& table, const Visitor& prototype, const RowBand& rows);
  int Width() const { return this->Camera ? this->Camera->GetWidth() : 0; }
  // The tiles [first, last) of rows, in the bins' grid.
  void TilesOf(const RowBand& rows, int64_t& first, int64_t& last) const;

  const CellMesh* Mesh = nullptr;
  std::unique_ptr<RayCamera> Camera;
  std::vector<float> RayEnds;
  std::unique_ptr<TileBins> Bins;
  // Per cell, for the march in progress: whether its transfer table may show it
  // (Walker::VisibleCells).
  std::vector<uint8_t> VisibleCells;
  std::unique_ptr<SampleCache> Cache;
  // This mesh's own moments from the last pass 1 that kept them (Hybrid), and their order
  // (0: none kept).
  std::vector<double> OwnMoments;
  int OwnMomentsOrder = 0;
  double LastColourCacheShare = 0;
  double LastHiddenShare = 0;
  double HiddenSampleWeight = kDefaultHiddenSampleWeight;
  int Threads = 0;
  bool LatticeJitter = false;
  EndWeightsMode SampleEndWeights = EndWeightsMode::Off;
  bool SampleLanes = true;
  bool DropClearCells = true;
  double OpaqueAbsorbance = std::numeric_limits<double>::infinity();
  double LinearTolerance = kDefaultLinearTolerance;
  // The opaque stop's bins of the last pass 1 (inactive without a stop), its own profile
  // and last bin per pixel, and once agreed, each pixel's cut, which pass 2 uses too.
  OpaqueBins Opaque;
  std::vector<uint16_t> OwnProfile; // the profile's memory unless some is lent
  unsigned char* LentProfile = nullptr;
  size_t LentProfileBytes = 0;
  uint16_t* Profile = nullptr; // the last pass 1's, in OwnProfile or the lent memory
  size_t ProfileValues = 0;
  std::vector<uint8_t> LastBin;
  std::vector<uint8_t> Cut;
  bool CutSet = false;
  bool RecordProfile = false;
  bool OpaqueStopAlone = false;
  bool OpaqueAlone = false; // this pass 1 marches tiles without the stop first
  int64_t LastUnstoppedTiles = 0;
  const uint8_t* Bound = nullptr;
  int64_t LastCutSamples = 0;
  int64_t LastRedoSamples = 0;
  int64_t LastSamples = 0;
  int64_t LastReplayed = 0;
  int64_t LastHidden = 0;
};

} // namespace apc

#endif
