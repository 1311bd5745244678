#include "apcVolumeRayMarcher.h"

#include "apcCellInterpolation.h"
#include "apcColourVisitors.h"
#include "apcCompressedRows.h"
#include "apcLatticeJitter.h"
#include "apcOpaqueCut.h"
#include "apcParallel.h"
#include "apcRayClip.h"
#include "apcRayVisitors.h"
#include "apcRayWalk.h"
#include "apcSampleCache.h"
#include "apcTileBins.h"

#include <tbb/combinable.h>

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>
#include <functional>
#include <limits>
#include <utility>

namespace apc
{

using walk::CellPlanes;
using walk::kSampleTolerance;
using walk::Lattice;
using walk::RayProgress;
using walk::RaySetup;
using walk::TileRays;
static_assert(walk::kTilePixels == VolumeRayMarcher::kTileSize * VolumeRayMarcher::kTileSize,
  "a tile's progress holds every pixel of it");

//------------------------------------------------------------------------------
// Marches one tile: all its cells against all its pixels.
struct VolumeRayMarcher::Walker
{
  const CellMesh& Mesh;
  const TileBins& Bins;
  const TransferTable& Table;
  double FarLimit;
  bool SharedOrigin;        // a perspective camera: every ray starts at the eye
  const OpaqueBins* Opaque; // the frame's opaque stop, or null

  Lattice Grid; // the samples t_k of every ray
  // Largest scalar error (scalar units) of a cell sampled by its linear inverse.
  double LinearTolerance;
  // With Opaque: the agreed last bin of each pixel of the band (rays stop there), or null for
  // pass 1's own stop, which writes each pixel's profile and last bin to the band's buffers.
  const uint8_t* Cut = nullptr;
  uint16_t* ProfileOut = nullptr;
  uint8_t* LastBinOut = nullptr;
  int BandWidth = 0;

  // A cell's scalars: its own (or none needed), linear along the ray, a twisted pyramid's
  // closed-form inverse, or by Newton.
  enum class Sampling
  {
    Constant,
    Linear,
    Pyramid,
    Follow
  };

  // What a cell needs while its rays are marched; reused from cell to cell.
  struct CellState
  {
    CellPlanes Planes;
    CellCorners Corners;
    CellInterpolator Interpolator;
    int64_t Cell = -1;
    double Near = 0; // no point of the cell lies at a smaller t (TileBins::Near)
    double Lo = 0;   // the cell's scalar range
    double Hi = 0;
    bool Interpolate = false; // point scalars of a visible cell
    bool HaveCorners = false; // Corners and Interpolator are set up
    bool Linear = false;      // the interpolator's linear inverse is close enough
    TransferSample CellSample{};
    double CellScalar = std::numeric_limits<double>::quiet_NaN();
    // Newton starts a ray from the first sample of the cell's previous ray (a neighbouring
    // pixel at about the same depth), then goes on from the previous sample.
    NewtonMemory FirstMemory;
    double Centre[3] = { 0, 0, 0 };
    // The tile's rays clipped against the cell.
    walk::ClippedRays Clipped;
  };

  // Sets state up for cell; false if the cell adds nothing to what the visitor makes.
  template <class Visitor>
  bool SetUp(
    int64_t cell, const RaySetup& anyRay, CellState& state, const RayProgress& progress) const
  {
    constexpr bool keepsTransparent = Visitor::WantsSegments || Visitor::WantsTransparentSamples;
    state.Near = this->Bins.Near[cell];
    if (Visitor::StopsWhenOpaque && state.Near >= progress.TileStop)
    {
      return false; // behind every ray of the tile, all opaque
    }
    const bool cellScalars = this->Mesh.HasCellScalars();
    const auto& range = this->Mesh.GetScalarRange(cell);
    state.Lo = range[0];
    state.Hi = range[1];
    // A cell whose scalars all map to zero opacity adds nothing: skip it, unless the visitor
    // needs its extent (segment runs go on through transparent cells).
    const bool visible = this->Table.MayBeVisible(state.Lo, state.Hi);
    if (!visible && !keepsTransparent)
    {
      return false;
    }
    state.CellSample = TransferSample{};
    state.CellScalar = std::numeric_limits<double>::quiet_NaN();
    if (cellScalars && visible)
    {
      state.CellScalar = this->Mesh.CellScalars[cell];
      state.CellSample = this->Table.Lookup(state.CellScalar);
    }
    int planeCount = 0;
    const FacePlane* planes = this->Mesh.GetPlanes(cell, planeCount);
    if (planeCount == 0)
    {
      return false; // a cell the mesh left out (see CellMesh::GetNumberOfSkippedCells)
    }
    state.Planes.Set(planes, planeCount, anyRay, this->SharedOrigin);
    state.Cell = cell;
    state.Interpolate = visible && !cellScalars;
    state.HaveCorners = false;
    state.FirstMemory = NewtonMemory();
    return true;
  }

  // One cell against the tile's rays; returns the lattice samples taken.
  template <class Visitor>
  int64_t Cell(int64_t cell, const std::vector<RaySetup>& rays, const TileRays& packed,
    const TileRect& tile, Visitor& visitor, CellState& state, RayProgress& progress) const
  {
    if (!this->SetUp<Visitor>(cell, rays.front(), state, progress))
    {
      return 0;
    }
    const auto& r = this->Bins.Rects[cell];
    const int i0 = std::max(r[0], tile.I0);
    const int i1 = std::min(r[2], tile.I1 - 1);
    const int j0 = std::max(r[1], tile.J0);
    const int j1 = std::min(r[3], tile.J1 - 1);
    if (i0 > i1 || j0 > j1)
    {
      return 0;
    }
    // All the rays first, then those with a sample: the clipping runs several rays at a
    // time, and a ray's interval does not depend on the samples of other rays.
    const int width = tile.Width();
    const walk::RayRect rect{ (j0 - tile.J0) * width + (i0 - tile.I0), i1 - i0 + 1, j1 - j0 + 1,
      width };
    // A visitor of segments sees every ray inside, with a sample or not.
    constexpr bool allInside = Visitor::WantsSegments || !Visitor::WantsSamples;
    walk::ClippedRays& c = state.Clipped;
    const int hits =
      walk::ClipRays(state.Planes, packed, rect, Visitor::StopsWhenOpaque ? progress.Stop : nullptr,
        state.Near, allInside ? nullptr : &this->Grid, c);
    int64_t samples = 0;
    for (int h = 0; h < hits; ++h)
    {
      const int l = c.Hits[h];
      const int64_t k = allInside ? 0 : static_cast<int64_t>(c.Lattice[l]);
      samples += this->Ray(l, rays[l], c.Tin[l], c.Tout[l], k, visitor, state, progress);
    }
    return samples;
  }

  // The tile's ray local inside the cell state holds, over [tin, tout) from lattice index k
  // on (the first one there, unless the visitor wants segments): sampled; returns the samples
  // taken.
  template <class Visitor>
  int64_t Ray(int local, const RaySetup& ray, double tin, double tout, int64_t k, Visitor& visitor,
    CellState& state, RayProgress& progress) const
  {
    visitor.Segment(local, tin, tout);
    if (!Visitor::WantsSamples)
    {
      return 0;
    }
    if (Visitor::WantsSegments)
    {
      k = this->Grid.First(tin, ray.Offset);
    }
    if (state.Interpolate && !state.HaveCorners)
    {
      // Set up lazily: most binned cells miss most of their rectangle's rays.
      this->Mesh.GetCorners(state.Cell, state.Corners);
      state.Interpolator.Set(state.Corners);
      ParametricCenter(state.Corners.Shape, state.Centre);
      state.Linear = state.Interpolator.IsAffine() ||
        state.Interpolator.GetLinearScalarError() <= this->LinearTolerance;
      state.HaveCorners = true;
    }
    if (!state.Interpolate)
    {
      return this->Samples<Sampling::Constant>(local, ray, k, tout, visitor, state, progress);
    }
    if (state.Linear)
    {
      return this->Samples<Sampling::Linear>(local, ray, k, tout, visitor, state, progress);
    }
    if (state.Interpolator.HasPyramidInverse())
    {
      return this->Samples<Sampling::Pyramid>(local, ray, k, tout, visitor, state, progress);
    }
    return this->Samples<Sampling::Follow>(local, ray, k, tout, visitor, state, progress);
  }

  // The lattice samples of the ray in [tin, tout), the same points on every rank; one loop
  // per way of finding the scalar.
  template <Sampling How, class Visitor>
  int64_t Samples(int local, const RaySetup& ray, int64_t k, double tout, Visitor& visitor,
    CellState& state, RayProgress& progress) const
  {
    double p0[3] = { 0, 0, 0 };
    double dp[3] = { 0, 0, 0 };
    NewtonMemory memory;
    if (How == Sampling::Linear || How == Sampling::Pyramid)
    {
      state.Interpolator.LinearRay(ray.O, ray.D, p0, dp);
    }
    else if (How == Sampling::Follow)
    {
      memory = state.FirstMemory;
    }
    double pcoords[3] = { state.Centre[0], state.Centre[1], state.Centre[2] };
    bool first = How == Sampling::Follow;
    int64_t samples = 0;
    // Pass 1's own stop: the bin of k, and the first index past it.
    const bool own = Visitor::StopsWhenOpaque && progress.Bins;
    int bin = own ? progress.Bins->Of(k) : 0;
    int64_t binEnd = own ? progress.Bins->End(bin) : 0;
    for (double t = this->Grid.At(k, ray.Offset); t < tout; ++k, t = this->Grid.At(k, ray.Offset))
    {
      TransferSample s = state.CellSample;
      double scalar = state.CellScalar;
      if (How == Sampling::Linear || How == Sampling::Pyramid)
      {
        for (int d = 0; d < 3; ++d)
        {
          pcoords[d] = p0[d] + t * dp[d];
        }
      }
      else if (How == Sampling::Follow)
      {
        const double x[3] = { ray.O[0] + t * ray.D[0], ray.O[1] + t * ray.D[1],
          ray.O[2] + t * ray.D[2] };
        state.Interpolator.Follow(x, memory, pcoords, kSampleTolerance);
        if (first)
        {
          state.FirstMemory = memory;
          first = false;
        }
      }
      if (How != Sampling::Constant)
      {
        // Clamped to the cell's range: a point inside the planes but outside the
        // interpolating map's cell (non-planar faces) must not extrapolate past the corners,
        // and it is what makes skipping by range exact.
        const double interpolated = How == Sampling::Linear
          ? state.Interpolator.LinearScalarAt(pcoords)
          : (How == Sampling::Pyramid ? state.Interpolator.PyramidScalarAt(pcoords)
                                      : state.Interpolator.ScalarAt(pcoords));
        scalar = std::min(std::max(interpolated, state.Lo), state.Hi);
        s = this->Table.Lookup(scalar);
      }
      ++samples;
      if (s.Absorbance > 0 || Visitor::WantsTransparentSamples)
      {
        visitor.Sample(local, k, t, scalar, s);
        if (own)
        {
          for (; k >= binEnd; binEnd = progress.Bins->End(++bin))
          {
          }
          if (progress.Add(local, k, bin, s.Absorbance))
          {
            // Opaque: nothing past the end of the farthest sample's bin is taken; what lies
            // in front of it still is (this pixel's profile stays complete up to there).
            const int64_t edge = progress.StopIndex(local);
            const double stop = edge == std::numeric_limits<int64_t>::max()
              ? std::numeric_limits<double>::infinity()
              : this->Grid.At(edge, ray.Offset);
            progress.SetStop(local, stop);
            tout = std::min(tout, stop);
          }
        }
      }
    }
    return samples;
  }

  // The visitor sees the tile rowOffset rows lower (where it lies in a band's buffers).
  template <class Visitor>
  int64_t Tile(
    const std::vector<RaySetup>& rays, const TileRect& tile, int rowOffset, Visitor& visitor) const
  {
    int64_t samples = 0;
    CellState state;
    RayProgress progress;
    const bool stops = Visitor::StopsWhenOpaque && this->Opaque;
    progress.Begin(tile.Pixels(), stops && !this->Cut ? this->Opaque : nullptr);
    const TileRect inBand = Shifted(tile, rowOffset);
    if (stops && this->Cut)
    {
      this->StopAtCut(rays, inBand, progress);
    }
    TileRays packed;
    packed.Set(rays.data(), tile.Pixels(), this->FarLimit);
    visitor.BeginTile(inBand);
    for (int64_t b = this->Bins.Start[tile.Index]; b < this->Bins.Start[tile.Index + 1]; ++b)
    {
      samples += this->Cell(this->Bins.Cells[b], rays, packed, tile, visitor, state, progress);
    }
    visitor.EndTile(inBand);
    if (progress.Bins && this->ProfileOut)
    {
      for (int p = 0; p < tile.Pixels(); ++p)
      {
        const int64_t pixel = inBand.ImagePixel(p, this->BandWidth);
        std::copy(progress.Profile[p], progress.Profile[p] + OpaqueBins::kBins,
          this->ProfileOut + pixel * OpaqueBins::kBins);
        this->LastBinOut[pixel] = static_cast<uint8_t>(progress.LastBin(p));
      }
    }
    return samples;
  }

  // Every ray of the tile stops at the end of its pixel's agreed last bin.
  void StopAtCut(
    const std::vector<RaySetup>& rays, const TileRect& inBand, RayProgress& progress) const
  {
    for (int p = 0; p < inBand.Pixels(); ++p)
    {
      const int last = this->Cut[inBand.ImagePixel(p, this->BandWidth)];
      if (last < OpaqueBins::kBins - 1)
      {
        progress.SetStop(p, this->Grid.At(this->Opaque->End(last), rays[p].Offset));
      }
    }
  }

  static TileRect Shifted(TileRect tile, int rows)
  {
    tile.J0 -= rows;
    tile.J1 -= rows;
    return tile;
  }
};

//------------------------------------------------------------------------------
VolumeRayMarcher::VolumeRayMarcher()
  : Bins(new TileBins)
  , Cache(new SampleCache)
{
}

VolumeRayMarcher::~VolumeRayMarcher() = default;

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
  this->Cache->Clear();
  this->OwnMomentsOrder = 0;
  this->Camera.reset(new RayCamera(camera));
  const size_t pixels = static_cast<size_t>(camera.GetWidth()) * camera.GetHeight();
  this->RayEnds = std::move(rayEnds);
  if (this->RayEnds.size() != pixels)
  {
    this->RayEnds.assign(pixels, std::numeric_limits<float>::infinity());
  }
  BinCells(this->Mesh, camera, kTileSize, this->Threads, *this->Bins);
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
  if (walker.Opaque && this->CutSet)
  {
    walker.Cut = this->Cut.data();
  }
  else if (walker.Opaque && this->RecordProfile)
  {
    walker.ProfileOut = this->Profile.data();
    walker.LastBinOut = this->LastBin.data();
  }
  tbb::combinable<Visitor> visitors([&prototype] { return prototype; });
  tbb::combinable<int64_t> samples([] { return int64_t(0); });
  tbb::combinable<std::vector<RaySetup>> rayBuffers;
  int64_t first = 0;
  int64_t last = 0;
  this->TilesOf(rows, first, last);
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
        rays.resize(tile.Pixels());
        for (int p = 0; p < tile.Pixels(); ++p)
        {
          const Ray ray =
            this->Camera->PixelRay(tile.I0 + p % tile.Width(), tile.J0 + p / tile.Width());
          RaySetup& r = rays[p];
          std::copy(ray.Origin.begin(), ray.Origin.end(), r.O);
          std::copy(ray.Direction.begin(), ray.Direction.end(), r.D);
          r.End = this->RayEnds[tile.ImagePixel(p, grid.Width)];
          r.Offset = this->LatticeJitter
            ? LatticeOffset(this->Camera->GetCropI0() + tile.I0 + p % tile.Width(),
                this->Camera->GetCropJ0() + tile.J0 + p / tile.Width())
            : 0.0;
        }
        samples.local() += walker.Tile(rays, tile, rows.J0, visitor);
      }
    });
  this->LastSamples = samples.combine(std::plus<int64_t>());
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
  visitors::Moments<N> visitor(moments, this->Width(), &warp, &cache);
  this->OwnMomentsOrder = 0;
  // Hybrid (keepOwn) promises the exact ordered blend of a rank's own samples: every sample
  // is marched. Pass 2 stops where this pass did, or at the cut ApplyOpaqueCut agreed.
  this->Opaque = OpaqueBins::Make(
    keepOwn ? 0.0 : this->OpaqueAbsorbance, warp.Near(), warp.Far(), table.GetSampleSpacing());
  this->CutSet = false;
  const size_t bandPixels = this->Camera ? static_cast<size_t>(this->Width()) *
      static_cast<size_t>(std::max(0, std::min(rows.J1, this->Camera->GetHeight()) - rows.J0))
                                         : 0;
  this->Profile.assign(this->Opaque.Active() ? bandPixels * OpaqueBins::kBins : 0, 0);
  this->LastBin.assign(this->Opaque.Active() ? bandPixels : 0, 0);
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
  this->March(visitor, table, nullptr, rows);
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
            this->LastBin.data(), table, moments);
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
    visitors::Moments<N> visitor(moments, width, &warp, nullptr);
    this->March(visitor, table, &skip, rows);
    this->LastCutSamples = this->LastSamples;
  }
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
        if (!cache.Kept[t] || recorded.Samples.empty())
        {
          continue;
        }
        visitor.ReplayTile(Walker::Shifted(grid.Tile(t), rows.J0), recorded, table);
        samples.local() += static_cast<int64_t>(recorded.Samples.size());
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
template void VolumeRayMarcher::AccumulateColour<4>(const TransferTable&, const LogDepthWarp&,
  const double*, const MomentSettings<4>&, double*, bool, const RowBand&);
template void VolumeRayMarcher::AccumulateColour<6>(const TransferTable&, const LogDepthWarp&,
  const double*, const MomentSettings<6>&, double*, bool, const RowBand&);
template void VolumeRayMarcher::AccumulateColour<8>(const TransferTable&, const LogDepthWarp&,
  const double*, const MomentSettings<8>&, double*, bool, const RowBand&);

} // namespace apc
