// Images in and out of tests and benchmarks: PNG files for people to look at, where they go,
// and the plain comparisons of two float images.
#ifndef apcTestImages_h
#define apcTestImages_h

#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPNGWriter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

namespace apctest
{

// 8-bit RGB, bottom row first (as vtkRenderWindow::GetPixelData gives it), written as PNG.
inline void WritePNG(
  const std::string& path, const std::vector<unsigned char>& rgb, int width, int height)
{
  vtkNew<vtkImageData> image;
  image->SetDimensions(width, height, 1);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  std::copy(rgb.begin(), rgb.end(), static_cast<unsigned char*>(image->GetScalarPointer()));
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(path.c_str());
  writer->SetInputData(image);
  writer->Write();
}

// Premultiplied RGBA over a background, as 8-bit RGB: what a viewer of the picture sees.
inline std::vector<unsigned char> ToRGB8(const std::vector<float>& rgba, int pixels,
  const std::array<double, 3>& background = { 1.0, 1.0, 1.0 })
{
  std::vector<unsigned char> rgb(3 * static_cast<size_t>(pixels));
  for (int p = 0; p < pixels; ++p)
  {
    for (int c = 0; c < 3; ++c)
    {
      const double v = rgba[4 * p + c] + (1.0 - rgba[4 * p + 3]) * background[c];
      rgb[3 * p + c] =
        static_cast<unsigned char>(std::lround(255.0 * std::min(1.0, std::max(0.0, v))));
    }
  }
  return rgb;
}

// Premultiplied RGBA over a background, written as PNG (for looking at).
inline void WritePNG(const std::string& path, const std::vector<float>& rgba, int width, int height,
  const std::array<double, 3>& background = { 1.0, 1.0, 1.0 })
{
  WritePNG(path, ToRGB8(rgba, width * height, background), width, height);
}

// Where tests put images for people to look at: $APC_TEST_OUTPUT or the working directory.
inline std::string OutputPath(const std::string& name)
{
  const char* dir = std::getenv("APC_TEST_OUTPUT");
  return (dir ? std::string(dir) + "/" : std::string()) + name;
}

// max |a - b| over two equally long float images; +inf if the sizes differ.
template <class T>
double MaxAbsDiff(const std::vector<T>& a, const std::vector<T>& b)
{
  if (a.size() != b.size())
  {
    return std::numeric_limits<double>::infinity();
  }
  double d = 0;
  for (size_t v = 0; v < a.size(); ++v)
  {
    const double e = std::abs(static_cast<double>(a[v]) - static_cast<double>(b[v]));
    d = std::max(d, e == e ? e : std::numeric_limits<double>::infinity());
  }
  return d;
}

// Largest value of one channel of an interleaved image (e.g. alpha: channel 3 of 4).
inline double MaxChannel(const std::vector<float>& image, int channels, int channel)
{
  double m = 0;
  for (size_t v = channel; v < image.size(); v += channels)
  {
    m = std::max(m, static_cast<double>(image[v]));
  }
  return m;
}

} // namespace apctest

#endif
