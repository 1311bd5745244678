// Summaries of repeated measurements in the benchmarks.
#ifndef apcTestStatistics_h
#define apcTestStatistics_h

#include <algorithm>
#include <cmath>
#include <vector>

namespace apctest
{

// The median resists the odd frame a busy machine slows down. whenEmpty: what a caller
// reports when nothing was measured (NaN prints as an empty CSV field).
inline double Median(std::vector<double> values, double whenEmpty = NAN)
{
  if (values.empty())
  {
    return whenEmpty;
  }
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

} // namespace apctest

#endif
