// Pass 1's hand-over of a lanes' call (LaneSamplesAvx2's steps of four rays, one pixel per
// lane) to the four pixels' moment sums, four pixels at once (internal to the marcher's
// walker): each step's depth warp, its four power-moment products and five sums, and the
// opaque stop's quanta, as vectors across the lanes instead of ray after ray. Each pixel still
// receives its own samples in lattice order, with the same operations, so its sums are the
// same bit for bit as from Moments::RunAdd per visible sample (the walker keeps or drops each
// lane's run and writes its records).
#ifndef apcLaneMoments_h
#define apcLaneMoments_h

#include "apcDepthWarp.h"
#include "apcLaneSamples.h"

#include <cstdint>

namespace apc
{
namespace walk
{

// What LaneMomentsAvx2 finds for one call's steps, by lane.
struct LaneMoments
{
  // Each lane's five sums (4 power moments) with its visible steps added, lane by lane.
  alignas(32) double Sums[4][4];
  alignas(32) double Sum4[4];
  // Each step's warped depth, rounded to float (the record's), and its quanta
  // (OpaqueBins::Quanta; 0 where the step is not visible), step by step.
  alignas(16) float Z[kLaneSteps][4];
  alignas(16) uint32_t Quanta[kLaneSteps][4];
  // The lane's steps inside its interval (t < Tout), the sum of their quanta, and a bit per
  // visible step (inside, absorbance > 0).
  alignas(32) int64_t Steps[4];
  alignas(32) int64_t QuantaSum[4];
  alignas(32) int64_t Visible[4];
  // With end weights (LaneWeightedMomentsAvx2): each step's record weight, step by step: its
  // end weight where the step is visible, else 1 (Moments::RunAddWeighted's).
  alignas(16) float Weight[kLaneSteps][4];
};

// With end weights: each lane's pair's first and last lattice index (integers, as doubles) and
// their float weights (walk::EndWeights' as the walker casts them); every other step weighs 1.
// A pair without a lattice point has First == Last and its middle weight in both.
struct LaneWeights
{
  alignas(32) double First[4];
  alignas(32) double Last[4];
  alignas(16) float FirstWeight[4];
  alignas(16) float LastWeight[4];
};

// Adds steps 0 .. taken - 1 of the four lanes (rays.K: each lane's first index, rays.Tout its
// end) to the sums of each lane's pixel (sums[i]: five doubles, read only): a step at or past
// Tout adds nothing, a visible one absorbance times 1, z, z^2, z^3, z^4 with z =
// warp(k, t) (the table where warp takes it, else the warp itself), in AccumulateCheckedPower
// Moments' order. With quantaPerAbsorbance > 0 each visible step's quanta are found too
// (OpaqueBins::Quanta of that scale). Only where HasAvx2().
void LaneMomentsAvx2(const LaneSteps& steps, int taken, const LaneRays& rays,
  const double* const sums[4], const LatticeDepthWarp& warp, double quantaPerAbsorbance,
  LaneMoments& out);

// LaneMomentsAvx2 of two groups of four lanes at once (eight lanes): group a's steps sa, rays
// ra and pixels sumsA into oa, group b's into ob, taken steps of both (LaneSamplesAvx512's
// count), each the same bit for bit as LaneMomentsAvx2 of that group with taken steps. Only
// where HasAvx512().
void LaneMomentsAvx512(const LaneSteps& sa, const LaneSteps& sb, int taken, const LaneRays& ra,
  const LaneRays& rb, const double* const sumsA[4], const double* const sumsB[4],
  const LatticeDepthWarp& warp, double quantaPerAbsorbance, LaneMoments& oa, LaneMoments& ob);

// LaneMomentsAvx2 of end-weighted steps: each step's float absorbance is first multiplied by
// its weight in float (weights: the lane's FirstWeight at its First index, else LastWeight at
// its Last index, else 1), as the walker's scalar hand-over does, and out.Weight keeps each
// step's record weight. The same sums, depths, quanta and weights bit for bit as
// Moments::RunAddWeighted per step.
void LaneWeightedMomentsAvx2(const LaneSteps& steps, int taken, const LaneRays& rays,
  const double* const sums[4], const LatticeDepthWarp& warp, double quantaPerAbsorbance,
  const LaneWeights& weights, LaneMoments& out);

// GatherLaneRays for end-weighted pairs (the walker's LaneSamples<true>): rays as
// GatherLaneRays fills them but each lane's first index from ends.First and its offset from
// ends.LaneOffset, and weights with the pairs' First, Last and their weights rounded to float;
// one vector store per field, so that the lanes' vector loads take them from the stores.
// Only where HasAvx2().
void GatherWeightedLaneRays(const TileRays& packed, const ClippedRays& clipped,
  const ClippedWeights& ends, const uint16_t* list, int n, LaneRays& rays, LaneWeights& weights);

} // namespace walk
} // namespace apc

#endif
