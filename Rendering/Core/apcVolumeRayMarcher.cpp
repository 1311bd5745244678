#include "apcVolumeRayMarcher.h"

#include "apcCellInterpolation.h"
#include "apcColourVisitors.h"
#include "apcCompressedRows.h"
#include "apcHugePages.h"
#include "apcLatticeJitter.h"
#include "apcOpaqueCut.h"
#include "apcParallel.h"
#include "apcRayClip.h"
#include "apcRayVisitors.h"
#include "apcRayWalk.h"
#include "apcSampleCache.h"
#include "apcTileBins.h"
#include "apcVolumeRayMarcherWalker.h"

#include <tbb/combinable.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>
#include <functional>
#include <limits>
#include <utility>

namespace apc
{

//------------------------------------------------------------------------------
VolumeRayMarcher::VolumeRayMarcher()
  : Bins(new TileBins)
  , Cache(new SampleCache)
{
}

VolumeRayMarcher::~VolumeRayMarcher() = default;

void VolumeRayMarcher::SetCompactSampleCache(bool compact)
{
  this->Cache->CompactRecords = compact;
}

//------------------------------------------------------------------------------
void VolumeRayMarcher::SetMaxSampleCacheBytes(size_t bytes)
{
  if (bytes < this->Cache->MaxBytes)
  {
    // The memory kept from frame to frame may exceed the new budget: give it back.
    this->Cache->Release();
  }
  this->Cache->MaxBytes = bytes;
}

//------------------------------------------------------------------------------
void VolumeRayMarcher::SetMesh(const CellMesh* mesh)
{
  this->Mesh = mesh;
  this->Cache->Clear();
  this->OwnMomentsOrder = 0;
}

//------------------------------------------------------------------------------
void VolumeRayMarcher::SetView(const RayCamera& camera, const float* rayEnds)
{
  const size_t pixels = static_cast<size_t>(camera.GetWidth()) * camera.GetHeight();
  std::vector<float> ends;
  if (rayEnds)
  {
    ends.assign(rayEnds, rayEnds + pixels);
  }
  this->SetView(camera, std::move(ends));
}

void VolumeRayMarcher::SetView(const RayCamera& camera, std::vector<float>&& rayEnds)
{
  this->SetCamera(camera, std::move(rayEnds));
  BinCells(this->Mesh, camera, kTileSize, this->Threads, *this->Bins);
}

void VolumeRayMarcher::SetCamera(const RayCamera& camera, std::vector<float>&& rayEnds)
{
  this->Cache->Clear();
  this->OwnMomentsOrder = 0;
  this->Camera.reset(new RayCamera(camera));
  const size_t pixels = static_cast<size_t>(camera.GetWidth()) * camera.GetHeight();
  this->RayEnds = std::move(rayEnds);
  if (this->RayEnds.size() != pixels)
  {
    this->RayEnds.assign(pixels, std::numeric_limits<float>::infinity());
  }
}

void VolumeRayMarcher::SetDecimatedView(
  const VolumeRayMarcher& frame, int step, int offset, std::vector<float>&& rayEnds)
{
  const RayCamera camera = frame.Camera->Decimated(step, offset);
  this->SetCamera(camera, std::move(rayEnds));
  if (frame.Mesh != this->Mesh ||
    !DecimateBins(*frame.Bins, step, offset, camera.GetWidth(), camera.GetHeight(), kTileSize,
      this->Threads, *this->Bins))
  {
    BinCells(this->Mesh, camera, kTileSize, this->Threads, *this->Bins);
  }
}

//------------------------------------------------------------------------------
void VolumeRayMarcher::TilesOf(const RowBand& rows, int64_t& first, int64_t& last) const
{
  const TileGrid& grid = this->Bins->Grid;
  // A band starting inside a tile row would hand its visitors rows below the band's buffers.
  assert(rows.J0 >= 0 && rows.J0 % grid.Size == 0);
  const int j1 = std::min(rows.J1, grid.Height);
  first = std::min(static_cast<int64_t>(rows.J0 / grid.Size) * grid.TilesX, grid.Count());
  last =
    j1 > rows.J0 ? static_cast<int64_t>((j1 + grid.Size - 1) / grid.Size) * grid.TilesX : first;
  last = std::min(last, grid.Count());
}

//------------------------------------------------------------------------------
void VolumeRayMarcher::SetUpRays(const TileRect& tile, std::vector<RaySetup>& rays) const
{
  const int width = this->Bins->Grid.Width;
  rays.resize(tile.Pixels());
  for (int p = 0; p < tile.Pixels(); ++p)
  {
    const Ray ray = this->Camera->PixelRay(tile.I0 + p % tile.Width(), tile.J0 + p / tile.Width());
    RaySetup& r = rays[p];
    std::copy(ray.Origin.begin(), ray.Origin.end(), r.O);
    std::copy(ray.Direction.begin(), ray.Direction.end(), r.D);
    r.End = this->RayEnds[tile.ImagePixel(p, width)];
    r.Offset = this->LatticeJitter
      ? LatticeOffset(this->Camera->ImageColumn(tile.I0 + p % tile.Width()),
          this->Camera->ImageRow(tile.J0 + p / tile.Width()))
      : 0.0;
  }
}

//------------------------------------------------------------------------------
template <class Visitor>
void VolumeRayMarcher::March(Visitor& prototype, const TransferTable& table,
  const std::vector<uint8_t>* skipTiles, const RowBand& rows)
{
  this->LastSamples = 0;
  if (!this->Mesh || !this->Camera || this->Mesh->GetNumberOfCells() == 0)
  {
    return;
  }
  const TileGrid& grid = this->Bins->Grid;
  double nearLimit = 0;
  double farLimit = 0;
  this->Camera->DistanceRange(this->Mesh->GetBounds(), nearLimit, farLimit);
  Walker walker{ *this->Mesh, *this->Bins, table, farLimit * (1 + 1e-12) + 1e-300,
    !this->Camera->IsParallel(),
    Visitor::StopsWhenOpaque && this->Opaque.Active() ? &this->Opaque : nullptr,
    Lattice(table.GetSampleSpacing()),
    this->LinearTolerance > 0 ? this->LinearTolerance * table.GetBinWidth() : 0.0 };
  walker.BandWidth = this->Width();
  walker.EndWeights = this->SampleEndWeights != EndWeightsMode::Off;
  walker.BoundaryWeights = this->SampleEndWeights == EndWeightsMode::Boundary;
  walker.Lanes = walker.Lanes && this->SampleLanes;
  if (!Visitor::WantsSegments && !Visitor::WantsTransparentSamples && this->DropClearCells)
  {
    // Once per march, not per (cell, tile) entry: with much of the range clear, most of a
    // tile's cells are (the lower-60 % view: six entries in ten).
    const int64_t cells = this->Mesh->GetNumberOfCells();
    this->VisibleCells.resize(static_cast<size_t>(cells));
    ParallelFor(this->Threads, cells, 16384,
      [&](int64_t begin, int64_t end)
      {
        table.MarkVisible(
          &this->Mesh->GetScalarRange(begin), end - begin, this->VisibleCells.data() + begin);
      });
    walker.VisibleCells = this->VisibleCells.data();
  }
  if (walker.Opaque && this->CutSet)
  {
    walker.Cut = this->Cut.data();
  }
  else if (walker.Opaque && this->RecordProfile)
  {
    walker.ProfileOut = this->Profile;
    walker.LastBinOut = this->LastBin.data();
    walker.Bound = this->Bound;
  }
  // Alone, pass 1 marches a tile without the stop's bookkeeping first and keeps it if no ray
  // came near the threshold: the stop would have stopped none, so the samples and moments
  // are the same, and the cut is none. A tile that came near is marched again with the stop,
  // and so is every tile after it (an opaque view loses a tile per thread).
  Walker plain = walker;
  plain.Opaque = nullptr;
  plain.ProfileOut = nullptr;
  plain.LastBinOut = nullptr;
  int64_t first = 0;
  int64_t last = 0;
  this->TilesOf(rows, first, last);
  // Each thread's first tile near the threshold is marched twice: not on a few tiles a thread.
  const int threads = ThreadsFor(this->Threads) > 0 ? ThreadsFor(this->Threads)
                                                    : tbb::this_task_arena::max_concurrency();
  const bool speculate = this->OpaqueAlone && walker.ProfileOut && !walker.Bound &&
    last - first >= kTilesPerThreadWithoutStop * threads;
  std::atomic<bool> opaqueSeen{ false };
  std::atomic<int64_t> unstopped{ 0 };
  tbb::combinable<Visitor> visitors([&prototype] { return prototype; });
  tbb::combinable<int64_t> samples([] { return int64_t(0); });
  tbb::combinable<std::vector<RaySetup>> rayBuffers;
  ParallelFor(this->Threads, last - first, 1,
    [&](int64_t begin, int64_t end)
    {
      Visitor& visitor = visitors.local();
      std::vector<RaySetup>& rays = rayBuffers.local();
      for (int64_t t = first + begin; t < first + end; ++t)
      {
        if (this->Bins->Empty(t) || (skipTiles && (*skipTiles)[t]))
        {
          continue;
        }
        const TileRect tile = grid.Tile(t);
        this->SetUpRays(tile, rays);
        if (speculate && !opaqueSeen.load(std::memory_order_relaxed))
        {
          samples.local() += plain.Tile(rays, tile, rows.J0, visitor);
          if (this->KeepUnstoppedTile(visitor, Walker::Shifted(tile, rows.J0), t))
          {
            ++unstopped;
            continue;
          }
          opaqueSeen = true;
        }
        samples.local() += walker.Tile(rays, tile, rows.J0, visitor);
      }
    });
  this->LastSamples = samples.combine(std::plus<int64_t>());
  this->LastUnstoppedTiles = unstopped.load();
}

//------------------------------------------------------------------------------
template <class Visitor>
bool VolumeRayMarcher::KeepUnstoppedTile(Visitor&, const TileRect&, int64_t)
{
  return false; // only pass 1's moments are marched without the stop first
}

template <int N>
bool VolumeRayMarcher::KeepUnstoppedTile(
  visitors::Moments<N>& visitor, const TileRect& inBand, int64_t tile)
{
  // The stop's quanta round each sample's absorbance down, so a pixel whose b0 stays below
  // the threshold (less a margin for b0's rounding) never reached it in quanta either.
  const double limit = OpaqueBins::kOpaque * (1 - 1e-6) / this->Opaque.QuantaPerAbsorbance;
  bool near = false;
  for (int p = 0; p < inBand.Pixels() && !near; ++p)
  {
    near = visitor.Sums[p * (N + 1)] >= limit;
  }
  if (!near)
  {
    return true;
  }
  // Undone: the tile's moments (pass 1 starts from zero, this mesh alone) and its samples.
  for (int p = 0; p < inBand.Pixels(); ++p)
  {
    std::fill_n(visitor.Output + (N + 1) * inBand.ImagePixel(p, visitor.Width), N + 1, 0.0);
  }
  SampleCache& cache = *this->Cache;
  if (visitor.Recording && static_cast<size_t>(tile) < cache.Tiles.size() && cache.Kept[tile])
  {
    cache.Bytes -= cache.Tiles[tile].Bytes();
    cache.Tiles[tile].Clear();
    cache.Kept[tile] = 0;
  }
  return false;
}

//------------------------------------------------------------------------------
void VolumeRayMarcher::LendOpaqueProfileMemory(unsigned char* bytes, size_t size)
{
  if (this->Profile && this->Profile != this->OwnProfile.data())
  {
    this->Profile = nullptr; // in the memory lent before, which its owner takes back
    this->ProfileValues = 0;
  }
  this->LentProfile = bytes;
  this->LentProfileBytes = bytes ? size : 0;
}

//------------------------------------------------------------------------------
void VolumeRayMarcher::RenderExact(const TransferTable& table, float* rgba)
{
  visitors::Exact visitor(rgba, this->Width());
  this->March(visitor, table);
}

//------------------------------------------------------------------------------
template <int N>
void VolumeRayMarcher::AccumulateMoments(const TransferTable& table, const LogDepthWarp& warp,
  double* moments, bool keepOwn, const RowBand& rows)
{
  SampleCache& cache = *this->Cache;
  int64_t first = 0;
  int64_t last = 0;
  this->TilesOf(rows, first, last);
  cache.Empty(static_cast<size_t>(this->Bins->Grid.Count()), static_cast<size_t>(first),
    static_cast<size_t>(last));
  const LatticeDepthWarp latticeWarp(warp, table.GetSampleSpacing());
  // The cache keeps its samples' depths as indices into this frame's table where it can.
  cache.SetDepthTable(latticeWarp.GetEntries(),
    cache.MaxBytes > 0 ? latticeWarp.GetNumberOfEntries() : 0, latticeWarp.GetBase());
  visitors::Moments<N> visitor(moments, this->Width(), &latticeWarp, &cache);
  visitor.Weighted = this->SampleEndWeights != EndWeightsMode::Off; // the cache keeps the weights
  this->OwnMomentsOrder = 0;
  // Hybrid (keepOwn) promises the exact ordered blend of a rank's own samples: every sample
  // is marched. Pass 2 stops where this pass did, or at the cut ApplyOpaqueCut agreed.
  this->Opaque = OpaqueBins::Make(
    keepOwn ? 0.0 : this->OpaqueAbsorbance, warp.Near(), warp.Far(), table.GetSampleSpacing());
  this->CutSet = false;
  const size_t bandPixels = this->Camera ? static_cast<size_t>(this->Width()) *
      static_cast<size_t>(std::max(0, std::min(rows.J1, this->Camera->GetHeight()) - rows.J0))
                                         : 0;
  const size_t profiled = this->Opaque.Active() ? bandPixels : 0;
  this->ProfileValues = profiled * OpaqueBins::kBins;
  if (this->LentProfile && this->LentProfileBytes >= this->ProfileValues * sizeof(uint16_t))
  {
    // Made there by writing them (uint16_t is implicit-lifetime; operator new aligns for it).
    this->Profile = reinterpret_cast<uint16_t*>(this->LentProfile);
  }
  else
  {
    ReserveInHugePages(this->OwnProfile, this->ProfileValues);
    this->OwnProfile.resize(this->ProfileValues);
    this->Profile = this->OwnProfile.data();
  }
  std::fill_n(this->Profile, this->ProfileValues, uint16_t(0));
  ReserveInHugePages(this->LastBin, profiled);
  this->LastBin.assign(profiled, 0);
  this->Cut.clear();
  visitor.KeepOrder = this->Opaque.Active(); // the cut reads the cached samples' bins
  if (keepOwn && this->Camera)
  {
    const int height = this->Camera->GetHeight();
    const size_t pixels = static_cast<size_t>(this->Camera->GetWidth()) *
      static_cast<size_t>(std::max(0, std::min(rows.J1, height) - rows.J0));
    this->OwnMoments.assign(pixels * (N + 1), 0.0);
    visitor.Own = this->OwnMoments.data();
  }
  else
  {
    std::vector<double>().swap(this->OwnMoments); // no memory unless Hybrid asks for it
  }
  this->RecordProfile = true;
  this->OpaqueAlone = this->OpaqueStopAlone && this->Opaque.Active() && !visitor.Own;
  this->March(visitor, table, nullptr, rows);
  this->OpaqueAlone = false;
  this->RecordProfile = false;
  this->OwnMomentsOrder = visitor.Own ? N : 0;
  cache.Valid = cache.MaxBytes > 0;
  cache.Table = &table;
  cache.WarpNear = warp.Near();
  cache.WarpFar = warp.Far();
  cache.Moments = N;
}

//------------------------------------------------------------------------------
template <int N>
void VolumeRayMarcher::ApplyOpaqueCut(const TransferTable& table, const LogDepthWarp& warp,
  const uint16_t* profile, double* moments, const RowBand& rows)
{
  if (!this->Opaque.Active() || !this->Camera)
  {
    return;
  }
  const size_t pixels = this->LastBin.size();
  this->Cut.resize(pixels);
  for (size_t p = 0; p < pixels; ++p)
  {
    this->Cut[p] = static_cast<uint8_t>(CutBin(profile + p * OpaqueBins::kBins));
  }
  this->CutSet = true;
  // Pixels that summed samples past their cut: from the cache where it holds their tile, else
  // their tile is zeroed and marched again up to the cut (skip[t] == 0).
  SampleCache& cache = *this->Cache;
  const bool cached = cache.Valid && cache.Table == &table && cache.Moments == N;
  const TileGrid& grid = this->Bins->Grid;
  std::vector<uint8_t> skip(static_cast<size_t>(grid.Count()), 1);
  std::atomic<bool> march{ false };
  int64_t first = 0;
  int64_t last = 0;
  this->TilesOf(rows, first, last);
  const int width = this->Width();
  ParallelFor(this->Threads, last - first, 1,
    [&](int64_t begin, int64_t end)
    {
      for (int64_t t = first + begin; t < first + end; ++t)
      {
        const TileRect inBand = Walker::Shifted(grid.Tile(t), rows.J0);
        if (this->Bins->Empty(t) ||
          !TileCrossesCut(inBand, width, this->Cut.data(), this->LastBin.data()))
        {
          continue;
        }
        if (cached && cache.Kept[t])
        {
          CutCachedTile<N>(cache.Tiles[t], inBand, width, this->Opaque, this->Cut.data(),
            this->LastBin.data(), table, moments, cache.DepthTable.data(), cache.DepthBase);
          continue;
        }
        for (int p = 0; p < inBand.Pixels(); ++p)
        {
          std::fill_n(moments + (N + 1) * inBand.ImagePixel(p, width), N + 1, 0.0);
        }
        skip[t] = 0;
        march = true;
      }
    });
  const int64_t pass1 = this->LastSamples;
  this->LastCutSamples = 0;
  if (march)
  {
    const LatticeDepthWarp latticeWarp(warp, table.GetSampleSpacing());
    visitors::Moments<N> visitor(moments, width, &latticeWarp, nullptr);
    visitor.Weighted = this->SampleEndWeights != EndWeightsMode::Off;
    this->March(visitor, table, &skip, rows);
    this->LastCutSamples = this->LastSamples;
  }
  this->LastSamples = pass1;
}

//------------------------------------------------------------------------------
template <int N>
void VolumeRayMarcher::RedoOpaqueTiles(const TransferTable& table, const LogDepthWarp& warp,
  const uint8_t* unresolved, double* moments, const RowBand& rows)
{
  this->LastRedoSamples = 0;
  if (!this->Opaque.Active() || !this->Camera || this->CutSet)
  {
    return;
  }
  // The tiles to march again start afresh: no moments, no cached samples (the cache's
  // budget gets their bytes back; pass 2 marches a tile that does not fit again).
  SampleCache& cache = *this->Cache;
  const TileGrid& grid = this->Bins->Grid;
  std::vector<uint8_t> skip(static_cast<size_t>(grid.Count()), 1);
  int64_t first = 0;
  int64_t last = 0;
  this->TilesOf(rows, first, last);
  const int width = this->Width();
  bool any = false;
  for (int64_t t = first; t < last; ++t)
  {
    const TileRect inBand = Walker::Shifted(grid.Tile(t), rows.J0);
    bool open = false;
    for (int p = 0; p < inBand.Pixels() && !open; ++p)
    {
      open = unresolved[inBand.ImagePixel(p, width)] != 0;
    }
    if (!open)
    {
      continue;
    }
    skip[t] = 0;
    any = true;
    for (int p = 0; p < inBand.Pixels(); ++p)
    {
      std::fill_n(moments + (N + 1) * inBand.ImagePixel(p, width), N + 1, 0.0);
      // Its profile too: the processes' sum may have been made in it (GetOpaqueProfileToSum),
      // and a tile without cells is not marched to write its zeros again.
      if (this->Profile)
      {
        std::fill_n(this->Profile + OpaqueBins::kBins * inBand.ImagePixel(p, width),
          OpaqueBins::kBins, uint16_t(0));
      }
    }
    if (static_cast<size_t>(t) < cache.Tiles.size())
    {
      if (cache.Kept[t])
      {
        cache.Bytes -= cache.Tiles[t].Bytes();
      }
      cache.Tiles[t].Clear();
      cache.Kept[t] = 0;
    }
  }
  if (!any)
  {
    return;
  }
  const bool caching = cache.Valid && cache.Table == &table && cache.Moments == N;
  cache.Record = caching && cache.Arena.Capacity() > 0;
  const LatticeDepthWarp latticeWarp(warp, table.GetSampleSpacing());
  visitors::Moments<N> visitor(moments, width, &latticeWarp, caching ? &cache : nullptr);
  visitor.Weighted = this->SampleEndWeights != EndWeightsMode::Off;
  visitor.KeepOrder = true;
  const uint8_t* bound = this->Bound;
  this->Bound = nullptr;
  const int64_t pass1 = this->LastSamples;
  this->RecordProfile = true;
  this->March(visitor, table, &skip, rows);
  this->RecordProfile = false;
  this->Bound = bound;
  this->LastRedoSamples = this->LastSamples;
  this->LastSamples = pass1;
}

//------------------------------------------------------------------------------
template <int N>
void VolumeRayMarcher::AccumulateColour(const TransferTable& table, const LogDepthWarp& warp,
  const double* moments, const MomentSettings<N>& settings, double* colourSums, bool hybrid,
  const RowBand& rows)
{
  const SampleCache& cache = *this->Cache;
  const bool usable = cache.Valid && cache.Table == &table && cache.Moments == N &&
    cache.WarpNear == warp.Near() && cache.WarpFar == warp.Far();
  // The tiles the cache does not hold (all of them without a cache) are marched again.
  auto run = [&](auto& visitor)
  {
    const int64_t replayed = usable ? this->ReplayColour(table, visitor, rows) : 0;
    this->March(visitor, table, usable ? &cache.Kept : nullptr, rows);
    return replayed;
  };
  int64_t replayed = 0;
  std::atomic<int64_t> hidden{ 0 };
  if (hybrid && this->OwnMomentsOrder == N)
  {
    visitors::HybridColour<N> visitor(
      colourSums, this->Width(), &warp, moments, this->OwnMoments.data(), settings);
    replayed = run(visitor);
  }
  else
  {
    visitors::Colour<N> visitor(colourSums, this->Width(), &warp, moments, settings);
    visitor.HiddenWeight = this->HiddenSampleWeight;
    visitor.Hidden = &hidden;
    replayed = run(visitor);
  }
  this->LastSamples += replayed;
  this->LastReplayed = replayed;
  this->LastHidden = hidden.load();
  this->LastColourCacheShare =
    this->LastSamples > 0 ? static_cast<double>(replayed) / this->LastSamples : (usable ? 1 : 0);
  this->LastHiddenShare =
    this->LastSamples > 0 ? static_cast<double>(hidden.load()) / this->LastSamples : 0.0;
}

//------------------------------------------------------------------------------
template <class Visitor>
int64_t VolumeRayMarcher::ReplayColour(
  const TransferTable& table, const Visitor& prototype, const RowBand& rows)
{
  // Pass 2 from pass 1's samples: the same samples with the same values, re-weighted by the
  // transmittance reconstructed from the global moments; no clipping, no interpolation.
  const TileGrid& grid = this->Bins->Grid;
  tbb::combinable<Visitor> perThread([&prototype] { return prototype; });
  tbb::combinable<int64_t> samples([] { return int64_t(0); });
  // Each thread's compact tiles expanded in its own scratch (in the processor's cache).
  tbb::enumerable_thread_specific<ExpandedTile> expanded;
  const SampleCache& cache = *this->Cache;
  int64_t first = 0;
  int64_t last = 0;
  this->TilesOf(rows, first, last);
  last = std::min(last, static_cast<int64_t>(cache.Tiles.size()));
  ParallelFor(this->Threads, std::max<int64_t>(0, last - first), 1,
    [&](int64_t begin, int64_t end)
    {
      Visitor& visitor = perThread.local();
      for (int64_t t = first + begin; t < first + end; ++t)
      {
        const CachedTile& recorded = cache.Tiles[t];
        if (!cache.Kept[t] || recorded.Count() == 0)
        {
          continue;
        }
        visitor.ReplayTile(Walker::Shifted(grid.Tile(t), rows.J0),
          Expand(recorded, cache.DepthTable, cache.DepthBase, expanded.local(),
            Visitor::ReadsCacheOrder),
          table);
        samples.local() += static_cast<int64_t>(recorded.Count());
      }
    });
  return samples.combine(std::plus<int64_t>());
}

//------------------------------------------------------------------------------
void VolumeRayMarcher::RenderSegments(const TransferTable& table, SegmentImage& segments)
{
  const TileGrid& grid = this->Bins->Grid;
  segments.Reset(this->Width(), this->Camera ? this->Camera->GetHeight() : 0);
  const int64_t tiles = this->Camera ? grid.Count() : 0;
  std::vector<visitors::TileSegments> perTile(static_cast<size_t>(tiles));
  visitors::Runs visitor(&perTile);
  this->March(visitor, table);

  // Tiles were filled in parallel and in any order; the compressed rows are in pixel order.
  for (int64_t t = 0; t < tiles; ++t)
  {
    const TileRect tile = grid.Tile(t);
    for (size_t p = 0; p < perTile[t].Counts.size(); ++p)
    {
      segments.Offsets[tile.ImagePixel(static_cast<int>(p), grid.Width) + 1] = perTile[t].Counts[p];
    }
  }
  PrefixSum(segments.Offsets);
  segments.Segments.resize(static_cast<size_t>(segments.Offsets.back()));
  ParallelFor(this->Threads, tiles, 1,
    [&](int64_t begin, int64_t end)
    {
      for (int64_t t = begin; t < end; ++t)
      {
        const visitors::TileSegments& tileSegments = perTile[t];
        const TileRect tile = grid.Tile(t);
        auto next = tileSegments.Segments.begin();
        for (size_t p = 0; p < tileSegments.Counts.size(); ++p)
        {
          const int32_t n = tileSegments.Counts[p];
          std::copy(next, next + n,
            segments.Segments.begin() +
              segments.Offsets[tile.ImagePixel(static_cast<int>(p), grid.Width)]);
          next += n;
        }
      }
    });
}

//------------------------------------------------------------------------------
void VolumeRayMarcher::CountSegments(int32_t* counts)
{
  // Segments take no samples, so the transfer function is never read.
  static const TransferTable none(0.0, 1.0, {}, {}, 1.0, 1.0);
  double diagonal = 1.0;
  if (this->Mesh && this->Mesh->GetNumberOfCells() > 0)
  {
    const auto& b = this->Mesh->GetBounds();
    diagonal = std::sqrt((b[1] - b[0]) * (b[1] - b[0]) + (b[3] - b[2]) * (b[3] - b[2]) +
      (b[5] - b[4]) * (b[5] - b[4]));
  }
  visitors::SegmentCounts visitor(counts, this->Width(), 1e-9 * diagonal);
  this->March(visitor, none);
}

template void VolumeRayMarcher::AccumulateMoments<4>(
  const TransferTable&, const LogDepthWarp&, double*, bool, const RowBand&);
template void VolumeRayMarcher::AccumulateMoments<6>(
  const TransferTable&, const LogDepthWarp&, double*, bool, const RowBand&);
template void VolumeRayMarcher::AccumulateMoments<8>(
  const TransferTable&, const LogDepthWarp&, double*, bool, const RowBand&);
template void VolumeRayMarcher::ApplyOpaqueCut<4>(
  const TransferTable&, const LogDepthWarp&, const uint16_t*, double*, const RowBand&);
template void VolumeRayMarcher::ApplyOpaqueCut<6>(
  const TransferTable&, const LogDepthWarp&, const uint16_t*, double*, const RowBand&);
template void VolumeRayMarcher::ApplyOpaqueCut<8>(
  const TransferTable&, const LogDepthWarp&, const uint16_t*, double*, const RowBand&);
template void VolumeRayMarcher::RedoOpaqueTiles<4>(
  const TransferTable&, const LogDepthWarp&, const uint8_t*, double*, const RowBand&);
template void VolumeRayMarcher::RedoOpaqueTiles<6>(
  const TransferTable&, const LogDepthWarp&, const uint8_t*, double*, const RowBand&);
template void VolumeRayMarcher::RedoOpaqueTiles<8>(
  const TransferTable&, const LogDepthWarp&, const uint8_t*, double*, const RowBand&);
template void VolumeRayMarcher::AccumulateColour<4>(const TransferTable&, const LogDepthWarp&,
  const double*, const MomentSettings<4>&, double*, bool, const RowBand&);
template void VolumeRayMarcher::AccumulateColour<6>(const TransferTable&, const LogDepthWarp&,
  const double*, const MomentSettings<6>&, double*, bool, const RowBand&);
template void VolumeRayMarcher::AccumulateColour<8>(const TransferTable&, const LogDepthWarp&,
  const double*, const MomentSettings<8>&, double*, bool, const RowBand&);

} // namespace apc
