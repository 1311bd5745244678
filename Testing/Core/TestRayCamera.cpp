#include "apcRayCamera.h"

#include <gtest/gtest.h>

#include <cmath>

namespace
{
const double Pi = 3.14159265358979323846;

// A tile of an s x s tiled screenshot, as vtkWindowToImageFilter sets the camera up: the view
// angle (or parallel scale) narrowed by s and the window centre moved onto the tile.
apc::RayCamera Tile(bool parallel, int s, int x, int y, int w, int h)
{
  const double angle = 30.0;
  const double tileAngle = 2.0 * std::atan(std::tan(0.5 * angle * Pi / 180.0) / s) * 180.0 / Pi;
  const double centerX = 2.0 * ((x + 0.5) / s - 0.5) * s;
  const double centerY = 2.0 * ((y + 0.5) / s - 0.5) * s;
  return apc::RayCamera({ 1, 2, 9 }, { 0, 0, 0 }, { 0, 1, 0 }, tileAngle, parallel, 2.5 / s, w, h,
    0.1, 100.0, { centerX, centerY });
}

// Each tile's rays are the full image's rays through the same pixels: before the window
// centre was honoured, every tile showed the whole picture (2 x 2 copies in a screenshot at
// twice the view size).
TEST(RayCamera, TilesOfALargeImageAreItsPixels)
{
  for (bool parallel : { false, true })
  {
    const int w = 16;
    const int h = 12;
    const int s = 2;
    const apc::RayCamera full(
      { 1, 2, 9 }, { 0, 0, 0 }, { 0, 1, 0 }, 30.0, parallel, 2.5, s * w, s * h, 0.1, 100.0);
    for (int y = 0; y < s; ++y)
    {
      for (int x = 0; x < s; ++x)
      {
        const apc::RayCamera tile = Tile(parallel, s, x, y, w, h);
        for (int j = 0; j < h; ++j)
        {
          for (int i = 0; i < w; ++i)
          {
            const apc::Ray a = tile.PixelRay(i, j);
            const apc::Ray b = full.PixelRay(x * w + i, y * h + j);
            for (int d = 0; d < 3; ++d)
            {
              // A few ulps: the narrowed angle goes through tan(atan()).
              ASSERT_NEAR(a.Origin[d], b.Origin[d], 1e-12) << parallel << x << y << i << j;
              ASSERT_NEAR(a.Direction[d], b.Direction[d], 1e-12) << parallel << x << y << i << j;
            }
            // Projection is the inverse of the pixel ray, window centre included.
            const std::array<double, 3> p = { a.Origin[0] + 5 * a.Direction[0],
              a.Origin[1] + 5 * a.Direction[1], a.Origin[2] + 5 * a.Direction[2] };
            double px = 0;
            double py = 0;
            ASSERT_TRUE(tile.Project(p, px, py));
            EXPECT_NEAR(px, i, 1e-9);
            EXPECT_NEAR(py, j, 1e-9);
          }
        }
      }
    }
  }
}

// A reduced image (fewer, larger pixels) covers the viewport's frustum: with the viewport's
// aspect given, its corner rays are the viewport's corner rays.
TEST(RayCamera, ReducedImageCoversTheSameFrustum)
{
  const apc::RayCamera full({ 0, 0, 5 }, { 0, 0, 0 }, { 0, 1, 0 }, 30.0, false, 1.0, 8, 6, 0.1, 10);
  const apc::RayCamera half(
    { 0, 0, 5 }, { 0, 0, 0 }, { 0, 1, 0 }, 30.0, false, 1.0, 4, 3, 0.1, 10, { 0, 0 }, 8.0 / 6.0);
  // Half-image pixel (i, j) is the centre of full pixels (2i..2i+1, 2j..2j+1): its ray meets
  // the full image at (2i + 0.5, 2j + 0.5).
  for (int j = 0; j < 3; ++j)
  {
    for (int i = 0; i < 4; ++i)
    {
      const apc::Ray a = half.PixelRay(i, j);
      const std::array<double, 3> p = { a.Origin[0] + 3 * a.Direction[0],
        a.Origin[1] + 3 * a.Direction[1], a.Origin[2] + 3 * a.Direction[2] };
      double px = 0;
      double py = 0;
      ASSERT_TRUE(full.Project(p, px, py));
      EXPECT_NEAR(px, 2 * i + 0.5, 1e-9);
      EXPECT_NEAR(py, 2 * j + 0.5, 1e-9);
    }
  }
}
}

// A cropped camera renders a rectangle of the full image's pixels with the very same rays
// (bit for bit: the pass renders only the data's screen rectangle and must equal a full
// render), projects onto crop-relative pixels, and knows where its pixels lie in the full
// image.
// A decimated camera casts every step-th ray of its crop (the opaque stop's first-frame
// probe): the same rays, projections onto its own pixels, and image columns and rows.
TEST(RayCamera, DecimatedCastsEveryStepthRayOfItsCrop)
{
  for (bool parallel : { false, true })
  {
    const apc::RayCamera full({ 1, 2, 9 }, { 0, 0, 0 }, { 0, 1, 0 }, 30.0, parallel, 2.5, 40, 30,
      0.1, 100.0, { 0.25, -0.5 }, 1.6);
    const apc::RayCamera crop = full.Cropped(7, 5, 13, 11);
    const apc::RayCamera coarse = crop.Decimated(4, 2);
    EXPECT_EQ(coarse.GetWidth(), 3);                // columns 2, 6, 10 of 13
    EXPECT_EQ(coarse.GetHeight(), 3);               // rows 2, 6, 10 of 11
    EXPECT_EQ(crop.Decimated(4, 3).GetWidth(), 3);  // 3, 7, 11
    EXPECT_EQ(crop.Decimated(4, 3).GetHeight(), 2); // 3, 7
    for (int j = 0; j < coarse.GetHeight(); ++j)
    {
      for (int i = 0; i < coarse.GetWidth(); ++i)
      {
        const apc::Ray a = coarse.PixelRay(i, j);
        const apc::Ray b = crop.PixelRay(4 * i + 2, 4 * j + 2);
        ASSERT_EQ(a.Origin, b.Origin);
        ASSERT_EQ(a.Direction, b.Direction);
        EXPECT_EQ(coarse.ImageColumn(i), 7 + 4 * i + 2);
        EXPECT_EQ(coarse.ImageRow(j), 5 + 4 * j + 2);
        const std::array<double, 3> p = { a.Origin[0] + 5 * a.Direction[0],
          a.Origin[1] + 5 * a.Direction[1], a.Origin[2] + 5 * a.Direction[2] };
        double px = 0;
        double py = 0;
        ASSERT_TRUE(coarse.Project(p, px, py));
        EXPECT_NEAR(px, i, 1e-9);
        EXPECT_NEAR(py, j, 1e-9);
      }
    }
    EXPECT_EQ(crop.ImageColumn(3), 10); // undecimated: the crop's offset alone
  }
}

TEST(RayCamera, CropIsARectangleOfTheSamePixels)
{
  for (bool parallel : { false, true })
  {
    const apc::RayCamera full({ 1, 2, 9 }, { 0, 0, 0 }, { 0, 1, 0 }, 30.0, parallel, 2.5, 40, 30,
      0.1, 100.0, { 0.25, -0.5 }, 1.6);
    const apc::RayCamera crop = full.Cropped(7, 5, 13, 11);
    EXPECT_EQ(crop.GetWidth(), 13);
    EXPECT_EQ(crop.GetHeight(), 11);
    const apc::RayCamera inner = crop.Cropped(2, 3, 4, 4);
    EXPECT_EQ(inner.GetCropI0(), 9);
    EXPECT_EQ(inner.GetCropJ0(), 8);
    for (int j = 0; j < 11; ++j)
    {
      for (int i = 0; i < 13; ++i)
      {
        const apc::Ray a = crop.PixelRay(i, j);
        const apc::Ray b = full.PixelRay(i + 7, j + 5);
        ASSERT_EQ(a.Origin, b.Origin);
        ASSERT_EQ(a.Direction, b.Direction);
        ASSERT_EQ(crop.DistanceFromDepth(i, j, 0.5), full.DistanceFromDepth(i + 7, j + 5, 0.5));
        const std::array<double, 3> p = { a.Origin[0] + 5 * a.Direction[0],
          a.Origin[1] + 5 * a.Direction[1], a.Origin[2] + 5 * a.Direction[2] };
        double px = 0;
        double py = 0;
        ASSERT_TRUE(crop.Project(p, px, py));
        EXPECT_NEAR(px, i, 1e-9);
        EXPECT_NEAR(py, j, 1e-9);
      }
    }
    const apc::Ray a = inner.PixelRay(1, 2);
    const apc::Ray b = full.PixelRay(10, 10);
    EXPECT_EQ(a.Direction, b.Direction);
  }
}
