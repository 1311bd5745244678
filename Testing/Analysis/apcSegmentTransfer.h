// What exact sort-last compositing of ray segments (see RaySegment in apcVolumeRayMarcher.h)
// moves between ranks, counted in segments, for two exchange patterns:
//
// - direct send, as vtkAPCCompositePass's SEGMENTS mode does it: the rows of the image are
//   split into one strip per rank and every rank sends each pixel's segments to the pixel's
//   strip owner (the owner's own segments stay);
// - binary swap (Ma et al. 1994), computed, not run: log2(n) rounds in which rank i and
//   i ^ 2^r split their common image region in halves (the lower rank keeps the first half,
//   in row-major pixel order) and send each other the half they give up. Before round r a
//   rank holds, for its region, the segments of its block of 2^r consecutive ranks, merged
//   where two runs are contiguous on the sample lattice (KLast + 1 == KFirst: no other rank
//   can have a sample between them, so blending them into one run is exact).
//
// This is the measure of the APC paper's comparison table ("average number of segments
// transferred per non-empty pixel"; Huang, Usher et al., arXiv 2501.12581, Sec. 6), which
// APC's fixed per-pixel payload is held against.
#ifndef apcSegmentTransfer_h
#define apcSegmentTransfer_h

#include "apcRaySegments.h"

#include <cstdint>
#include <vector>

namespace apc
{

struct SegmentTransferCounts
{
  int Ranks = 0;
  // Rows [RowBegin, RowEnd) were split into the direct-send strips and ordered for binary swap.
  int RowBegin = 0;
  int RowEnd = 0;
  int64_t NonEmptyPixels = 0; // pixels with a segment on some rank
  int64_t Segments = 0;       // all ranks' segments
  int64_t MaxSegmentsPerPixel = 0;
  int64_t DirectSend = 0;
  // -1 when the number of ranks is not a power of two.
  int64_t BinarySwap = -1;
  int64_t BinarySwapUnmerged = -1; // the same exchange without merging contiguous runs

  // Per rank, for the alpha-beta model (scaling_model.py), whose time is set by the busiest
  // rank rather than by the total. DirectSendMatrix[p * Ranks + o]: segments rank p has for
  // strip owner o (the diagonal stays on p). BinarySwapSent[k * Ranks + r]: merged runs rank r
  // sends in round k (empty when the number of ranks is not a power of two).
  std::vector<int64_t> DirectSendMatrix;
  std::vector<int64_t> BinarySwapSent;
  // The data's screen rectangle cut into 8 x 8 tiles anchored at its corner (as the pass's
  // compact wire does): all tiles, those with a segment on some rank, and their pixels.
  int64_t Tiles = 0;
  int64_t CoveredTiles = 0;
  int64_t CoveredTilePixels = 0;

  double PerNonEmptyPixel(int64_t count) const
  {
    return this->NonEmptyPixels > 0 ? static_cast<double>(count) / this->NonEmptyPixels : 0.0;
  }

  // Direct send, the busiest rank: most segments sent to, or received from, the others.
  int64_t DirectSendMaxSent() const;
  int64_t DirectSendMaxReceived() const;
  // Messages of direct send (ordered pairs p != o with segments).
  int64_t DirectSendMessages() const;
  // vtkAPCCompositePass's direct send meets partners in rounds (partner = rank XOR round) and
  // each pair sends one way, then the other: the sum over rounds of the busiest pair's
  // segments both ways is its critical path.
  int64_t DirectSendPairwiseCritical() const;
  // Binary swap: the sum over rounds of the most merged runs one rank sends (pairs exchange
  // at once, so a round lasts as long as its largest message); -1 when not 2^k ranks.
  int64_t BinarySwapCritical() const;
};

// ranks[r] holds rank r's segments (every image the same size, each pixel's list in increasing
// KFirst, as VolumeRayMarcher::RenderSegments makes them). rowBegin/rowEnd: the rows to split
// among the ranks (vtkAPCCompositePass uses the projected data rectangle); rowBegin < 0 uses
// the rows that have segments. Throws std::invalid_argument for no ranks, null or mismatched
// images, or rows outside the image.
// colBegin/colEnd: the rectangle's columns, for the tiles (colBegin < 0: the whole width).
SegmentTransferCounts CountSegmentTransfer(const std::vector<const SegmentImage*>& ranks,
  int rowBegin = -1, int rowEnd = -1, int colBegin = -1, int colEnd = -1);

// Segments per pixel over all ranks (Width * Height, row 0 at the bottom): the heatmap.
std::vector<int32_t> SegmentCountImage(const std::vector<const SegmentImage*>& ranks);

} // namespace apc

#endif
