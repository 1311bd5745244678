// The samples of one (cell, ray) pair weighted so that they sum to the pair's exact length
// (VolumeRayMarcher::SetSampleEndWeights). Every lattice sample stands for one spacing s of
// ray, so a ray's sampled length inside the mesh jumps by s whenever a boundary face crosses
// a lattice point: along a grazing silhouette those jumps line up into a staircase. Weighted,
// the pair's first sample counts (t_first - tin) / s + 1/2, its last (tout - t_last) / s + 1/2
// and a pair's only sample (tout - tin) / s, the others 1: the weights sum to (tout - tin) / s,
// two pairs meeting at a shared face still sum to 2 there (the interior hardly changes), and
// the mesh's boundary is integrated exactly. A pair with no lattice point gets one sample at
// its middle weighted by its length, so that grazing slivers of boundary cells do not drop in
// and out. The weights depend only on the pair's interval (the cell and the ray), never on
// which process holds the cell. Internal to the core's marcher.
#ifndef apcEndWeights_h
#define apcEndWeights_h

#include "apcRayWalk.h"

#include <cstdint>

namespace apc
{
namespace walk
{

struct EndWeights
{
  int64_t First = 0; // the first lattice index in [tin, tout); with Mid, the one before tin
  int64_t Last = -1; // the last lattice index in [tin, tout) (< First: none)
  double FirstWeight = 1;
  double LastWeight = 1;
  // No lattice point in [tin, tout): one sample at MidT of weight MidWeight, which counts as
  // lattice index First (the lattice point before it, so that it falls in the opaque stop's
  // bin whose edge lies behind it). MidT is Lattice::At(First, MidOffset), the pair's middle
  // as a point of the ray's lattice shifted by MidOffset - offset: the lanes, which step
  // from (K + Offset) spacing, take it as a lane's first step with Offset = MidOffset.
  bool Mid = false;
  double MidT = 0;
  double MidOffset = 0;
  double MidWeight = 0;

  // The weight of lattice sample k of the pair (First <= k <= Last).
  double Of(int64_t k) const
  {
    return k == this->First ? this->FirstWeight : (k == this->Last ? this->LastWeight : 1.0);
  }
};

// The weights of the pair [tin, tout) (tin < tout) of a ray with this lattice offset, given
// first = lattice.First(tin, offset) and next = lattice.First(tout, offset) (a caller that
// has them already does not search the lattice again).
[[gnu::always_inline]] inline EndWeights EndWeightsOf(
  const Lattice& lattice, double tin, double tout, double offset, int64_t first, int64_t next)
{
  EndWeights w;
  w.First = first;
  w.Last = next - 1;
  if (w.Last < w.First)
  {
    w.Mid = true;
    w.First -= 1;
    w.MidOffset = 0.5 * (tin + tout) * lattice.InverseSpacing - static_cast<double>(w.First);
    w.MidT = lattice.At(w.First, w.MidOffset);
    w.MidWeight = (tout - tin) * lattice.InverseSpacing;
    return w;
  }
  if (w.Last == w.First)
  {
    w.FirstWeight = w.LastWeight = (tout - tin) * lattice.InverseSpacing;
    return w;
  }
  w.FirstWeight = (lattice.At(w.First, offset) - tin) * lattice.InverseSpacing + 0.5;
  w.LastWeight = (tout - lattice.At(w.Last, offset)) * lattice.InverseSpacing + 0.5;
  return w;
}

// The weights of the pair [tin, tout) (tin < tout) of a ray with this lattice offset.
[[gnu::always_inline]] inline EndWeights EndWeightsOf(
  const Lattice& lattice, double tin, double tout, double offset)
{
  return EndWeightsOf(
    lattice, tin, tout, offset, lattice.First(tin, offset), lattice.First(tout, offset));
}

// The weights of the pair [tin, tout) with only some of its ends weighted (Sample End Weights
// = Boundary: the ends on the mesh's boundary, CellMesh::GetBoundaryPlanes). A weighted end
// counts exactly from the face, a plain one covers half a spacing past its last lattice
// point, as the plain lattice does, so that it meets a plain neighbour's first sample exactly
// at the half way point between their lattice points. Both ends weighted: EndWeightsOf, bit
// for bit; neither: the plain lattice's samples, each of weight 1, none without a lattice
// point. A pair without a lattice point and one weighted end is the only one whose exact
// weight can be negative: entered at tin through the boundary, left through a plain face
// before the next lattice point t_next, whose sample (in the next cell) already covers from
// t_next - s/2, so the pair's exact weight is (t_next - s/2 - tin) / s, down to -1/2. A
// negative weight is clamped to no sample (the marcher takes no sample of non-positive
// absorbance either): the ray then counts up to s/2 more than its length there.
// With firstIndex = lattice.First(tin, offset) and nextIndex = lattice.First(tout, offset)
// given.
[[gnu::always_inline]] inline EndWeights EndWeightsAt(const Lattice& lattice, double tin,
  double tout, double offset, bool weightedIn, bool weightedOut, int64_t firstIndex,
  int64_t nextIndex)
{
  if (weightedIn && weightedOut)
  {
    return EndWeightsOf(lattice, tin, tout, offset, firstIndex, nextIndex);
  }
  EndWeights w;
  w.First = firstIndex;
  w.Last = nextIndex - 1;
  if (!weightedIn && !weightedOut)
  {
    return w;
  }
  if (w.Last < w.First)
  {
    // The half spacing before the next lattice point / after the previous one belongs to
    // the plain end's neighbour.
    const double weight = weightedIn
      ? (lattice.At(w.First, offset) - tin) * lattice.InverseSpacing - 0.5
      : (tout - lattice.At(w.First - 1, offset)) * lattice.InverseSpacing - 0.5;
    if (!(weight > 0))
    {
      w.Last = w.First - 1; // no sample
      return w;
    }
    w.Mid = true;
    w.First -= 1;
    w.MidOffset = 0.5 * (tin + tout) * lattice.InverseSpacing - static_cast<double>(w.First);
    w.MidT = lattice.At(w.First, w.MidOffset);
    w.MidWeight = weight;
    return w;
  }
  const double first =
    weightedIn ? (lattice.At(w.First, offset) - tin) * lattice.InverseSpacing + 0.5 : 1.0;
  const double last =
    weightedOut ? (tout - lattice.At(w.Last, offset)) * lattice.InverseSpacing + 0.5 : 1.0;
  if (w.Last == w.First)
  {
    // One lattice point: its weight counts the weighted end exactly and the plain one as
    // the plain lattice does.
    w.FirstWeight = w.LastWeight = first + last - 1.0;
    return w;
  }
  w.FirstWeight = first;
  w.LastWeight = last;
  return w;
}

[[gnu::always_inline]] inline EndWeights EndWeightsAt(
  const Lattice& lattice, double tin, double tout, double offset, bool weightedIn, bool weightedOut)
{
  return EndWeightsAt(lattice, tin, tout, offset, weightedIn, weightedOut,
    lattice.First(tin, offset), lattice.First(tout, offset));
}

} // namespace walk
} // namespace apc

#endif
