#include "apcRaySegments.h"

#include "apcCompressedRows.h"
#include "apcParallel.h"

#include <algorithm>

namespace apc
{

void SegmentImage::Reset(int width, int height)
{
  this->Width = std::max(width, 0);
  this->Height = std::max(height, 0);
  this->Offsets.assign(static_cast<size_t>(this->Width) * this->Height + 1, 0);
  this->Segments.clear();
}

SegmentStatistics GetSegmentStatistics(const SegmentImage& image)
{
  SegmentStatistics stats;
  const int64_t pixels = static_cast<int64_t>(image.Offsets.size()) - 1;
  for (int64_t p = 0; p < pixels; ++p)
  {
    const int64_t n = image.Count(p);
    stats.Segments += n;
    stats.NonEmptyPixels += n > 0;
    stats.MaxPerPixel = std::max(stats.MaxPerPixel, n);
  }
  return stats;
}

std::array<double, 4> CompositeSegments(RaySegment* segments, size_t count)
{
  std::sort(segments, segments + count,
    [](const RaySegment& a, const RaySegment& b) { return a.KFirst < b.KFirst; });
  double transmittance = 1.0;
  std::array<double, 4> rgba = { 0, 0, 0, 0 };
  for (size_t s = 0; s < count; ++s)
  {
    for (int c = 0; c < 3; ++c)
    {
      rgba[c] += transmittance * segments[s].Colour[c];
    }
    transmittance *= segments[s].Transmittance;
  }
  rgba[3] = 1.0 - transmittance;
  return rgba;
}

void CompositeSegmentImage(SegmentImage& image, float* rgba, int threads)
{
  const int64_t pixels = static_cast<int64_t>(image.Offsets.size()) - 1;
  ParallelFor(threads, pixels, 1024,
    [&](int64_t begin, int64_t end)
    {
      for (int64_t p = begin; p < end; ++p)
      {
        const int64_t n = image.Count(p);
        if (n == 0)
        {
          continue;
        }
        const std::array<double, 4> c =
          CompositeSegments(image.Segments.data() + image.Offsets[p], static_cast<size_t>(n));
        for (int k = 0; k < 4; ++k)
        {
          rgba[4 * p + k] += static_cast<float>(c[k]);
        }
      }
    });
}

void GroupByPixel(
  const std::vector<std::vector<WireSegment>>& from, int width, int rows, SegmentImage& strip)
{
  strip.Reset(width, rows);
  const int64_t pixels = static_cast<int64_t>(strip.Width) * strip.Height;
  BuildCompressedRows<RaySegment>(
    pixels,
    [&](auto&& emit)
    {
      for (const auto& segments : from)
      {
        for (const WireSegment& seg : segments)
        {
          emit(seg.Pixel, seg.ToSegment());
        }
      }
    },
    strip.Offsets, strip.Segments);
}

} // namespace apc
