// apcImageMetricsTool a.raw b.raw W H C [dataRange [ssimMap.raw]]
//
// Compares two raw little-endian float32 images (W x H x C interleaved) with APC's metrics and
// prints {"mse": .., "psnr": .., "ssim": ..} on one line. It exists so that
// Testing/Python/TestImageMetricsSkimage.py can hold the C++ metrics against scikit-image, an
// independent implementation. Identical images print "psnr": Infinity, which Python's json
// module reads as float('inf'). If ssimMap.raw is given, the full per-pixel SSIM map
// (W x H x C, border strip included) is written there as little-endian float64: the mean
// skips the border strip, so only the map shows whether borders are filtered as in
// scikit-image. Exit status 2 on any error, with the reason on stderr.
#include "apcImageMetrics.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <iostream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

namespace
{

int ParsePositiveInt(const char* text, const char* name)
{
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || v < 1 || v > 1000000)
  {
    throw std::invalid_argument(std::string("bad ") + name + ": " + text);
  }
  return static_cast<int>(v);
}

// Decoded byte by byte so that the file format does not depend on the host's byte order.
std::vector<float> ReadRawFloat32(const char* path, std::size_t count)
{
  std::ifstream in(path, std::ios::binary);
  if (!in)
  {
    throw std::runtime_error(std::string("cannot open ") + path);
  }
  const std::vector<unsigned char> bytes(
    (std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.size() != count * 4)
  {
    throw std::runtime_error(std::string(path) + ": expected " + std::to_string(count * 4) +
      " bytes, found " + std::to_string(bytes.size()));
  }
  std::vector<float> values(count);
  for (std::size_t i = 0; i < count; ++i)
  {
    const unsigned char* p = &bytes[4 * i];
    const std::uint32_t u = static_cast<std::uint32_t>(p[0]) |
      (static_cast<std::uint32_t>(p[1]) << 8) | (static_cast<std::uint32_t>(p[2]) << 16) |
      (static_cast<std::uint32_t>(p[3]) << 24);
    std::memcpy(&values[i], &u, sizeof(float));
  }
  return values;
}

void WriteRawFloat64(const char* path, const std::vector<double>& values)
{
  std::vector<unsigned char> bytes(values.size() * 8);
  for (std::size_t i = 0; i < values.size(); ++i)
  {
    std::uint64_t u = 0;
    std::memcpy(&u, &values[i], sizeof(double));
    for (int b = 0; b < 8; ++b)
    {
      bytes[8 * i + b] = static_cast<unsigned char>(u >> (8 * b));
    }
  }
  std::ofstream out(path, std::ios::binary);
  out.write(
    reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!out)
  {
    throw std::runtime_error(std::string("cannot write ") + path);
  }
}

void PrintNumber(const char* key, double v, bool last)
{
  if (std::isinf(v))
  {
    std::printf("\"%s\": %sInfinity", key, v < 0 ? "-" : "");
  }
  else if (std::isnan(v))
  {
    std::printf("\"%s\": NaN", key);
  }
  else
  {
    std::printf("\"%s\": %.17g", key, v);
  }
  std::printf(last ? "}\n" : ", ");
}

} // namespace

int main(int argc, char* argv[])
{
  if (argc < 6 || argc > 8)
  {
    std::cerr << "usage: " << argv[0] << " a.raw b.raw W H C [dataRange [ssimMap.raw]]\n";
    return 2;
  }
  try
  {
    const int w = ParsePositiveInt(argv[3], "W");
    const int h = ParsePositiveInt(argv[4], "H");
    const int c = ParsePositiveInt(argv[5], "C");
    const double dataRange = argc >= 7 ? std::strtod(argv[6], nullptr) : 1.0;
    const std::size_t count =
      static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * static_cast<std::size_t>(c);
    const std::vector<float> a = ReadRawFloat32(argv[1], count);
    const std::vector<float> b = ReadRawFloat32(argv[2], count);
    std::vector<double> map;
    const apc::ImageComparison r =
      apc::CompareImages(a.data(), b.data(), w, h, c, dataRange, 0.0, argc == 8 ? &map : nullptr);
    if (argc == 8)
    {
      WriteRawFloat64(argv[7], map);
    }
    std::printf("{");
    PrintNumber("mse", r.Mse, false);
    PrintNumber("psnr", r.Psnr, false);
    PrintNumber("ssim", r.Ssim, true);
  }
  catch (const std::exception& e)
  {
    std::cerr << argv[0] << ": " << e.what() << "\n";
    return 2;
  }
  return 0;
}
