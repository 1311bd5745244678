// Compressed rows (CSR): the entries of row r are Values[Offsets[r] .. Offsets[r + 1]). The
// builder of segments per pixel of a strip; the cells per screen tile (apcTileBins.cpp) count
// and fill their rows in different orders, so they use only PrefixSum.
#ifndef apcCompressedRows_h
#define apcCompressedRows_h

#include <cstddef>
#include <cstdint>
#include <vector>

namespace apc
{

// Turns per-row counts stored at offsets[r + 1] (offsets[0] = 0) into offsets, in place.
inline void PrefixSum(std::vector<int64_t>& offsets)
{
  for (size_t r = 1; r < offsets.size(); ++r)
  {
    offsets[r] += offsets[r - 1];
  }
}

// Counting sort into compressed rows, stable within a row. forEachEntry(emit) must call
// emit(row, value) for every entry, the same entries in the same order each time: it runs
// twice, once to count and once to fill. values: a std::vector of T (any allocator).
template <class T, class ForEachEntry, class Values>
void BuildCompressedRows(
  int64_t rows, ForEachEntry&& forEachEntry, std::vector<int64_t>& offsets, Values& values)
{
  offsets.assign(static_cast<size_t>(rows) + 1, 0);
  forEachEntry([&](int64_t row, const T&) { ++offsets[row + 1]; });
  PrefixSum(offsets);
  values.resize(static_cast<size_t>(offsets.back()));
  std::vector<int64_t> fill(offsets.begin(), offsets.end() - 1);
  forEachEntry([&](int64_t row, const T& value) { values[fill[row]++] = value; });
}

} // namespace apc

#endif
