#include "apcImageMetrics.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>

namespace apc
{
namespace
{

// Compensated (Neumaier) sum: a megapixel image sums ~1e6 terms, and the skimage check asks
// for agreement to ~1e-9 relative with numpy's pairwise summation.
class AccurateSum
{
public:
  void Add(double v)
  {
    const double t = this->Sum + v;
    if (std::fabs(this->Sum) >= std::fabs(v))
    {
      this->Compensation += (this->Sum - t) + v;
    }
    else
    {
      this->Compensation += (v - t) + this->Sum;
    }
    this->Sum = t;
  }
  double Value() const { return this->Sum + this->Compensation; }

private:
  double Sum = 0.0;
  double Compensation = 0.0;
};

void CheckImages(const void* a, const void* b, int w, int h, int c, const char* what)
{
  if (a == nullptr || b == nullptr)
  {
    throw std::invalid_argument(std::string(what) + ": null image");
  }
  if (w < 1 || h < 1 || c < 1)
  {
    throw std::invalid_argument(std::string(what) + ": image size must be at least 1x1x1, got " +
      std::to_string(w) + "x" + std::to_string(h) + "x" + std::to_string(c));
  }
}

void CheckDataRange(double dataRange, const char* what)
{
  if (!(dataRange > 0.0) || !std::isfinite(dataRange))
  {
    throw std::invalid_argument(std::string(what) + ": dataRange must be positive and finite");
  }
}

std::size_t SampleCount(int w, int h, int c)
{
  return static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * static_cast<std::size_t>(c);
}

template <typename T>
double MseImpl(const T* a, const T* b, int w, int h, int c)
{
  CheckImages(a, b, w, h, c, "MeanSquaredError");
  const std::size_t n = SampleCount(w, h, c);
  AccurateSum sum;
  for (std::size_t i = 0; i < n; ++i)
  {
    const double d = static_cast<double>(a[i]) - static_cast<double>(b[i]);
    sum.Add(d * d);
  }
  return sum.Value() / static_cast<double>(n);
}

double PsnrFromMse(double mse, double dataRange)
{
  if (mse == 0.0)
  {
    return std::numeric_limits<double>::infinity();
  }
  return 10.0 * std::log10(dataRange * dataRange / mse);
}

// scipy.ndimage's Gaussian kernel (_gaussian_kernel1d): exp(-x^2 / (2 sigma^2)) sampled at
// the integers of [-radius, radius] and normalised to sum 1 after truncation, so that flat
// regions stay flat.
std::array<double, kSsimWindowSize> GaussianKernel()
{
  std::array<double, kSsimWindowSize> k{};
  double sum = 0.0;
  for (int i = 0; i < kSsimWindowSize; ++i)
  {
    const double x = i - kSsimRadius;
    k[i] = std::exp(-0.5 / (kSsimSigma * kSsimSigma) * x * x);
    sum += k[i];
  }
  for (double& v : k)
  {
    v /= sum;
  }
  return k;
}

// scipy's mode 'reflect' (d c b a | a b c d | d c b a): the half-sample symmetric extension,
// periodic with period 2n, so that any offset maps into the image.
int Reflect(int i, int n)
{
  const int period = 2 * n;
  i %= period;
  if (i < 0)
  {
    i += period;
  }
  return i < n ? i : period - 1 - i;
}

// Separable Gaussian filter of a w x h plane, first along y then along x (scipy's axis
// order; the result is the same up to rounding either way).
class GaussianFilter
{
public:
  GaussianFilter(int w, int h)
    : W(w)
    , H(h)
    , Kernel(GaussianKernel())
    , Temp(static_cast<std::size_t>(w) * static_cast<std::size_t>(h))
  {
    for (int i = -kSsimRadius; i < w + kSsimRadius; ++i)
    {
      this->ColumnIndex.push_back(Reflect(i, w));
    }
    for (int i = -kSsimRadius; i < h + kSsimRadius; ++i)
    {
      this->RowIndex.push_back(Reflect(i, h));
    }
  }

  void operator()(const std::vector<double>& in, std::vector<double>& out)
  {
    const std::size_t w = static_cast<std::size_t>(this->W);
    for (int y = 0; y < this->H; ++y)
    {
      double* dst = &this->Temp[y * w];
      std::fill(dst, dst + w, 0.0);
      for (int j = 0; j < kSsimWindowSize; ++j)
      {
        const double* src = &in[this->RowIndex[y + j] * w];
        const double k = this->Kernel[j];
        for (std::size_t x = 0; x < w; ++x)
        {
          dst[x] += k * src[x];
        }
      }
    }
    out.resize(this->Temp.size());
    for (int y = 0; y < this->H; ++y)
    {
      const double* src = &this->Temp[y * w];
      double* dst = &out[y * w];
      for (int x = 0; x < this->W; ++x)
      {
        const int* idx = &this->ColumnIndex[x];
        double s = 0.0;
        for (int j = 0; j < kSsimWindowSize; ++j)
        {
          s += this->Kernel[j] * src[idx[j]];
        }
        dst[x] = s;
      }
    }
  }

private:
  int W;
  int H;
  std::array<double, kSsimWindowSize> Kernel;
  std::vector<int> ColumnIndex; // reflected x of x - radius, entry x + radius is x
  std::vector<int> RowIndex;
  std::vector<double> Temp;
};

template <typename T>
double SsimImpl(
  const T* a, const T* b, int w, int h, int c, double dataRange, std::vector<double>* ssimMap)
{
  CheckImages(a, b, w, h, c, "StructuralSimilarity");
  CheckDataRange(dataRange, "StructuralSimilarity");
  if (w < kSsimWindowSize || h < kSsimWindowSize)
  {
    throw std::invalid_argument("StructuralSimilarity: images must be at least " +
      std::to_string(kSsimWindowSize) + "x" + std::to_string(kSsimWindowSize) + ", got " +
      std::to_string(w) + "x" + std::to_string(h));
  }
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  if (ssimMap)
  {
    ssimMap->assign(n * static_cast<std::size_t>(c), 0.0);
  }

  const double c1 = (kSsimK1 * dataRange) * (kSsimK1 * dataRange);
  const double c2 = (kSsimK2 * dataRange) * (kSsimK2 * dataRange);
  GaussianFilter filter(w, h);
  std::vector<double> x(n), y(n), product(n);
  std::vector<double> ux, uy, uxx, uyy, uxy;
  double channelSum = 0.0;

  for (int k = 0; k < c; ++k)
  {
    for (std::size_t i = 0; i < n; ++i)
    {
      x[i] = static_cast<double>(a[i * c + k]);
      y[i] = static_cast<double>(b[i * c + k]);
    }
    filter(x, ux);
    filter(y, uy);
    for (std::size_t i = 0; i < n; ++i)
    {
      product[i] = x[i] * x[i];
    }
    filter(product, uxx);
    for (std::size_t i = 0; i < n; ++i)
    {
      product[i] = y[i] * y[i];
    }
    filter(product, uyy);
    for (std::size_t i = 0; i < n; ++i)
    {
      product[i] = x[i] * y[i];
    }
    filter(product, uxy);

    // Population (co)variances, as Wang et al.; no clamping of the slightly negative
    // variances that cancellation can produce, so that the result matches scikit-image.
    AccurateSum cropped;
    for (int py = 0; py < h; ++py)
    {
      const bool rowInside = py >= kSsimRadius && py < h - kSsimRadius;
      for (int px = 0; px < w; ++px)
      {
        const std::size_t i = static_cast<std::size_t>(py) * w + px;
        const double vx = uxx[i] - ux[i] * ux[i];
        const double vy = uyy[i] - uy[i] * uy[i];
        const double vxy = uxy[i] - ux[i] * uy[i];
        const double a1 = 2.0 * ux[i] * uy[i] + c1;
        const double a2 = 2.0 * vxy + c2;
        const double b1 = ux[i] * ux[i] + uy[i] * uy[i] + c1;
        const double b2 = vx + vy + c2;
        const double s = (a1 * a2) / (b1 * b2);
        if (ssimMap)
        {
          (*ssimMap)[i * c + k] = s;
        }
        if (rowInside && px >= kSsimRadius && px < w - kSsimRadius)
        {
          cropped.Add(s);
        }
      }
    }
    const double count =
      static_cast<double>(h - 2 * kSsimRadius) * static_cast<double>(w - 2 * kSsimRadius);
    channelSum += cropped.Value() / count;
  }
  return channelSum / c;
}

template <typename T>
ImageComparison CompareImpl(const T* a, const T* b, int w, int h, int c, double dataRange,
  double threshold, std::vector<double>* ssimMap)
{
  ImageComparison result;
  // SSIM first: it validates every argument before any work is reported.
  result.Ssim = SsimImpl(a, b, w, h, c, dataRange, ssimMap);
  const std::size_t pixels = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  AccurateSum sum;
  for (std::size_t p = 0; p < pixels; ++p)
  {
    bool over = false;
    for (int k = 0; k < c; ++k)
    {
      const std::size_t i = p * c + k;
      const double d = static_cast<double>(a[i]) - static_cast<double>(b[i]);
      sum.Add(d * d);
      const double ad = std::fabs(d);
      result.MaxAbsDiff = std::max(result.MaxAbsDiff, ad);
      over = over || ad > threshold;
    }
    result.PixelsOverThreshold += over ? 1 : 0;
  }
  result.Mse = sum.Value() / static_cast<double>(SampleCount(w, h, c));
  result.Psnr = PsnrFromMse(result.Mse, dataRange);
  return result;
}

template <typename T>
std::vector<T> CompositeImpl(const T* rgba, int w, int h, const std::array<double, 3>& background)
{
  if (rgba == nullptr || w < 1 || h < 1)
  {
    throw std::invalid_argument("CompositeOverBackground: null or empty image");
  }
  const std::size_t pixels = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  std::vector<T> rgb(pixels * 3);
  for (std::size_t p = 0; p < pixels; ++p)
  {
    const double transmitted = 1.0 - static_cast<double>(rgba[4 * p + 3]);
    for (int k = 0; k < 3; ++k)
    {
      rgb[3 * p + k] =
        static_cast<T>(static_cast<double>(rgba[4 * p + k]) + transmitted * background[k]);
    }
  }
  return rgb;
}

} // namespace

double MeanSquaredError(const float* a, const float* b, int w, int h, int c)
{
  return MseImpl(a, b, w, h, c);
}

double MeanSquaredError(const double* a, const double* b, int w, int h, int c)
{
  return MseImpl(a, b, w, h, c);
}

double PeakSignalToNoiseRatio(const float* a, const float* b, int w, int h, int c, double dataRange)
{
  CheckDataRange(dataRange, "PeakSignalToNoiseRatio");
  return PsnrFromMse(MseImpl(a, b, w, h, c), dataRange);
}

double PeakSignalToNoiseRatio(
  const double* a, const double* b, int w, int h, int c, double dataRange)
{
  CheckDataRange(dataRange, "PeakSignalToNoiseRatio");
  return PsnrFromMse(MseImpl(a, b, w, h, c), dataRange);
}

double StructuralSimilarity(const float* a, const float* b, int w, int h, int c, double dataRange,
  std::vector<double>* ssimMap)
{
  return SsimImpl(a, b, w, h, c, dataRange, ssimMap);
}

double StructuralSimilarity(const double* a, const double* b, int w, int h, int c, double dataRange,
  std::vector<double>* ssimMap)
{
  return SsimImpl(a, b, w, h, c, dataRange, ssimMap);
}

ImageComparison CompareImages(const float* a, const float* b, int w, int h, int c, double dataRange,
  double threshold, std::vector<double>* ssimMap)
{
  return CompareImpl(a, b, w, h, c, dataRange, threshold, ssimMap);
}

ImageComparison CompareImages(const double* a, const double* b, int w, int h, int c,
  double dataRange, double threshold, std::vector<double>* ssimMap)
{
  return CompareImpl(a, b, w, h, c, dataRange, threshold, ssimMap);
}

std::vector<float> CompositeOverBackground(
  const float* premultipliedRGBA, int w, int h, const std::array<double, 3>& background)
{
  return CompositeImpl(premultipliedRGBA, w, h, background);
}

std::vector<double> CompositeOverBackground(
  const double* premultipliedRGBA, int w, int h, const std::array<double, 3>& background)
{
  return CompositeImpl(premultipliedRGBA, w, h, background);
}

} // namespace apc
