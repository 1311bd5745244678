// Image-quality metrics for comparing APC's approximate image with the exact one, as the APC
// paper reports them (Huang, Usher et al., arXiv 2501.12581): MSE, PSNR and SSIM (Wang, Bovik,
// Sheikh, Simoncelli, "Image quality assessment: from error visibility to structural
// similarity", IEEE TIP 13(4), 2004).
//
// SSIM reproduces scikit-image's reference choice,
//   skimage.metrics.structural_similarity(a, b, data_range=R, gaussian_weights=True,
//     sigma=1.5, use_sample_covariance=False, channel_axis=-1)
// so that numbers can be quoted next to those of other papers, and
// Testing/Python/TestImageMetricsSkimage.py checks it against scikit-image itself.
//
// Images are W x H x C interleaved (pixel (x, y), channel k at ((y * W + x) * C + k)), rows
// top to bottom or bottom to top alike, values in [0, dataRange]. Everything is accumulated
// in double whatever the buffer type. Invalid sizes or a non-positive data range throw
// std::invalid_argument; NaN pixels propagate into the results.
#ifndef apcImageMetrics_h
#define apcImageMetrics_h

#include <array>
#include <cstdint>
#include <vector>

namespace apc
{

// SSIM's Gaussian window: sigma 1.5 truncated at 3.5 sigma gives radius int(3.5 * 1.5 + 0.5)
// = 5, the 11 x 11 window of Wang et al. Both sides of an image must be at least that long
// (scikit-image refuses smaller images with these settings).
constexpr double kSsimSigma = 1.5;
constexpr int kSsimRadius = 5;
constexpr int kSsimWindowSize = 2 * kSsimRadius + 1;
constexpr double kSsimK1 = 0.01;
constexpr double kSsimK2 = 0.03;

// Mean of (a - b)^2 over all pixels and channels. Needs w, h, c >= 1.
double MeanSquaredError(const float* a, const float* b, int w, int h, int c);
double MeanSquaredError(const double* a, const double* b, int w, int h, int c);

// 10 log10(dataRange^2 / MSE) in dB. Identical images have MSE 0 and give +infinity
// (std::numeric_limits<double>::infinity()), as numpy does for scikit-image; callers printing
// tables should handle that case.
double PeakSignalToNoiseRatio(
  const float* a, const float* b, int w, int h, int c, double dataRange = 1.0);
double PeakSignalToNoiseRatio(
  const double* a, const double* b, int w, int h, int c, double dataRange = 1.0);

// Mean SSIM, averaged over channels (each channel is compared on its own). Needs
// w, h >= kSsimWindowSize. Borders are filtered with half-sample symmetric reflection
// (scipy's mode 'reflect'), and the kSsimRadius-wide border strip, where the window reaches
// outside the image, is left out of the mean. If ssimMap is given it receives the full
// per-pixel, per-channel SSIM, w x h x c interleaved like the input, border strip included.
double StructuralSimilarity(const float* a, const float* b, int w, int h, int c,
  double dataRange = 1.0, std::vector<double>* ssimMap = nullptr);
double StructuralSimilarity(const double* a, const double* b, int w, int h, int c,
  double dataRange = 1.0, std::vector<double>* ssimMap = nullptr);

struct ImageComparison
{
  double Mse = 0.0;
  double Psnr = 0.0; // dB, +infinity for identical images
  double Ssim = 0.0;
  double MaxAbsDiff = 0.0; // over all pixels and channels
  // Pixels with at least one channel differing by more than the threshold.
  int64_t PixelsOverThreshold = 0;
};

// All of the above in one call (same requirements as StructuralSimilarity).
ImageComparison CompareImages(const float* a, const float* b, int w, int h, int c, double dataRange,
  double threshold, std::vector<double>* ssimMap = nullptr);
ImageComparison CompareImages(const double* a, const double* b, int w, int h, int c,
  double dataRange, double threshold, std::vector<double>* ssimMap = nullptr);

// Premultiplied RGBA (w x h x 4) over an opaque background into RGB (w x h x 3):
// rgb + (1 - alpha) background. Comparing images composited this way measures what a viewer
// sees; comparing raw RGBA would weigh alpha errors as if they were a fourth colour.
std::vector<float> CompositeOverBackground(
  const float* premultipliedRGBA, int w, int h, const std::array<double, 3>& background);
std::vector<double> CompositeOverBackground(
  const double* premultipliedRGBA, int w, int h, const std::array<double, 3>& background);

} // namespace apc

#endif
