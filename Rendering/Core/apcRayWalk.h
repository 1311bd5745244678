// The marcher's per-ray pieces (internal to apcVolumeRayMarcher.cpp): a ray's set-up, the
// exact clipping of rays against a cell's face planes, the shared sample lattice, and how far
// each ray of a tile has come towards opaque.
#ifndef apcRayWalk_h
#define apcRayWalk_h

#include "apcCellMesh.h"
#include "apcOpaqueBins.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace apc
{
namespace walk
{

// Pixels of a tile (VolumeRayMarcher::kTileSize squared; the marcher checks).
constexpr int kTilePixels = 16 * 16;

struct RaySetup
{
  double O[3];
  double D[3];
  double End;
  double Offset; // the ray's lattice offset, in units of the spacing: 0, or apcLatticeJitter
};

// A cell's face planes, set up once per cell and tile. Every ray of a perspective camera
// starts at the eye, so each plane's distance from it is computed here once, not per ray
// (with the same expression, so the numbers are the ones a per-ray evaluation gives).
// Stored by component and padded to kMaxPlanes with planes that clip nothing, so that Clip
// runs one fixed, branch-free loop the compiler unrolls and vectorises.
struct CellPlanes
{
  static constexpr int kMaxPlanes = 6;
  int Count = 0;
  bool SharedOrigin = false;
  double Nx[kMaxPlanes];
  double Ny[kMaxPlanes];
  double Nz[kMaxPlanes];
  double Offset[kMaxPlanes];
  double Num[kMaxPlanes];
  // 1 where a ray running inside the plane is kept (see Clip), else 0: the face plane's
  // FacePlane::KeepsParallelRays.
  double KeepsParallelRays[kMaxPlanes];
  // Bit p: plane p lies on the mesh's boundary (CellMesh::GetBoundaryPlanes); set by the
  // caller after Set where the end weights ask for it (ClipEnds), else 0.
  unsigned BoundaryMask = 0;

  void Set(const FacePlane* planes, int count, const RaySetup& anyRay, bool sharedOrigin)
  {
    this->Count = std::min(count, kMaxPlanes);
    this->SharedOrigin = sharedOrigin;
    for (int p = 0; p < kMaxPlanes; ++p)
    {
      if (p < this->Count)
      {
        this->Nx[p] = planes[p].Normal[0];
        this->Ny[p] = planes[p].Normal[1];
        this->Nz[p] = planes[p].Normal[2];
        this->Offset[p] = planes[p].Offset;
        this->KeepsParallelRays[p] = planes[p].KeepsParallelRays;
      }
      else
      {
        // Parallel to every ray with every ray strictly inside: no effect.
        this->Nx[p] = this->Ny[p] = this->Nz[p] = 0;
        this->Offset[p] = 1;
        this->KeepsParallelRays[p] = 1;
      }
      this->Num[p] = sharedOrigin ? this->Numerator(p, anyRay) : 0;
    }
  }
  double Numerator(int p, const RaySetup& ray) const
  {
    return this->Offset[p] -
      (this->Nx[p] * ray.O[0] + this->Ny[p] * ray.O[1] + this->Nz[p] * ray.O[2]);
  }

  // Clips a ray against the planes: [tin, tout) is the part inside the cell. Every cell
  // evaluates a shared face with the same numbers (up to an exact sign flip), so the
  // intervals of neighbours meet exactly. Each quotient is the one a per-plane division
  // gives, and the interval is their max and min, so the result does not depend on the
  // order or the vectorisation (two planes per SSE2 instruction, the same IEEE operations).
  void Clip(const RaySetup& ray, double& tin, double& tout) const
  {
#ifdef __SSE2__
    const __m128d dx = _mm_set1_pd(ray.D[0]);
    const __m128d dy = _mm_set1_pd(ray.D[1]);
    const __m128d dz = _mm_set1_pd(ray.D[2]);
    const __m128d zero = _mm_setzero_pd();
    const __m128d inf = _mm_set1_pd(std::numeric_limits<double>::infinity());
    __m128d lo = _mm_set1_pd(tin);
    __m128d hi = _mm_set1_pd(tout);
    __m128d out = zero;
    for (int p = 0; p < kMaxPlanes; p += 2)
    {
      const __m128d denom = _mm_add_pd(_mm_add_pd(_mm_mul_pd(_mm_loadu_pd(this->Nx + p), dx),
                                         _mm_mul_pd(_mm_loadu_pd(this->Ny + p), dy)),
        _mm_mul_pd(_mm_loadu_pd(this->Nz + p), dz));
      const __m128d num =
        this->SharedOrigin ? _mm_loadu_pd(this->Num + p) : this->Numerators(p, ray);
      const __m128d q = _mm_div_pd(num, denom);
      // max/min return the second operand if the first is NaN, as std::max(lo, q) keeps lo.
      const __m128d entering = _mm_cmplt_pd(denom, zero);
      const __m128d leaving = _mm_cmpgt_pd(denom, zero);
      lo = _mm_max_pd(
        _mm_or_pd(_mm_and_pd(entering, q), _mm_andnot_pd(entering, _mm_sub_pd(zero, inf))), lo);
      hi = _mm_min_pd(_mm_or_pd(_mm_and_pd(leaving, q), _mm_andnot_pd(leaving, inf)), hi);
      // See the scalar form below for the rays parallel to a plane.
      const __m128d parallelOut = _mm_and_pd(_mm_cmpeq_pd(denom, zero),
        _mm_or_pd(_mm_cmplt_pd(num, zero),
          _mm_and_pd(_mm_cmpeq_pd(num, zero),
            _mm_cmpeq_pd(_mm_loadu_pd(this->KeepsParallelRays + p), zero))));
      out = _mm_or_pd(out, parallelOut);
    }
    const double lo2 = std::max(_mm_cvtsd_f64(lo), _mm_cvtsd_f64(_mm_unpackhi_pd(lo, lo)));
    const double hi2 = std::min(_mm_cvtsd_f64(hi), _mm_cvtsd_f64(_mm_unpackhi_pd(hi, hi)));
    tin = lo2;
    tout = _mm_movemask_pd(out) != 0 ? -std::numeric_limits<double>::infinity() : hi2;
#else
    double lo = tin;
    double hi = tout;
    bool out = false;
    for (int p = 0; p < kMaxPlanes; ++p)
    {
      const double denom = this->Nx[p] * ray.D[0] + this->Ny[p] * ray.D[1] + this->Nz[p] * ray.D[2];
      const double num = this->SharedOrigin ? this->Num[p] : this->Numerator(p, ray);
      const double q = num / denom; // unused where denom == 0
      lo = denom < 0 && lo < q ? q : lo;
      hi = denom > 0 && q < hi ? q : hi;
      // The ray is outside this plane, or runs inside it. A plane shared by two cells appears
      // in both with exactly opposite normals, so letting only the copy whose normal points
      // into the "positive" half-space keep such a ray gives it to exactly one cell.
      out = out || (denom == 0 && (num < 0 || (num == 0 && this->KeepsParallelRays[p] == 0)));
    }
    tin = lo;
    tout = out ? -std::numeric_limits<double>::infinity() : hi;
#endif
  }

  // Clip, and whether the interval's ends lie on a boundary plane (BoundaryMask): in / out
  // say that a boundary plane's quotient is the interval's tin / tout. The quotients are
  // Clip's, with its operations, so an end on a boundary plane is found exactly; where a
  // boundary plane and another one give the same quotient (the ray through their edge) the
  // end counts as on the boundary.
  void ClipEnds(const RaySetup& ray, double& tin, double& tout, bool& in, bool& out) const
  {
    this->Clip(ray, tin, tout);
    this->BoundaryEnds(ray, tin, tout, in, out);
  }

  // ClipEnds' in / out for the interval [tin, tout) Clip gave this ray (from ClipRays, whose
  // intervals are Clip's bit for bit), without clipping again.
  void BoundaryEnds(const RaySetup& ray, double tin, double tout, bool& in, bool& out) const
  {
    const double inf = std::numeric_limits<double>::infinity();
    double loB = -inf;
    double hiB = inf;
    for (int p = 0; p < this->Count; ++p)
    {
      if (!(this->BoundaryMask & (1u << p)))
      {
        continue;
      }
#ifdef __SSE2__
      // Clip's expression for lane p (no contraction into FMA in intrinsics).
      const __m128d denomV =
        _mm_add_pd(_mm_add_pd(_mm_mul_pd(_mm_set_sd(this->Nx[p]), _mm_set_sd(ray.D[0])),
                     _mm_mul_pd(_mm_set_sd(this->Ny[p]), _mm_set_sd(ray.D[1]))),
          _mm_mul_pd(_mm_set_sd(this->Nz[p]), _mm_set_sd(ray.D[2])));
      __m128d numV;
      if (this->SharedOrigin)
      {
        numV = _mm_set_sd(this->Num[p]);
      }
      else
      {
        const __m128d dot =
          _mm_add_pd(_mm_add_pd(_mm_mul_pd(_mm_set_sd(this->Nx[p]), _mm_set_sd(ray.O[0])),
                       _mm_mul_pd(_mm_set_sd(this->Ny[p]), _mm_set_sd(ray.O[1]))),
            _mm_mul_pd(_mm_set_sd(this->Nz[p]), _mm_set_sd(ray.O[2])));
        numV = _mm_sub_pd(_mm_set_sd(this->Offset[p]), dot);
      }
      const double denom = _mm_cvtsd_f64(denomV);
      const double q = _mm_cvtsd_f64(_mm_div_pd(numV, denomV));
#else
      const double denom = this->Nx[p] * ray.D[0] + this->Ny[p] * ray.D[1] + this->Nz[p] * ray.D[2];
      const double num = this->SharedOrigin ? this->Num[p] : this->Numerator(p, ray);
      const double q = num / denom;
#endif
      if (denom < 0)
      {
        loB = std::max(loB, q);
      }
      else if (denom > 0)
      {
        hiB = std::min(hiB, q);
      }
    }
    in = loB >= tin;
    out = hiB <= tout;
  }

#ifdef __SSE2__
  // Planes p and p + 1's numerators for a ray of its own origin (a parallel camera).
  __m128d Numerators(int p, const RaySetup& ray) const
  {
    const __m128d dot =
      _mm_add_pd(_mm_add_pd(_mm_mul_pd(_mm_loadu_pd(this->Nx + p), _mm_set1_pd(ray.O[0])),
                   _mm_mul_pd(_mm_loadu_pd(this->Ny + p), _mm_set1_pd(ray.O[1]))),
        _mm_mul_pd(_mm_loadu_pd(this->Nz + p), _mm_set1_pd(ray.O[2])));
    return _mm_sub_pd(_mm_loadu_pd(this->Offset + p), dot);
  }
#endif
};

// Scalars need about single precision: 1e-7 in parametric units is ample and saves Newton
// steps on distorted cells.
constexpr double kSampleTolerance = 1e-7;

// The lattice t_k = (k + offset) * spacing of one ray (offset 0 unless jittered). A sample
// belongs to the cell whose [tin, tout) holds the rounded value, so the first index of an
// interval must be the smallest k whose value is >= tin, exactly; a quotient only gives a
// first guess, which rounding can leave one off in either direction. Every cell computes
// t_k with the same expression, so neighbours agree on which of them takes a sample.
struct Lattice
{
  double Spacing;
  double InverseSpacing;

  explicit Lattice(double spacing)
    : Spacing(spacing)
    , InverseSpacing(1.0 / spacing)
  {
  }
  double At(int64_t k, double offset) const
  {
    return (static_cast<double>(k) + offset) * this->Spacing;
  }
  int64_t First(double t, double offset) const
  {
    // A cheap ceiling (the loops below correct it): truncation, then up for positive
    // fractions. t is finite and at most the mesh's far bound here.
    const double x = t * this->InverseSpacing - offset;
    int64_t k = static_cast<int64_t>(x);
    k += static_cast<double>(k) < x ? 1 : 0;
    while (this->At(k - 1, offset) >= t)
    {
      --k;
    }
    while (this->At(k, offset) < t)
    {
      ++k;
    }
    return k;
  }
};

//------------------------------------------------------------------------------
// How far each ray of a tile has come towards opaque (apcOpaqueBins.h). In pass 1 (Own) each
// pixel sums its samples' absorbance per bin in quanta; once its total reaches the threshold
// it takes no sample past the end of the bin of its farthest sample so far (Stop, set by the
// walker), so its profile is complete up to that edge and zero beyond it. A pass that knows
// the agreed cut instead gets every pixel's Stop preset and sums nothing; a pass 1 bounded by
// a predicted cut gets its Stop preset and sums too. The walker keeps
// this, not the visitor, so that pass 1 and a pass 2 that marches a tile again make the same
// decisions from the same samples in the same order.
struct RayProgress
{
  static constexpr int kPixels = kTilePixels;
  static constexpr int kBins = OpaqueBins::kBins;
  const OpaqueBins* Bins = nullptr; // pass 1's own stop, or null
  // With Bins: Bins->End(b) for every bin, read per (cell, ray) pair and per bin crossing
  // instead of a multiplication each time.
  int64_t Ends[kBins];
  // With Bins: Ends[0 .. kBins - 2] as doubles, exact (OpaqueBins::Make keeps them below
  // 2^53), for the lanes' bins (walk::LaneCell::BinEnds).
  double BinEnds[kBins - 1];
  uint32_t Profile[kPixels][kBins];
  uint32_t Total[kPixels];
  int64_t FarK[kPixels]; // the largest lattice index summed
  bool Opaque[kPixels];
  double Stop[kPixels];
  // Once every pixel of the tile has a stop, the largest: a cell nearer than none of them is
  // skipped without looking at its rays.
  double TileStop = std::numeric_limits<double>::infinity();
  // The nearest of the tile's ray ends (Sample End Weights = Boundary: only a cell reaching
  // within a spacing of it may hold a pair weighted to a ray's end).
  double NearestEnd = std::numeric_limits<double>::infinity();
  int Pixels = 0;
  int Open = 0;         // pixels without a stop
  bool Lowered = false; // a stop came nearer since TileStop was set

  // own: pass 1's bins (null: no pixel stops unless SetStop presets it).
  void Begin(int pixels, const OpaqueBins* own)
  {
    this->Bins = own;
    this->Pixels = pixels;
    this->Open = pixels;
    this->TileStop = std::numeric_limits<double>::infinity();
    this->Lowered = false;
    std::fill(this->Stop, this->Stop + pixels, std::numeric_limits<double>::infinity());
    if (own)
    {
      for (int b = 0; b < kBins; ++b)
      {
        this->Ends[b] = own->End(b);
      }
      for (int b = 0; b < kBins - 1; ++b)
      {
        this->BinEnds[b] = static_cast<double>(this->Ends[b]);
      }
      std::fill(&this->Profile[0][0], &this->Profile[0][0] + pixels * kBins, 0u);
      std::fill(this->Total, this->Total + pixels, 0u);
      std::fill(this->FarK, this->FarK + pixels, std::numeric_limits<int64_t>::min());
      std::fill(this->Opaque, this->Opaque + pixels, false);
    }
  }
  // Adds pass 1's sample k (in bin) to pixel p; true if it made the ray opaque (the walker
  // then stops it at the end of FarK's bin).
  [[gnu::always_inline]] bool Add(int p, int64_t k, int bin, double absorbance)
  {
    if (!this->Bins)
    {
      return false;
    }
    const uint32_t q = this->Bins->Quanta(absorbance);
    this->Profile[p][bin] = OpaqueBins::Add(this->Profile[p][bin], q);
    this->FarK[p] = std::max(this->FarK[p], k);
    if (this->Opaque[p])
    {
      return false;
    }
    this->Total[p] = OpaqueBins::Add(this->Total[p], q);
    this->Opaque[p] = this->Total[p] >= OpaqueBins::kOpaque;
    return this->Opaque[p];
  }
  // Runs of pass 1's samples of one pixel added at once (the walker's lanes): at most kMaxRun
  // samples at lattice indices k, k + 1, ..., q[s] the quanta of sample s (0 where it is
  // not visible), sum their sum and last the index of the run's last visible sample. Such a
  // run adds as Add adds each of its visible samples in order, bin following k, only where
  // it cannot make the pixel opaque (RunStaysOpen: then no Add would return true, and the
  // saturating sums of the run's quanta are those of its samples one at a time); the walker
  // takes any other run sample by sample, so that the stop falls where it does.
  static constexpr int kMaxRun = 8;
  bool RunStaysOpen(int p, uint32_t sum) const
  {
    return this->Opaque[p] || this->Total[p] + sum < OpaqueBins::kOpaque;
  }
  // bin: BinOf(k); sample s's quanta q[s * stride].
  [[gnu::always_inline]] void AddRun(
    int p, int64_t k, int bin, const uint32_t* q, uint32_t sum, int last, int stride = 1)
  {
    if (last < 0)
    {
      return; // no visible sample
    }
    if (k + last < this->Ends[bin])
    {
      // One bin: min(a + b + c, max) is the saturating sum's value for values that are not
      // negative.
      this->Profile[p][bin] = OpaqueBins::Add(this->Profile[p][bin], sum);
    }
    else
    {
      for (int s = 0; s <= last; ++s)
      {
        while (k + s >= this->Ends[bin])
        {
          ++bin;
        }
        this->Profile[p][bin] = OpaqueBins::Add(this->Profile[p][bin], q[s * stride]);
      }
    }
    this->FarK[p] = std::max(this->FarK[p], k + last);
    if (!this->Opaque[p])
    {
      this->Total[p] += sum; // below kOpaque (RunStaysOpen), as the saturating sums are
    }
  }
  // Pixel p takes no sample at or past t (nor past a stop it already has: a pass 1 bounded
  // by a predicted cut also stops where its own absorbance turns opaque, whichever is first).
  void SetStop(int p, double t)
  {
    const bool first = this->Stop[p] == std::numeric_limits<double>::infinity();
    if (!first && !(t < this->Stop[p]))
    {
      return;
    }
    this->Stop[p] = t;
    if (first && --this->Open == 0)
    {
      this->TileStop = *std::max_element(this->Stop, this->Stop + this->Pixels);
    }
    else if (!first && this->Open == 0)
    {
      this->Lowered = true; // TileStop may come nearer: refreshed before the next cell
    }
  }
  // The largest stop again after some were lowered (a bound still holds until then).
  void RefreshTileStop()
  {
    if (this->Lowered)
    {
      this->TileStop = *std::max_element(this->Stop, this->Stop + this->Pixels);
      this->Lowered = false;
    }
  }
  // Bins->Of(k) without its 64-bit division, whose latency exceeded the rest of a (cell,
  // ray) pair's set-up: the number of bin ends at or before k, found in four steps (the ends
  // grow with the bin; End(b) <= k exactly when (b + 1) Width <= k - Base, so the count is
  // min(floor((k - Base) / Width), kBins - 1), Of's value, and 0 for k before the bins).
  [[gnu::always_inline]] int BinOf(int64_t k) const
  {
    static_assert(kBins == 16, "four halving steps find one of 16 bins");
    const int64_t* end = this->Ends;
    int bin = end[7] <= k ? 8 : 0;
    bin += end[bin + 3] <= k ? 4 : 0;
    bin += end[bin + 1] <= k ? 2 : 0;
    bin += end[bin] <= k ? 1 : 0;
    return bin;
  }
  // Where an opaque pixel p stops: the first lattice index past the bin of its farthest
  // sample (none past the last bin). Stopping at that sample instead would leave the
  // profile's bin incomplete, and the cut then depends on the partition.
  int64_t StopIndex(int p) const { return this->Ends[this->LastBin(p)]; }
  // The last bin holding a sample pixel p summed (0 if none).
  int LastBin(int p) const
  {
    return this->FarK[p] == std::numeric_limits<int64_t>::min() ? 0 : this->BinOf(this->FarK[p]);
  }
};

} // namespace walk
} // namespace apc

#endif
