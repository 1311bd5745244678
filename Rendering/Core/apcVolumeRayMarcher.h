// Ray marching of one rank's unstructured cells on the global sample lattice, in the three
// ways APC needs: exact front-to-back blending (the ground truth), MBOIT pass 1 (absorbance
// moments) and MBOIT pass 2 (colour weighted by the transmittance reconstructed from the
// global moments), plus the per-pixel count of disjoint ray segments through the cells and
// the segments themselves, pre-blended, for exact sort-last compositing across ranks.
//
// Work is organised by cell, not by ray: every cell is binned once per view into the screen
// tiles its projection covers, then each tile (one TBB task) intersects its pixels' rays with
// its cells' face planes and takes the lattice samples t_k = k * spacing that fall in
// [t_in, t_out). No per-ray cell search is needed: a VTK cell locator query per ray
// (FindCellsAlongLine) measured 200-360 us per ray on a 330k-cell mesh here, i.e. minutes
// per 1024^2 frame. The moment and colour passes are sums, so the order in which cells and
// samples arrive does not matter and nothing is sorted; only the exact mode sorts each
// pixel's samples by k.
//
// Images are W x H, row 0 at the bottom, pixel (i, j) at index j * W + i. Output buffers are
// accumulated into (+=), so the caller zeroes them once and may sum several meshes or passes.
#ifndef apcVolumeRayMarcher_h
#define apcVolumeRayMarcher_h

#include "apcCellMesh.h"
#include "apcDepthWarp.h"
#include "apcMomentTransmittance.h"
#include "apcRayCamera.h"
#include "apcTransferTable.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

namespace apc
{

// One pass-1 sample kept for pass 2: its warped depth, its scalar, its pixel in the tile.
struct CachedSample
{
  float Z;
  float Scalar;
  uint16_t Pixel;
};

// One run of consecutive lattice samples k = KFirst..KLast along one pixel's ray that all lie
// in this rank's cells (transparent samples included: a run ends only where the ray leaves
// the rank's cells between two lattice points, or at the ray's end), blended front to back:
// premultiplied colour and transmittance (1 - alpha). Runs of different ranks never
// interleave on a ray, since every lattice sample belongs to exactly one rank, so blending all
// ranks' runs in KFirst order is exactly the ordered blend of all samples. Wholly transparent
// runs are not kept: they change nothing and would only be sent.
struct RaySegment
{
  int64_t KFirst;
  int64_t KLast;
  std::array<float, 3> Colour;
  // Rather than alpha: a float keeps a small transmittance to full relative precision, while
  // 1 - alpha of an almost opaque run would lose it, and with it the weight of everything
  // behind the run.
  float Transmittance;
};

// Per-pixel segment lists in compressed rows: pixel p's segments are
// Segments[Offsets[p] .. Offsets[p + 1]), in increasing KFirst. Width * Height pixels, row 0 at
// the bottom, pixel (i, j) at j * Width + i.
struct SegmentImage
{
  int Width = 0;
  int Height = 0;
  std::vector<int64_t> Offsets{ 0 };
  std::vector<RaySegment> Segments;

  int64_t Count(int64_t pixel) const { return this->Offsets[pixel + 1] - this->Offsets[pixel]; }
  // Empty lists for every pixel of a width x height image.
  void Reset(int width, int height);
};

// Segment statistics over the pixels that have at least one segment.
struct SegmentStatistics
{
  int64_t Segments = 0;
  int64_t NonEmptyPixels = 0;
  int64_t MaxPerPixel = 0;
  double Average() const
  {
    return this->NonEmptyPixels > 0 ? static_cast<double>(this->Segments) / this->NonEmptyPixels
                                    : 0.0;
  }
};
SegmentStatistics GetSegmentStatistics(const SegmentImage& image);

// Blends one pixel's segments, from any ranks, front to back in KFirst order (sorting them in
// place): premultiplied RGBA. Exact (to rounding) as long as the segments' k ranges do not
// interleave.
std::array<double, 4> CompositeSegments(RaySegment* segments, size_t count);

// CompositeSegments for every pixel of an image (whose lists need not be sorted), added (+=)
// to rgba, Width * Height * 4. threads: 0 = as many as TBB offers.
void CompositeSegmentImage(SegmentImage& image, float* rgba, int threads = 0);

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

  // 0 = as many as TBB offers.
  void SetNumberOfThreads(int threads) { this->Threads = threads; }
  // Square tiles of 1..256 pixels a side (default 16).
  void SetTileSize(int pixels) { this->TileSize = std::min(std::max(pixels, 1), 256); }

  // Pass 1 keeps its samples (depth and scalar, 12 bytes each) for pass 2 up to this many
  // bytes, so that pass 2 only re-weights them instead of clipping and interpolating again;
  // over the budget pass 2 marches again. 0 disables. Default 1 GiB.
  void SetMaxSampleCacheBytes(size_t bytes) { this->Cache->MaxBytes = bytes; }
  // Whether the last AccumulateColour replayed cached samples.
  bool GetLastColourUsedCache() const { return this->LastColourUsedCache; }

  // Exact ordered blending: premultiplied RGBA, W*H*4.
  void RenderExact(const TransferTable& table, float* rgba);

  // MBOIT pass 1: unnormalised power moments b0..bN per pixel, W*H*(N+1).
  template <int N>
  void AccumulateMoments(const TransferTable& table, const LogDepthWarp& warp, double* moments);

  // MBOIT pass 2: (sum w r, sum w g, sum w b, sum w) per pixel, W*H*4, w = alpha * T(z) with
  // T reconstructed from the (global) moments.
  template <int N>
  void AccumulateColour(const TransferTable& table, const LogDepthWarp& warp, const double* moments,
    const MomentSettings<N>& settings, double* colourSums);

  // This mesh's segments of every pixel (see RaySegment), replacing segments' content.
  void RenderSegments(const TransferTable& table, SegmentImage& segments);

  // Number of disjoint intervals of each ray inside the cells (before the ray end), W*H.
  void CountSegments(int32_t* counts);

  // Samples taken (lattice points inside cells) by the last pass, for benchmarks.
  int64_t GetLastSampleCount() const { return this->LastSamples; }

  const RayCamera* GetCamera() const { return this->Camera.get(); }

  struct Bins; // tile -> cells, per view
  struct Walker;
  struct SampleCache
  {
    std::vector<std::vector<CachedSample>> Tiles;
    std::atomic<size_t> Bytes{ 0 };
    size_t MaxBytes = size_t(1) << 30;
    std::atomic<bool> Record{ false };
    bool Valid = false;
    const TransferTable* Table = nullptr;
    double WarpNear = 0;
    double WarpFar = 0;
    int Moments = 0;
  };

private:
  template <class Visitor>
  void March(Visitor& prototype, const TransferTable& table);
  template <int N>
  void ReplayColour(const TransferTable& table, const LogDepthWarp& warp, const double* moments,
    const MomentSettings<N>& settings, double* colourSums);

  const CellMesh* Mesh = nullptr;
  std::unique_ptr<RayCamera> Camera;
  std::vector<float> RayEnds;
  std::unique_ptr<Bins> TileBins;
  std::unique_ptr<SampleCache> Cache;
  bool LastColourUsedCache = false;
  int Threads = 0;
  int TileSize = 16;
  int64_t LastSamples = 0;
};

} // namespace apc

#endif
