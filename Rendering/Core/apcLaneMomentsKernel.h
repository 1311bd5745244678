// The lanes' hand-over to the pixels' moment sums (LaneMomentsAvx2, LaneWeightedMomentsAvx2,
// LaneMomentsAvx512), written once over the width (internal to apcLaneMoments.cpp and
// apcLaneMomentsAvx512.cpp): each includes it after a "#pragma GCC target" of its instruction
// set, with its width's Ops (apcLaneOps4.h, apcLaneOps8.h), so that every lane performs
// Moments::RunAdd's and OpaqueBins::Quanta's IEEE operations in the same order at either width
// and every sum, depth and quanta is the same bit for bit. No product and sum may be fused:
// both files are compiled with -ffp-contract=off (AVX-512 includes FMA).
#ifndef apcLaneMomentsKernel_h
#define apcLaneMomentsKernel_h

#include "apcDepthWarp.h"
#include "apcLaneMoments.h"
#include "apcOpaqueBins.h"

namespace apc
{
namespace walk
{
namespace kernel
{

// Steps without end weights: each absorbance as the lanes found it, no record weights.
template <class O>
struct Unweighted
{
  __attribute__((always_inline)) typename O::F Apply(int, typename O::F absorbance) const
  {
    return absorbance;
  }
  __attribute__((always_inline)) void Store(typename O::Out&, int, typename O::M) const {}
};

// Adds steps 0 .. taken - 1 of O::Width lanes to their pixels' sums (LaneMomentsAvx2's
// contract); weigh first weighs each step's float absorbance (weigh.Apply) and keeps each
// visible step's record weight (weigh.Store).
template <class O, class Weigh>
__attribute__((always_inline)) inline void Moments(const typename O::StepsIn& steps, int taken,
  const typename O::Rays& rays, const typename O::Sums& sums, const LatticeDepthWarp& warp,
  double quantaPerAbsorbance, Weigh& weigh, typename O::Out& out)
{
  using D = typename O::D;
  using M = typename O::M;
  // The pixels' sums, one pixel per lane.
  D b[5];
  O::LoadSums(sums, b);
  const D zero = O::Zero();
  const D one = O::Set(1.0);
  const D tout = O::Load(rays, &LaneRays::Tout);
  // LatticeDepthWarp's table: index k - Base in [0, size) and t == k spacing (the lattice's
  // own depth, not a jittered one); the integers are exact as doubles.
  const double* entries = warp.GetEntries();
  const D base = O::Set(static_cast<double>(warp.GetBase()));
  const D size = O::Set(static_cast<double>(warp.GetNumberOfEntries()));
  const D spacing = O::Set(warp.GetSpacing());
  const D perAbsorbance = O::Set(quantaPerAbsorbance);
  const D opaque = O::Set(static_cast<double>(OpaqueBins::kOpaque));
  D k = O::Load(rays, &LaneRays::K);
  typename O::Counts count = O::NoCounts();
  typename O::Counts visible = O::NoCounts();
  typename O::I quanta = O::NoQuanta();
  for (int s = 0; s < taken; ++s, k = O::Add(k, one)) // k + 1 is exact: an integer
  {
    const D t = O::Load(steps, &LaneSteps::T, s);
    const M inside = O::Lt(t, tout);
    D a = O::Widen(weigh.Apply(s, O::LoadAbsorbance(steps, s)));
    const M vis = O::Both(inside, O::Gt(a, zero));
    weigh.Store(out, s, vis);
    // A step that is not visible adds a * z^m = +0 (z = 0): the sums stay as they are.
    a = O::Keep(vis, a);
    const D index = O::Sub(k, base);
    const M inTable =
      O::Both(O::Both(O::Ge(index, zero), O::Lt(index, size)), O::Eq(t, O::Mul(k, spacing)));
    const M take = O::Both(inTable, vis);
    D z = O::Gather(entries, index, take);
    const unsigned miss = O::Missing(inTable, vis);
    if (miss != 0)
    {
      // A jittered ray's depth, or an index outside the table: the warp itself.
      alignas(64) double zs[O::Width];
      alignas(64) double ts[O::Width];
      O::Store(zs, z);
      O::Store(ts, t);
      for (unsigned m = miss; m; m &= m - 1)
      {
        const int i = __builtin_ctz(m);
        zs[i] = warp.GetWarp()(ts[i]);
      }
      z = O::Load(zs);
    }
    // AccumulateCheckedPowerMoments: w = a, then w *= z for each higher moment.
    b[0] = O::Add(b[0], a);
    D w = O::Mul(a, z);
    b[1] = O::Add(b[1], w);
    w = O::Mul(w, z);
    b[2] = O::Add(b[2], w);
    w = O::Mul(w, z);
    b[3] = O::Add(b[3], w);
    w = O::Mul(w, z);
    b[4] = O::Add(b[4], w);
    O::StoreZ(out, s, z);
    // OpaqueBins::Quanta: q >= kOpaque ? kOpaque : (q > 0 ? truncated q : 0).
    D q = O::Mul(a, perAbsorbance);
    q = O::Blend(q, opaque, O::Ge(q, opaque));
    q = O::Keep(O::Gt(q, zero), q);
    const typename O::I qi = O::Truncate(q);
    O::StoreQuanta(out, s, qi);
    quanta = O::AddQuanta(quanta, qi); // at most kLaneSteps times kOpaque: no overflow
    count = O::CountIn(count, inside);
    visible = O::Mark(visible, vis, s);
  }
  O::StoreMoments(out, b, count, visible, quanta);
}

} // namespace kernel
} // namespace walk
} // namespace apc

#endif
