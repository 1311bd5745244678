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
  const std::vector<const SegmentImage*>& ranks, int rowBegin, int rowEnd, int colBegin, int colEnd)
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
  if (colBegin < 0)
  {
    colBegin = 0;
    colEnd = width;
  }
  if (colBegin > colEnd || colEnd > width)
  {
    throw std::invalid_argument("CountSegmentTransfer: columns outside the image");
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
  counts.DirectSendMatrix.assign(static_cast<size_t>(n) * n, 0);
  if (powerOfTwo)
  {
    counts.BinarySwap = 0;
    counts.BinarySwapUnmerged = 0;
    counts.BinarySwapSent.assign(static_cast<size_t>(rounds) * n, 0);
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
      for (int p = 0; p < n; ++p)
      {
        counts.DirectSendMatrix[static_cast<size_t>(p) * n + owner] += ranks[p]->Count(pixel);
      }
      if (!powerOfTwo)
      {
        continue;
      }
      // Follow the pixel down the halvings of the region.
      const int64_t position = static_cast<int64_t>(j - rowBegin) * width + i;
      int64_t lo = 0;
      int64_t hi = regionPixels;
      // Which rank of its block of 2^r holds the pixel before round r: bit r' is set where
      // the pixel went to the upper rank in round r'.
      int holder = 0;
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
          const int64_t runs = MergedRuns(ranks, b * block, block, pixel, scratch);
          counts.BinarySwap += runs;
          counts.BinarySwapSent[static_cast<size_t>(r) * n + b * block + holder] += runs;
          for (int k = b * block; k < (b + 1) * block; ++k)
          {
            counts.BinarySwapUnmerged += ranks[k]->Count(pixel);
          }
        }
        holder |= lowerKeeps ? 0 : block;
      }
    }
  }

  // Tiles of the rectangle [colBegin, colEnd) x [rowBegin, rowEnd), clipped at its far edges.
  constexpr int kTile = 8;
  for (int tj = rowBegin; tj < rowEnd; tj += kTile)
  {
    for (int ti = colBegin; ti < colEnd; ti += kTile)
    {
      const int j1 = std::min(tj + kTile, rowEnd);
      const int i1 = std::min(ti + kTile, colEnd);
      bool covered = false;
      for (int j = tj; j < j1 && !covered; ++j)
      {
        for (int i = ti; i < i1 && !covered; ++i)
        {
          covered = count(static_cast<int64_t>(j) * width + i) > 0;
        }
      }
      ++counts.Tiles;
      if (covered)
      {
        ++counts.CoveredTiles;
        counts.CoveredTilePixels += static_cast<int64_t>(j1 - tj) * (i1 - ti);
      }
    }
  }
  return counts;
}

int64_t SegmentTransferCounts::DirectSendMaxSent() const
{
  int64_t most = 0;
  for (int p = 0; p < this->Ranks; ++p)
  {
    int64_t sent = 0;
    for (int o = 0; o < this->Ranks; ++o)
    {
      sent += o == p ? 0 : this->DirectSendMatrix[static_cast<size_t>(p) * this->Ranks + o];
    }
    most = std::max(most, sent);
  }
  return most;
}

int64_t SegmentTransferCounts::DirectSendMaxReceived() const
{
  int64_t most = 0;
  for (int o = 0; o < this->Ranks; ++o)
  {
    int64_t received = 0;
    for (int p = 0; p < this->Ranks; ++p)
    {
      received += o == p ? 0 : this->DirectSendMatrix[static_cast<size_t>(p) * this->Ranks + o];
    }
    most = std::max(most, received);
  }
  return most;
}

int64_t SegmentTransferCounts::DirectSendMessages() const
{
  int64_t messages = 0;
  for (int p = 0; p < this->Ranks; ++p)
  {
    for (int o = 0; o < this->Ranks; ++o)
    {
      messages += o != p && this->DirectSendMatrix[static_cast<size_t>(p) * this->Ranks + o] > 0;
    }
  }
  return messages;
}

int64_t SegmentTransferCounts::DirectSendPairwiseCritical() const
{
  const int n = this->Ranks;
  int rounds = 1;
  while (rounds < n)
  {
    rounds *= 2;
  }
  int64_t critical = 0;
  for (int round = 1; round < rounds; ++round)
  {
    int64_t busiest = 0;
    for (int p = 0; p < n; ++p)
    {
      const int q = p ^ round;
      if (q < n)
      {
        busiest = std::max(busiest,
          this->DirectSendMatrix[static_cast<size_t>(p) * n + q] +
            this->DirectSendMatrix[static_cast<size_t>(q) * n + p]);
      }
    }
    critical += busiest;
  }
  return critical;
}

int64_t SegmentTransferCounts::BinarySwapCritical() const
{
  if (this->BinarySwap < 0)
  {
    return -1;
  }
  int64_t critical = 0;
  for (size_t first = 0; first < this->BinarySwapSent.size(); first += this->Ranks)
  {
    critical += *std::max_element(
      this->BinarySwapSent.begin() + first, this->BinarySwapSent.begin() + first + this->Ranks);
  }
  return critical;
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
