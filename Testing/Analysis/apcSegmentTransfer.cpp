#include "apcSegmentTransfer.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace apc
{
namespace
{
void Validate(const std::vector<const SegmentImage*>& ranks)
{
  if (ranks.empty())
  {
    throw std::invalid_argument("CountSegmentTransfer: no ranks");
  }
  for (const SegmentImage* image : ranks)
  {
    if (!image)
    {
      throw std::invalid_argument("CountSegmentTransfer: null segment image");
    }
    const int64_t pixels = static_cast<int64_t>(image->Width) * image->Height;
    if (image->Width != ranks[0]->Width || image->Height != ranks[0]->Height ||
      static_cast<int64_t>(image->Offsets.size()) != pixels + 1 ||
      image->Offsets.back() != static_cast<int64_t>(image->Segments.size()))
    {
      throw std::invalid_argument("CountSegmentTransfer: segment images of different sizes or "
                                  "inconsistent offsets");
    }
  }
}

// Runs left after merging the lists of ranks [first, first + count) at one pixel.
int64_t MergedRuns(const std::vector<const SegmentImage*>& ranks, int first, int count,
  int64_t pixel, std::vector<std::pair<int64_t, int64_t>>& scratch)
{
  scratch.clear();
  for (int r = first; r < first + count; ++r)
  {
    const SegmentImage& image = *ranks[r];
    for (int64_t s = image.Offsets[pixel]; s < image.Offsets[pixel + 1]; ++s)
    {
      scratch.emplace_back(image.Segments[s].KFirst, image.Segments[s].KLast);
    }
  }
  if (scratch.empty())
  {
    return 0;
  }
  std::sort(scratch.begin(), scratch.end());
  int64_t runs = 1;
  for (size_t s = 1; s < scratch.size(); ++s)
  {
    runs += scratch[s].first == scratch[s - 1].second + 1 ? 0 : 1;
  }
  return runs;
}
}

SegmentTransferCounts CountSegmentTransfer(
  const std::vector<const SegmentImage*>& ranks, int rowBegin, int rowEnd)
{
  Validate(ranks);
  const int width = ranks[0]->Width;
  const int height = ranks[0]->Height;
  const int n = static_cast<int>(ranks.size());
  auto count = [&](int64_t pixel)
  {
    int64_t total = 0;
    for (const SegmentImage* image : ranks)
    {
      total += image->Count(pixel);
    }
    return total;
  };

  if (rowBegin < 0)
  {
    rowBegin = height;
    rowEnd = 0;
    for (int j = 0; j < height; ++j)
    {
      for (int i = 0; i < width; ++i)
      {
        if (count(static_cast<int64_t>(j) * width + i) > 0)
        {
          rowBegin = std::min(rowBegin, j);
          rowEnd = j + 1;
          break;
        }
      }
    }
    if (rowEnd == 0)
    {
      rowBegin = 0;
    }
  }
  if (rowBegin > rowEnd || rowEnd > height)
  {
    throw std::invalid_argument("CountSegmentTransfer: rows outside the image");
  }

  SegmentTransferCounts counts;
  counts.Ranks = n;
  counts.RowBegin = rowBegin;
  counts.RowEnd = rowEnd;
  const bool powerOfTwo = (n & (n - 1)) == 0;
  int rounds = 0;
  while ((1 << rounds) < n)
  {
    ++rounds;
  }
  if (powerOfTwo)
  {
    counts.BinarySwap = 0;
    counts.BinarySwapUnmerged = 0;
  }
  const int rows = rowEnd - rowBegin;
  const int64_t regionPixels = static_cast<int64_t>(rows) * width;
  std::vector<std::pair<int64_t, int64_t>> scratch;

  const SegmentStrips strips{ rowBegin, rows, n };
  int owner = 0;
  for (int j = rowBegin; j < rowEnd; ++j)
  {
    while (owner + 1 < n && strips.Begin(owner + 1) <= j)
    {
      ++owner;
    }
    for (int i = 0; i < width; ++i)
    {
      const int64_t pixel = static_cast<int64_t>(j) * width + i;
      const int64_t total = count(pixel);
      if (total == 0)
      {
        continue;
      }
      ++counts.NonEmptyPixels;
      counts.Segments += total;
      counts.MaxSegmentsPerPixel = std::max(counts.MaxSegmentsPerPixel, total);
      counts.DirectSend += total - ranks[owner]->Count(pixel);
      if (!powerOfTwo)
      {
        continue;
      }
      // Follow the pixel down the halvings of the region.
      const int64_t position = static_cast<int64_t>(j - rowBegin) * width + i;
      int64_t lo = 0;
      int64_t hi = regionPixels;
      for (int r = 0; r < rounds; ++r)
      {
        const int64_t middle = lo + (hi - lo) / 2;
        const bool lowerKeeps = position < middle;
        (lowerKeeps ? hi : lo) = middle;
        // The blocks of 2^r ranks on the giving side of each pair: odd blocks if the lower
        // ranks keep the pixel, even ones otherwise.
        const int block = 1 << r;
        for (int b = lowerKeeps ? 1 : 0; b < n / block; b += 2)
        {
          counts.BinarySwap += MergedRuns(ranks, b * block, block, pixel, scratch);
          for (int k = b * block; k < (b + 1) * block; ++k)
          {
            counts.BinarySwapUnmerged += ranks[k]->Count(pixel);
          }
        }
      }
    }
  }
  return counts;
}

std::vector<int32_t> SegmentCountImage(const std::vector<const SegmentImage*>& ranks)
{
  Validate(ranks);
  std::vector<int32_t> image(static_cast<size_t>(ranks[0]->Width) * ranks[0]->Height, 0);
  for (const SegmentImage* segments : ranks)
  {
    for (size_t p = 0; p < image.size(); ++p)
    {
      image[p] += static_cast<int32_t>(segments->Count(static_cast<int64_t>(p)));
    }
  }
  return image;
}

} // namespace apc
