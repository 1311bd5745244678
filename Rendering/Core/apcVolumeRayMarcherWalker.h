// VolumeRayMarcher's walker: one screen tile's cells against the tile's rays (clipping, the
// lattice, the interpolation and the opaque stop), for every visitor. Internal to
// apcVolumeRayMarcher.cpp, which runs it per tile for each pass.
#ifndef apcVolumeRayMarcherWalker_h
#define apcVolumeRayMarcherWalker_h

#include "apcVolumeRayMarcher.h"

#include "apcCellInterpolation.h"
#include "apcEndWeights.h"
#include "apcLaneMoments.h"
#include "apcLaneSamples.h"
#include "apcOpaqueBins.h"
#include "apcRayClip.h"
#include "apcRayWalk.h"
#include "apcTileBins.h"
#include "apcTransferTable.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>
#include <vector>

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

// Visitors whose Sample reads only the absorbance of its TransferSample (the lanes fill no
// colour) say so with SamplesAbsorbanceOnly.
template <class Visitor, class = void>
struct AbsorbanceOnly : std::false_type
{
};
template <class Visitor>
struct AbsorbanceOnly<Visitor, std::void_t<decltype(Visitor::SamplesAbsorbanceOnly)>>
  : std::bool_constant<Visitor::SamplesAbsorbanceOnly>
{
};

// Visitors that keep each sample's end weight (the sample cache) take weighted samples with
// WeightedSample; the others see the weighted absorbance in Sample.
template <class Visitor, class = void>
struct TakesWeights : std::false_type
{
};
template <class Visitor>
struct TakesWeights<Visitor,
  std::void_t<decltype(std::declval<Visitor&>().WeightedSample(
    0, int64_t(0), 0.0, 0.0, std::declval<const TransferSample&>(), 1.0f))>> : std::true_type
{
};

// Visitors that take the lanes' hand-over four pixels at a time (walk::LaneMomentsAvx2:
// Moments<4>) say so with TakesLaneMoments.
template <class Visitor, class = void>
struct LaneMomentsVisitor : std::false_type
{
};
template <class Visitor>
struct LaneMomentsVisitor<Visitor, std::void_t<decltype(Visitor::TakesLaneMoments)>>
  : std::bool_constant<Visitor::TakesLaneMoments>
{
};

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
  // With pass 1's own stop: a last bin per pixel of the band that no ray passes either (a
  // predicted cut, the same on every process; kBins - 1 bounds nothing), or null.
  const uint8_t* Bound = nullptr;
  int BandWidth = 0;
  // Nearly affine cells' and twisted pyramids' samples four rays at a time (LaneSamplesAvx2)
  // where the processor has AVX2 and the visitor reads only absorbance.
  bool Lanes = walk::HasAvx2();
  // With Lanes: two groups of four rays per kernel call where the processor has AVX-512.
  bool WideLanes = walk::HasAvx512();
  // Weight each (cell, ray) pair's end samples so that they sum to its exact length, and give
  // a pair without a lattice point one sample at its middle (apcEndWeights.h), for the
  // visitors that take them (the MBOIT passes; Visitor::TakesEndWeights). The lanes take
  // such pairs too (their hand-over weights a run's first and last step); a pair without a
  // lattice point, and every pair of a cell the lanes do not take, goes through the scalar
  // loop (WeightedRay).
  bool EndWeights = false;
  // With EndWeights: weight only the ends on the mesh's boundary (EndWeightsMode::Boundary).
  // A cell without a boundary plane takes the plain lattice's path; one with takes the
  // scalar weighted loop, which finds each pair's ends by CellPlanes::ClipEnds.
  bool BoundaryWeights = false;
  // Per cell: 1 if Table.MayBeVisible of its scalar range, 0 if every sample of it is clear;
  // or null. Only for visitors that skip clear cells (not WantsSegments nor
  // WantsTransparentSamples): Tile then drops the clear cells from its list before the loop,
  // which would otherwise call Cell for each (a read of its range and a table test) and
  // prefetch its planes and corners for nothing.
  const uint8_t* VisibleCells = nullptr;

  // A cell's scalars: its own (or none needed), linear along the ray (a nearly affine pyramid
  // in its own coordinates, LinearPyramid), a twisted pyramid's closed-form inverse, or by
  // Newton. The pyramid's linear form is its own loop: a test of the cell's shape per sample
  // had the loop reload the scalar's coefficients for every sample.
  enum class Sampling
  {
    Constant,
    Linear,
    LinearPyramid,
    Pyramid,
    Follow
  };
  static constexpr bool IsLinear(Sampling how)
  {
    return how == Sampling::Linear || how == Sampling::LinearPyramid || how == Sampling::Pyramid;
  }

  // What a cell needs while its rays are marched; reused from cell to cell.
  struct CellState
  {
    CellPlanes Planes;
    CellCorners Corners;
    CellInterpolator Interpolator;
    int64_t Cell = -1;
    double Near = 0; // no point of the cell lies at a smaller t (TileBins::Near)
    double Far = 0;  // nor at a larger one (TileBins::Far)
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
    // With a shared origin: LinearRay's p0, the same for every ray of the cell.
    double LinearOrigin[3] = { 0, 0, 0 };
    // The tile's rays clipped against the cell.
    walk::ClippedRays Clipped;
    // With end weights where the lanes are on: each kept pair's weights, found by the
    // clipping (walk::ClipRaysWeighted).
    walk::ClippedWeights Ends;
    // With the lanes: the cell's constants as they read them (the part the tile's cells
    // share set once per tile by Tile, the cell's own by LaneSamples).
    walk::LaneCellVectors Vectors;
  };

  // Sets state up for cell; false if the cell adds nothing to what the visitor makes.
  template <class Visitor>
  bool SetUp(
    int64_t cell, const RaySetup& anyRay, CellState& state, const RayProgress& progress) const
  {
    constexpr bool keepsTransparent = Visitor::WantsSegments || Visitor::WantsTransparentSamples;
    state.Near = this->Bins.Near[cell];
    state.Far = this->Bins.Far[cell];
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
    const bool visible = this->VisibleCells || this->Table.MayBeVisible(state.Lo, state.Hi);
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
    state.Planes.BoundaryMask = this->BoundaryWeights ? this->Mesh.GetBoundaryPlanes(cell) : 0;
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
    if (Visitor::StopsWhenOpaque)
    {
      progress.RefreshTileStop(); // an own stop may have come before a bound's
    }
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
    // A visitor of segments sees every ray inside, with a sample or not; so do the end
    // weights, which sample a pair without a lattice point too.
    constexpr bool allInside = Visitor::WantsSegments || !Visitor::WantsSamples;
    const bool weighted = this->EndWeights && !allInside && Visitor::TakesEndWeights &&
      (!this->BoundaryWeights || state.Planes.BoundaryMask != 0 ||
        this->NearRayEnds(state, progress));
    walk::ClippedRays& c = state.Clipped;
    const double* stop = Visitor::StopsWhenOpaque ? progress.Stop : nullptr;
    // Where the lanes are on, the clipping finds the pairs' end weights four rays at a time;
    // else PairWeights finds them ray by ray (the form the lanes' weights are tested against).
    const bool clipWeights = weighted && this->Lanes && !this->BoundaryWeights;
    const int hits = clipWeights ? walk::ClipRaysWeighted(state.Planes, packed, rect, stop,
                                     state.Near, this->Grid, c, state.Ends)
                                 : walk::ClipRays(state.Planes, packed, rect, stop, state.Near,
                                     allInside || weighted ? nullptr : &this->Grid, c);
    if constexpr (!allInside)
    {
      if (clipWeights)
      {
        // Hits: the pairs with a lattice point; Ends.MidHits: those without one.
        const walk::ClippedWeights& ends = state.Ends;
        if (hits + ends.MidCount == 0)
        {
          return 0;
        }
        if constexpr (AbsorbanceOnly<Visitor>::value && !Visitor::WantsTransparentSamples)
        {
          if (this->SharedOrigin)
          {
            this->Prepare(rays[hits > 0 ? c.Hits[0] : ends.MidHits[0]], state);
            if (state.Interpolate && (state.Linear || state.Interpolator.HasPyramidInverse()))
            {
              return this->LaneSamples<true>(rays, packed, hits, visitor, state, progress);
            }
          }
        }
        // In the rectangle's order, the two lists merged: Newton starts each ray from the
        // cell's previous ray's first sample (CellState::FirstMemory).
        int64_t samples = 0;
        for (int h = 0, m = 0; h < hits || m < ends.MidCount;)
        {
          const bool mid = h == hits || (m < ends.MidCount && ends.MidHits[m] < c.Hits[h]);
          const int l = mid ? ends.MidHits[m++] : c.Hits[h++];
          visitor.Segment(l, c.Tin[l], c.Tout[l]);
          samples +=
            this->WeightedSamples(l, rays[l], c.Tout[l], ends.Of(l), visitor, state, progress);
        }
        return samples;
      }
      if (weighted)
      {
        if constexpr (AbsorbanceOnly<Visitor>::value && !Visitor::WantsTransparentSamples)
        {
          // Boundary: a cell with a boundary face in the lanes too (its pairs' weights found
          // ray by ray first).
          if (hits > 0 && this->SharedOrigin && this->Lanes)
          {
            this->Prepare(rays[c.Hits[0]], state);
            if (state.Interpolate && (state.Linear || state.Interpolator.HasPyramidInverse()))
            {
              return this->BoundaryLaneSamples(rays, packed, hits, visitor, state, progress);
            }
          }
        }
        int64_t samples = 0;
        for (int h = 0; h < hits; ++h)
        {
          const int l = c.Hits[h];
          samples += this->WeightedRay(l, rays[l], c.Tin[l], c.Tout[l], visitor, state, progress);
        }
        return samples;
      }
    }
    if (!Visitor::WantsSegments && Visitor::WantsSamples && hits > 0)
    {
      this->Prepare(rays[c.Hits[0]], state);
      if (!state.Interpolate)
      {
        return this->CellSamples<Sampling::Constant>(rays, hits, visitor, state, progress);
      }
      if constexpr (AbsorbanceOnly<Visitor>::value && !Visitor::WantsTransparentSamples)
      {
        if ((state.Linear || state.Interpolator.HasPyramidInverse()) && this->SharedOrigin &&
          this->Lanes)
        {
          return this->LaneSamples<false>(rays, packed, hits, visitor, state, progress);
        }
      }
      if (state.Linear && state.Interpolator.Shape() == CellShape::Pyramid)
      {
        return this->CellSamples<Sampling::LinearPyramid>(rays, hits, visitor, state, progress);
      }
      if (state.Linear)
      {
        return this->CellSamples<Sampling::Linear>(rays, hits, visitor, state, progress);
      }
      if (state.Interpolator.HasPyramidInverse())
      {
        return this->CellSamples<Sampling::Pyramid>(rays, hits, visitor, state, progress);
      }
    }
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
    this->Prepare(ray, state);
    return BySampling(state,
      [&](auto how) {
        return this->Samples<decltype(how)::value>(local, ray, k, tout, visitor, state, progress);
      });
  }

  // Calls f with the sampling a prepared cell state takes (Prepare), as a
  // std::integral_constant: the one choice for the loops that take one ray at a time.
  template <class F>
  static int64_t BySampling(const CellState& state, F&& f)
  {
    using S = Sampling;
    if (!state.Interpolate)
    {
      return f(std::integral_constant<S, S::Constant>());
    }
    if (state.Linear && state.Interpolator.Shape() == CellShape::Pyramid)
    {
      return f(std::integral_constant<S, S::LinearPyramid>());
    }
    if (state.Linear)
    {
      return f(std::integral_constant<S, S::Linear>());
    }
    if (state.Interpolator.HasPyramidInverse())
    {
      return f(std::integral_constant<S, S::Pyramid>());
    }
    return f(std::integral_constant<S, S::Follow>());
  }

  // Ray's samples with end weights (EndWeights): the ray local inside the cell over
  // [tin, tout), the pair's interval up to the ray's stop, if any; returns the samples taken.
  template <class Visitor>
  int64_t WeightedRay(int local, const RaySetup& ray, double tin, double tout, Visitor& visitor,
    CellState& state, RayProgress& progress) const
  {
    visitor.Segment(local, tin, tout);
    const walk::EndWeights w = this->PairWeights<Visitor>(local, ray, tin, tout, state, progress);
    if (w.Last < w.First && !w.Mid)
    {
      return 0; // no sample (Boundary: no lattice point and no weighted end): no set-up
    }
    const int64_t samples = this->WeightedSamples(local, ray, tout, w, visitor, state, progress);
    return w.End ? samples + this->EndSample(local, ray, tout, w, visitor, state, progress)
                 : samples;
  }

  // Boundary: the end sample of a pair with lattice samples and a weighted end
  // (EndWeights::End), after them; where they turned the pixel opaque, only if it lies before
  // the stop they set (its lattice index is the pair's last, so it shares that sample's bin).
  template <class Visitor>
  int64_t EndSample(int local, const RaySetup& ray, double tout, const walk::EndWeights& w,
    Visitor& visitor, CellState& state, RayProgress& progress) const
  {
    if (Visitor::StopsWhenOpaque)
    {
      tout = std::min(tout, progress.Stop[local]);
    }
    return this->WeightedSamples(local, ray, tout, w.EndSample(), visitor, state, progress);
  }

  // Boundary: whether a cell without a boundary face may still hold a pair that
  // BoundaryPairWeights weights by the ray's own begin or end: one holding the eye, or
  // reaching within a spacing of the tile's nearest ray end. The others take the plain lattice.
  [[gnu::always_inline]] bool NearRayEnds(const CellState& state, const RayProgress& progress) const
  {
    return state.Near <= 0.0 || state.Far + this->Grid.Spacing > progress.NearestEnd;
  }

  // Boundary: the end weights of the pair of ray local over [tin, tout) (tout: up to the ray's
  // stop), and whether they are the plain lattice's (plain). An end on the mesh's boundary is
  // weighted (CellPlanes::BoundaryEnds); where the stop cut the pair, its end is found again
  // with ClipRays' own arithmetic (clipped again only there: else [tin, tout) is already
  // Clip's interval from [0, min(End, far)), bit for bit).
  //
  // The ray's own end (an opaque surface's depth) counts exactly too, whichever cell it falls
  // in, continuous in where it falls (walk::RayPairWeights). The eye inside the mesh: the pair
  // it cuts starts weighted.
  // first: Grid.First(tin, ray.Offset) (BoundaryLaneSamples hands its plain pairs that index).
  template <class Visitor>
  [[gnu::always_inline]] walk::EndWeights BoundaryPairWeights(int local, const RaySetup& ray,
    double tin, double tout, int64_t first, CellState& state, const RayProgress& progress,
    bool& plain) const
  {
    bool in = false;
    bool out = false;
    double end = tout;
    if (Visitor::StopsWhenOpaque && tout == progress.Stop[local])
    {
      double start = 0;
      end = std::min(ray.End, this->FarLimit);
      state.Planes.ClipEnds(ray, start, end, in, out);
    }
    else
    {
      state.Planes.BoundaryEnds(ray, tin, tout, in, out);
    }
    return this->BoundaryPairWeightsAt(ray, tin, end, first, in, out, plain, state);
  }

  // BoundaryPairWeights once the pair's end (end: before the stop cut it) and whether its ends
  // lie on the boundary (in, out) are known.
  [[gnu::always_inline]] walk::EndWeights BoundaryPairWeightsAt(const RaySetup& ray, double tin,
    double end, int64_t first, bool in, bool out, bool& plain, const CellState& state) const
  {
    // The ray's own end, not the clip's min(end, far bound): the far bound is each process's
    // own piece's, and N processes must weigh what one process weighs.
    const auto cellExit = [&](double& face, bool& faceOut)
    {
      double start = 0;
      bool faceIn = false;
      face = this->FarLimit;
      state.Planes.ClipEnds(ray, start, face, faceIn, faceOut);
    };
    return walk::RayPairWeights(
      this->Grid, tin, end, ray.Offset, in || tin <= 0.0, out, first, ray.End, cellExit, plain);
  }

  // The end weights of the pair of ray local over [tin, tout) (tout: up to the ray's stop).
  template <class Visitor>
  [[gnu::always_inline]] walk::EndWeights PairWeights(int local, const RaySetup& ray, double tin,
    double tout, CellState& state, const RayProgress& progress) const
  {
    // The weights are the whole pair's: where ClipRays cut it at the stop, its end is found
    // again, with ClipRays' own arithmetic (CellPlanes::Clip from [0, min(End, far))).
    double end = tout;
    if (this->BoundaryWeights)
    {
      bool plain = false;
      return this->BoundaryPairWeights<Visitor>(
        local, ray, tin, tout, this->Grid.First(tin, ray.Offset), state, progress, plain);
    }
    if (Visitor::StopsWhenOpaque && tout == progress.Stop[local])
    {
      double start = 0;
      end = std::min(ray.End, this->FarLimit);
      state.Planes.Clip(ray, start, end);
    }
    return walk::EndWeightsOf(this->Grid, tin, end, ray.Offset);
  }

  // Boundary: the samples of a cell with a boundary face, or near a ray's begin or end
  // (NearRayEnds; ClipRays kept hits rays of it, without the lattice's filter) through the lanes.
  // Each pair's ends first (as PairWeights finds them): a pair with both ends plain and a lattice
  // point takes the plain lattice's samples, so it goes to LaneSamples<false> (its first index
  // to Clipped.Lattice, as ClipRays with the lattice gives it); the others' weights go to
  // state.Ends in the form ClipRaysWeighted gives them, for LaneSamples<true>: those with a lattice
  // point in Clipped.Hits, those with a middle sample in Ends.MidHits. A pair without a sample (no
  // lattice point and no weighted end, or a clamped sliver) is dropped, as WeightedRay drops
  // it. A pixel holds one pair of the cell, so splitting the cell's rays changes no pixel's
  // order.
  template <class Visitor>
  int64_t BoundaryLaneSamples(const std::vector<RaySetup>& rays, const TileRays& packed, int hits,
    Visitor& visitor, CellState& state, RayProgress& progress) const
  {
    walk::ClippedRays& c = state.Clipped;
    walk::ClippedWeights& ends = state.Ends;
    uint16_t plain[walk::kTilePixels];
    int plainCount = 0;
    int kept = 0;
    ends.MidCount = 0;
    // Whether each pair enters or leaves through a boundary plane (CellPlanes::BoundaryEnds),
    // four pairs at a time; a cell here only for its rays' ends (NearRayEnds) has none (and
    // BoundaryEnds would find none: tout is at most the mesh's finite far bound).
    int64_t samples = 0;
    uint8_t boundary[walk::kTilePixels + 3];
    const bool onBoundary = state.Planes.BoundaryMask != 0;
    if (onBoundary)
    {
      walk::BoundaryEnds(state.Planes, packed, c, c.Hits, hits, boundary);
    }
    for (int h = 0; h < hits; ++h)
    {
      const int l = c.Hits[h];
      const RaySetup& ray = rays[l];
      const double tin = c.Tin[l];
      const double tout = c.Tout[l];
      const int64_t first = this->Grid.First(tin, ray.Offset);
      c.Lattice[l] = static_cast<double>(first);
      // PairWeights' Boundary form, with the ends' flags kept.
      bool plainEnds = false;
      walk::EndWeights w;
      if (Visitor::StopsWhenOpaque && tout == progress.Stop[l])
      {
        w =
          this->BoundaryPairWeights<Visitor>(l, ray, tin, tout, first, state, progress, plainEnds);
      }
      else
      {
        const bool in = onBoundary && (boundary[h] & 1) != 0;
        const bool out = onBoundary && (boundary[h] & 2) != 0;
        if (!in && !out && tin > 0.0 && ray.End > tout + 2.0 * this->Grid.Spacing)
        {
          // Neither end on the boundary, the eye before the pair and the ray's end more than
          // a spacing past the next lattice point t_next (t_next < tout + spacing, give or
          // take roundings far below a spacing): BoundaryPairWeightsAt would keep the plain
          // lattice's samples, from first up to tout, some where t_first < tout and else
          // none; without its search for t_next (Lattice::First(tout)).
          if (this->Grid.At(first, ray.Offset) < tout)
          {
            plain[plainCount++] = static_cast<uint16_t>(l);
          }
          else
          {
            visitor.Segment(l, tin, tout);
          }
          continue;
        }
        w = this->BoundaryPairWeightsAt(ray, tin, tout, first, in, out, plainEnds, state);
      }
      if (w.End)
      {
        // Lattice samples and an end sample: the scalar loop, at once (a few pairs at the
        // ray's end or a boundary exit; a pixel holds one pair of the cell).
        visitor.Segment(l, tin, tout);
        samples += this->WeightedSamples(l, ray, tout, w, visitor, state, progress);
        samples += this->EndSample(l, ray, tout, w, visitor, state, progress);
        continue;
      }
      if (w.Mid)
      {
        ends.MidHits[ends.MidCount++] = static_cast<uint16_t>(l);
      }
      else if (w.Last < w.First)
      {
        visitor.Segment(l, tin, tout);
        continue;
      }
      else if (plainEnds)
      {
        // Its first index, w.First, is in Clipped.Lattice already.
        plain[plainCount++] = static_cast<uint16_t>(l);
        continue;
      }
      else
      {
        c.Hits[kept++] = static_cast<uint16_t>(l);
      }
      ends.First[l] = static_cast<double>(w.First);
      ends.Last[l] = static_cast<double>(w.Last);
      ends.FirstWeight[l] = w.Mid ? w.MidWeight : w.FirstWeight;
      ends.LastWeight[l] = w.Mid ? w.MidWeight : w.LastWeight;
      ends.MidT[l] = w.MidT;
      ends.LaneOffset[l] = w.Mid ? w.MidOffset : ray.Offset;
      ends.Mid[l] = w.Mid ? 1.0 : 0.0;
    }
    if (plainCount > 0)
    {
      // LaneSamples takes its rays from Clipped.Hits: the weighted ones wait meanwhile.
      uint16_t weighted[walk::kTilePixels];
      std::copy(c.Hits, c.Hits + kept, weighted);
      std::copy(plain, plain + plainCount, c.Hits);
      samples += this->LaneSamples<false>(rays, packed, plainCount, visitor, state, progress);
      std::copy(weighted, weighted + kept, c.Hits);
    }
    if (kept + ends.MidCount > 0)
    {
      samples += this->LaneSamples<true>(rays, packed, kept, visitor, state, progress);
    }
    return samples;
  }

  // WeightedRay's samples once the pair's weights w are known.
  template <class Visitor>
  int64_t WeightedSamples(int local, const RaySetup& ray, double tout, const walk::EndWeights& w,
    Visitor& visitor, CellState& state, RayProgress& progress) const
  {
    this->Prepare(ray, state);
    const TransferTable::Layout table = this->Table.GetLayout();
    return BySampling(state,
      [&](auto how)
      {
        return this->SampleLoop<decltype(how)::value, true>(
          local, ray, w.First, tout, table, visitor, state, progress, &w);
      });
  }

  // Sets the cell's interpolation up once one of its rays (ray) has a sample: lazily, since
  // most binned cells miss most of their rectangle's rays.
  void Prepare(const RaySetup& ray, CellState& state) const
  {
    if (!state.Interpolate || state.HaveCorners)
    {
      return;
    }
    this->Mesh.GetCorners(state.Cell, state.Corners);
    state.Interpolator.Set(state.Corners);
    ParametricCenter(state.Corners.Shape, state.Centre);
    state.Linear = state.Interpolator.IsAffine() ||
      state.Interpolator.GetLinearScalarError() <= this->LinearTolerance;
    if (this->SharedOrigin && (state.Linear || state.Interpolator.HasPyramidInverse()))
    {
      state.Interpolator.LinearRayOrigin(ray.O, state.LinearOrigin);
    }
    state.HaveCorners = true;
  }

  // The samples of every ray ClipRays kept (hits of them) in a cell whose scalar needs no
  // Newton search, ray by ray as Ray takes them: one call per cell, not per (cell, ray) pair,
  // whose call, saved registers and per-cell loads cost about as much as a pair's samples.
  template <Sampling How, class Visitor>
  [[gnu::noinline]] int64_t CellSamples(const std::vector<RaySetup>& rays, int hits,
    Visitor& visitor, CellState& state, RayProgress& progress) const
  {
    const walk::ClippedRays& c = state.Clipped;
    // Once per cell: taken per pair, the loop's stores made the compiler reload the table's
    // fields through the table for every pair.
    const TransferTable::Layout table = this->Table.GetLayout();
    int64_t samples = 0;
    for (int h = 0; h < hits; ++h)
    {
      const int l = c.Hits[h];
      visitor.Segment(l, c.Tin[l], c.Tout[l]);
      samples += this->SampleLoop<How>(
        l, rays[l], static_cast<int64_t>(c.Lattice[l]), c.Tout[l], table, visitor, state, progress);
    }
    return samples;
  }

  // CellSamples<Sampling::Linear>, <LinearPyramid> or <Pyramid> with a shared origin, four
  // rays at a time: LaneSamplesAvx2 finds up to kLaneSteps samples of each (lane i holds ray
  // i's k-th sample, so the rays' table look-ups overlap), then each ray's steps go to the
  // visitor (Moments::RunAdd) and the stop's bookkeeping (RayProgress::AddRun) as one run,
  // ray after ray: a visitor's pixel state read once per run, not per sample. A run in which
  // the pixel turns opaque goes sample by sample as in the scalar loop, and leaves the rest of
  // its steps untaken, as that loop's lowered tout does. Each pixel sees the same samples in
  // the same order, with the same sums, records and profile, as from the scalar loop.
  // Weighted (end weights, found by the clipping: state.Ends): a pair goes to the lanes from
  // its first index, a pair without a lattice point as a lane stepping from its middle
  // (EndWeights::MidOffset: its one step is MidT, the next lies past the pair), and the
  // hand-over multiplies each step's absorbance by its weight (1 but at the pair's first and
  // last index; a middle sample's MidWeight) as the scalar loop does, before the visitor and
  // the stop see it: the same weighted samples, sums, records, weights and cut as
  // WeightedRay's. Its four pixels' sums are found at once as the plain ones' are
  // (walk::LaneWeightedMomentsAvx2: the weights multiplied in the lanes, each record's weight
  // kept by Moments::LaneRunEnd<true>). With AVX-512 (WideLanes) eight rays at a time, as two
  // groups of four whose kernel (walk::LaneSamplesAvx512) and plain sums
  // (walk::LaneMomentsAvx512) run at once, each group's values bit for bit the four-wide ones.
  static_assert(walk::kLaneSteps <= RayProgress::kMaxRun, "a call's steps fit one run");
  template <bool Weighted, class Visitor>
  [[gnu::noinline]] int64_t LaneSamples(const std::vector<RaySetup>& rays, const TileRays& packed,
    int hits, Visitor& visitor, CellState& state, RayProgress& progress) const
  {
    const walk::ClippedRays& c = state.Clipped;
    const bool own = Visitor::StopsWhenOpaque && progress.Bins;
    // The tile's part of the lanes' constants is Tile's (SetUpLaneTile); the cell's own part
    // is broadcast here once for all the cell's calls, straight from its interpolator (a
    // twisted pyramid: one whose linear inverse is not close enough takes its closed form).
    walk::LaneCellVectors& vectors = state.Vectors;
    walk::SetUpLaneCellOf(
      state.Interpolator, !state.Linear, state.LinearOrigin, state.Lo, state.Hi, vectors);
    // One group of four lanes: its rays, its steps and each lane's own state. With AVX-512 the
    // kernel takes two groups at once (LaneSamplesAvx512: each group's steps bit for bit the
    // four-wide kernel's), and each group's hand-over is the four-wide one.
    struct Group
    {
      walk::LaneRays Lanes;
      walk::LaneSteps Steps;
      // Weighted: as LaneWeightedMomentsAvx2 reads them (GatherWeightedLaneRays).
      walk::LaneWeights Weights;
      // Set where a group is filled, each field for all four lanes, and read only after
      // (initialised here, they were stored again on every call).
      int N; // lanes used
      int Local[4];
      int64_t K[4]; // Weighted: each lane's next index (plain: Lanes.K)
      // Weighted: each ray's pair's first and last index and their float weights (as
      // EndWeights::Of gives them, then cast as the scalar loop does).
      int64_t FirstK[4];
      int64_t LastK[4];
      float FirstWeight[4];
      float LastWeight[4];
      bool Live;                // some lane has steps left (its Tout is not -inf)
      walk::LaneMoments Across; // its four pixels' hand-over (LaneMomentsAvx2's)
      const double* Sums[4];    // with acrossLanes: its pixels' sums (Moments::PixelSums)
    };
    Group groups[2];
    // Four pixels' sums at once: each step's warp, moments and quanta across the lanes
    // (Weighted: each step's weight first, and the records' weights).
    constexpr bool acrossLanes =
      LaneMomentsVisitor<Visitor>::value && (!Weighted || TakesWeights<Visitor>::value);
    int64_t samples = 0;
    // The rays the lanes take, in the rectangle's order; Weighted: then the pairs without a
    // lattice point (Ends.MidHits), each a lane whose one step lies at its middle
    // (Ends.LaneOffset). A pixel holds one pair of a cell, so no pixel's order changes.
    const uint16_t* list = c.Hits;
    int count = hits;
    const walk::ClippedWeights& ends = state.Ends;
    if constexpr (Weighted)
    {
      std::copy(ends.MidHits, ends.MidHits + ends.MidCount, state.Clipped.Hits + hits);
      count = hits + ends.MidCount;
    }
    const double perAbsorbance = own ? progress.Bins->QuantaPerAbsorbance : 0.0;
    const int span = this->WideLanes ? 8 : 4;
    for (int h = 0; h < count; h += span)
    {
      const int used = this->WideLanes && count - h > 4 ? 2 : 1;
      for (int gi = 0; gi < used; ++gi)
      {
        Group& g = groups[gi];
        const int first = h + 4 * gi;
        g.N = std::min(4, count - first);
        g.Live = true;
        for (int i = 0; i < 4; ++i)
        {
          const int at = first + (i < g.N ? i : 0);
          const int l = list[at];
          g.Local[i] = l;
          if constexpr (Weighted)
          {
            g.FirstK[i] = static_cast<int64_t>(ends.First[l]);
            g.LastK[i] = static_cast<int64_t>(ends.Last[l]);
            g.FirstWeight[i] = static_cast<float>(ends.FirstWeight[l]);
            g.LastWeight[i] = static_cast<float>(ends.LastWeight[l]);
            g.K[i] = g.FirstK[i];
          }
          if constexpr (acrossLanes)
          {
            g.Sums[i] = visitor.PixelSums(l);
          }
          if (i < g.N)
          {
            visitor.Segment(l, c.Tin[l], c.Tout[l]);
          }
        }
        // One vector store per field: the lanes' vector loads of fields stored one double at a
        // time waited for those stores to reach the cache.
        if constexpr (Weighted)
        {
          walk::GatherWeightedLaneRays(packed, c, ends, list + first, g.N, g.Lanes, g.Weights);
        }
        else
        {
          walk::GatherLaneRays(packed, c, list + first, g.N, g.Lanes);
        }
      }
      for (bool more = true; more;)
      {
        // Both groups at once where both have steps left, else the one that has.
        int taken = 0;
        const bool both = used == 2 && groups[0].Live && groups[1].Live;
        if (both)
        {
          taken = walk::LaneSamplesAvx512(
            vectors, groups[0].Lanes, groups[1].Lanes, groups[0].Steps, groups[1].Steps);
          if constexpr (acrossLanes && !Weighted)
          {
            // And both groups' sums at once (the weighted ones stay four wide).
            walk::LaneMomentsAvx512(groups[0].Steps, groups[1].Steps, taken, groups[0].Lanes,
              groups[1].Lanes, groups[0].Sums, groups[1].Sums, *visitor.Warp, perAbsorbance,
              groups[0].Across, groups[1].Across);
          }
        }
        else
        {
          Group& g = groups[used == 2 && !groups[0].Live ? 1 : 0];
          taken = walk::LaneSamplesAvx2(vectors, g.Lanes, g.Steps);
        }
        more = false;
        for (int gi = 0; gi < used; ++gi)
        {
          Group& g = groups[gi];
          if (!g.Live)
          {
            continue; // every lane's Tout is -inf: nothing to hand over
          }
          walk::LaneMoments& across = g.Across;
          // (Both groups' plain sums were found at once above.)
          if constexpr (acrossLanes)
          {
            if (Weighted || !both)
            {
              if constexpr (Weighted)
              {
                walk::LaneWeightedMomentsAvx2(
                  g.Steps, taken, g.Lanes, g.Sums, *visitor.Warp, perAbsorbance, g.Weights, across);
              }
              else
              {
                walk::LaneMomentsAvx2(
                  g.Steps, taken, g.Lanes, g.Sums, *visitor.Warp, perAbsorbance, across);
              }
            }
          }
          bool live = false; // some lane's chunk ended at kLaneSteps: it goes on
          for (int i = 0; i < g.N; ++i)
          {
            const int l = g.Local[i];
            double tout = g.Lanes.Tout[i];
            // Plain: the lane's first index as GatherLaneRays gathered it (Clipped.Lattice) or
            // the call before left it, an integer below 2^53: converted here, where it is read,
            // instead of once more from Clipped.Lattice per group (a chain of dependent loads
            // and a conversion for each lane before the kernel).
            int64_t kk = Weighted ? g.K[i] : static_cast<int64_t>(g.Lanes.K[i]);
            int s = 0;
            bool kept = false;
            if constexpr (acrossLanes)
            {
              // The lane's run as LaneMomentsAvx2 found it: kept where it cannot turn the
              // pixel opaque, else taken again sample by sample below.
              const uint32_t sum = static_cast<uint32_t>(across.QuantaSum[i]);
              kept = !own || progress.RunStaysOpen(l, sum);
              if (kept)
              {
                s = static_cast<int>(across.Steps[i]);
                visitor.template LaneRunEnd<Weighted>(l, across, i, kk, g.Steps, taken);
                if (own)
                {
                  const uint64_t visible = static_cast<uint64_t>(across.Visible[i]);
                  const int last = visible ? 63 - __builtin_clzll(visible) : -1;
                  progress.AddRun(
                    l, kk, static_cast<int>(g.Steps.Bin[i]), &across.Quanta[0][i], sum, last, 4);
                }
              }
            }
            else
            {
              // The ray's steps inside its interval, handed over as one run in one loop: the
              // pixel's sums in registers, its records' room taken once. A run in which the
              // pixel turns opaque is dropped and taken again sample by sample below, so that
              // the samples past the stop are not taken.
              typename Visitor::Run run;
              visitor.RunBegin(run, l, taken, Weighted);
              uint32_t q[RayProgress::kMaxRun];
              uint32_t sum = 0;
              int last = -1;
              for (; s < taken; ++s)
              {
                const double t = g.Steps.T[s][i];
                if (!(t < tout))
                {
                  break;
                }
                float absorbance = g.Steps.Absorbance[s][i];
                // A float weight and a float product, as in the scalar loop.
                float weight = 1;
                if constexpr (Weighted)
                {
                  weight = kk + s == g.FirstK[i] ? g.FirstWeight[i]
                                                 : (kk + s == g.LastK[i] ? g.LastWeight[i] : 1.f);
                  absorbance *= weight;
                }
                q[s] = 0;
                if (absorbance > 0)
                {
                  if constexpr (Weighted)
                  {
                    visitor.RunAddWeighted(
                      run, l, kk + s, t, g.Steps.Scalar[s][i], absorbance, weight);
                  }
                  else
                  {
                    visitor.RunAdd(run, l, kk + s, t, g.Steps.Scalar[s][i], absorbance);
                  }
                  if (own)
                  {
                    q[s] = progress.Bins->Quanta(absorbance);
                    sum += q[s]; // at most kMaxRun times kOpaque: no overflow
                    last = s;
                  }
                }
              }
              kept = !own || progress.RunStaysOpen(l, sum);
              if (kept)
              {
                visitor.RunEnd(run, l);
                if (own)
                {
                  progress.AddRun(l, kk, static_cast<int>(g.Steps.Bin[i]), q, sum, last);
                }
              }
              else if constexpr (Weighted)
              {
                visitor.RunDrop(run);
              }
            }
            if (kept)
            {
              samples += s;
              kk += s;
            }
            else
            {
              int bin = static_cast<int>(g.Steps.Bin[i]);
              int64_t binEnd = progress.Ends[bin];
              for (s = 0; s < taken; ++s, ++kk)
              {
                const double t = g.Steps.T[s][i];
                if (!(t < tout))
                {
                  break;
                }
                ++samples;
                float absorbance = g.Steps.Absorbance[s][i];
                float weight = 1;
                if constexpr (Weighted)
                {
                  weight = kk == g.FirstK[i] ? g.FirstWeight[i]
                                             : (kk == g.LastK[i] ? g.LastWeight[i] : 1.f);
                  absorbance *= weight;
                }
                if (absorbance > 0)
                {
                  const TransferSample sample{ { 0.f, 0.f, 0.f }, absorbance };
                  if constexpr (Weighted && TakesWeights<Visitor>::value)
                  {
                    visitor.WeightedSample(l, kk, t, g.Steps.Scalar[s][i], sample, weight);
                  }
                  else
                  {
                    visitor.Sample(l, kk, t, g.Steps.Scalar[s][i], sample);
                  }
                  this->OwnStop(l, rays[l].Offset, kk, absorbance, bin, binEnd, tout, progress);
                }
              }
            }
            if constexpr (Weighted)
            {
              g.K[i] = kk;
            }
            g.Lanes.K[i] = static_cast<double>(kk);
            // A ray that left the chunk before its end is done.
            g.Lanes.Tout[i] =
              s == walk::kLaneSteps ? tout : -std::numeric_limits<double>::infinity();
            live = live || s == walk::kLaneSteps;
          }
          g.Live = live;
          more = more || g.Live;
        }
      }
    }
    return samples;
  }

  // Pass 1's own stop after a visible sample at lattice index k of pixel local: bin and
  // binEnd (the bin of k and the first index past it) follow k, and where the pixel turns
  // opaque tout falls to its stop. Shared by the scalar sample loop and the lanes' hand-over.
  [[gnu::always_inline]] void OwnStop(int local, double offset, int64_t k, float absorbance,
    int& bin, int64_t& binEnd, double& tout, RayProgress& progress) const
  {
    for (; k >= binEnd; binEnd = progress.Ends[++bin])
    {
    }
    if (progress.Add(local, k, bin, absorbance))
    {
      // Opaque: nothing past the end of the farthest sample's bin is taken; what lies in
      // front of it still is (this pixel's profile stays complete up to there).
      const int64_t edge = progress.StopIndex(local);
      const double stop = edge == std::numeric_limits<int64_t>::max()
        ? std::numeric_limits<double>::infinity()
        : this->Grid.At(edge, offset);
      progress.SetStop(local, stop); // the nearer of this and a bound's stop
      tout = std::min(tout, progress.Stop[local]);
    }
  }

  // The lattice samples of the ray in [tin, tout), the same points on every rank; one loop
  // per way of finding the scalar.
  template <Sampling How, class Visitor>
  int64_t Samples(int local, const RaySetup& ray, int64_t k, double tout, Visitor& visitor,
    CellState& state, RayProgress& progress) const
  {
    return this->SampleLoop<How>(
      local, ray, k, tout, this->Table.GetLayout(), visitor, state, progress);
  }
  // Weighted: each sample's absorbance times its end weight (apcEndWeights.h; k is
  // weights->First), before the visitor and the stop see it.
  template <Sampling How, bool Weighted = false, class Visitor>
  [[gnu::always_inline]] int64_t SampleLoop(int local, const RaySetup& ray, int64_t k, double tout,
    const TransferTable::Layout& table, Visitor& visitor, CellState& state, RayProgress& progress,
    const walk::EndWeights* weights = nullptr) const
  {
    double p0[3] = { 0, 0, 0 };
    double dp[3] = { 0, 0, 0 };
    NewtonMemory memory;
    if (IsLinear(How))
    {
      if (this->SharedOrigin)
      {
        // Element by element: std::copy of three doubles compiled to a call to memcpy
        // per (cell, ray) pair.
        p0[0] = state.LinearOrigin[0];
        p0[1] = state.LinearOrigin[1];
        p0[2] = state.LinearOrigin[2];
        state.Interpolator.LinearRayDirection(ray.D, dp);
      }
      else
      {
        state.Interpolator.LinearRay(ray.O, ray.D, p0, dp);
      }
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
    int bin = own ? progress.BinOf(k) : 0;
    int64_t binEnd = own ? progress.Ends[bin] : 0;
    // A pair without a lattice point: its one sample at the middle.
    const bool mid = Weighted && weights->Mid;
    for (double t = mid ? weights->MidT : this->Grid.At(k, ray.Offset); t < tout;
         ++k, t = this->Grid.At(k, ray.Offset))
    {
      TransferSample s = state.CellSample;
      double scalar = state.CellScalar;
      if (IsLinear(How))
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
        // LinearScalarAt of a cell other than a pyramid is ScalarAt.
        const double interpolated = How == Sampling::LinearPyramid
          ? state.Interpolator.LinearScalarAt(pcoords)
          : (How == Sampling::Pyramid ? state.Interpolator.PyramidScalarAt(pcoords)
                                      : state.Interpolator.ScalarAt(pcoords));
        scalar = std::min(std::max(interpolated, state.Lo), state.Hi);
        s = TransferTable::Lookup(table, scalar);
      }
      // A float weight and a float product: what pass 2 takes again from the cache.
      float weight = 1;
      if (Weighted)
      {
        weight = static_cast<float>(mid ? weights->MidWeight : weights->Of(k));
        s.Absorbance *= weight;
      }
      ++samples;
      if (s.Absorbance > 0 || Visitor::WantsTransparentSamples)
      {
        if constexpr (Weighted && TakesWeights<Visitor>::value)
        {
          visitor.WeightedSample(local, k, t, scalar, s, weight);
        }
        else
        {
          visitor.Sample(local, k, t, scalar, s);
        }
        if (own)
        {
          this->OwnStop(local, ray.Offset, k, s.Absorbance, bin, binEnd, tout, progress);
        }
      }
      if (mid)
      {
        break;
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
      this->StopAtCut(rays, inBand, this->Cut, progress);
    }
    else if (stops && this->Bound)
    {
      this->StopAtCut(rays, inBand, this->Bound, progress);
    }
    TileRays packed;
    packed.Set(rays.data(), tile.Pixels(), this->FarLimit);
    progress.NearestEnd = std::min_element(rays.begin(), rays.begin() + tile.Pixels(),
      [](const RaySetup& a, const RaySetup& b) {
        return a.End < b.End;
      })->End;
    if (this->Lanes)
    {
      // What the lanes' constants share over the tile's cells (LaneSamples sets the rest).
      walk::LaneCell shared;
      shared.Table = this->Table.GetLayout();
      shared.Spacing = this->Grid.Spacing;
      static_assert(walk::kBinEnds == RayProgress::kBins - 1, "the lanes compare every bin end");
      shared.BinEnds = Visitor::StopsWhenOpaque && progress.Bins ? progress.BinEnds : nullptr;
      walk::SetUpLaneTile(shared, state.Vectors);
    }
    visitor.BeginTile(inBand);
    const int64_t begin = this->Bins.Start[tile.Index];
    const int64_t* cells = this->Bins.Cells.data() + begin;
    int64_t count = this->Bins.Start[tile.Index + 1] - begin;
    if (this->VisibleCells)
    {
      // The tile's cells that may be visible, in the bins' order. Written whatever the test
      // says and counted by it: no branch on a cell's visibility, which follows no pattern.
      static thread_local std::vector<int64_t> visible;
      visible.resize(static_cast<size_t>(count));
      int64_t kept = 0;
      for (int64_t b = 0; b < count; ++b)
      {
        const int64_t cell = cells[b];
        visible[kept] = cell;
        kept += this->VisibleCells[cell];
      }
      cells = visible.data();
      count = kept;
    }
    for (int64_t b = 0; b < count; ++b)
    {
      this->Prefetch(cells, b, count);
      samples += this->Cell(cells[b], rays, packed, tile, visitor, state, progress);
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

  // A tile's cells come in depth order, scattered over the mesh's arrays, and a cell's
  // set-up waited on memory for its depth, rectangle, scalar range, face planes and corners:
  // these are requested a few cells ahead (the planes and corner ids later, once their offsets
  // have arrived, and the corners' points later still). Forced inline: called as a function
  // of its own, which only reads memory, GCC 12 dropped the call and left no prefetch at all.
  [[gnu::always_inline]] void Prefetch(const int64_t* cells, int64_t b, int64_t end) const
  {
    constexpr int64_t kAhead = 16;
    if (b + kAhead < end)
    {
      const int64_t cell = cells[b + kAhead];
      __builtin_prefetch(&this->Bins.Near[cell]);
      __builtin_prefetch(&this->Bins.Rects[cell]);
      __builtin_prefetch(&this->Mesh.GetScalarRange(cell));
      this->Mesh.PrefetchIds(cell);
    }
    if (b + kAhead / 2 < end)
    {
      int count = 0;
      const char* planes =
        reinterpret_cast<const char*>(this->Mesh.GetPlanes(cells[b + kAhead / 2], count));
      const int bytes = count * static_cast<int>(sizeof(FacePlane));
      for (int at = 0; at < bytes; at += 64)
      {
        __builtin_prefetch(planes + at);
      }
      __builtin_prefetch(planes + bytes - 1);
      __builtin_prefetch(this->Mesh.GetCellPoints(cells[b + kAhead / 2]));
    }
    if (b + kAhead / 4 < end)
    {
      this->Mesh.PrefetchCorners(cells[b + kAhead / 4]);
    }
  }

  // Every ray of the tile stops at the end of its pixel's last bin (cut: the agreed cut, or
  // pass 1's predicted bound).
  void StopAtCut(const std::vector<RaySetup>& rays, const TileRect& inBand, const uint8_t* cut,
    RayProgress& progress) const
  {
    for (int p = 0; p < inBand.Pixels(); ++p)
    {
      const int last = cut[inBand.ImagePixel(p, this->BandWidth)];
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

} // namespace apc

#endif
