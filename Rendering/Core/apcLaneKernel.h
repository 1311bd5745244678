// Pass 1's lanes kernel (LaneSamplesAvx2, LaneSamplesAvx512), written once over the width
// (internal to apcLaneSamples.cpp and apcLaneSamplesAvx512.cpp). Each includes it after a
// "#pragma GCC target" of its instruction set and with its own Ops: the vector operations of
// its width (D, M, C, Set, Add, ..., Absorbances) and its rays' loads and steps' stores (Rays,
// Steps: one group of four rays, or two groups a and b side by side, a's low). So the two
// widths perform the same IEEE operations per lane in the same order and give the same values
// bit for bit. Neither may fuse a product and a sum: both files are compiled with
// -ffp-contract=off (AVX-512 includes FMA).
#ifndef apcLaneKernel_h
#define apcLaneKernel_h

#include "apcCellInterpolation.h"
#include "apcLaneSamples.h"

#include <limits>

namespace apc
{
namespace walk
{
namespace kernel
{

// The scalar forms a cell's lanes take (CellInterpolator's).
enum class Form
{
  ScalarAt,       // LinearScalarAt of any shape but a pyramid
  LinearPyramid,  // LinearScalarAt of a pyramid
  PyramidScalarAt // a twisted pyramid's closed-form inverse
};

// std::max(a, b) is (a < b ? b : a); Max(x, y) is (x > y ? x : y): with the arguments
// swapped the same value, NaN and signed zeros included.
template <class O>
__attribute__((always_inline)) inline typename O::D StdMax(typename O::D a, typename O::D b)
{
  return O::Max(b, a);
}

// CellInterpolator::PyramidOutside of (q0, q1, q2).
template <class O>
__attribute__((always_inline)) inline typename O::D Outside(
  typename O::D q0, typename O::D q1, typename O::D q2, typename O::D one, typename O::D zero)
{
  const typename O::D below = O::Sub(one, q2);
  return StdMax<O>(StdMax<O>(StdMax<O>(O::Negate(q0), O::Sub(q0, below)),
                     StdMax<O>(O::Negate(q1), O::Sub(q1, below))),
    StdMax<O>(O::Negate(q2), zero));
}

// CellInterpolator::PyramidScalarAt at a = (a0, a1, a2), lane by lane: the same operations
// in the same order (PyramidCoordinates, PyramidPoint, PyramidOutside, the sum), the choice
// of root by blends; the other root only where some lane's first lies outside.
template <class O>
__attribute__((always_inline)) inline typename O::D PyramidScalar(const LaneCellVectors& cell,
  typename O::D a0, typename O::D a1, typename O::D a2, typename O::D one, typename O::D zero)
{
  using D = typename O::D;
  using M = typename O::M;
  const D g[3] = { O::C(cell.G[0]), O::C(cell.G[1]), O::C(cell.G[2]) };
  const D b = O::Add(O::Add(O::Sub(one, a2), O::Mul(a0, g[1])), O::Mul(a1, g[0]));
  const D cc = O::Mul(a0, a1);
  const D root = O::Sqrt(StdMax<O>(O::Add(O::Mul(b, b), O::Mul(O::C(cell.FourA), cc)), zero));
  const D denom = O::Blend(O::Sub(b, root), O::Add(b, root), O::Ge(b, zero));
  // denom != 0 (true for NaN) ? 2.0 * C / denom : 0.0
  D w = O::Keep(O::Neq(denom, zero), O::Div(O::Mul(O::Set(2.0), cc), denom));
  D q0 = O::Sub(a0, O::Mul(g[0], w));
  D q1 = O::Sub(a1, O::Mul(g[1], w));
  D q2 = O::Sub(a2, O::Mul(g[2], w));
  if (cell.Other)
  {
    const D outside = Outside<O>(q0, q1, q2, one, zero);
    const M far = O::Gt(outside, O::Set(apc::CellInterpolator::kPyramidInside));
    if (O::Any(far))
    {
      // A strongly twisted pyramid: the other root where its point lies nearer.
      const D other = O::Div(O::Negate(denom), O::C(cell.TwoA));
      const D r0 = O::Sub(a0, O::Mul(g[0], other));
      const D r1 = O::Sub(a1, O::Mul(g[1], other));
      const D r2 = O::Sub(a2, O::Mul(g[2], other));
      const M take = O::Both(far, O::Lt(Outside<O>(r0, r1, r2, one, zero), outside));
      w = O::Blend(w, other, take);
      q0 = O::Blend(q0, r0, take);
      q1 = O::Blend(q1, r1, take);
      q2 = O::Blend(q2, r2, take);
    }
  }
  D v = O::Add(O::C(cell.SC[0]), O::Mul(q0, O::C(cell.SC[1])));
  v = O::Add(v, O::Mul(q1, O::C(cell.SC[2])));
  v = O::Add(v, O::Mul(q2, O::C(cell.SC[3])));
  return O::Add(v, O::Mul(w, O::C(cell.SC[4])));
}

// The samples of up to kLaneSteps steps of O::Width lanes (LaneSamplesAvx2's contract, and
// LaneSamplesAvx512's for two groups). No FMA: a fused multiply-add would round once where the
// scalar loop rounds twice.
template <Form How, class O>
__attribute__((always_inline)) inline int Lanes(
  const LaneCellVectors& cell, const typename O::Rays& rays, typename O::Steps& steps)
{
  using D = typename O::D;
  // The pair's set-up for all lanes at once: dp = Inverse d, row by row as
  // LinearRayDirection sums it. The cell's constants are read from cell where they are used
  // (memory operands), not held in registers across the loop.
  const D dx = O::Direction(rays, 0);
  const D dy = O::Direction(rays, 1);
  const D dz = O::Direction(rays, 2);
  D dp[3];
  for (int i = 0; i < 3; ++i)
  {
    dp[i] =
      O::Add(O::Add(O::Mul(O::C(cell.Inverse[i][0]), dx), O::Mul(O::C(cell.Inverse[i][1]), dy)),
        O::Mul(O::C(cell.Inverse[i][2]), dz));
  }
  const D zero = O::Zero();
  const D one = O::Set(1.0);
  const D inf = O::Set(std::numeric_limits<double>::infinity());
  const D offset = O::Load(rays, &LaneRays::Offset);
  const D tout = O::Load(rays, &LaneRays::Tout);
  D k = O::Load(rays, &LaneRays::K);
  if (cell.Bins)
  {
    // The number of ends at or before K, BinOf's value, is floor((K - Base) / Width) held to
    // 0 .. kBinEnds (the ends are Base + (b + 1) Width): a multiply instead of a compare per
    // end (and instead of a division, whose latency showed). K - Base and Width are integers
    // below 2^53, exact as doubles. Where the quotient matters (about -1 to 16) the product
    // with the rounded inverse lies within 2^-47 of it, and a quotient that is not an integer
    // lies at least 1 / Width from the next one, so the product's floor is the integers' but
    // where the quotient is an integer n and the product rounds below it (width 49, n = 1):
    // then (floor + 1) Width, exact, is at most K - Base, and the bin is one more. Far from
    // the bins the clamp gives the first or last bin either way.
    const D d = O::Sub(k, O::C(cell.BinBase));
    D bin = O::Floor(O::Mul(d, O::C(cell.BinInverse)));
    const D up = O::Add(bin, O::Set(1.0));
    bin = O::Blend(bin, up, O::Le(O::Mul(up, O::C(cell.BinWidth)), d));
    bin = O::Min(O::Max(bin, O::Zero()), O::Set(static_cast<double>(kBinEnds)));
    O::StoreBins(steps, bin);
  }
  int s = 0;
  for (; s < kLaneSteps; ++s, k = O::Add(k, one)) // k + 1 is exact: an integer
  {
    // Lattice::At.
    const D t = O::Mul(O::Add(k, offset), O::C(cell.Spacing));
    if (!O::Any(O::Lt(t, tout)))
    {
      break;
    }
    const D r = O::Add(O::C(cell.P0[0]), O::Mul(t, dp[0]));
    const D q = O::Add(O::C(cell.P0[1]), O::Mul(t, dp[1]));
    const D u = O::Add(O::C(cell.P0[2]), O::Mul(t, dp[2]));
    D v;
    if (How == Form::PyramidScalarAt)
    {
      v = PyramidScalar<O>(cell, r, q, u, one, zero);
    }
    else if (How == Form::LinearPyramid)
    {
      // LinearScalarAt of a pyramid, (r, q, u) its (u, v, t): the twist where 1 - t > 0
      // (0 elsewhere, and for NaN), r and s clamped as std::min(std::max(x, 0.0), 1.0).
      const D below = O::Sub(one, u);
      const D rr = O::Min(one, O::Max(zero, O::Div(r, below)));
      const D ss = O::Min(one, O::Max(zero, O::Div(q, below)));
      const D twist = O::Keep(O::Gt(below, zero), O::Mul(O::Mul(rr, ss), below));
      v = O::Add(O::C(cell.SC[0]), O::Mul(u, O::C(cell.SC[3])));
      v = O::Add(v, O::Mul(r, O::C(cell.SC[1])));
      v = O::Add(v, O::Mul(q, O::C(cell.SC[2])));
      v = O::Add(v, O::Mul(twist, O::C(cell.SC[4])));
    }
    else
    {
      // ScalarAt, summed left to right.
      const D rq = O::Mul(r, q);
      v = O::Add(O::C(cell.SC[0]), O::Mul(r, O::C(cell.SC[1])));
      v = O::Add(v, O::Mul(q, O::C(cell.SC[2])));
      v = O::Add(v, O::Mul(u, O::C(cell.SC[3])));
      v = O::Add(v, O::Mul(rq, O::C(cell.SC[4])));
      v = O::Add(v, O::Mul(O::Mul(r, u), O::C(cell.SC[5])));
      v = O::Add(v, O::Mul(O::Mul(q, u), O::C(cell.SC[6])));
      v = O::Add(v, O::Mul(O::Mul(rq, u), O::C(cell.SC[7])));
    }
    // std::min(std::max(v, Lo), Hi): Max(Lo, v) is (Lo > v ? Lo : v), NaN kept, as
    // std::max(v, Lo); likewise Min(Hi, w) and std::min(w, Hi).
    const D scalar = O::Min(O::C(cell.Hi), O::Max(O::C(cell.Lo), v));
    // TransferTable::Lookup: a scalar that is not finite gives 0 (its lane reads entry 0).
    const typename O::M finite = O::Lt(O::Abs(scalar), inf);
    const D position = O::Mul(O::Sub(scalar, O::C(cell.Min)), O::C(cell.Scale));
    const D above = O::Blend(position, O::C(cell.Last), O::Gt(position, O::C(cell.Last)));
    const D x = O::Keep(finite, O::Blend(above, zero, O::Lt(position, zero)));
    O::Store(steps, &LaneSteps::T, s, t);
    O::Store(steps, &LaneSteps::Scalar, s, scalar);
    O::Absorbances(cell.AbsorbancePairs, x, finite, steps, s);
  }
  return s;
}

} // namespace kernel
} // namespace walk
} // namespace apc

#endif
