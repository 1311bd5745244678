#include "apcVolumeRayMarcher.h"

#include "apcPowerMoments.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace apc
{

// Cells per screen tile for the current view.
struct VolumeRayMarcher::Bins
{
  int TilesX = 0;
  int TilesY = 0;
  std::vector<std::array<int, 4>> Rects; // per cell: i0, j0, i1, j1 (inclusive); empty if i0 > i1
  std::vector<int64_t> Start;            // per tile, into Cells
  std::vector<int64_t> Cells;
};

namespace
{
struct TileRect
{
  int I0, J0, I1, J1; // exclusive ends
  int64_t Index;
  int Width() const { return this->I1 - this->I0; }
  int Pixels() const { return (this->I1 - this->I0) * (this->J1 - this->J0); }
};

struct RaySetup
{
  double O[3];
  double D[3];
  double End;
};

struct SampleRecord
{
  int64_t K;
  float Absorbance;
  std::array<float, 3> Colour;
};

// Each pixel's samples of one tile, in arrival order (the exact and segment modes sort them);
// the base of the visitors that need whole rays.
struct PixelSampleLists
{
  std::vector<std::vector<SampleRecord>> Pixels;

  void BeginTile(const TileRect& tile)
  {
    this->Pixels.resize(tile.Pixels());
    for (auto& p : this->Pixels)
    {
      p.clear();
    }
  }
  void Segment(int, double, double) {}
  void Sample(int pixel, int64_t k, double, double, const TransferSample& s)
  {
    this->Pixels[pixel].push_back({ k, s.Absorbance, s.Colour });
  }
  // Pixel p's samples in depth (lattice) order.
  std::vector<SampleRecord>& Sorted(int p)
  {
    auto& samples = this->Pixels[p];
    std::sort(samples.begin(), samples.end(),
      [](const SampleRecord& a, const SampleRecord& b) { return a.K < b.K; });
    return samples;
  }
};

// Front-to-back blending of samples in depth order: the exact reference arithmetic, shared by
// the exact mode and the segments so that one segment equals the exact blend of its run.
struct FrontToBack
{
  double Transmittance = 1.0;
  double Colour[3] = { 0, 0, 0 };

  void Add(const SampleRecord& s)
  {
    const double alpha = -std::expm1(-static_cast<double>(s.Absorbance));
    for (int c = 0; c < 3; ++c)
    {
      this->Colour[c] += this->Transmittance * alpha * s.Colour[c];
    }
    this->Transmittance *= 1.0 - alpha;
  }
};

// Exact mode: each pixel's samples, sorted by lattice index and blended front to back.
struct ExactVisitor : PixelSampleLists
{
  static constexpr bool WantsSegments = false;
  static constexpr bool WantsSamples = true;
  static constexpr bool WantsTransparentSamples = false;
  float* Output;
  int Width;
  void EndTile(const TileRect& tile)
  {
    for (int p = 0; p < tile.Pixels(); ++p)
    {
      if (this->Pixels[p].empty())
      {
        continue;
      }
      FrontToBack blend;
      for (const SampleRecord& s : this->Sorted(p))
      {
        blend.Add(s);
      }
      const int i = tile.I0 + p % tile.Width();
      const int j = tile.J0 + p / tile.Width();
      float* out = this->Output + 4 * (static_cast<int64_t>(j) * this->Width + i);
      for (int c = 0; c < 3; ++c)
      {
        out[c] += static_cast<float>(blend.Colour[c]);
      }
      out[3] += static_cast<float>(1.0 - blend.Transmittance);
    }
  }
};

template <int N>
struct MomentVisitor
{
  static constexpr bool WantsSegments = false;
  static constexpr bool WantsSamples = true;
  static constexpr bool WantsTransparentSamples = false;
  double* Output;
  int Width;
  const LogDepthWarp* Warp;
  VolumeRayMarcher::SampleCache* Cache;
  std::vector<double> Sums;
  std::vector<CachedSample>* Recorded = nullptr;

  void BeginTile(const TileRect& tile)
  {
    this->Sums.assign(tile.Pixels() * (N + 1), 0.0);
    this->Recorded = this->Cache ? &this->Cache->Tiles[tile.Index] : nullptr;
  }
  void Segment(int, double, double) {}
  void Sample(int pixel, int64_t, double t, double scalar, const TransferSample& s)
  {
    const double z = (*this->Warp)(t);
    AccumulatePowerMoments<N>(this->Sums.data() + pixel * (N + 1), z, s.Absorbance);
    if (this->Cache && this->Cache->Record)
    {
      this->Recorded->push_back(
        { static_cast<float>(z), static_cast<float>(scalar), static_cast<uint16_t>(pixel) });
    }
  }
  void EndTile(const TileRect& tile)
  {
    if (this->Recorded && this->Cache->Record)
    {
      // Over budget, the cache is dropped as a whole and pass 2 marches again.
      const size_t bytes = this->Recorded->capacity() * sizeof(CachedSample);
      if (this->Cache->Bytes.fetch_add(bytes) + bytes > this->Cache->MaxBytes)
      {
        this->Cache->Record = false;
      }
    }
    for (int p = 0; p < tile.Pixels(); ++p)
    {
      const int i = tile.I0 + p % tile.Width();
      const int j = tile.J0 + p / tile.Width();
      AddPowerMoments<N>(this->Output + (N + 1) * (static_cast<int64_t>(j) * this->Width + i),
        this->Sums.data() + p * (N + 1));
    }
  }
};

template <int N>
struct ColourVisitor
{
  static constexpr bool WantsSegments = false;
  static constexpr bool WantsSamples = true;
  static constexpr bool WantsTransparentSamples = false;
  double* Output;
  int Width;
  const LogDepthWarp* Warp;
  const double* Moments;
  const MomentSettings<N>* Settings;
  std::vector<MomentTransmittance<N>> Transmittance;
  std::vector<std::array<double, 4>> Sums;

  void BeginTile(const TileRect& tile)
  {
    this->Transmittance.clear();
    this->Transmittance.reserve(tile.Pixels());
    for (int p = 0; p < tile.Pixels(); ++p)
    {
      const int i = tile.I0 + p % tile.Width();
      const int j = tile.J0 + p / tile.Width();
      this->Transmittance.emplace_back(
        this->Moments + (N + 1) * (static_cast<int64_t>(j) * this->Width + i), *this->Settings);
    }
    this->Sums.assign(tile.Pixels(), { 0.0, 0.0, 0.0, 0.0 });
  }
  void Segment(int, double, double) {}
  void Sample(int pixel, int64_t, double t, double, const TransferSample& s)
  {
    this->Add(pixel, (*this->Warp)(t), s);
  }
  void Add(int pixel, double z, const TransferSample& s)
  {
    const double alpha = -std::expm1(-static_cast<double>(s.Absorbance));
    const double w = alpha * this->Transmittance[pixel](z);
    auto& sum = this->Sums[pixel];
    sum[0] += w * s.Colour[0];
    sum[1] += w * s.Colour[1];
    sum[2] += w * s.Colour[2];
    sum[3] += w;
  }
  void EndTile(const TileRect& tile)
  {
    for (int p = 0; p < tile.Pixels(); ++p)
    {
      const int i = tile.I0 + p % tile.Width();
      const int j = tile.J0 + p / tile.Width();
      double* out = this->Output + 4 * (static_cast<int64_t>(j) * this->Width + i);
      for (int c = 0; c < 4; ++c)
      {
        out[c] += this->Sums[p][c];
      }
    }
  }
};

struct SegmentVisitor
{
  static constexpr bool WantsSegments = true;
  static constexpr bool WantsSamples = false;
  static constexpr bool WantsTransparentSamples = false;
  int32_t* Output;
  int Width;
  double Tolerance;
  std::vector<std::vector<std::pair<double, double>>> Pixels;

  void BeginTile(const TileRect& tile)
  {
    this->Pixels.resize(tile.Pixels());
    for (auto& p : this->Pixels)
    {
      p.clear();
    }
  }
  void Segment(int pixel, double tin, double tout) { this->Pixels[pixel].emplace_back(tin, tout); }
  void Sample(int, int64_t, double, double, const TransferSample&) {}
  void EndTile(const TileRect& tile)
  {
    for (int p = 0; p < tile.Pixels(); ++p)
    {
      auto& intervals = this->Pixels[p];
      std::sort(intervals.begin(), intervals.end());
      int32_t count = 0;
      double end = -std::numeric_limits<double>::infinity();
      for (const auto& interval : intervals)
      {
        // Neighbouring cells share their face planes exactly, so a gap below a tiny fraction
        // of the mesh size is rounding, not empty space.
        if (interval.first > end + this->Tolerance)
        {
          ++count;
        }
        end = std::max(end, interval.second);
      }
      const int i = tile.I0 + p % tile.Width();
      const int j = tile.J0 + p / tile.Width();
      this->Output[static_cast<int64_t>(j) * this->Width + i] += count;
    }
  }
};

// The segments of one tile, pixel by pixel in the tile's order.
struct TileSegments
{
  std::vector<int32_t> Counts;
  std::vector<RaySegment> Segments;
};

// Sort-last segments: each pixel's samples sorted by k and cut into runs of consecutive k.
// Transparent samples are taken too (they keep a run going), so that a run ends only where
// the ray leaves this mesh's cells, whatever the transfer function.
struct RunVisitor : PixelSampleLists
{
  static constexpr bool WantsSegments = false;
  static constexpr bool WantsSamples = true;
  static constexpr bool WantsTransparentSamples = true;
  std::vector<TileSegments>* Tiles;
  void EndTile(const TileRect& tile)
  {
    TileSegments& out = (*this->Tiles)[tile.Index];
    out.Counts.assign(tile.Pixels(), 0);
    out.Segments.clear();
    for (int p = 0; p < tile.Pixels(); ++p)
    {
      if (this->Pixels[p].empty())
      {
        continue;
      }
      const std::vector<SampleRecord>& samples = this->Sorted(p);
      RaySegment run{ samples.front().K, samples.front().K, { 0, 0, 0 }, 1.0f };
      FrontToBack blend;
      bool visible = false;
      auto flush = [&]
      {
        if (visible)
        {
          run.Colour = { static_cast<float>(blend.Colour[0]), static_cast<float>(blend.Colour[1]),
            static_cast<float>(blend.Colour[2]) };
          run.Transmittance = static_cast<float>(blend.Transmittance);
          out.Segments.push_back(run);
          ++out.Counts[p];
        }
      };
      for (const SampleRecord& s : samples)
      {
        if (s.K > run.KLast + 1)
        {
          flush();
          run.KFirst = s.K;
          blend = FrontToBack();
          visible = false;
        }
        run.KLast = s.K;
        // Not (a > 0) also covers NaN scalars, whose colour must not reach the sums.
        if (!(s.Absorbance > 0))
        {
          continue;
        }
        blend.Add(s);
        visible = true;
      }
      flush();
    }
  }
};

// True for exactly one of n and -n (n non-zero): the first non-zero component is positive.
inline bool InPositiveHalf(const std::array<float, 3>& n)
{
  return n[0] != 0 ? n[0] > 0 : (n[1] != 0 ? n[1] > 0 : n[2] > 0);
}

// Clips a ray against a cell's face planes: [tin, tout) is the part inside the cell. Every
// cell evaluates a shared face with the same numbers (up to an exact sign flip), so the
// intervals of neighbours meet exactly.
inline void ClipRay(
  const RaySetup& ray, const FacePlane* planes, int count, double& tin, double& tout)
{
  for (int p = 0; p < count && tin < tout; ++p)
  {
    const double nx = planes[p].Normal[0];
    const double ny = planes[p].Normal[1];
    const double nz = planes[p].Normal[2];
    const double denom = nx * ray.D[0] + ny * ray.D[1] + nz * ray.D[2];
    const double num = planes[p].Offset - (nx * ray.O[0] + ny * ray.O[1] + nz * ray.O[2]);
    if (denom < 0)
    {
      tin = std::max(tin, num / denom);
    }
    else if (denom > 0)
    {
      tout = std::min(tout, num / denom);
    }
    else if (num < 0 || (num == 0 && !InPositiveHalf(planes[p].Normal)))
    {
      // The ray is outside this plane, or runs inside it. A plane shared by two cells
      // appears in both with exactly opposite normals, so letting only the copy whose normal
      // points into the "positive" half-space keep such a ray gives it to exactly one cell.
      tout = -std::numeric_limits<double>::infinity();
    }
  }
}
}

//------------------------------------------------------------------------------
// Marches one tile: all its cells against all its pixels.
struct VolumeRayMarcher::Walker
{
  template <class Visitor>
  static int64_t Tile(const CellMesh& mesh, const Bins& bins, const std::vector<RaySetup>& rays,
    const TileRect& tile, int64_t tileIndex, const TransferTable& table, double farLimit,
    Visitor& visitor)
  {
    const double spacing = table.GetSampleSpacing();
    const bool cellScalars = mesh.HasCellScalars();
    int64_t samples = 0;
    CellCorners corners;
    CellInterpolator interpolator;
    visitor.BeginTile(tile);
    for (int64_t b = bins.Start[tileIndex]; b < bins.Start[tileIndex + 1]; ++b)
    {
      const int64_t cell = bins.Cells[b];
      const auto& r = bins.Rects[cell];
      const int i0 = std::max(r[0], tile.I0);
      const int i1 = std::min(r[2], tile.I1 - 1);
      const int j0 = std::max(r[1], tile.J0);
      const int j1 = std::min(r[3], tile.J1 - 1);
      TransferSample cellSample{};
      double cellScalar = 0.0;
      if (cellScalars)
      {
        cellScalar = mesh.CellScalars[cell];
        cellSample = table.Lookup(cellScalar);
        if (!(cellSample.Absorbance > 0) && !Visitor::WantsSegments &&
          !Visitor::WantsTransparentSamples)
        {
          continue; // an invisible cell
        }
      }
      int planeCount = 0;
      const FacePlane* planes = mesh.GetPlanes(cell, planeCount);
      if (planeCount == 0)
      {
        continue; // a cell the mesh left out (see CellMesh::GetNumberOfSkippedCells)
      }
      bool haveCorners = false;
      double pcoords[3] = { 0, 0, 0 };
      for (int j = j0; j <= j1; ++j)
      {
        for (int i = i0; i <= i1; ++i)
        {
          const int local = (j - tile.J0) * tile.Width() + (i - tile.I0);
          const RaySetup& ray = rays[local];
          double tin = 0.0;
          // No sample lies beyond the mesh's far bound: this also keeps a cell whose planes
          // fail to enclose it (rounding on a nearly flat cell) from sampling forever.
          double tout = std::min(ray.End, farLimit);
          ClipRay(ray, planes, planeCount, tin, tout);
          if (!(tin < tout))
          {
            continue;
          }
          visitor.Segment(local, tin, tout);
          if (!Visitor::WantsSamples)
          {
            continue;
          }
          // Lattice samples in [tin, tout): t_k = k * spacing, the same points on every rank.
          int64_t k = static_cast<int64_t>(std::ceil(tin / spacing));
          if (static_cast<double>(k) * spacing < tin)
          {
            ++k;
          }
          for (double t = static_cast<double>(k) * spacing; t < tout;
               ++k, t = static_cast<double>(k) * spacing)
          {
            TransferSample s = cellSample;
            double scalar = cellScalar;
            if (!cellScalars)
            {
              if (!haveCorners)
              {
                // Set up lazily: most binned cells miss most of their rectangle's rays.
                mesh.GetCorners(cell, corners);
                interpolator.Set(corners);
                ParametricCenter(corners.Shape, pcoords);
                haveCorners = true;
              }
              const double x[3] = { ray.O[0] + t * ray.D[0], ray.O[1] + t * ray.D[1],
                ray.O[2] + t * ray.D[2] };
              // The previous sample's coordinates are a close first guess for Newton (an
              // extrapolated guess was tried: it can leave the cell and converge to another
              // root of a non-affine map). Scalars need about single precision: 1e-7 in
              // parametric units is ample and saves Newton steps on distorted cells.
              interpolator.ParametricCoordinates(x, pcoords, nullptr, 1e-7);
              scalar = interpolator.InterpolateScalar(pcoords);
              s = table.Lookup(scalar);
            }
            ++samples;
            if (s.Absorbance > 0 || Visitor::WantsTransparentSamples)
            {
              visitor.Sample(local, k, t, scalar, s);
            }
          }
        }
      }
    }
    visitor.EndTile(tile);
    return samples;
  }
};

//------------------------------------------------------------------------------
VolumeRayMarcher::VolumeRayMarcher()
  : TileBins(new Bins)
  , Cache(new SampleCache)
{
}

VolumeRayMarcher::~VolumeRayMarcher() = default;

//------------------------------------------------------------------------------
void VolumeRayMarcher::SetMesh(const CellMesh* mesh)
{
  this->Mesh = mesh;
  this->Cache->Valid = false;
  this->Cache->Tiles.clear();
}

//------------------------------------------------------------------------------
void VolumeRayMarcher::SetView(const RayCamera& camera, const float* rayEnds)
{
  this->Cache->Valid = false;
  this->Cache->Tiles.clear();
  this->Camera.reset(new RayCamera(camera));
  const int w = camera.GetWidth();
  const int h = camera.GetHeight();
  this->RayEnds.assign(static_cast<size_t>(w) * h, std::numeric_limits<float>::infinity());
  if (rayEnds)
  {
    std::copy(rayEnds, rayEnds + this->RayEnds.size(), this->RayEnds.begin());
  }

  Bins& bins = *this->TileBins;
  bins.TilesX = (w + this->TileSize - 1) / this->TileSize;
  bins.TilesY = (h + this->TileSize - 1) / this->TileSize;
  const int64_t tiles = static_cast<int64_t>(bins.TilesX) * bins.TilesY;
  const int64_t numCells = this->Mesh ? this->Mesh->GetNumberOfCells() : 0;
  bins.Rects.resize(numCells);

  // Screen rectangle of each cell's projected corners; a cell reaching behind the eye
  // gets the whole screen (conservative), one wholly behind it none.
  tbb::task_arena arena(this->Threads > 0 ? this->Threads : tbb::task_arena::automatic);
  arena.execute(
    [&]
    {
      tbb::parallel_for(tbb::blocked_range<int64_t>(0, numCells, 4096),
        [&](const tbb::blocked_range<int64_t>& range)
        {
          for (int64_t cell = range.begin(); cell < range.end(); ++cell)
          {
            const int64_t* ids = this->Mesh->GetCellPoints(cell);
            const int corners = static_cast<int>(this->Mesh->GetShape(cell));
            double x0 = std::numeric_limits<double>::infinity();
            double y0 = x0;
            double x1 = -x0;
            double y1 = -x0;
            int behind = 0;
            for (int c = 0; c < corners; ++c)
            {
              double px, py;
              if (camera.Project(this->Mesh->Points[ids[c]], px, py))
              {
                x0 = std::min(x0, px);
                x1 = std::max(x1, px);
                y0 = std::min(y0, py);
                y1 = std::max(y1, py);
              }
              else
              {
                ++behind;
              }
            }
            std::array<int, 4>& r = bins.Rects[cell];
            if (behind == corners)
            {
              r = { 1, 1, 0, 0 };
              continue;
            }
            if (behind > 0)
            {
              x0 = y0 = -1.0;
              x1 = w;
              y1 = h;
            }
            // Pixel centres sit at integers: the covered ones are ceil(x0) .. floor(x1).
            r[0] = static_cast<int>(std::max(0.0, std::ceil(x0)));
            r[1] = static_cast<int>(std::max(0.0, std::ceil(y0)));
            r[2] = static_cast<int>(std::min(w - 1.0, std::floor(x1)));
            r[3] = static_cast<int>(std::min(h - 1.0, std::floor(y1)));
          }
        });
    });

  // Counting sort of (tile, cell) pairs: one pass counts, the second fills.
  auto forEachTileOf = [&](int64_t cell, auto&& visit)
  {
    const auto& r = bins.Rects[cell];
    if (r[0] > r[2] || r[1] > r[3])
    {
      return;
    }
    for (int ty = r[1] / this->TileSize; ty <= r[3] / this->TileSize; ++ty)
    {
      for (int tx = r[0] / this->TileSize; tx <= r[2] / this->TileSize; ++tx)
      {
        visit(static_cast<int64_t>(ty) * bins.TilesX + tx);
      }
    }
  };
  bins.Start.assign(tiles + 1, 0);
  for (int64_t cell = 0; cell < numCells; ++cell)
  {
    forEachTileOf(cell, [&](int64_t tile) { ++bins.Start[tile + 1]; });
  }
  for (int64_t t = 0; t < tiles; ++t)
  {
    bins.Start[t + 1] += bins.Start[t];
  }
  bins.Cells.resize(bins.Start[tiles]);
  std::vector<int64_t> fill(bins.Start.begin(), bins.Start.end() - 1);
  for (int64_t cell = 0; cell < numCells; ++cell)
  {
    forEachTileOf(cell, [&](int64_t tile) { bins.Cells[fill[tile]++] = cell; });
  }
}

//------------------------------------------------------------------------------
template <class Visitor>
void VolumeRayMarcher::March(Visitor& prototype, const TransferTable& table)
{
  this->LastSamples = 0;
  if (!this->Mesh || !this->Camera || this->Mesh->GetNumberOfCells() == 0)
  {
    return;
  }
  const Bins& bins = *this->TileBins;
  const int w = this->Camera->GetWidth();
  const int h = this->Camera->GetHeight();
  const int64_t tiles = static_cast<int64_t>(bins.TilesX) * bins.TilesY;
  double nearLimit = 0;
  double farLimit = 0;
  this->Camera->DistanceRange(this->Mesh->GetBounds(), nearLimit, farLimit);
  farLimit = farLimit * (1 + 1e-12) + 1e-300;
  tbb::combinable<Visitor> visitors([&prototype] { return prototype; });
  tbb::combinable<int64_t> samples([] { return int64_t(0); });
  tbb::combinable<std::vector<RaySetup>> rayBuffers;

  tbb::task_arena arena(this->Threads > 0 ? this->Threads : tbb::task_arena::automatic);
  arena.execute(
    [&]
    {
      tbb::parallel_for(tbb::blocked_range<int64_t>(0, tiles, 1),
        [&](const tbb::blocked_range<int64_t>& range)
        {
          Visitor& visitor = visitors.local();
          std::vector<RaySetup>& rays = rayBuffers.local();
          for (int64_t t = range.begin(); t < range.end(); ++t)
          {
            if (bins.Start[t] == bins.Start[t + 1])
            {
              continue;
            }
            const int tx = static_cast<int>(t % bins.TilesX);
            const int ty = static_cast<int>(t / bins.TilesX);
            const TileRect tile = { tx * this->TileSize, ty * this->TileSize,
              std::min(w, (tx + 1) * this->TileSize), std::min(h, (ty + 1) * this->TileSize), t };
            rays.resize(tile.Pixels());
            for (int j = tile.J0; j < tile.J1; ++j)
            {
              for (int i = tile.I0; i < tile.I1; ++i)
              {
                const Ray ray = this->Camera->PixelRay(i, j);
                RaySetup& r = rays[(j - tile.J0) * tile.Width() + (i - tile.I0)];
                std::copy(ray.Origin.begin(), ray.Origin.end(), r.O);
                std::copy(ray.Direction.begin(), ray.Direction.end(), r.D);
                r.End = this->RayEnds[static_cast<int64_t>(j) * w + i];
              }
            }
            samples.local() +=
              Walker::Tile(*this->Mesh, bins, rays, tile, t, table, farLimit, visitor);
          }
        });
    });
  this->LastSamples = samples.combine(std::plus<int64_t>());
}

//------------------------------------------------------------------------------
void VolumeRayMarcher::RenderExact(const TransferTable& table, float* rgba)
{
  ExactVisitor visitor{ {}, rgba, this->Camera ? this->Camera->GetWidth() : 0 };
  this->March(visitor, table);
}

//------------------------------------------------------------------------------
template <int N>
void VolumeRayMarcher::AccumulateMoments(
  const TransferTable& table, const LogDepthWarp& warp, double* moments)
{
  SampleCache& cache = *this->Cache;
  const int64_t tiles = static_cast<int64_t>(this->TileBins->TilesX) * this->TileBins->TilesY;
  cache.Tiles.assign(static_cast<size_t>(tiles), {});
  cache.Bytes = 0;
  cache.Record = cache.MaxBytes > 0;
  MomentVisitor<N> visitor{ moments, this->Camera ? this->Camera->GetWidth() : 0, &warp, &cache,
    {} };
  this->March(visitor, table);
  cache.Valid = cache.Record;
  cache.Table = &table;
  cache.WarpNear = warp.Near();
  cache.WarpFar = warp.Far();
  cache.Moments = N;
  if (!cache.Valid)
  {
    cache.Tiles.clear();
  }
}

//------------------------------------------------------------------------------
template <int N>
void VolumeRayMarcher::AccumulateColour(const TransferTable& table, const LogDepthWarp& warp,
  const double* moments, const MomentSettings<N>& settings, double* colourSums)
{
  const SampleCache& cache = *this->Cache;
  this->LastColourUsedCache = cache.Valid && cache.Table == &table && cache.Moments == N &&
    cache.WarpNear == warp.Near() && cache.WarpFar == warp.Far();
  if (this->LastColourUsedCache)
  {
    this->ReplayColour<N>(table, warp, moments, settings, colourSums);
    return;
  }
  ColourVisitor<N> visitor{ colourSums, this->Camera ? this->Camera->GetWidth() : 0, &warp, moments,
    &settings, {}, {} };
  this->March(visitor, table);
}

//------------------------------------------------------------------------------
template <int N>
void VolumeRayMarcher::ReplayColour(const TransferTable& table, const LogDepthWarp& warp,
  const double* moments, const MomentSettings<N>& settings, double* colourSums)
{
  // Pass 2 from pass 1's samples: the same samples with the same values, re-weighted by the
  // transmittance reconstructed from the global moments; no clipping, no interpolation.
  const Bins& bins = *this->TileBins;
  const int w = this->Camera->GetWidth();
  const int h = this->Camera->GetHeight();
  const ColourVisitor<N> prototype{ colourSums, w, &warp, moments, &settings, {}, {} };
  tbb::combinable<ColourVisitor<N>> visitors([&prototype] { return prototype; });
  tbb::combinable<int64_t> samples([] { return int64_t(0); });
  const SampleCache& cache = *this->Cache;
  tbb::task_arena arena(this->Threads > 0 ? this->Threads : tbb::task_arena::automatic);
  arena.execute(
    [&]
    {
      tbb::parallel_for(tbb::blocked_range<int64_t>(0, static_cast<int64_t>(cache.Tiles.size()), 1),
        [&](const tbb::blocked_range<int64_t>& range)
        {
          ColourVisitor<N>& visitor = visitors.local();
          for (int64_t t = range.begin(); t < range.end(); ++t)
          {
            const std::vector<CachedSample>& recorded = cache.Tiles[t];
            if (recorded.empty())
            {
              continue;
            }
            const int tx = static_cast<int>(t % bins.TilesX);
            const int ty = static_cast<int>(t / bins.TilesX);
            const TileRect tile = { tx * this->TileSize, ty * this->TileSize,
              std::min(w, (tx + 1) * this->TileSize), std::min(h, (ty + 1) * this->TileSize), t };
            visitor.BeginTile(tile);
            for (const CachedSample& sample : recorded)
            {
              visitor.Add(sample.Pixel, sample.Z, table.Lookup(sample.Scalar));
            }
            visitor.EndTile(tile);
            samples.local() += static_cast<int64_t>(recorded.size());
          }
        });
    });
  this->LastSamples = samples.combine(std::plus<int64_t>());
}

//------------------------------------------------------------------------------
void SegmentImage::Reset(int width, int height)
{
  this->Width = std::max(width, 0);
  this->Height = std::max(height, 0);
  this->Offsets.assign(static_cast<size_t>(this->Width) * this->Height + 1, 0);
  this->Segments.clear();
}

SegmentStatistics GetSegmentStatistics(const SegmentImage& image)
{
  SegmentStatistics stats;
  const int64_t pixels = static_cast<int64_t>(image.Offsets.size()) - 1;
  for (int64_t p = 0; p < pixels; ++p)
  {
    const int64_t n = image.Count(p);
    stats.Segments += n;
    stats.NonEmptyPixels += n > 0;
    stats.MaxPerPixel = std::max(stats.MaxPerPixel, n);
  }
  return stats;
}

std::array<double, 4> CompositeSegments(RaySegment* segments, size_t count)
{
  std::sort(segments, segments + count,
    [](const RaySegment& a, const RaySegment& b) { return a.KFirst < b.KFirst; });
  double transmittance = 1.0;
  std::array<double, 4> rgba = { 0, 0, 0, 0 };
  for (size_t s = 0; s < count; ++s)
  {
    for (int c = 0; c < 3; ++c)
    {
      rgba[c] += transmittance * segments[s].Colour[c];
    }
    transmittance *= segments[s].Transmittance;
  }
  rgba[3] = 1.0 - transmittance;
  return rgba;
}

void CompositeSegmentImage(SegmentImage& image, float* rgba, int threads)
{
  const int64_t pixels = static_cast<int64_t>(image.Offsets.size()) - 1;
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute(
    [&]
    {
      tbb::parallel_for(tbb::blocked_range<int64_t>(0, pixels, 1024),
        [&](const tbb::blocked_range<int64_t>& range)
        {
          for (int64_t p = range.begin(); p < range.end(); ++p)
          {
            const int64_t n = image.Count(p);
            if (n == 0)
            {
              continue;
            }
            const std::array<double, 4> c =
              CompositeSegments(image.Segments.data() + image.Offsets[p], static_cast<size_t>(n));
            for (int k = 0; k < 4; ++k)
            {
              rgba[4 * p + k] += static_cast<float>(c[k]);
            }
          }
        });
    });
}

//------------------------------------------------------------------------------
void VolumeRayMarcher::RenderSegments(const TransferTable& table, SegmentImage& segments)
{
  const int w = this->Camera ? this->Camera->GetWidth() : 0;
  const int h = this->Camera ? this->Camera->GetHeight() : 0;
  segments.Reset(w, h);
  const Bins& bins = *this->TileBins;
  const int64_t tiles = this->Camera ? static_cast<int64_t>(bins.TilesX) * bins.TilesY : 0;
  std::vector<TileSegments> perTile(static_cast<size_t>(tiles));
  RunVisitor visitor{ {}, &perTile };
  this->March(visitor, table);

  // Tiles were filled in parallel and in any order; the compressed rows are in pixel order.
  auto forEachTilePixel = [&](int64_t t, auto&& visit)
  {
    const int tx = static_cast<int>(t % bins.TilesX);
    const int ty = static_cast<int>(t / bins.TilesX);
    const int i0 = tx * this->TileSize;
    const int j0 = ty * this->TileSize;
    const int i1 = std::min(w, i0 + this->TileSize);
    const int j1 = std::min(h, j0 + this->TileSize);
    int local = 0;
    for (int j = j0; j < j1; ++j)
    {
      for (int i = i0; i < i1; ++i, ++local)
      {
        visit(local, static_cast<int64_t>(j) * w + i);
      }
    }
  };
  for (int64_t t = 0; t < tiles; ++t)
  {
    if (perTile[t].Counts.empty())
    {
      continue;
    }
    forEachTilePixel(
      t, [&](int local, int64_t pixel) { segments.Offsets[pixel + 1] = perTile[t].Counts[local]; });
  }
  for (size_t p = 1; p < segments.Offsets.size(); ++p)
  {
    segments.Offsets[p] += segments.Offsets[p - 1];
  }
  segments.Segments.resize(static_cast<size_t>(segments.Offsets.back()));
  tbb::task_arena arena(this->Threads > 0 ? this->Threads : tbb::task_arena::automatic);
  arena.execute(
    [&]
    {
      tbb::parallel_for(tbb::blocked_range<int64_t>(0, tiles, 1),
        [&](const tbb::blocked_range<int64_t>& range)
        {
          for (int64_t t = range.begin(); t < range.end(); ++t)
          {
            const TileSegments& tile = perTile[t];
            size_t next = 0;
            if (tile.Segments.empty())
            {
              continue;
            }
            forEachTilePixel(t,
              [&](int local, int64_t pixel)
              {
                const int32_t n = tile.Counts[local];
                std::copy(tile.Segments.begin() + next, tile.Segments.begin() + next + n,
                  segments.Segments.begin() + segments.Offsets[pixel]);
                next += n;
              });
          }
        });
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
  SegmentVisitor visitor{ counts, this->Camera ? this->Camera->GetWidth() : 0, 1e-9 * diagonal,
    {} };
  this->March(visitor, none);
}

template void VolumeRayMarcher::AccumulateMoments<4>(
  const TransferTable&, const LogDepthWarp&, double*);
template void VolumeRayMarcher::AccumulateMoments<6>(
  const TransferTable&, const LogDepthWarp&, double*);
template void VolumeRayMarcher::AccumulateMoments<8>(
  const TransferTable&, const LogDepthWarp&, double*);
template void VolumeRayMarcher::AccumulateColour<4>(
  const TransferTable&, const LogDepthWarp&, const double*, const MomentSettings<4>&, double*);
template void VolumeRayMarcher::AccumulateColour<6>(
  const TransferTable&, const LogDepthWarp&, const double*, const MomentSettings<6>&, double*);
template void VolumeRayMarcher::AccumulateColour<8>(
  const TransferTable&, const LogDepthWarp&, const double*, const MomentSettings<8>&, double*);

} // namespace apc
