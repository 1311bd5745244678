// Clipping a tile's rays against one cell several rays at a time (internal to
// apcVolumeRayMarcher.cpp): the same intervals as CellPlanes::Clip ray by ray, bit for bit,
// and each ray's first lattice index, so that only the rays with a sample reach the sample
// loop.
#ifndef apcRayClip_h
#define apcRayClip_h

#include "apcEndWeights.h"
#include "apcRayWalk.h"

#include <algorithm>
#include <cstdint>

namespace apc
{
namespace walk
{

// A tile's rays by component. Padded by kPad entries so that a packet of rays may read (and
// ClipRays write) past the last one.
struct TileRays
{
  static constexpr int kPad = 4;
  static constexpr int kSize = kTilePixels + kPad;
  double Dx[kSize], Dy[kSize], Dz[kSize];
  double Ox[kSize], Oy[kSize], Oz[kSize];
  // Where clipping starts from: min(ray end, the mesh's far bound). No sample lies beyond
  // the far bound, which also keeps a cell whose planes fail to enclose it (rounding on a
  // nearly flat cell) from sampling forever.
  double End[kSize];
  double Offset[kSize]; // the ray's lattice offset (RaySetup::Offset)

  // Copies rays[0, count) (0 < count <= kTilePixels); far bounds every ray's end.
  void Set(const RaySetup* rays, int count, double far)
  {
    for (int p = 0; p < kSize; ++p)
    {
      const RaySetup& r = rays[std::min(p, count - 1)];
      this->Dx[p] = r.D[0];
      this->Dy[p] = r.D[1];
      this->Dz[p] = r.D[2];
      this->Ox[p] = r.O[0];
      this->Oy[p] = r.O[1];
      this->Oz[p] = r.O[2];
      this->End[p] = std::min(r.End, far);
      this->Offset[p] = r.Offset;
    }
  }
};

// Rows x Width rays of a tile: ray First, then a row every Stride rays.
struct RayRect
{
  int First;
  int Width;
  int Rows;
  int Stride;
};

// What ClipRays finds, by the ray's index in the tile (Tin, Tout, Lattice: kSize entries,
// written for the rectangle's rays and possibly a few beyond).
struct ClippedRays
{
  double Tin[TileRays::kSize];
  double Tout[TileRays::kSize];
  // Lattice::First(Tin, Offset), exactly, as a double (an integer; only with a lattice).
  double Lattice[TileRays::kSize];
  // The rays kept, in the rectangle's order; ClipRays may write up to 3 entries past the last.
  uint16_t Hits[kTilePixels + 3];
};

// The rays of rect clipped against one cell: [Tin, Tout) is what CellPlanes::Clip gives from
// [0, min(End, stop)), bit for bit where that is not empty (an empty one may be held by other
// empty values), and nothing where near >= stop (the cell
// lies behind where the ray is opaque); stop (by ray) may be null. Without a lattice the rays
// kept are those with Tin < Tout; with one, those whose interval holds a lattice point, whose
// first index goes to Lattice. Returns how many rays were kept. Eight rays per AVX-512
// instruction or four per AVX2 instruction where the processor has them, else ray by ray
// (CellPlanes::Clip, Lattice::First).
int ClipRays(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
  const double* stop, double near, const Lattice* lattice, ClippedRays& out);
// The two forms ClipRays chooses from (tests); ClipRaysAvx2 only where HasAvx2().
int ClipRaysScalar(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
  const double* stop, double near, const Lattice* lattice, ClippedRays& out);
int ClipRaysAvx2(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
  const double* stop, double near, const Lattice* lattice, ClippedRays& out);
// ClipRaysAvx2 with eight rays per instruction (two packets of four at once), the same
// output; only where HasAvx512().
int ClipRaysAvx512(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
  const double* stop, double near, const Lattice* lattice, ClippedRays& out);
bool HasAvx2();
bool HasAvx512();

// Sample End Weights = Boundary: CellPlanes::BoundaryEnds of the rays hits[0, count) of out
// (each over [Tin, Tout), as ClipRays left it), bit for bit, four rays at a time: ends[h]
// bit 0 the entry's flag (in), bit 1 the exit's (out) of ray hits[h]. ends holds count + 3
// entries. Ray by ray, a loop over the cell's planes with a division per boundary plane.
void BoundaryEnds(const CellPlanes& planes, const TileRays& rays, const ClippedRays& out,
  const uint16_t* hits, int count, uint8_t* ends);
// The two forms BoundaryEnds chooses from (tests); the AVX2 one only where HasAvx2().
void BoundaryEndsScalar(const CellPlanes& planes, const TileRays& rays, const ClippedRays& out,
  const uint16_t* hits, int count, uint8_t* ends);
void BoundaryEndsAvx2(const CellPlanes& planes, const TileRays& rays, const ClippedRays& out,
  const uint16_t* hits, int count, uint8_t* ends);

// With end weights (apcEndWeights.h): each kept pair's EndWeightsOf(lattice, Tin, End,
// Offset), bit for bit, by the ray's index in the tile, End the pair's end before the opaque
// stop cut it (CellPlanes::Clip from [0, TileRays::End)). Found with the clipping, four rays
// at a time: ray by ray, the two Lattice::First of each pair and their corrections cost the
// weighted marcher about as much as the samples' hand-over.
struct ClippedWeights
{
  double First[TileRays::kSize]; // EndWeights::First, Last (integers)
  double Last[TileRays::kSize];
  double FirstWeight[TileRays::kSize]; // EndWeights::FirstWeight, LastWeight; with Mid, both
  double LastWeight[TileRays::kSize];  // MidWeight
  double MidT[TileRays::kSize];        // with Mid
  // The lattice offset a lane steps from: the ray's, or with Mid EndWeights::MidOffset.
  double LaneOffset[TileRays::kSize];
  double Mid[TileRays::kSize]; // 1: no lattice point in the pair (EndWeights::Mid)
  // The kept rays with Mid, in the rectangle's order (ClippedRays::Hits holds the others):
  // the lanes take those, the scalar loop these, with no test per ray to tell them apart.
  uint16_t MidHits[kTilePixels + 3];
  int MidCount = 0;

  EndWeights Of(int l) const
  {
    EndWeights w;
    w.First = static_cast<int64_t>(this->First[l]);
    w.Last = static_cast<int64_t>(this->Last[l]);
    w.FirstWeight = this->FirstWeight[l];
    w.LastWeight = this->LastWeight[l];
    w.Mid = this->Mid[l] != 0;
    w.MidT = this->MidT[l];
    w.MidOffset = w.Mid ? this->LaneOffset[l] : 0.0;
    w.MidWeight = this->FirstWeight[l];
    return w;
  }
};

// ClipRays without a lattice (every ray with Tin < Tout kept, the same Tin and Tout) and each
// kept ray's end weights on the lattice to weights; the kept rays with a lattice point go to
// out.Hits (their count is returned), those without one to weights.MidHits (MidCount), each
// in the rectangle's order. Four rays per AVX2 instruction where the processor has it, else
// ray by ray (CellPlanes::Clip, EndWeightsOf).
int ClipRaysWeighted(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
  const double* stop, double near, const Lattice& lattice, ClippedRays& out,
  ClippedWeights& weights);
// The two forms ClipRaysWeighted chooses from (tests); the AVX2 one only where HasAvx2().
int ClipRaysWeightedScalar(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
  const double* stop, double near, const Lattice& lattice, ClippedRays& out,
  ClippedWeights& weights);
int ClipRaysWeightedAvx2(const CellPlanes& planes, const TileRays& rays, const RayRect& rect,
  const double* stop, double near, const Lattice& lattice, ClippedRays& out,
  ClippedWeights& weights);

} // namespace walk
} // namespace apc

#endif
