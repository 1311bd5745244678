#include "apcImageMetrics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

namespace
{

// A smooth, non-trivial test picture: gradients and a ripple, in [0.1, 0.9].
std::vector<double> SmoothImage(int w, int h, int c)
{
  std::vector<double> img(static_cast<std::size_t>(w) * h * c);
  for (int y = 0; y < h; ++y)
  {
    for (int x = 0; x < w; ++x)
    {
      for (int k = 0; k < c; ++k)
      {
        const double u = static_cast<double>(x) / w;
        const double v = static_cast<double>(y) / h;
        img[(static_cast<std::size_t>(y) * w + x) * c + k] =
          0.5 + 0.2 * (u - v) + 0.2 * std::sin(6.0 * u + 4.0 * v + k);
      }
    }
  }
  return img;
}

std::vector<double> WithNoise(const std::vector<double>& img, double sigma, unsigned seed)
{
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<double> out(img);
  for (double& v : out)
  {
    v = std::clamp(v + noise(rng), 0.0, 1.0);
  }
  return out;
}

// Independent of the library's separable filter: the 2-D Gaussian window summed directly,
// with the half-sample reflection written out for a single reflection.
double BruteForceSsimAt(const std::vector<double>& a, const std::vector<double>& b, int w, int h,
  int px, int py, double range)
{
  const auto reflect = [](int i, int n) { return i < 0 ? -i - 1 : (i >= n ? 2 * n - i - 1 : i); };
  double weightSum = 0.0;
  double mx = 0.0, my = 0.0, mxx = 0.0, myy = 0.0, mxy = 0.0;
  for (int dy = -5; dy <= 5; ++dy)
  {
    for (int dx = -5; dx <= 5; ++dx)
    {
      const double g = std::exp(-(dx * dx + dy * dy) / (2.0 * 1.5 * 1.5));
      const std::size_t i = static_cast<std::size_t>(reflect(py + dy, h)) * w + reflect(px + dx, w);
      weightSum += g;
      mx += g * a[i];
      my += g * b[i];
      mxx += g * a[i] * a[i];
      myy += g * b[i] * b[i];
      mxy += g * a[i] * b[i];
    }
  }
  mx /= weightSum;
  my /= weightSum;
  const double vx = mxx / weightSum - mx * mx;
  const double vy = myy / weightSum - my * my;
  const double vxy = mxy / weightSum - mx * my;
  const double c1 = (0.01 * range) * (0.01 * range);
  const double c2 = (0.03 * range) * (0.03 * range);
  return (2 * mx * my + c1) * (2 * vxy + c2) / ((mx * mx + my * my + c1) * (vx + vy + c2));
}

} // namespace

TEST(ImageMetrics, IdenticalImages)
{
  for (int c : { 1, 3, 4 })
  {
    const std::vector<double> img = SmoothImage(32, 20, c);
    EXPECT_EQ(apc::MeanSquaredError(img.data(), img.data(), 32, 20, c), 0.0);
    const double psnr = apc::PeakSignalToNoiseRatio(img.data(), img.data(), 32, 20, c);
    EXPECT_TRUE(std::isinf(psnr) && psnr > 0);
    EXPECT_DOUBLE_EQ(apc::StructuralSimilarity(img.data(), img.data(), 32, 20, c), 1.0);
  }
}

TEST(ImageMetrics, HandComputedMseAndPsnr)
{
  const double a[2] = { 0.0, 0.0 };
  const double b[2] = { 0.5, 0.0 };
  EXPECT_DOUBLE_EQ(apc::MeanSquaredError(a, b, 2, 1, 1), 0.125);
  EXPECT_DOUBLE_EQ(apc::PeakSignalToNoiseRatio(a, b, 2, 1, 1), 10.0 * std::log10(8.0));
  // Averaged over channels as well as pixels.
  const float rgbA[3] = { 0.0f, 0.0f, 0.0f };
  const float rgbB[3] = { 0.25f, 0.5f, 0.75f };
  EXPECT_DOUBLE_EQ(apc::MeanSquaredError(rgbA, rgbB, 1, 1, 3), (0.0625 + 0.25 + 0.5625) / 3.0);
  // A constant error of 5 on an 8-bit scale: MSE 25, PSNR 20 log10(255 / 5).
  std::vector<float> x(40 * 30, 100.0f), y(40 * 30, 105.0f);
  EXPECT_DOUBLE_EQ(apc::MeanSquaredError(x.data(), y.data(), 40, 30, 1), 25.0);
  EXPECT_NEAR(apc::PeakSignalToNoiseRatio(x.data(), y.data(), 40, 30, 1, 255.0),
    20.0 * std::log10(51.0), 1e-12);
}

TEST(ImageMetrics, SsimSymmetricBoundedAndDecreasingWithNoise)
{
  const int w = 64, h = 48, c = 3;
  const std::vector<double> clean = SmoothImage(w, h, c);
  double previous = 1.0;
  for (double sigma : { 0.005, 0.02, 0.05, 0.1, 0.3 })
  {
    const std::vector<double> noisy = WithNoise(clean, sigma, 7);
    const double ab = apc::StructuralSimilarity(clean.data(), noisy.data(), w, h, c);
    const double ba = apc::StructuralSimilarity(noisy.data(), clean.data(), w, h, c);
    EXPECT_NEAR(ab, ba, 1e-14);
    EXPECT_LE(ab, 1.0);
    EXPECT_LT(ab, previous) << "sigma " << sigma;
    previous = ab;
  }
  EXPECT_LT(previous, 0.5);
}

TEST(ImageMetrics, ConstantOffsetOfFlatImages)
{
  // No variance anywhere: SSIM is the luminance term alone, (2ab + C1) / (a^2 + b^2 + C1).
  const int w = 16, h = 12;
  std::vector<float> a(w * h, 0.5f), b(w * h, 0.625f);
  const double c1 = 1e-4;
  const double expected = (2 * 0.5 * 0.625 + c1) / (0.25 + 0.390625 + c1);
  EXPECT_NEAR(apc::StructuralSimilarity(a.data(), b.data(), w, h, 1), expected, 1e-12);
}

TEST(ImageMetrics, ConstantOffsetOfGradient)
{
  // b = a + d: variances and covariance agree, so the contrast-structure term is 1. Away from
  // the border the symmetric window leaves a linear ramp's mean unchanged, so each SSIM map
  // value is the luminance term of the pixel itself.
  const int w = 40, h = 25;
  const double d = 0.1;
  std::vector<double> a(w * h), b(w * h);
  for (int y = 0; y < h; ++y)
  {
    for (int x = 0; x < w; ++x)
    {
      a[y * w + x] = 0.1 + 0.02 * x;
      b[y * w + x] = a[y * w + x] + d;
    }
  }
  std::vector<double> map;
  const double ssim = apc::StructuralSimilarity(a.data(), b.data(), w, h, 1, 1.0, &map);
  ASSERT_EQ(map.size(), a.size());
  const double c1 = 1e-4;
  double sum = 0.0;
  for (int y = 5; y < h - 5; ++y)
  {
    for (int x = 5; x < w - 5; ++x)
    {
      const double v = a[y * w + x];
      const double expected = (2 * v * (v + d) + c1) / (v * v + (v + d) * (v + d) + c1);
      EXPECT_NEAR(map[y * w + x], expected, 1e-12) << x << "," << y;
      sum += expected;
    }
  }
  EXPECT_NEAR(ssim, sum / ((w - 10) * (h - 10)), 1e-12);
}

TEST(ImageMetrics, MapMatchesBruteForceWindowIncludingBorders)
{
  const int w = 23, h = 17;
  const std::vector<double> a = SmoothImage(w, h, 1);
  const std::vector<double> b = WithNoise(a, 0.05, 3);
  std::vector<double> map;
  apc::StructuralSimilarity(a.data(), b.data(), w, h, 1, 1.0, &map);
  for (int y = 0; y < h; ++y)
  {
    for (int x = 0; x < w; ++x)
    {
      EXPECT_NEAR(map[y * w + x], BruteForceSsimAt(a, b, w, h, x, y, 1.0), 1e-12) << x << "," << y;
    }
  }
}

TEST(ImageMetrics, ChannelsAreComparedSeparatelyAndAveraged)
{
  const int w = 30, h = 20;
  const std::vector<double> a = SmoothImage(w, h, 3);
  const std::vector<double> b = WithNoise(a, 0.04, 11);
  std::vector<double> map;
  const double all = apc::StructuralSimilarity(a.data(), b.data(), w, h, 3, 1.0, &map);
  double sum = 0.0;
  for (int k = 0; k < 3; ++k)
  {
    std::vector<double> ak(w * h), bk(w * h), mapk;
    for (int i = 0; i < w * h; ++i)
    {
      ak[i] = a[3 * i + k];
      bk[i] = b[3 * i + k];
    }
    sum += apc::StructuralSimilarity(ak.data(), bk.data(), w, h, 1, 1.0, &mapk);
    for (int i = 0; i < w * h; ++i)
    {
      EXPECT_EQ(map[3 * i + k], mapk[i]);
    }
  }
  EXPECT_NEAR(all, sum / 3.0, 1e-15);
}

TEST(ImageMetrics, ScaleInvarianceWithDataRange)
{
  const int w = 24, h = 24;
  const std::vector<double> a = SmoothImage(w, h, 1);
  const std::vector<double> b = WithNoise(a, 0.03, 5);
  std::vector<double> a255(a), b255(b);
  for (double& v : a255)
  {
    v *= 255.0;
  }
  for (double& v : b255)
  {
    v *= 255.0;
  }
  EXPECT_NEAR(apc::StructuralSimilarity(a.data(), b.data(), w, h, 1),
    apc::StructuralSimilarity(a255.data(), b255.data(), w, h, 1, 255.0), 1e-12);
  EXPECT_NEAR(apc::PeakSignalToNoiseRatio(a.data(), b.data(), w, h, 1),
    apc::PeakSignalToNoiseRatio(a255.data(), b255.data(), w, h, 1, 255.0), 1e-10);
  EXPECT_NEAR(apc::MeanSquaredError(a255.data(), b255.data(), w, h, 1),
    255.0 * 255.0 * apc::MeanSquaredError(a.data(), b.data(), w, h, 1), 1e-9);
}

TEST(ImageMetrics, FloatAndDoubleBuffersAgree)
{
  const int w = 20, h = 15;
  const std::vector<double> a = SmoothImage(w, h, 4);
  const std::vector<double> b = WithNoise(a, 0.05, 9);
  // The double images hold exactly the float values, so the two paths see the same data.
  std::vector<float> af(a.begin(), a.end()), bf(b.begin(), b.end());
  std::vector<double> ad(af.begin(), af.end()), bd(bf.begin(), bf.end());
  const apc::ImageComparison f = apc::CompareImages(af.data(), bf.data(), w, h, 4, 1.0, 0.1);
  const apc::ImageComparison d = apc::CompareImages(ad.data(), bd.data(), w, h, 4, 1.0, 0.1);
  EXPECT_EQ(f.Mse, d.Mse);
  EXPECT_EQ(f.Psnr, d.Psnr);
  EXPECT_EQ(f.Ssim, d.Ssim);
  EXPECT_EQ(f.MaxAbsDiff, d.MaxAbsDiff);
  EXPECT_EQ(f.PixelsOverThreshold, d.PixelsOverThreshold);
}

TEST(ImageMetrics, CompareImagesMatchesSingleMetrics)
{
  const int w = 16, h = 13, c = 3;
  std::vector<float> a(w * h * c, 0.5f), b(a);
  // Two pixels over the threshold (one with two channels over), one just under it.
  b[(2 * w + 3) * c + 0] = 0.9f;
  b[(2 * w + 3) * c + 2] = 0.1f;
  b[(7 * w + 8) * c + 1] = 0.25f;
  b[(9 * w + 1) * c + 1] = 0.55f;
  std::vector<double> map;
  const apc::ImageComparison r = apc::CompareImages(a.data(), b.data(), w, h, c, 1.0, 0.1, &map);
  EXPECT_DOUBLE_EQ(r.Mse, apc::MeanSquaredError(a.data(), b.data(), w, h, c));
  EXPECT_DOUBLE_EQ(r.Psnr, apc::PeakSignalToNoiseRatio(a.data(), b.data(), w, h, c));
  EXPECT_DOUBLE_EQ(r.Ssim, apc::StructuralSimilarity(a.data(), b.data(), w, h, c));
  EXPECT_NEAR(r.MaxAbsDiff, 0.4, 1e-7);
  EXPECT_EQ(r.PixelsOverThreshold, 2);
  EXPECT_EQ(map.size(), a.size());
  const apc::ImageComparison same = apc::CompareImages(a.data(), a.data(), w, h, c, 1.0, 0.0);
  EXPECT_EQ(same.Mse, 0.0);
  EXPECT_TRUE(std::isinf(same.Psnr));
  EXPECT_EQ(same.Ssim, 1.0);
  EXPECT_EQ(same.MaxAbsDiff, 0.0);
  EXPECT_EQ(same.PixelsOverThreshold, 0);
}

TEST(ImageMetrics, CompositeOverBackground)
{
  // Premultiplied (0.2, 0.1, 0, 0.5) over white, and a transparent and an opaque pixel.
  const float rgba[12] = { 0.2f, 0.1f, 0.0f, 0.5f, 0.0f, 0.0f, 0.0f, 0.0f, 0.3f, 0.6f, 0.9f, 1.0f };
  const std::vector<float> rgb = apc::CompositeOverBackground(rgba, 3, 1, { 1.0, 1.0, 1.0 });
  const float expected[9] = { 0.7f, 0.6f, 0.5f, 1.0f, 1.0f, 1.0f, 0.3f, 0.6f, 0.9f };
  ASSERT_EQ(rgb.size(), 9u);
  for (int i = 0; i < 9; ++i)
  {
    EXPECT_NEAR(rgb[i], expected[i], 1e-7) << i;
  }
  const double rgbaD[4] = { 0.1, 0.2, 0.3, 0.25 };
  const std::vector<double> rgbD = apc::CompositeOverBackground(rgbaD, 1, 1, { 0.4, 0.0, 0.8 });
  EXPECT_DOUBLE_EQ(rgbD[0], 0.1 + 0.75 * 0.4);
  EXPECT_DOUBLE_EQ(rgbD[1], 0.2);
  EXPECT_DOUBLE_EQ(rgbD[2], 0.3 + 0.75 * 0.8);
}

TEST(ImageMetrics, RejectsInvalidArguments)
{
  std::vector<float> img(11 * 11 * 4, 0.5f);
  // 11 x 11 is the smallest image the 11 x 11 window accepts.
  EXPECT_DOUBLE_EQ(apc::StructuralSimilarity(img.data(), img.data(), 11, 11, 4), 1.0);
  EXPECT_THROW(apc::StructuralSimilarity(img.data(), img.data(), 10, 11, 1), std::invalid_argument);
  EXPECT_THROW(apc::StructuralSimilarity(img.data(), img.data(), 11, 7, 1), std::invalid_argument);
  EXPECT_THROW(
    apc::StructuralSimilarity(img.data(), img.data(), 11, 11, 1, 0.0), std::invalid_argument);
  EXPECT_THROW(
    apc::PeakSignalToNoiseRatio(img.data(), img.data(), 11, 11, 1, -1.0), std::invalid_argument);
  EXPECT_THROW(apc::MeanSquaredError(img.data(), img.data(), 0, 11, 1), std::invalid_argument);
  EXPECT_THROW(apc::MeanSquaredError(static_cast<const float*>(nullptr), img.data(), 1, 1, 1),
    std::invalid_argument);
  EXPECT_THROW(
    apc::CompareImages(img.data(), img.data(), 11, 11, 0, 1.0, 0.0), std::invalid_argument);
  // MSE and PSNR have no window, so tiny images are fine.
  EXPECT_EQ(apc::MeanSquaredError(img.data(), img.data(), 1, 1, 1), 0.0);
}
