// The clip's packet of rays against one cell and its first lattice indices (ClipRaysAvx2,
// ClipRaysWeightedAvx2, ClipRaysAvx512), written once over the width (internal to
// apcRayClip.cpp and apcRayClipAvx512.cpp): each includes it after a "#pragma GCC target" of
// its instruction set, with its width's Ops (apcLaneOps4.h: one packet of four rays from l on;
// apcLaneOps8.h: two such packets side by side), so that every lane performs the IEEE
// operations of CellPlanes::Clip and Lattice::First in the same order at either width. No
// product and sum may be fused: both files are compiled with -ffp-contract=off (AVX-512
// includes FMA).
#ifndef apcRayClipKernel_h
#define apcRayClipKernel_h

#include "apcRayClip.h"

#include <cstdint>
#include <limits>

namespace apc
{
namespace walk
{
namespace kernel
{

// Plane p against the packet's rays (directions d, origins o where the rays do not share one
// and O::kOriginsOnce, else the origins read from rays here): the denominator n.d and the
// numerator offset - n.o of Clip's quotient. No FMA: the products and sums must round as
// Clip's do, and ParallelOut's as ClipPacket's.
template <class O>
__attribute__((always_inline)) inline void PlaneTerms(const CellPlanes& planes,
  const TileRays& rays, typename O::Packet packet, int p, const typename O::D* d,
  const typename O::D* o, typename O::D& denom, typename O::D& num)
{
  using D = typename O::D;
  const D nx = O::Set(planes.Nx[p]);
  const D ny = O::Set(planes.Ny[p]);
  const D nz = O::Set(planes.Nz[p]);
  denom = O::Add(O::Add(O::Mul(nx, d[0]), O::Mul(ny, d[1])), O::Mul(nz, d[2]));
  if (planes.SharedOrigin)
  {
    num = O::Set(planes.Num[p]);
    return;
  }
  D dot;
  if constexpr (O::kOriginsOnce)
  {
    dot = O::Add(O::Add(O::Mul(nx, o[0]), O::Mul(ny, o[1])), O::Mul(nz, o[2]));
  }
  else
  {
    dot = O::Add(O::Add(O::Mul(nx, O::Row(rays.Ox, packet)), O::Mul(ny, O::Row(rays.Oy, packet))),
      O::Mul(nz, O::Row(rays.Oz, packet)));
  }
  num = O::Sub(O::Set(planes.Offset[p]), dot);
}

// The packet's directions, and with O::kOriginsOnce its origins where the rays do not share
// one (else zero).
template <class O>
__attribute__((always_inline)) inline void Directions(const CellPlanes& planes,
  const TileRays& rays, typename O::Packet packet, typename O::D* d, typename O::D* o)
{
  d[0] = O::Row(rays.Dx, packet);
  d[1] = O::Row(rays.Dy, packet);
  d[2] = O::Row(rays.Dz, packet);
  o[0] = o[1] = o[2] = O::Zero();
  if (O::kOriginsOnce && !planes.SharedOrigin)
  {
    o[0] = O::Row(rays.Ox, packet);
    o[1] = O::Row(rays.Oy, packet);
    o[2] = O::Row(rays.Oz, packet);
  }
}

// The lanes of the packet that run inside a plane of the cell and are outside it (see Clip).
// Rare (rays parallel to a plane), so ClipPacket looks for them only where some lane's
// denominator is zero, with the same products and sums; out of line, so that the rare path
// does not take the inlining and unrolling the plane loop above it gets.
template <class O>
__attribute__((noinline)) typename O::M ParallelOut(
  const CellPlanes& planes, const TileRays& rays, typename O::Packet packet)
{
  using D = typename O::D;
  using M = typename O::M;
  const D zero = O::Zero();
  D d[3];
  D o[3];
  Directions<O>(planes, rays, packet, d, o);
  M out = O::None();
  for (int p = 0; p < planes.Count; ++p)
  {
    D denom;
    D num;
    PlaneTerms<O>(planes, rays, packet, p, d, o, denom, num);
    M parallelOut = O::Lt(num, zero);
    if (planes.KeepsParallelRays[p] == 0)
    {
      parallelOut = O::Or(parallelOut, O::Eq(num, zero));
    }
    out = O::Or(out, O::Both(O::Eq(denom, zero), parallelOut));
  }
  return out;
}

// The interval of the packet's rays; lanes not valid (past the row's end, or no second packet)
// read no stop. Only the planes the cell has: the padding planes of CellPlanes clip nothing.
// No FMA: the products and sums must round as Clip's do. A packet left early holds empty
// intervals that need not be Clip's (ClipRays keeps no ray of it either way).
template <class O>
__attribute__((always_inline)) inline void ClipPacket(const CellPlanes& planes,
  const TileRays& rays, typename O::Packet packet, typename O::M valid, const double* stop,
  double near, typename O::D& lo, typename O::D& hi)
{
  using D = typename O::D;
  using M = typename O::M;
  const D zero = O::Zero();
  const D inf = O::Set(std::numeric_limits<double>::infinity());
  const D minusInf = O::Set(-std::numeric_limits<double>::infinity());
  D d[3];
  D o[3];
  Directions<O>(planes, rays, packet, d, o);
  lo = zero;
  hi = O::Row(rays.End, packet);
  M out = O::None();
  M parallel = O::None(); // lanes running inside some plane (rare: see ParallelOut)
  if (stop)
  {
    // min(tout, stop) as std::min keeps tout on a tie. stop holds no padding.
    const D s = O::RowWhere(stop, packet, valid);
    hi = O::Min(s, hi);
    out = O::Ge(O::Set(near), s);
    // A lane out here (the cell lies behind where its ray is opaque) ends empty whatever the
    // planes give: a packet whose valid lanes are all out needs no plane (such packets come
    // in runs, where a tile's rays turned opaque in front of the cell), and the test after
    // the third plane below counts only the others as open.
    if (!O::Any(O::AndNot(out, valid)))
    {
      hi = minusInf;
      return;
    }
  }
  // The valid lanes not out: the only ones that can keep a ray.
  const M open = O::AndNot(out, valid);
  for (int p = 0; p < planes.Count; ++p)
  {
    D denom;
    D num;
    PlaneTerms<O>(planes, rays, packet, p, d, o, denom, num);
    const D q = O::Div(num, denom);
    const M entering = O::Lt(denom, zero);
    const M leaving = O::Gt(denom, zero);
    lo = O::Max(O::Blend(minusInf, q, entering), lo);
    hi = O::Min(O::Blend(inf, q, leaving), hi);
    parallel = O::Or(parallel, O::Eq(denom, zero));
    // lo only grows and hi only falls from plane to plane: where no valid lane is open after
    // three planes, the packet keeps no ray whatever the others give (about half of the
    // packets keep none at 1024²). Once per packet: a test after every plane cost more in
    // unpredictable branches than the planes it saved.
    if (p == 2 && planes.Count > 4 && !O::Any(O::Both(O::Lt(lo, hi), open)))
    {
      hi = minusInf; // an out lane may still be open here
      return;
    }
  }
  if (O::Any(parallel))
  {
    out = O::Or(out, ParallelOut<O>(planes, rays, packet));
  }
  hi = O::Blend(hi, minusInf, out);
}

// Lattice::First(lo) of the packet's rays, as doubles, and t_k: the smallest k with t_k >= lo.
// The ceiling k0 of the quotient is Lattice::First's first guess (truncation, then up for a
// positive fraction), which rounding leaves at most one off; t_k = (k + offset) spacing with
// Lattice::At's operations does not decrease with k, so t_(k0-2) < lo <= t_(k0+1) puts the
// answer in k0-1 .. k0+1, and the compares of those four values, formed side by side instead
// of a step down, a step up and a check one after the other, say which. A lane the window
// does not settle (never seen) is marked in unsettled (a bit per lane) and left to
// Lattice::First.
template <class O>
__attribute__((always_inline)) inline typename O::D FirstIndex(
  const Lattice& lattice, typename O::D lo, typename O::D offset, typename O::D& tk, int& unsettled)
{
  using D = typename O::D;
  using M = typename O::M;
  const D one = O::Set(1.0);
  const D two = O::Set(2.0);
  const D spacing = O::Set(lattice.Spacing);
  const D x = O::Sub(O::Mul(lo, O::Set(lattice.InverseSpacing)), offset);
  const D k0 = O::Ceil(x);
  const D k1 = O::Add(k0, one);
  // t_(k0+j), j = -2 .. 1 (the integers k0 + j are exact).
  const D tm2 = O::Mul(O::Add(O::Sub(k0, two), offset), spacing);
  const D tm1 = O::Mul(O::Add(O::Sub(k0, one), offset), spacing);
  const D t0 = O::Mul(O::Add(k0, offset), spacing);
  const D t1 = O::Mul(O::Add(k1, offset), spacing);
  const M cm2 = O::Ge(tm2, lo);
  const M cm1 = O::Ge(tm1, lo);
  const M c0 = O::Ge(t0, lo);
  const M c1 = O::Ge(t1, lo);
  // Settled: not t_(k0-2) >= lo, and t_(k0+1) >= lo; then k = k0 + 1 - [c_-1] - [c_0].
  unsettled = O::Bits(O::AndNot(cm2, c1)) ^ O::kAllLanes;
  tk = O::Blend(O::Blend(t1, t0, c0), tm1, cm1);
  return O::Sub(O::Sub(k1, O::Keep(cm1, one)), O::Keep(c0, one));
}

// The offsets in a packet of four rays of the lanes set in a 4-bit mask, in order, as four
// 16-bit numbers: the packet's kept rays are appended to ClippedRays::Hits with one store
// and a count instead of a loop per set lane, whose exits the processor could not predict.
struct LaneList
{
  uint64_t Lanes[16];
  constexpr LaneList()
    : Lanes()
  {
    for (int m = 0; m < 16; ++m)
    {
      int n = 0;
      for (int b = 0; b < 4; ++b)
      {
        if (m >> b & 1)
        {
          this->Lanes[m] |= static_cast<uint64_t>(b) << (16 * n++);
        }
      }
    }
  }
};
constexpr LaneList kLaneList;

} // namespace kernel
} // namespace walk
} // namespace apc

#endif
