// A 1D transfer function sampled into a table: colour and per-sample absorbance over a
// scalar range, linearly interpolated between entries.
//
// Opacity is stored in absorbance form, already corrected for the sample spacing:
// a = -ln(1 - alpha_tf) * spacing / unitDistance, where alpha_tf is the opacity the transfer
// function gives per unitDistance of travel (VTK's scalar opacity unit distance). Absorbances
// add, so the correction is exact for any spacing, and it is what the moments sum.
#ifndef apcTransferTable_h
#define apcTransferTable_h

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace apc
{

struct TransferSample
{
  std::array<float, 3> Colour;
  float Absorbance; // per sample, in [0, kAbsorbanceMax]
};

class TransferTable
{
public:
  // colours: rgb per entry; opacities: alpha_tf per entry; both sampled uniformly over
  // [scalarMin, scalarMax] (at least 2 entries). Scalars outside the range clamp to the end
  // entries, as VTK's transfer functions do by default.
  TransferTable(double scalarMin, double scalarMax,
    const std::vector<std::array<float, 3>>& colours, const std::vector<double>& opacities,
    double sampleSpacing, double unitDistance);

  // Non-finite scalars (NaN, +-inf) give a fully transparent sample: one rule for all of
  // them, as CellMesh's scalar ranges have. Always inlined: the marcher looks up every
  // sample, and a call per sample costs pass 1 about a twentieth.
  [[gnu::always_inline]] TransferSample Lookup(double scalar) const
  {
    return Lookup(this->GetLayout(), scalar);
  }

  // The table as a vectorised lookup reads it, with Lookup's arithmetic (pass 2's replay).
  struct Layout
  {
    const TransferSample* Entries;
    int Count;
    double Min;
    double Scale;
    double Last;
    // By entry i: the absorbances Lookup interpolates between, entry i's and entry j's (i + 1,
    // or i for the last), side by side, so that a vectorised lookup reads both with one 64-bit
    // gather instead of two gathers of floats (pass 1's lanes).
    const float* AbsorbancePairs;
    // By entry i, 8 floats on a 32-byte boundary: entry i (r, g, b, absorbance), then entry j
    // minus entry i, each difference the float subtraction Lookup makes, so that a vectorised
    // lookup reads both with one aligned load and interpolates without subtracting (pass 2's
    // replay), to the bit as Lookup.
    const float* EntryDifferences;
  };
  Layout GetLayout() const
  {
    return { this->Entries.data(), this->Count(), this->Min, this->Scale, this->Last,
      this->AbsorbancePairs.data(), this->EntryDifferences.data()->Values };
  }
  // Lookup from a layout held in registers: a loop that stores samples between its look-ups
  // (the marcher's) otherwise reloads the table's fields through the table for every one.
  [[gnu::always_inline]] static TransferSample Lookup(const Layout& table, double scalar)
  {
    if (!std::isfinite(scalar))
    {
      return { { 0.f, 0.f, 0.f }, 0.f };
    }
    const double position = (scalar - table.Min) * table.Scale;
    const double x = position < 0 ? 0 : (position > table.Last ? table.Last : position);
    const int i = static_cast<int>(x);
    const int j = i + 1 < table.Count ? i + 1 : i;
    const float f = static_cast<float>(x - i);
    const TransferSample& a = table.Entries[i];
    const TransferSample& b = table.Entries[j];
    return { { a.Colour[0] + f * (b.Colour[0] - a.Colour[0]),
               a.Colour[1] + f * (b.Colour[1] - a.Colour[1]),
               a.Colour[2] + f * (b.Colour[2] - a.Colour[2]) },
      a.Absorbance + f * (b.Absorbance - a.Absorbance) };
  }

  // False if no scalar in [lo, hi] can give a sample any opacity, so a cell whose scalars
  // stay in that range may be skipped (a NaN bound: nothing to see). Exact, not a heuristic:
  // Position is monotonic in floating point, so every scalar of the range interpolates
  // between entries floor(Position(lo)) and floor(Position(hi)) + 1, and the answer comes
  // from a count of the non-transparent entries before each index.
  bool MayBeVisible(double lo, double hi) const
  {
    if (!(lo <= hi))
    {
      return false;
    }
    const int first = static_cast<int>(this->Position(lo));
    const int last = std::min(static_cast<int>(this->Position(hi)) + 1, this->Count() - 1);
    return this->VisibleBefore[last + 1] > this->VisibleBefore[first];
  }

  // visible[c] = MayBeVisible(ranges[c][0], ranges[c][1]) for c in [0, count), the same
  // arithmetic without a call or a branch per range (a march marks every cell of the mesh).
  void MarkVisible(const std::array<float, 2>* ranges, int64_t count, uint8_t* visible) const
  {
    // Position's operands in locals: the byte stores may alias the table's fields.
    const double min = this->Min;
    const double scale = this->Scale;
    const double end = this->Last;
    const int* before = this->VisibleBefore.data();
    const int top = this->Count() - 1;
    const auto position = [=](double scalar)
    {
      const double x = (scalar - min) * scale;
      return x < 0 ? 0 : (x > end ? end : x);
    };
    for (int64_t c = 0; c < count; ++c)
    {
      const double lo = ranges[c][0];
      const double hi = ranges[c][1];
      // A NaN or empty range is hidden; its positions are not formed (a NaN has no index).
      const bool ordered = lo <= hi;
      const int first = static_cast<int>(position(ordered ? lo : min));
      const int last = std::min(static_cast<int>(position(ordered ? hi : min)) + 1, top);
      visible[c] = static_cast<uint8_t>(ordered & (before[last + 1] > before[first]));
    }
  }

  double GetSampleSpacing() const { return this->Spacing; }
  // The scalar step between entries (+inf for a zero-width range: every scalar looks alike).
  double GetBinWidth() const
  {
    return this->Scale > 0 ? 1.0 / this->Scale : std::numeric_limits<double>::infinity();
  }
  // True if no entry can make a sample visible: nothing to render.
  bool IsTransparent() const;

private:
  // The continuous table index of a scalar, clamped to the table.
  double Position(double scalar) const
  {
    const double x = (scalar - this->Min) * this->Scale;
    return x < 0 ? 0 : (x > this->Last ? this->Last : x);
  }
  int Count() const { return static_cast<int>(this->Entries.size()); }

  double Min;
  double Scale;
  double Last;
  double Spacing;
  std::vector<TransferSample> Entries;
  std::vector<float> AbsorbancePairs; // Layout::AbsorbancePairs
  struct alignas(32) EntryDifference
  {
    float Values[8];
  };
  std::vector<EntryDifference> EntryDifferences; // Layout::EntryDifferences
  // VisibleBefore[i]: how many of the first i entries have a positive absorbance.
  std::vector<int> VisibleBefore;
};

} // namespace apc

#endif
