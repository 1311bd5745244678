#include "apcCoveredTiles.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace
{

// A 37 x 23 image, rectangle [3, 30) x [2, 21): tiles of 8 leave clipped edge tiles both ways.
constexpr int kWidth = 37;
constexpr int kHeight = 23;
const apc::TileGrid kGrid(kWidth, 3, 2, 30, 21);

bool InRect(int i, int j)
{
  return i >= 3 && i < 30 && j >= 2 && j < 21;
}

TEST(CoveredTiles, GridCountsClippedTiles)
{
  EXPECT_EQ(kGrid.Tiles(), 4u * 3u); // ceil(27 / 8) x ceil(19 / 8)
  EXPECT_EQ(kGrid.PixelsIn(std::vector<unsigned char>(kGrid.Tiles(), 1)), 27u * 19u);
  EXPECT_EQ(kGrid.PixelsIn(std::vector<unsigned char>(kGrid.Tiles(), 0)), 0u);
  EXPECT_EQ(apc::TileGrid(kWidth, 5, 5, 5, 9).Tiles(), 0u); // an empty rectangle
}

TEST(CoveredTiles, MarkFindsTheTileOfEveryCoveredPixel)
{
  // One covered pixel at a time: exactly its tile is marked, and the marked tile's pixels
  // include it. Pixels outside the rectangle are never looked at.
  for (int j = 0; j < kHeight; ++j)
  {
    for (int i = 0; i < kWidth; ++i)
    {
      const size_t target = static_cast<size_t>(j) * kWidth + i;
      const std::vector<unsigned char> mask = kGrid.Mark([&](size_t p) { return p == target; });
      size_t marked = 0;
      for (unsigned char m : mask)
      {
        marked += m;
      }
      ASSERT_EQ(marked, InRect(i, j) ? 1u : 0u) << i << ", " << j;
      if (InRect(i, j))
      {
        const size_t t = static_cast<size_t>((j - 2) / 8) * 4 + (i - 3) / 8;
        EXPECT_EQ(mask[t], 1);
      }
    }
  }
}

TEST(CoveredTiles, PackUnpackRoundTripsMarkedTilesOnly)
{
  std::mt19937 random(7);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  constexpr int kComponents = 3;
  std::vector<double> full(static_cast<size_t>(kWidth) * kHeight * kComponents);
  for (double& v : full)
  {
    v = value(random);
  }
  std::vector<unsigned char> mask(kGrid.Tiles(), 0);
  mask[0] = mask[3] = mask[5] = mask[11] = 1; // corner, clipped column, inner, clipped corner
  std::vector<float> packed(kGrid.PixelsIn(mask) * kComponents, 0.0f);
  kGrid.Pack(mask, full.data(), kComponents, packed.data());

  std::vector<double> back(full.size(), 42.0);
  kGrid.Unpack(mask, packed.data(), kComponents, back.data());
  size_t restored = 0;
  for (int j = 0; j < kHeight; ++j)
  {
    for (int i = 0; i < kWidth; ++i)
    {
      const bool inMarked =
        InRect(i, j) && mask[static_cast<size_t>((j - 2) / 8) * 4 + (i - 3) / 8];
      for (int c = 0; c < kComponents; ++c)
      {
        const size_t v = (static_cast<size_t>(j) * kWidth + i) * kComponents + c;
        if (inMarked)
        {
          // Through float: the wire's rounding and nothing else.
          ASSERT_EQ(back[v], static_cast<double>(static_cast<float>(full[v])));
          ++restored;
        }
        else
        {
          ASSERT_EQ(back[v], 42.0) << "a pixel outside the marked tiles was written";
        }
      }
    }
  }
  EXPECT_EQ(restored, packed.size());
}

TEST(CoveredTiles, PackedBuffersOfDifferentImagesLineUp)
{
  // What makes the packed sum right: two processes' images packed with the same (union) mask
  // sum element by element to the packed sum of the images.
  std::vector<double> a(static_cast<size_t>(kWidth) * kHeight, 0.0);
  std::vector<double> b(a.size(), 0.0);
  a[static_cast<size_t>(4) * kWidth + 5] = 1.0;   // tile 0
  b[static_cast<size_t>(19) * kWidth + 28] = 2.0; // tile 11
  const std::vector<unsigned char> maskA = kGrid.Mark([&](size_t p) { return a[p] > 0; });
  const std::vector<unsigned char> maskB = kGrid.Mark([&](size_t p) { return b[p] > 0; });
  std::vector<unsigned char> both(kGrid.Tiles());
  for (size_t t = 0; t < both.size(); ++t)
  {
    both[t] = std::max(maskA[t], maskB[t]);
  }
  std::vector<double> packedA(kGrid.PixelsIn(both));
  std::vector<double> packedB(packedA.size());
  kGrid.Pack(both, a.data(), 1, packedA.data());
  kGrid.Pack(both, b.data(), 1, packedB.data());
  for (size_t v = 0; v < packedA.size(); ++v)
  {
    packedA[v] += packedB[v];
  }
  std::vector<double> sum(a.size(), 0.0);
  kGrid.Unpack(both, packedA.data(), 1, sum.data());
  for (size_t p = 0; p < sum.size(); ++p)
  {
    ASSERT_EQ(sum[p], a[p] + b[p]) << p;
  }
}

} // namespace

// Large images are packed and summed chunk by chunk: the chunks cover the marked tiles once,
// in order, each within the pixel budget (a lone tile may exceed it), and packing them one
// after the other gives the same buffer as packing everything at once.
TEST(CoveredTiles, ChunksPartitionTheMarkedTilesInOrder)
{
  std::vector<unsigned char> mask(kGrid.Tiles(), 0);
  mask[0] = mask[1] = mask[3] = mask[5] = mask[6] = mask[11] = 1;
  std::vector<double> full(static_cast<size_t>(kWidth) * kHeight);
  for (size_t p = 0; p < full.size(); ++p)
  {
    full[p] = static_cast<double>(p);
  }
  std::vector<double> whole(kGrid.PixelsIn(mask));
  kGrid.Pack(mask, full.data(), 1, whole.data());
  for (size_t budget : { size_t(1), size_t(64), size_t(100), size_t(128), size_t(10000) })
  {
    const std::vector<size_t> bounds = kGrid.Chunks(mask, budget);
    ASSERT_GE(bounds.size(), 2u);
    EXPECT_EQ(bounds.front(), 0u);
    EXPECT_EQ(bounds.back(), kGrid.Tiles());
    std::vector<double> chunked;
    for (size_t c = 0; c + 1 < bounds.size(); ++c)
    {
      ASSERT_LT(bounds[c], bounds[c + 1]);
      const size_t pixels = kGrid.PixelsIn(mask, bounds[c], bounds[c + 1]);
      ASSERT_GT(pixels, 0u) << "an empty chunk";
      ASSERT_TRUE(pixels <= budget || kGrid.PixelsIn(mask, bounds[c], bounds[c] + 1) == pixels)
        << "chunk " << c << " over the budget " << budget;
      std::vector<double> part(pixels);
      kGrid.Pack(mask, full.data(), 1, part.data(), bounds[c], bounds[c + 1]);
      chunked.insert(chunked.end(), part.begin(), part.end());
      std::vector<double> back(full.size(), -1.0);
      kGrid.Unpack(mask, part.data(), 1, back.data(), bounds[c], bounds[c + 1]);
      for (size_t p = 0; p < back.size(); ++p)
      {
        ASSERT_TRUE(back[p] == -1.0 || back[p] == full[p]);
      }
    }
    EXPECT_EQ(chunked, whole) << "budget " << budget;
  }
  EXPECT_EQ(kGrid.Chunks(mask, 10000).size(), 2u) << "one chunk when everything fits";
  const std::vector<unsigned char> none(kGrid.Tiles(), 0);
  EXPECT_EQ(kGrid.Chunks(none, 64), (std::vector<size_t>{ 0, kGrid.Tiles() }));
}
