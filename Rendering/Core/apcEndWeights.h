// The samples of one (cell, ray) pair weighted so that they sum to the pair's exact length
// (VolumeRayMarcher::SetSampleEndWeights). Every lattice sample stands for one spacing s of
// ray, so a ray's sampled length inside the mesh jumps by s whenever a boundary face crosses
// a lattice point: along a grazing silhouette those jumps line up into a staircase.
//
// All (EndWeightsOf): the pair's first sample counts (t_first - tin) / s + 1/2, its last
// (tout - t_last) / s + 1/2 and a pair's only sample (tout - tin) / s, the others 1: the
// weights sum to (tout - tin) / s, two pairs meeting at a shared face still sum to 2 there
// (the interior hardly changes), and the mesh's boundary is integrated exactly. A pair with
// no lattice point gets one sample at its middle weighted by its length, so that grazing
// slivers of boundary cells do not drop in and out.
//
// Boundary (EndWeightsAt): only the ends on the mesh's boundary, and the ray's own end (an
// opaque surface's depth), are weighted. A sample at an end must be continuous in where the
// end lies: processes composite an opaque depth a few roundings apart, and a rule that moves
// weight from one sample to another as the end crosses a lattice point turns those roundings
// into half a sample's difference. So at a weighted end E (a boundary exit or the ray's end)
// no lattice sample covers more than its own half spacing past its point, and the rest, from
// t_last + s/2 to E, goes to one more sample taken at E itself (EndWeights::End), in the pair
// that holds E: as E reaches the next lattice point that sample becomes the lattice sample
// there with weight 1/2; as E falls back to t_last + s/2 its weight goes to 0 and t_last's
// begins to shrink. A weighted entry keeps the first sample's weight (t_first - tin) / s + 1/2:
// where the ray enters depends on the mesh alone, the same bits on every process.
//
// The weights depend only on the pair's interval, its ends' flags and the ray's end, never on
// which process holds the cell. Internal to the core's marcher.
#ifndef apcEndWeights_h
#define apcEndWeights_h

#include "apcRayWalk.h"

#include <algorithm>
#include <cfloat>
#include <cstdint>
#include <limits>

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
  // bin whose edge lies behind it). MidT is Lattice::At(First, MidOffset), as a point of the
  // ray's lattice shifted by MidOffset - offset: the lanes, which step from (K + Offset)
  // spacing, take it as a lane's first step with Offset = MidOffset. (Boundary: the pair's
  // middle, or its weighted end as End below.)
  bool Mid = false;
  double MidT = 0;
  double MidOffset = 0;
  double MidWeight = 0;
  // Boundary, a pair with a lattice point and a weighted end past t_Last + s/2: one more
  // sample after the lattice ones, at EndT (its end, a rounding before it) of weight
  // EndWeight, counted as lattice index Last; EndSample() gives it as a pair of its own.
  bool End = false;
  double EndT = 0;
  double EndOffset = 0;
  double EndWeight = 0;

  // The weight of lattice sample k of the pair (First <= k <= Last).
  double Of(int64_t k) const
  {
    return k == this->First ? this->FirstWeight : (k == this->Last ? this->LastWeight : 1.0);
  }

  // With End: the end sample alone, in the Mid form (the loops and lanes take it so).
  EndWeights EndSample() const
  {
    EndWeights e;
    e.First = e.Last = this->Last;
    e.Mid = true;
    e.MidT = this->EndT;
    e.MidOffset = this->EndOffset;
    e.MidWeight = e.FirstWeight = e.LastWeight = this->EndWeight;
    return e;
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

// A sample at the pair's end tout, counted as lattice index k: its point a rounding before
// tout (the loops and lanes take samples at t < tout), a function of tout and k alone, so
// that every process takes it at the same t.
[[gnu::always_inline]] inline void EndSampleAt(
  const Lattice& lattice, double tout, int64_t k, double& t, double& offset)
{
  const double step = (static_cast<double>(k < 0 ? -k : k) + 2.0) * DBL_EPSILON;
  offset = tout * lattice.InverseSpacing - static_cast<double>(k);
  t = lattice.At(k, offset);
  while (!(t < tout))
  {
    offset -= step;
    t = lattice.At(k, offset);
  }
}

// The weights of the pair [tin, tout) with only some of its ends weighted (Sample End Weights
// = Boundary: the ends on the mesh's boundary, CellMesh::GetBoundaryPlanes, and the ray's own
// end). A lattice sample covers the half spacing either side of its point, cut at a weighted
// end; a plain end leaves the half spacing before the next lattice point to that point's
// sample, so that it meets a plain neighbour's first sample exactly half way.
// - A weighted entry (weightedIn) counts exactly from tin: the first sample's weight is
//   (t_first - tin) / s + 1/2 (up to 3/2).
// - A weighted end (weightedOut): the last sample covers min(tout - t_last, s/2), and what lies
//   past t_last + s/2 goes to the end sample at tout (EndWeights::End, weight
//   (tout - t_last) / s - 1/2); both continuous as tout crosses a lattice point.
// - cap (plain end only): the ray's end where it lies before the next lattice point (which is
//   then never sampled): the last sample covers only up to it, the pair that holds the ray's
//   end takes the rest past t_last + s/2 (its own weighted end).
// A pair without a lattice point: with a weighted end, one sample at tout (in the Mid form)
// of weight (tout - tin) / s if the entry is weighted too, else (tout - t_prev) / s - 1/2
// (the previous lattice point's sample, in an earlier pair, covers up to t_prev + s/2); with
// only a weighted entry one sample at its middle of weight (min(t_next - s/2, cap) - tin) / s,
// t_next's sample covering from t_next - s/2. Either weight can come out negative (the ray
// re-enters or leaves the mesh within half a spacing of a lattice point whose sample lies in
// another pair): it is clamped to no sample (the marcher takes no sample of non-positive
// absorbance either) and the ray then counts up to s/2 more than its length there.
// With firstIndex = lattice.First(tin, offset) and nextIndex = lattice.First(tout, offset)
// given.
[[gnu::always_inline]] inline EndWeights EndWeightsAt(const Lattice& lattice, double tin,
  double tout, double offset, bool weightedIn, bool weightedOut, int64_t firstIndex,
  int64_t nextIndex, double cap = std::numeric_limits<double>::infinity())
{
  EndWeights w;
  w.First = firstIndex;
  w.Last = nextIndex - 1;
  const double inverse = lattice.InverseSpacing;
  if (w.Last < w.First)
  {
    double weight = 0;
    if (weightedOut)
    {
      weight =
        weightedIn ? (tout - tin) * inverse : (tout - lattice.At(w.Last, offset)) * inverse - 0.5;
    }
    else if (weightedIn)
    {
      // The half spacing before the next lattice point belongs to its sample, if the ray
      // reaches it.
      weight = (std::min(lattice.At(w.First, offset) - 0.5 * lattice.Spacing, cap) - tin) * inverse;
    }
    if (!(weight > 0))
    {
      w.Last = w.First - 1; // no sample
      return w;
    }
    w.Mid = true;
    w.First -= 1;
    w.Last = w.First;
    w.MidWeight = w.FirstWeight = w.LastWeight = weight;
    if (weightedOut || weightedIn)
    {
      EndSampleAt(lattice, tout, w.First, w.MidT, w.MidOffset);
    }
    else
    {
      w.MidOffset = 0.5 * (tin + tout) * inverse - static_cast<double>(w.First);
      w.MidT = lattice.At(w.First, w.MidOffset);
    }
    return w;
  }
  if (!weightedIn && !weightedOut && !(cap < lattice.At(w.Last, offset) + 0.5 * lattice.Spacing))
  {
    return w; // the plain lattice's samples
  }
  // The parts of the first sample's spacing before its point and of the last's after it.
  const double below = weightedIn ? (lattice.At(w.First, offset) - tin) * inverse : 0.5;
  const double past = ((weightedOut ? tout : cap) - lattice.At(w.Last, offset)) * inverse;
  const double above = past < 0.5 ? past : 0.5;
  if (w.Last == w.First)
  {
    w.FirstWeight = w.LastWeight = below + above;
  }
  else
  {
    w.FirstWeight = below + 0.5;
    w.LastWeight = 0.5 + above;
  }
  if (weightedOut && past > 0.5)
  {
    w.End = true;
    w.EndWeight = past - 0.5;
    EndSampleAt(lattice, tout, w.Last, w.EndT, w.EndOffset);
  }
  return w;
}

[[gnu::always_inline]] inline EndWeights EndWeightsAt(const Lattice& lattice, double tin,
  double tout, double offset, bool weightedIn, bool weightedOut,
  double cap = std::numeric_limits<double>::infinity())
{
  return EndWeightsAt(lattice, tin, tout, offset, weightedIn, weightedOut,
    lattice.First(tin, offset), lattice.First(tout, offset), cap);
}

// The weights of the pair [tin, end) of a ray that ends at rayEnd (an opaque surface's depth;
// infinity for none), with Sample End Weights = Boundary (VolumeRayMarcher::Walker's
// BoundaryPairWeights): in / out whether its ends lie on the mesh's boundary (or the eye in
// the pair), first = lattice.First(tin, offset); cellExit(face, faceOut) gives where the ray
// leaves the pair's cell and whether through the boundary, asked for only where the pair holds
// the ray's end and the entry is late (below). plain: whether the weights are the plain
// lattice's (the lanes take those pairs).
//
// The ray's end counts exactly too, whichever cell it falls in: the pair that holds it is
// weighted there (EndWeightsAt's weighted end: no lattice sample covers more than its half
// spacing past its point, and what lies past goes to one sample at the end itself), and where
// the ray's next lattice point t_next after a pair lies at or past the ray's end nobody
// samples it, so the pair's last sample covers only up to the ray's end (cap) and the pair
// holding the end takes what lies past h = t_next - s/2. Each pair decides from its own
// interval, its flags and the ray's end, so every partition weighs alike, and the ray's
// integral is continuous in its end across every face and every lattice point: processes
// composite an opaque depth a few roundings apart, and a rule that switched there (a plain
// end in one cell and a weighted one in the next, or half a spacing moved from one lattice
// sample to the next) turned those roundings into half a sample's difference.
//
// A late entry (through the boundary past h, in a pair without a lattice point before the
// ray's end): the pairs after it in that spacing cannot tell it from a mesh that goes on to h,
// so the pair holding the end counts from h, and the late entry leaves [h, tin) to it as if
// its entry were plain: the ray counts up to s/2 more there (as a late entry whose t_next is
// sampled does: EndWeightsAt's clamped sliver), and its integral stays continuous where its end
// crosses the face F that ends the entry's pair. Where the entry's pair holds the ray's end
// itself, its weight rises from 0 at tin to (F - h) / s at F, continuous at both.
template <class CellExit>
[[gnu::always_inline]] inline EndWeights RayPairWeights(const Lattice& lattice, double tin,
  double end, double offset, bool in, bool out, int64_t first, double rayEnd,
  const CellExit& cellExit, bool& plain)
{
  const int64_t next = lattice.First(end, offset);
  const bool holdsEnd = end >= rayEnd;
  out = out || holdsEnd;
  const double tNext = lattice.At(next, offset);
  const double cap = tNext >= rayEnd ? rayEnd : std::numeric_limits<double>::infinity();
  const double h = tNext - 0.5 * lattice.Spacing;
  if (in && tin > h && tin > 0.0 && first == next && cap == rayEnd)
  {
    double face = end;
    bool faceOut = out;
    if (holdsEnd)
    {
      cellExit(face, faceOut);
      face = std::max(face, end);
    }
    if (!faceOut && lattice.First(face, offset) == next)
    {
      if (!holdsEnd)
      {
        in = false;
      }
      else
      {
        plain = false;
        EndWeights w;
        w.First = w.Last = next - 1;
        const double weight = (end - tin) * ((face - h) / (face - tin)) * lattice.InverseSpacing;
        if (!(weight > 0))
        {
          w.Last = w.First - 1; // no sample
          return w;
        }
        w.Mid = true;
        w.MidWeight = w.FirstWeight = w.LastWeight = weight;
        EndSampleAt(lattice, end, w.First, w.MidT, w.MidOffset);
        return w;
      }
    }
  }
  plain = !in && !out && cap == std::numeric_limits<double>::infinity();
  return EndWeightsAt(lattice, tin, end, offset, in, out, first, next, cap);
}

} // namespace walk
} // namespace apc

#endif
