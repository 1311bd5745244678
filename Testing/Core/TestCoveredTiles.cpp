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

// The wire's messages are packed and taken back one at a time (apcMomentCompositing.cxx):
// walked in pieces of any size, ending inside a pixel or not, the packed values are Pack's,
// in Pack's order, and pixels holding different numbers of values (none for some) walk as one
// buffer of all their values one after the other.
TEST(CoveredTiles, PackedWalkInPiecesIsPackInOrder)
{
  std::vector<unsigned char> mask(kGrid.Tiles(), 0);
  mask[0] = mask[2] = mask[3] = mask[7] = mask[11] = 1;
  constexpr int kComponents = 5;
  std::vector<double> full(static_cast<size_t>(kWidth) * kHeight * kComponents);
  for (size_t v = 0; v < full.size(); ++v)
  {
    full[v] = static_cast<double>(v);
  }
  const size_t pixels = kGrid.PixelsIn(mask);
  std::vector<double> whole(pixels * kComponents);
  kGrid.Pack(mask, full.data(), kComponents, whole.data());
  // Variable counts: 0..6 values a pixel, by its index in the walk.
  const auto varying = [](size_t i) { return (i * 7 + 3) % 7; };
  std::vector<double> wholeVarying;
  size_t i = 0;
  kGrid.ForEachPacked(mask,
    [&](size_t p)
    {
      for (size_t k = 0; k < varying(i); ++k)
      {
        wholeVarying.push_back(static_cast<double>(p * 16 + k));
      }
      ++i;
    });
  for (size_t piece :
    { size_t(1), size_t(2), size_t(3), size_t(5), size_t(7), size_t(64), size_t(100000) })
  {
    apc::PackedWalk walk(kGrid, mask);
    apc::PackedWalk back(kGrid, mask);
    std::vector<double> packed;
    std::vector<double> restored(full.size(), -1.0);
    while (!walk.Done())
    {
      std::vector<double> message(piece, -2.0);
      const size_t n = walk.Next(
        piece, [](size_t) { return size_t(kComponents); },
        [&](size_t p, size_t, size_t k0, size_t k1, size_t at)
        {
          ASSERT_LE(at + k1 - k0, piece);
          for (size_t k = k0; k < k1; ++k)
          {
            message[at + k - k0] = full[p * kComponents + k];
          }
        });
      ASSERT_GT(n, 0u);
      packed.insert(packed.end(), message.begin(), message.begin() + n);
      EXPECT_EQ(back.Next(
                  n, [](size_t) { return size_t(kComponents); },
                  [&](size_t p, size_t, size_t k0, size_t k1, size_t at)
                  {
                    for (size_t k = k0; k < k1; ++k)
                    {
                      restored[p * kComponents + k] = message[at + k - k0];
                    }
                  }),
        n);
    }
    EXPECT_EQ(packed, whole) << "piece " << piece;
    // The same values a row's run at a time (NextSpans).
    apc::PackedWalk spans(kGrid, mask);
    std::vector<double> packedSpans;
    while (!spans.Done())
    {
      std::vector<double> message(piece, -2.0);
      const size_t n = spans.NextSpans(piece, kComponents,
        [&](size_t start, size_t count, size_t at)
        {
          ASSERT_LE(at + count, piece);
          std::copy_n(full.begin() + static_cast<std::ptrdiff_t>(start), count,
            message.begin() + static_cast<std::ptrdiff_t>(at));
        });
      ASSERT_GT(n, 0u);
      packedSpans.insert(packedSpans.end(), message.begin(), message.begin() + n);
    }
    EXPECT_EQ(packedSpans, whole) << "spans, piece " << piece;
    for (size_t v = 0; v < full.size(); ++v)
    {
      ASSERT_TRUE(restored[v] == -1.0 || restored[v] == full[v]) << v;
    }
    EXPECT_EQ(std::count(restored.begin(), restored.end(), -1.0),
      static_cast<std::ptrdiff_t>(full.size() - whole.size()));

    apc::PackedWalk varyingWalk(kGrid, mask);
    std::vector<double> packedVarying;
    size_t expectedIndex = 0;
    while (!varyingWalk.Done())
    {
      std::vector<double> message(piece, -2.0);
      const size_t n = varyingWalk.Next(piece, varying,
        [&](size_t p, size_t index, size_t k0, size_t k1, size_t at)
        {
          ASSERT_LT(k0, k1) << "a pixel without values is passed over";
          ASSERT_GE(index, expectedIndex);
          expectedIndex = index;
          for (size_t k = k0; k < k1; ++k)
          {
            message[at + k - k0] = static_cast<double>(p * 16 + k);
          }
        });
      packedVarying.insert(packedVarying.end(), message.begin(), message.begin() + n);
    }
    EXPECT_EQ(packedVarying, wholeVarying) << "piece " << piece;
  }
  // A range of tiles walks that chunk's pixels only.
  apc::PackedWalk part(kGrid, mask, 2, 4);
  std::vector<double> chunk(kGrid.PixelsIn(mask, 2, 4));
  kGrid.Pack(mask, full.data(), 1, chunk.data(), 2, 4);
  std::vector<double> walked;
  part.Next(
    1000, [](size_t) { return size_t(1); },
    [&](size_t p, size_t, size_t, size_t, size_t) { walked.push_back(full[p]); });
  EXPECT_EQ(walked, chunk);
  EXPECT_TRUE(part.Done());
}
