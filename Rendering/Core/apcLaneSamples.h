// Pass 1's samples of up to four rays of one nearly affine cell at a time, one ray per AVX2
// lane: lane i holds ray i's k-th sample, so the rays' independent table look-ups overlap
// (internal to the marcher; VolumeRayMarcher::Walker hands the results to its visitor ray by
// ray). The same samples and values, bit for bit, as the walker's scalar sample loop.
#ifndef apcLaneSamples_h
#define apcLaneSamples_h

#include "apcRayClip.h"
#include "apcTransferTable.h"

#include <cstdint>

namespace apc
{
class CellInterpolator;

namespace walk
{

// What the lanes need of a cell sampled by its linear inverse (CellInterpolator::LinearRay,
// LinearScalarAt), or of a twisted pyramid sampled by its closed-form inverse
// (PyramidScalarAt at LinearRay's coordinates), with every ray starting at the same point.
struct LaneCell
{
  bool Pyramid;         // LinearScalarAt's pyramid form (SC[0 .. 4]), else ScalarAt
  bool Twisted = false; // PyramidScalarAt (SC[0 .. 4] and G) instead of LinearScalarAt
  double Inverse[3][3]; // LinearRayDirection's matrix
  double P0[3];         // LinearRayOrigin of the shared origin
  double SC[8];         // LinearScalarAt's coefficients
  double G[3] = {};     // with Twisted: CellInterpolator::GetPyramidG
  double Lo;            // the cell's scalar range (the loop's clamp)
  double Hi;
  TransferTable::Layout Table;
  double Spacing; // Lattice::Spacing
  // Pass 1's own stop: the first kBinEnds bin ends (RayProgress::BinEnds, exact as doubles,
  // evenly spaced as OpaqueBins::End makes them), or null (no bins to find).
  const double* BinEnds = nullptr;
};

// The bin ends a lane compares with (the last bin reaches to the end of every ray).
constexpr int kBinEnds = 15;

// Four rays, one per lane: each one's next lattice index (an integer, as a double), its
// lattice offset, the end of its interval (-inf for an unused lane) and its direction.
struct LaneRays
{
  alignas(32) double K[4];
  alignas(32) double Offset[4];
  alignas(32) double Tout[4];
  alignas(32) double D[3][4];
};

// Samples per lane and call: most (cell, ray) pairs hold one to three.
constexpr int kLaneSteps = 8;

// Step s of lane i: the depth t of lattice index K[i] + s, the clamped scalar there and the
// table's absorbance (0 for a scalar that is not finite, as TransferTable::Lookup gives).
// Values of a step at or past a lane's Tout are left unspecified.
struct LaneSteps
{
  alignas(32) double T[kLaneSteps][4];
  alignas(32) double Scalar[kLaneSteps][4];
  alignas(16) float Absorbance[kLaneSteps][4];
  // With BinEnds: the opaque bin of each lane's first index K (RayProgress::BinOf's value),
  // from compares side by side instead of BinOf's chain of dependent loads.
  alignas(32) int64_t Bin[4];
};

// A LaneCell's constants as the lanes use them, each one already broadcast to four lanes:
// formed once per cell (SetUpLaneCell) and read by every call of the cell. Formed per call,
// the thirty-odd broadcasts did not fit the registers and were spilled to the stack on every
// call (a call takes two or three steps at 1024²), about a fifth of the kernel's time.
struct LaneCellVectors
{
  alignas(32) double Inverse[3][3][4];
  alignas(32) double P0[3][4];
  alignas(32) double SC[8][4];
  alignas(32) double G[3][4];  // with Twisted
  alignas(32) double FourA[4]; // with Twisted: 4.0 * A, as B * B + 4.0 * A * C groups it
  alignas(32) double TwoA[4];
  alignas(32) double Lo[4];
  alignas(32) double Hi[4];
  alignas(32) double Spacing[4];
  alignas(32) double Min[4]; // the table's layout
  alignas(32) double Scale[4];
  alignas(32) double Last[4];
  // With Bins: where bin 0 starts and the bins' width (OpaqueBins::Base, Width), exact, and
  // the width's rounded inverse.
  alignas(32) double BinBase[4];
  alignas(32) double BinWidth[4];
  alignas(32) double BinInverse[4];
  const float* AbsorbancePairs; // the table's (TransferTable::Layout)
  bool Pyramid;
  bool Twisted;
  bool Other; // with Twisted: A != 0, the second root may be tried
  bool Bins;  // LaneCell::BinEnds was set
};

// Forms vectors from cell. Only where HasAvx2() (apcRayClip.h).
void SetUpLaneCell(const LaneCell& cell, LaneCellVectors& vectors);

// SetUpLaneCell in two parts, for the walker: what every cell of a tile shares (cell.Table,
// Spacing and BinEnds), formed once per tile, and each cell's own part, formed from the
// interpolator it was set up with (its linear inverse, scalar coefficients, pyramid form and,
// twisted, G), the shared origin's p0 and its scalar range, with no LaneCell copied between.
// Together the same vectors as SetUpLaneCell's. Only where HasAvx2().
void SetUpLaneTile(const LaneCell& cell, LaneCellVectors& vectors);
void SetUpLaneCellOf(const CellInterpolator& interpolator, bool twisted, const double p0[3],
  double lo, double hi, LaneCellVectors& vectors);

// Fills steps 0 .. n - 1 for the four lanes of the cell set up in vectors and returns n:
// kLaneSteps, or fewer where no lane has a sample at step n (t >= Tout in every lane). Each
// lane performs the IEEE operations of the scalar loop (LinearRayDirection, p0 + t dp,
// LinearScalarAt or PyramidScalarAt, the clamp, TransferTable::Lookup's position, entries and
// interpolation) in the same order and without FMA. Only where HasAvx2().
int LaneSamplesAvx2(const LaneCellVectors& cell, const LaneRays& rays, LaneSteps& steps);

// LaneSamplesAvx2 of two groups of four rays at once (a and b, eight lanes): the steps of each
// group in sa and sb, bit for bit those LaneSamplesAvx2 gives it, and the count of steps of
// the two together (the larger of the two calls' counts; a group's steps past its own count
// are computed as its lanes' values there, past every lane's Tout). Only where HasAvx512().
int LaneSamplesAvx512(
  const LaneCellVectors& cell, const LaneRays& a, const LaneRays& b, LaneSteps& sa, LaneSteps& sb);

// Fills rays with the tile's rays list[0 .. n - 1] (n <= 4; directions and offsets from packed,
// first lattice indices and interval ends from clipped), lanes n .. 3 unused (Tout = -inf),
// one vector store per field: loads of the lanes from stores of one double each waited for
// those stores to reach the cache. Only where HasAvx2().
void GatherLaneRays(
  const TileRays& packed, const ClippedRays& clipped, const uint16_t* list, int n, LaneRays& rays);

} // namespace walk
} // namespace apc

#endif
