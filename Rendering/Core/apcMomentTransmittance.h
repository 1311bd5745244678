// Reconstruction of the transmittance T(z) in front of a warped depth z from N power
// moments, the core of MBOIT (Münstermann et al. 2018, "Moment-Based Order-Independent
// Transparency", I3D, Sec. 3 and its supplementary code). APC (Huang, Usher et al.,
// "Approximate Puzzlepiece Compositing", arXiv 2501.12581) evaluates it from the globally
// all-reduced moments, so every rank weights its own samples consistently.
//
// Method, for N = 2m moments: normalise b_k / b0, bias b <- (1-eps) b + eps v so that the
// (m+1)x(m+1) Hankel matrix B = [b_{i+j}] is safely positive definite, factorise B = L D L^T
// and invert L and D once per pixel. Per query z0: c = B^-1 (1, z0, ..., z0^m), a few
// multiply-adds with those inverses (no triangular solves); the m real roots of
// sum c_k z^k together with z0 are the support points of the canonical distribution that
// matches the moments. The expectation of the step function (beta at z0, [z_i < z0]
// elsewhere) under that distribution is the normalised absorbance A in front of z0;
// T = exp(-b0 A). beta = 0 gives the largest transmittance consistent with the moments,
// beta = 1 the smallest. MBOIT evaluates the expectation through Newton divided differences
// of the interpolating polynomial; here it is summed from the canonical weights (Christoffel
// function values), which is the same quantity without the cancellation (see the .cpp).
//
// Guards (T is always finite and in [0,1]):
// - b0 < kEmptyPixelAbsorbance (total opacity below 0.1%, also b0 <= 0): the pixel is
//   empty and T = 1 for every z. MBOIT discards such pixels; T = 1 keeps their faint
//   samples at full weight, which the resolve then normalises.
// - Degenerate pixel: b0 = +inf/NaN, a non-finite normalised moment, or a non-positive or
//   non-finite LDL^T pivot. Every query returns the fallback exp(-beta b0), i.e. "all
//   absorbance sits at the query depth" (0 for b0 = +inf and beta > 0, 1 for beta = 0 or
//   NaN b0).
// - Degenerate query: NaN z, fewer real roots than the kernel polynomial's degree (a
//   discriminant clearly below zero; slightly negative ones are clamped to a double root),
//   non-finite roots or a non-finite absorbance. (A leading coefficient that is exactly 0
//   is not a failure: that support point lies at infinity with weight 0.) The query returns the
//   same fallback and reports it in TransmittanceQuery::Fallback.
// - z is clamped to [-1,1], the warp's range.
#ifndef apcMomentTransmittance_h
#define apcMomentTransmittance_h

#include "apcHiddenDecisions.h"
#include "apcPolynomialRoots.h"
#include "apcPowerMoments.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <utility>

namespace apc
{

// -ln(0.999): MBOIT's threshold below which a pixel holds nothing worth reconstructing.
constexpr double kEmptyPixelAbsorbance = 1.00050033e-3;

// The APC paper's overestimation; MBOIT's own implementations mostly use 0.25. Higher values
// (0.5) fit opaque slabs better but tint translucent shells: docs/evaluation.md, section 4.
constexpr double kDefaultOverestimation = 0.3;

// The paper's fp32 bias constants. They suffice in double precision as well, where the
// accumulation and the solve are far more accurate than the fp32 they were tuned for.
template <int N>
constexpr double DefaultMomentBias()
{
  static_assert(N == 4 || N == 6 || N == 8, "APC supports 4, 6 or 8 power moments");
  if constexpr (N == 4)
  {
    return 5e-7;
  }
  else if constexpr (N == 6)
  {
    return 5e-6;
  }
  else
  {
    return 5e-5;
  }
}

// Moments (b1..bN) the bias pulls towards; their Hankel matrices are well conditioned.
template <int N>
constexpr std::array<double, N> DefaultBiasVector()
{
  static_assert(N == 4 || N == 6 || N == 8, "APC supports 4, 6 or 8 power moments");
  if constexpr (N == 4)
  {
    return { 0.0, 0.375, 0.0, 0.375 };
  }
  else if constexpr (N == 6)
  {
    return { 0.0, 0.48, 0.0, 0.451, 0.0, 0.45 };
  }
  else
  {
    return { 0.0, 0.75, 0.0, 0.676667, 0.0, 0.63, 0.0, 0.600303 };
  }
}

// A negative (or NaN) bias means the published constant for the number of moments.
constexpr double kUseDefaultMomentBias = -1.0;

template <int N>
struct MomentSettings
{
  // beta in [0,1]; out-of-range values are clamped, NaN means the default.
  double Overestimation = kDefaultOverestimation;
  // epsilon in [0,1]; above 1 is clamped, negative or NaN means DefaultMomentBias<N>().
  double Bias = DefaultMomentBias<N>();
  std::array<double, N> BiasVector = DefaultBiasVector<N>();
};

// The 4-moment reconstruction's per-pixel constants as a query reads them: entries 3, 4, 6, 7
// and 8 of L^-1 (row major), D^-1, b0 and the overestimation.
struct FourMomentPixel
{
  double L3, L4, L6, L7, L8, D0, D1, D2, B0, Beta;
};

struct TransmittanceQuery
{
  double Transmittance = 1.0;
  bool Fallback = false; // the documented fallback was used instead of the reconstruction
};

// Built once per pixel from its (global) unnormalised moment sums; cheap to query many
// times. Queries are const and touch no shared state, so one object may serve many threads.
template <int N>
class MomentTransmittance
{
public:
  static_assert(N == 4 || N == 6 || N == 8, "APC supports 4, 6 or 8 power moments");

  // sums: N+1 unnormalised values (b0, b1, ..., bN).
  explicit MomentTransmittance(const double* sums, const MomentSettings<N>& settings = {});
  explicit MomentTransmittance(
    const PowerMoments<N>& moments, const MomentSettings<N>& settings = {})
    : MomentTransmittance(moments.Data(), settings)
  {
  }

  // Inline for 4 moments (pass 2 queries once per sample); the rest out of line.
  TransmittanceQuery Query(double z) const;
  double operator()(double z) const { return this->Query(z).Transmittance; }

  // Pass 2's weights alpha T(z) of n samples at once: weights[i] = (1 - exp(-absorbances[i]))
  // T(depths[i]), as Query and std::expm1 give them to a few units in the last place. For 4
  // moments the samples go through vector arithmetic (the CPU's widest that the build knows),
  // and those an unusual case stops (see Query) through Query.
  void Weights(const double* depths, const double* absorbances, double* weights, int n) const;

  // A depth from which on every sample is hidden: for z >= HiddenDepth(w), T(z) b0 <= w (up to
  // the ~1e-10 by which rounding lets T rise). A pixel's samples weigh alpha T(z) each and
  // their alphas sum to at most b0, so the samples there weigh at most w together, whichever
  // process holds them. Found by bisection on a fixed grid of [-1,1] from the moments alone,
  // hence the same on every process. +inf where no depth qualifies.
  double HiddenDepth(double maxWeight) const;
  // The same for a pixel whose samples all lie in [range().first, range().second] (range is
  // called once, and only if the bisection is reached): the depth it returns skips exactly
  // the samples HiddenDepth(w) skips, but the bisection stops as soon as no sample lies
  // between its bounds, where further steps could not move any sample across the depth
  // returned. Pass 2 calls it with each pixel's cached samples' nearest and farthest depth.
  template <class Range>
  double HiddenDepth(double maxWeight, const Range& range) const;
  // HiddenDepth(maxWeight, ranges[i]) of pixels[i], i < count, into depths[i]: the same depths
  // to the bit. With 4 moments the pixels' bisections go round by round together, each round's
  // decisions for all of them in one batch: a pixel's rounds wait on each other (the next
  // depths come from the last answers), other pixels' rounds need not.
  template <class Range>
  static void HiddenDepths(const MomentTransmittance* pixels, double maxWeight, const Range* ranges,
    double* depths, int count);

  // For 4 moments and a valid pixel, its constants for kernels that weight many samples at
  // once (pass 2's replay); false otherwise (then query sample by sample).
  bool GetFourMomentPixel(FourMomentPixel& px) const
  {
    if (M != 2 || this->State != PixelState::Valid)
    {
      return false;
    }
    px = { this->LInv[3], this->LInv[4], this->LInv[6], this->LInv[7], this->LInv[8], this->InvD[0],
      this->InvD[1], this->InvD[2], this->B0, this->Beta };
    return true;
  }

  bool IsEmpty() const { return this->State == PixelState::Empty; }
  bool IsDegenerate() const { return this->State == PixelState::Degenerate; }
  double TotalAbsorbance() const { return this->B0; }
  double FallbackTransmittance() const;
  double Overestimation() const { return this->Beta; }

private:
  static constexpr int M = N / 2;
  bool SetUpFourMoments(const double* sums, double eps, const double* biasVector, double* moments);
  bool MayHaveHiddenDepth(double maxWeight) const;
  template <class Range>
  double FourMomentHiddenDepth(double limit, const Range& range) const;
  double ChristoffelKernel(double x) const;
  TransmittanceQuery FullQuery(double z) const;
  TransmittanceQuery GeneralQuery(double z, double kernelAtZ, const double* c) const;

  enum class PixelState
  {
    Empty,
    Valid,
    Degenerate
  };

  PixelState State = PixelState::Valid;
  double B0 = 0.0;
  double Beta = kDefaultOverestimation;
  // Per-pixel precomputation, so that a query is a few multiply-adds before its roots:
  // B = L D L^T is the normalised, biased Hankel matrix. Row i of L^-1 holds the coefficients
  // (lowest degree first) of y_i(x) = (L^-1 e(x))_i: the terms of the Christoffel kernel,
  // and with L^-T D^-1 the kernel polynomial. D is kept inverted.
  std::array<double, (M + 1) * (M + 1)> LInv{};
  std::array<double, M + 1> InvD{};
};

template <int N>
inline TransmittanceQuery MomentTransmittance<N>::Query(double z) const
{
  if constexpr (M == 2)
  {
    // 4 moments, the common case. The kernel polynomial P(x) = sum c_k x^k, c = B^-1 e(z),
    // has P(z) = K(z) > 0, so with two real roots z lies between them iff c2 < 0, and beyond
    // both iff also past the vertex. The three canonical weights sum to 1 (the normalised
    // b0), so outside the roots the absorbance in front needs only w_z = 1 / K(z): no roots,
    // no square root. Between them only the nearer root's weight is formed. Everything
    // unusual (degree drop, discriminant <= 0, a zero or non-finite root) takes the full
    // query.
    if (this->State == PixelState::Valid && !std::isnan(z))
    {
      z = z < -1.0 ? -1.0 : (z > 1.0 ? 1.0 : z);
      const double* l = this->LInv.data();
      const double y1 = l[4] * z + l[3];
      const double y2 = (l[8] * z + l[7]) * z + l[6];
      const double u0 = this->InvD[0];
      const double u1 = y1 * this->InvD[1];
      const double u2 = y2 * this->InvD[2];
      const double kernelAtZ = u0 + y1 * u1 + y2 * u2;
      const double c2 = u2;
      const double c1 = u1 + u2 * l[7];
      const double c0 = u2 * l[6] + u1 * l[3] + u0;
      const double disc = c1 * c1 - 4.0 * c0 * c2;
      if (c2 != 0.0 && disc > 0.0)
      {
        const double wz = 1.0 / kernelAtZ;
        double absorbance = 0.0;
        bool ok = true;
        if (c2 > 0.0)
        {
          absorbance = 2.0 * c2 * z > -c1 ? 1.0 - (1.0 - this->Beta) * wz : this->Beta * wz;
        }
        else
        {
          const double q = -0.5 * (c1 + std::copysign(std::sqrt(disc), c1));
          const double lo = std::min(q / c2, c0 / q);
          ok = q != 0.0 && std::isfinite(lo);
          absorbance = this->Beta * wz + 1.0 / this->ChristoffelKernel(lo);
        }
        const double t = std::exp(-this->B0 * absorbance);
        if (ok && std::isfinite(absorbance) && !std::isnan(t))
        {
          return { t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t), false };
        }
      }
    }
  }
  return this->FullQuery(z);
}

template <int N>
inline double MomentTransmittance<N>::ChristoffelKernel(double x) const
{
  // e(x)^T (L D L^T)^-1 e(x) = |L^-1 e(x)|^2 in the D^-1 norm: a sum of positive terms.
  double kernel = 0.0;
  for (int i = 0; i <= M; ++i)
  {
    const double yi = EvaluatePolynomial(&this->LInv[i * (M + 1)], i, x);
    kernel += yi * yi * this->InvD[i];
  }
  return kernel;
}

// True where exp(-b0) b0 > w is certain without an exponential: exp(-b0) >= 2^-k for an integer
// k >= b0 log2(e), and b0 2^-k (exact) above w by a margin far beyond the roundings of
// exp(-b0) b0 as HiddenDepth forms it, so that HiddenDepth's own test would find the same
// (no hidden depth). Most pixels of a frame have b0 below ln(1/w) or so and answer here
// instead of calling libm's exp; the few near the crossing, and b0 <= w, are not answered.
inline bool SurelyNoHiddenDepth(double b0, double w)
{
  if (!(b0 > 0.0 && b0 < 512.0))
  {
    return false;
  }
  // b0 log2(e) as rounded is within 1e-13 of the exact product: 1e-9 more and the floor's
  // next integer is above the exact one.
  const int k = static_cast<int>(b0 * 1.4426950408889634 + 1e-9) + 1;
  const uint64_t bits = static_cast<uint64_t>(1023 - k) << 52;
  double power;
  std::memcpy(&power, &bits, sizeof(power));
  return b0 * power > w * (1.0 + 1e-12);
}

// The other side: true where exp(-b0) b0 <= w is certain without an exponential. exp(-b0) <= 2^-k
// for an integer k <= b0 log2(e), and b0 2^-k below w by the same margin. It answers b0 from
// about ln 2 past the far crossing (b0 ~ ln(1/w) + ln ln(1/w)) up; pixels with a hidden depth
// mostly lie there, and the rest, and b0 near the crossings, are not answered.
inline bool SurelyMayHaveHiddenDepth(double b0, double w)
{
  if (!(b0 > 0.0 && b0 < 512.0))
  {
    return false;
  }
  // 1e-9 less than the rounded product is below the exact one, and so is its integer part.
  const int k = static_cast<int>(b0 * 1.4426950408889634 - 1e-9);
  const uint64_t bits = static_cast<uint64_t>(1023 - k) << 52;
  double power;
  std::memcpy(&power, &bits, sizeof(power));
  return b0 * power < w * (1.0 - 1e-12);
}

// HiddenDepth's bisection over [-1, 1], whatever answers its tests T(z) <= limit: atEnd(z) at
// z = 1 and -1, atRound(step, mid, left, right, hidden) at a round's three points.
// T(hi) <= limit throughout; T non-increasing carries it to every z >= hi. 2^-9 of the warped
// range: a sample or two of a ray's front lie between the true crossing and hi. Two steps a
// round: the middle and both points the next step may query, three tests independent of each
// other, which the CPU overlaps (a query is a chain of dependent divisions, a square root and
// an exponential); the same points, hence the same answer, as one step at a time, in about half
// the time. range() gives the nearest and farthest of the pixel's samples, asked for only here.
template <class Range, class AtEnd, class AtRound>
inline double BisectHiddenDepth(const Range& range, const AtEnd& atEnd, const AtRound& atRound)
{
  if (!atEnd(1.0))
  {
    return std::numeric_limits<double>::infinity();
  }
  if (atEnd(-1.0))
  {
    return -1.0;
  }
  const std::pair<double, double> samples = range();
  double lo = -1.0;
  double hi = 1.0;
  for (int step = 0; step < 10; step += 2)
  {
    // The depth found lies in (lo, hi]: a sample at or before lo stays in front of it, one at
    // or behind hi behind it, whatever the steps left decide.
    if (samples.second <= lo || samples.first >= hi)
    {
      break;
    }
    const double mid = 0.5 * (lo + hi);
    const double left = 0.5 * (lo + mid);
    const double right = 0.5 * (mid + hi);
    bool hidden[3]; // at mid, left, right
    atRound(step, mid, left, right, hidden);
    (hidden[0] ? hi : lo) = mid;
    const double next = hidden[0] ? left : right;
    ((hidden[0] ? hidden[1] : hidden[2]) ? hi : lo) = next;
  }
  return hi;
}

// Empty pixels have T = 1; degenerate ones are left alone. T >= exp(-b0) everywhere, so a
// pixel whose b0 cannot push T b0 below the bound has no hidden depth (no query needed).
template <int N>
inline bool MomentTransmittance<N>::MayHaveHiddenDepth(double maxWeight) const
{
  return !(this->State != PixelState::Valid || !(maxWeight > 0.0) ||
    SurelyNoHiddenDepth(this->B0, maxWeight) ||
    !(SurelyMayHaveHiddenDepth(this->B0, maxWeight) ||
      std::exp(-this->B0) * this->B0 <= maxWeight));
}

template <int N>
template <class Range>
inline double MomentTransmittance<N>::HiddenDepth(double maxWeight, const Range& range) const
{
  constexpr double kNone = std::numeric_limits<double>::infinity();
  if (!this->MayHaveHiddenDepth(maxWeight))
  {
    return kNone;
  }
  const double limit = maxWeight / this->B0;
  if constexpr (M == 2)
  {
    if (limit < 1.0 && limit >= kLowestHiddenLimit)
    {
      return this->FourMomentHiddenDepth(limit, range);
    }
  }
  auto hidden = [&](double z)
  {
    const TransmittanceQuery q = this->Query(z);
    return !q.Fallback && q.Transmittance <= limit;
  };
  return BisectHiddenDepth(range, hidden,
    [&](int, double mid, double left, double right, bool* at)
    {
      at[0] = hidden(mid);
      at[1] = hidden(left);
      at[2] = hidden(right);
    });
}

// HiddenDepth's bisection, each test T(z) <= limit decided for the points of a round at once by
// DecideHidden (the same answers as Query's, see apcHiddenDecisions.h), Query asked only for the
// points it leaves undecided: the depth returned is the one above to the bit. The first batch
// holds 1, -1 and the first round's three points (most pixels that get this far bisect), each
// later round its three.
template <int N>
template <class Range>
inline double MomentTransmittance<N>::FourMomentHiddenDepth(double limit, const Range& range) const
{
  FourMomentPixel px;
  this->GetFourMomentPixel(px);
  const double lnLimit = std::log(limit);
  auto resolve = [&](double z, int8_t decision)
  {
    if (decision == kHiddenUndecided)
    {
      const TransmittanceQuery q = this->Query(z);
      return !q.Fallback && q.Transmittance <= limit;
    }
    return decision == kHiddenYes;
  };
  // Padded to whole vectors (a lane more costs nothing on the chain's latency).
  const double first[8] = { 1.0, -1.0, 0.0, -0.5, 0.5, 0.5, 0.5, 0.5 };
  int8_t decided[8];
  DecideHidden(px, lnLimit, first, decided, 8);
  return BisectHiddenDepth(
    range, [&](double z) { return resolve(z, decided[z > 0.0 ? 0 : 1]); },
    [&](int step, double mid, double left, double right, bool* at)
    {
      if (step > 0)
      {
        const double points[4] = { mid, left, right, right };
        DecideHidden(px, lnLimit, points, decided + 2, 4);
      }
      at[0] = resolve(mid, decided[2]);
      at[1] = resolve(left, decided[3]);
      at[2] = resolve(right, decided[4]);
    });
}

// HiddenDepths: FourMomentHiddenDepth's walk for a group of pixels at once, as a state per pixel
// (its bounds and step) advanced a round at a time: the first batch holds each pixel's 1, -1
// and first round's three points (a job a pixel for 1, -1, 0 and -0.5, and 0.5 in a lane of a
// job shared by four pixels), each later one the three points of every pixel still bisecting
// (a job each). Every test is decided as FourMomentHiddenDepth decides
// it (the same decision for the same pixel, limit and depth, the query where it is undecided),
// in the same order of steps, so each pixel ends on the same depth.
template <int N>
template <class Range>
inline void MomentTransmittance<N>::HiddenDepths(const MomentTransmittance* pixels,
  double maxWeight, const Range* ranges, double* depths, int count)
{
  constexpr double kNone = std::numeric_limits<double>::infinity();
  if constexpr (M != 2)
  {
    for (int i = 0; i < count; ++i)
    {
      depths[i] = pixels[i].HiddenDepth(maxWeight, ranges[i]);
    }
  }
  else
  {
    // Enough pixels a group for their rounds to overlap, few enough to stay on the stack.
    constexpr int kGroup = 8;
    struct Walk
    {
      const MomentTransmittance* T;
      double Limit, Lo, Hi, First, Last;
      int Index;
    };
    for (int g = 0; g < count; g += kGroup)
    {
      const int end = std::min(count, g + kGroup);
      Walk walks[kGroup];
      FourMomentPixel px[kGroup];
      double lnLimits[kGroup];
      const FourMomentPixel* jobPixels[kGroup];
      alignas(32) double z[4 * kGroup];
      int8_t decided[4 * kGroup];
      // The first round's right point, 0.5, of each pixel: a lane each.
      double halves[kGroup];
      int8_t decidedHalves[kGroup];
      int active = 0;
      for (int i = g; i < end; ++i)
      {
        const MomentTransmittance& t = pixels[i];
        depths[i] = kNone;
        if (!t.MayHaveHiddenDepth(maxWeight))
        {
          continue;
        }
        const double limit = maxWeight / t.B0;
        if (!(limit < 1.0 && limit >= kLowestHiddenLimit))
        {
          depths[i] = t.HiddenDepth(maxWeight, ranges[i]);
          continue;
        }
        t.GetFourMomentPixel(px[active]);
        walks[active] = { &t, limit, -1.0, 1.0, 0.0, 0.0, i };
        const double first[4] = { 1.0, -1.0, 0.0, -0.5 };
        std::copy(first, first + 4, z + 4 * active);
        halves[active] = 0.5;
        jobPixels[active] = &px[active];
        lnLimits[active] = std::log(limit);
        ++active;
      }
      if (active == 0)
      {
        continue;
      }
      DecideHiddenJobs(jobPixels, lnLimits, z, decided, active);
      // Padded to whole vectors with the last pixel's lane again.
      const int lanes = (active + 3) & ~3;
      for (int a = active; a < lanes; ++a)
      {
        halves[a] = 0.5;
        jobPixels[a] = jobPixels[active - 1];
        lnLimits[a] = lnLimits[active - 1];
      }
      DecideHiddenLanes(jobPixels, lnLimits, halves, decidedHalves, lanes);
      auto resolve = [](const Walk& w, double at, int8_t decision)
      {
        if (decision == kHiddenUndecided)
        {
          const TransmittanceQuery q = w.T->Query(at);
          return !q.Fallback && q.Transmittance <= w.Limit;
        }
        return decision == kHiddenYes;
      };
      // A round of BisectHiddenDepth's: the answers at mid, left and right move the bounds.
      auto step = [&resolve](Walk& w, const double* at, const int8_t* decision)
      {
        const bool hidden[3] = { resolve(w, at[0], decision[0]), resolve(w, at[1], decision[1]),
          resolve(w, at[2], decision[2]) };
        (hidden[0] ? w.Hi : w.Lo) = at[0];
        const double next = hidden[0] ? at[1] : at[2];
        ((hidden[0] ? hidden[1] : hidden[2]) ? w.Hi : w.Lo) = next;
      };
      // The walks still bisecting, by their place in walks (which stay where they are, with
      // their pixels' constants).
      double lnOf[kGroup];
      int open[kGroup];
      int opened = 0;
      for (int a = 0; a < active; ++a)
      {
        Walk& w = walks[a];
        const int8_t* d = decided + 4 * a;
        if (!resolve(w, 1.0, d[0]))
        {
          continue; // kNone
        }
        if (resolve(w, -1.0, d[1]))
        {
          depths[w.Index] = -1.0;
          continue;
        }
        const std::pair<double, double> samples = ranges[w.Index]();
        w.First = samples.first;
        w.Last = samples.second;
        // Step 0, whose points the first batch decided.
        if (w.Last <= w.Lo || w.First >= w.Hi)
        {
          depths[w.Index] = w.Hi;
          continue;
        }
        const double at[3] = { 0.0, -0.5, 0.5 };
        const int8_t decision[3] = { d[2], d[3], decidedHalves[a] };
        step(w, at, decision);
        lnOf[a] = lnLimits[a];
        open[opened++] = a;
      }
      for (int s = 2; s < 10 && opened > 0; s += 2)
      {
        int jobs = 0;
        for (int o = 0; o < opened; ++o)
        {
          const int a = open[o];
          Walk& w = walks[a];
          if (w.Last <= w.Lo || w.First >= w.Hi)
          {
            depths[w.Index] = w.Hi;
            continue;
          }
          const double mid = 0.5 * (w.Lo + w.Hi);
          const double left = 0.5 * (w.Lo + mid);
          const double right = 0.5 * (mid + w.Hi);
          open[jobs] = a;
          lnLimits[jobs] = lnOf[a];
          jobPixels[jobs] = &px[a];
          double* at = z + 4 * jobs;
          at[0] = mid;
          at[1] = left;
          at[2] = right;
          at[3] = right;
          ++jobs;
        }
        opened = jobs;
        DecideHiddenJobs(jobPixels, lnLimits, z, decided, jobs);
        for (int o = 0; o < opened; ++o)
        {
          step(walks[open[o]], z + 4 * o, decided + 4 * o);
        }
      }
      for (int o = 0; o < opened; ++o)
      {
        depths[walks[open[o]].Index] = walks[open[o]].Hi; // the bisection's last step taken
      }
    }
  }
}

extern template class MomentTransmittance<4>;
extern template class MomentTransmittance<6>;
extern template class MomentTransmittance<8>;

} // namespace apc

#endif
