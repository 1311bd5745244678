#include "apcTransferTable.h"

#include "apcAbsorbance.h"

#include <algorithm>
#include <cmath>

namespace apc
{

TransferTable::TransferTable(double scalarMin, double scalarMax,
  const std::vector<std::array<float, 3>>& colours, const std::vector<double>& opacities,
  double sampleSpacing, double unitDistance)
  : Min(scalarMin)
  , Spacing(sampleSpacing)
{
  const size_t n = std::max<size_t>(2, std::min(colours.size(), opacities.size()));
  this->Entries.resize(n);
  const double scale = unitDistance > 0 ? sampleSpacing / unitDistance : 1.0;
  for (size_t i = 0; i < n; ++i)
  {
    const size_t c = std::min(i, colours.empty() ? 0 : colours.size() - 1);
    const size_t o = std::min(i, opacities.empty() ? 0 : opacities.size() - 1);
    TransferSample& e = this->Entries[i];
    e.Colour = colours.empty() ? std::array<float, 3>{ 1.f, 1.f, 1.f } : colours[c];
    const double alpha = opacities.empty() ? 0.0 : opacities[o];
    e.Absorbance = static_cast<float>(std::min(kAbsorbanceMax, AbsorbanceFromAlpha(alpha) * scale));
  }
  this->AbsorbancePairs.resize(2 * n);
  for (size_t i = 0; i < n; ++i)
  {
    this->AbsorbancePairs[2 * i] = this->Entries[i].Absorbance;
    this->AbsorbancePairs[2 * i + 1] = this->Entries[std::min(i + 1, n - 1)].Absorbance;
  }
  this->EntryDifferences.resize(n);
  for (size_t i = 0; i < n; ++i)
  {
    const TransferSample& a = this->Entries[i];
    const TransferSample& b = this->Entries[std::min(i + 1, n - 1)];
    float* pair = this->EntryDifferences[i].Values;
    for (int c = 0; c < 3; ++c)
    {
      pair[c] = a.Colour[c];
      pair[4 + c] = b.Colour[c] - a.Colour[c];
    }
    pair[3] = a.Absorbance;
    pair[7] = b.Absorbance - a.Absorbance;
  }
  this->VisibleBefore.assign(n + 1, 0);
  for (size_t i = 0; i < n; ++i)
  {
    this->VisibleBefore[i + 1] = this->VisibleBefore[i] + (this->Entries[i].Absorbance > 0 ? 1 : 0);
  }
  const double range = scalarMax - scalarMin;
  this->Last = static_cast<double>(n - 1);
  // A zero-width range maps everything onto the first entry.
  this->Scale = range > 0 && std::isfinite(range) ? this->Last / range : 0.0;
}

bool TransferTable::IsTransparent() const
{
  return this->VisibleBefore.back() == 0;
}

} // namespace apc
