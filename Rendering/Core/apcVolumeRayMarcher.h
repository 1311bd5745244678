// Ray marching of one rank's unstructured cells on the global sample lattice, in the three
// ways APC needs: exact front-to-back blending (the ground truth), MBOIT pass 1 (absorbance
// moments) and MBOIT pass 2 (colour weighted by the transmittance reconstructed from the
// global moments), plus the per-pixel count of disjoint ray segments through the cells.
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
