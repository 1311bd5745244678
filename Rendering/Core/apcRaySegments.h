// Ray segments, the exact sort-last baseline's unit of work (the APC paper's comparison):
// what one rank blended along one pixel's ray, how they are listed per pixel, blended across
// ranks, split among the ranks that blend them (the strip-owner rule) and sent (the wire
// format). VTK-free; the marcher makes them, vtkAPCCompositePass exchanges them and the
// segment-transfer model counts them.
#ifndef apcRaySegments_h
#define apcRaySegments_h

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace apc
{

// One run of consecutive lattice samples k = KFirst..KLast along one pixel's ray that all lie
// in this rank's cells (transparent samples included: a run ends only where the ray leaves
// the rank's cells between two lattice points, or at the ray's end), blended front to back:
// premultiplied colour and transmittance (1 - alpha). Runs of different ranks never
// interleave on a ray, since every lattice sample belongs to exactly one rank, so blending all
// ranks' runs in KFirst order is exactly the ordered blend of all samples. Wholly transparent
// runs are not kept: they change nothing and would only be sent.
struct RaySegment
{
  int64_t KFirst;
  int64_t KLast;
  std::array<float, 3> Colour;
  // Rather than alpha: a float keeps a small transmittance to full relative precision, while
  // 1 - alpha of an almost opaque run would lose it, and with it the weight of everything
  // behind the run.
  float Transmittance;
};

// Per-pixel segment lists in compressed rows: pixel p's segments are
// Segments[Offsets[p] .. Offsets[p + 1]), in increasing KFirst. Width * Height pixels, row 0 at
// the bottom, pixel (i, j) at j * Width + i.
struct SegmentImage
{
  int Width = 0;
  int Height = 0;
  std::vector<int64_t> Offsets{ 0 };
  std::vector<RaySegment> Segments;

  int64_t Count(int64_t pixel) const { return this->Offsets[pixel + 1] - this->Offsets[pixel]; }
  // Empty lists for every pixel of a width x height image.
  void Reset(int width, int height);
};

// Segment statistics over the pixels that have at least one segment.
struct SegmentStatistics
{
  int64_t Segments = 0;
  int64_t NonEmptyPixels = 0;
  int64_t MaxPerPixel = 0;
  double Average() const
  {
    return this->NonEmptyPixels > 0 ? static_cast<double>(this->Segments) / this->NonEmptyPixels
                                    : 0.0;
  }
};
SegmentStatistics GetSegmentStatistics(const SegmentImage& image);

// Blends one pixel's segments, from any ranks, front to back in KFirst order (sorting them in
// place): premultiplied RGBA. Exact (to rounding) as long as the segments' k ranges do not
// interleave.
std::array<double, 4> CompositeSegments(RaySegment* segments, size_t count);

// CompositeSegments for every pixel of an image (whose lists need not be sorted), added (+=)
// to rgba, Width * Height * 4. threads: 0 = as many as TBB offers.
void CompositeSegmentImage(SegmentImage& image, float* rgba, int threads = 0);

// The strip-owner rule: rows [RowBegin, RowBegin + Rows) of the screen are split among
// Processes ranks, rank o blending rows [Begin(o), Begin(o + 1)).
struct SegmentStrips
{
  int RowBegin = 0;
  int Rows = 0;
  int Processes = 1;

  int Begin(int owner) const
  {
    return this->RowBegin +
      static_cast<int>(static_cast<int64_t>(this->Rows) * owner / this->Processes);
  }
  int RowsOf(int owner) const { return this->Begin(owner + 1) - this->Begin(owner); }
};

// A segment as sent to its strip owner: the pixel within the owner's strip, the first lattice
// index relative to the frame's smallest (so that it fits 32 bits: a ray would need 2^31
// samples to overflow it), the premultiplied colour and the transmittance. KLast is not needed
// for blending.
struct WireSegment
{
  int32_t Pixel;
  int32_t KFirst;
  float Colour[3];
  float Transmittance;

  static WireSegment From(const RaySegment& s, int32_t pixel, int64_t kBase)
  {
    return { pixel, static_cast<int32_t>(s.KFirst - kBase),
      { s.Colour[0], s.Colour[1], s.Colour[2] }, s.Transmittance };
  }
  RaySegment ToSegment() const
  {
    return { this->KFirst, this->KFirst, { this->Colour[0], this->Colour[1], this->Colour[2] },
      this->Transmittance };
  }
};
static_assert(sizeof(WireSegment) == 24, "segments travel as 24 bytes");

// The received segments of a width x rows strip, grouped by pixel (stable: in arrival order
// within a pixel, as from is ordered), replacing strip's content.
void GroupByPixel(
  const std::vector<std::vector<WireSegment>>& from, int width, int rows, SegmentImage& strip);

} // namespace apc

#endif
