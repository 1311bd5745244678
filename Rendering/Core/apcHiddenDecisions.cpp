#include "apcHiddenDecisions.h"

#include "apcMomentTransmittance.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#if defined(__GNUC__) && defined(__x86_64__)
#include "apcFourMomentLanes.h"
#include <immintrin.h>
#define APC_HAVE_AVX2_HIDDEN 1
#endif

namespace apc
{
namespace
{

// One lane as Query computes it, up to its exponential (see the header). Written out with
// Query's operations in Query's order; the comments name Query's lines where they differ in form.
int8_t DecideLane(const FourMomentPixel& px, double low, double high, double z)
{
  const double y1 = px.L4 * z + px.L3;
  const double y2 = (px.L8 * z + px.L7) * z + px.L6;
  const double u0 = px.D0;
  const double u1 = y1 * px.D1;
  const double u2 = y2 * px.D2;
  const double kernelAtZ = u0 + y1 * u1 + y2 * u2;
  const double c2 = u2;
  const double c1 = u1 + u2 * px.L7;
  const double c0 = u2 * px.L6 + u1 * px.L3 + u0;
  const double disc = c1 * c1 - 4.0 * c0 * c2;
  if (!(c2 != 0.0 && disc > 0.0))
  {
    return kHiddenUndecided;
  }
  const double wz = 1.0 / kernelAtZ;
  double absorbance;
  if (c2 > 0.0)
  {
    absorbance = 2.0 * c2 * z > -c1 ? 1.0 - (1.0 - px.Beta) * wz : px.Beta * wz;
  }
  else
  {
    const double q = -0.5 * (c1 + std::copysign(std::sqrt(disc), c1));
    const double r0 = q / c2;
    const double r1 = c0 / q;
    const double lo = r1 < r0 ? r1 : r0; // std::min(q / c2, c0 / q)
    if (!(q != 0.0 && std::isfinite(lo)))
    {
      return kHiddenUndecided;
    }
    // ChristoffelKernel(lo): 0 + 1 * 1 * d0 is d0 exactly.
    const double ylo1 = px.L4 * lo + px.L3;
    const double ylo2 = (px.L8 * lo + px.L7) * lo + px.L6;
    const double kernelAtLo = px.D0 + ylo1 * ylo1 * px.D1 + ylo2 * ylo2 * px.D2;
    absorbance = px.Beta * wz + 1.0 / kernelAtLo;
  }
  if (!std::isfinite(absorbance))
  {
    return kHiddenUndecided;
  }
  const double exponent = -px.B0 * absorbance;
  return exponent < low ? kHiddenYes : (exponent > high ? kHiddenNo : kHiddenUndecided);
}

void DecideHiddenScalar(
  const FourMomentPixel& px, double low, double high, const double* z, int8_t* decisions, int n)
{
  for (int i = 0; i < n; ++i)
  {
    decisions[i] = DecideLane(px, low, high, z[i]);
  }
}

#ifdef APC_HAVE_AVX2_HIDDEN
#define APC_HIDDEN_AVX2_INLINE inline __attribute__((always_inline, target("avx2")))

// A pixel's constants and limits in every lane, or each lane's own pixel's.
struct Constants4 : FourMomentLanes
{
  __m256d NegB0, Low, High;

  APC_HIDDEN_AVX2_INLINE Constants4(const FourMomentPixel& px, double low, double high)
    : FourMomentLanes(px)
    , NegB0(_mm256_set1_pd(-px.B0))
    , Low(_mm256_set1_pd(low))
    , High(_mm256_set1_pd(high))
  {
  }

  // Lane i from *px[i] and lnLimits[i].
  APC_HIDDEN_AVX2_INLINE Constants4(const FourMomentPixel* const* px, const double* lnLimits)
    : FourMomentLanes(px)
    , NegB0(_mm256_xor_pd(this->B0, _mm256_set1_pd(-0.0)))
    , Low(_mm256_sub_pd(_mm256_loadu_pd(lnLimits), _mm256_set1_pd(kHiddenMargin)))
    , High(_mm256_add_pd(_mm256_loadu_pd(lnLimits), _mm256_set1_pd(kHiddenMargin)))
  {
  }
};

// DecideLane for four depths: the same operations lane by lane, both arms of each branch
// formed and blended; the lanes DecideLane would leave undecided are found from the same tests.
APC_HIDDEN_AVX2_INLINE void DecideFour(const Constants4& k, const double* z, int8_t* decisions)
{
  const __m256d zero = _mm256_setzero_pd();
  const __m256d one = _mm256_set1_pd(1.0);
  const __m256d two = _mm256_set1_pd(2.0);
  const __m256d four = _mm256_set1_pd(4.0);
  const __m256d minusHalf = _mm256_set1_pd(-0.5);
  const __m256d sign = _mm256_set1_pd(-0.0);
  const __m256d largest = _mm256_set1_pd(std::numeric_limits<double>::max());
  const __m256d l3 = k.L3, l4 = k.L4, l6 = k.L6, l7 = k.L7, l8 = k.L8;
  const __m256d d0 = k.D0, d1 = k.D1, d2 = k.D2, beta = k.Beta;
  const __m256d oneMinusBeta = k.OneMinusBeta;
  const __m256d zv = _mm256_loadu_pd(z);
  const __m256d y1 = _mm256_add_pd(_mm256_mul_pd(l4, zv), l3);
  const __m256d y2 = _mm256_add_pd(_mm256_mul_pd(_mm256_add_pd(_mm256_mul_pd(l8, zv), l7), zv), l6);
  const __m256d u1 = _mm256_mul_pd(y1, d1);
  const __m256d u2 = _mm256_mul_pd(y2, d2);
  const __m256d kernelAtZ =
    _mm256_add_pd(_mm256_add_pd(d0, _mm256_mul_pd(y1, u1)), _mm256_mul_pd(y2, u2));
  const __m256d c2 = u2;
  const __m256d c1 = _mm256_add_pd(u1, _mm256_mul_pd(u2, l7));
  const __m256d c0 = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(u2, l6), _mm256_mul_pd(u1, l3)), d0);
  const __m256d disc =
    _mm256_sub_pd(_mm256_mul_pd(c1, c1), _mm256_mul_pd(_mm256_mul_pd(four, c0), c2));
  const __m256d wz = _mm256_div_pd(one, kernelAtZ);
  // c2 > 0: outside both roots.
  const __m256d past =
    _mm256_cmp_pd(_mm256_mul_pd(_mm256_mul_pd(two, c2), zv), _mm256_xor_pd(c1, sign), _CMP_GT_OQ);
  const __m256d outside = _mm256_blendv_pd(
    _mm256_mul_pd(beta, wz), _mm256_sub_pd(one, _mm256_mul_pd(oneMinusBeta, wz)), past);
  // c2 < 0: between them, the nearer root's weight.
  const __m256d root = _mm256_sqrt_pd(disc);
  const __m256d signedRoot =
    _mm256_or_pd(_mm256_andnot_pd(sign, root), _mm256_and_pd(sign, c1)); // copysign
  const __m256d q = _mm256_mul_pd(minusHalf, _mm256_add_pd(c1, signedRoot));
  const __m256d r0 = _mm256_div_pd(q, c2);
  const __m256d r1 = _mm256_div_pd(c0, q);
  const __m256d lo = _mm256_blendv_pd(r0, r1, _mm256_cmp_pd(r1, r0, _CMP_LT_OQ));
  const __m256d ylo1 = _mm256_add_pd(_mm256_mul_pd(l4, lo), l3);
  const __m256d ylo2 =
    _mm256_add_pd(_mm256_mul_pd(_mm256_add_pd(_mm256_mul_pd(l8, lo), l7), lo), l6);
  const __m256d kernelAtLo =
    _mm256_add_pd(_mm256_add_pd(d0, _mm256_mul_pd(_mm256_mul_pd(ylo1, ylo1), d1)),
      _mm256_mul_pd(_mm256_mul_pd(ylo2, ylo2), d2));
  const __m256d between = _mm256_add_pd(_mm256_mul_pd(beta, wz), _mm256_div_pd(one, kernelAtLo));
  const __m256d positive = _mm256_cmp_pd(c2, zero, _CMP_GT_OQ);
  const __m256d absorbance = _mm256_blendv_pd(between, outside, positive);
  // Query's fast path: c2 != 0, disc > 0, (c2 > 0 or (q != 0 and lo finite)), A finite.
  const __m256d finiteLo = _mm256_cmp_pd(_mm256_andnot_pd(sign, lo), largest, _CMP_LE_OQ);
  const __m256d finiteA = _mm256_cmp_pd(_mm256_andnot_pd(sign, absorbance), largest, _CMP_LE_OQ);
  const __m256d rootsOk =
    _mm256_or_pd(positive, _mm256_and_pd(_mm256_cmp_pd(q, zero, _CMP_NEQ_UQ), finiteLo));
  const __m256d usual = _mm256_and_pd(
    _mm256_and_pd(_mm256_cmp_pd(c2, zero, _CMP_NEQ_UQ), _mm256_cmp_pd(disc, zero, _CMP_GT_OQ)),
    _mm256_and_pd(rootsOk, finiteA));
  const __m256d exponent = _mm256_mul_pd(k.NegB0, absorbance);
  const int yes =
    _mm256_movemask_pd(_mm256_and_pd(usual, _mm256_cmp_pd(exponent, k.Low, _CMP_LT_OQ)));
  const int no =
    _mm256_movemask_pd(_mm256_and_pd(usual, _mm256_cmp_pd(exponent, k.High, _CMP_GT_OQ)));
  for (int i = 0; i < 4; ++i)
  {
    decisions[i] = (yes >> i) & 1 ? kHiddenYes : ((no >> i) & 1 ? kHiddenNo : kHiddenUndecided);
  }
}

__attribute__((target("avx2"))) void DecideHiddenAvx2(
  const FourMomentPixel& px, double low, double high, const double* z, int8_t* decisions, int n)
{
  const Constants4 k(px, low, high);
  int i = 0;
  for (; i + 4 <= n; i += 4)
  {
    DecideFour(k, z + i, decisions + i);
  }
  DecideHiddenScalar(px, low, high, z + i, decisions + i, n - i);
}

// The jobs one after the other with no branch on their answers between them: the processor
// overlaps their chains of dependent operations (the pixels are independent).
__attribute__((target("avx2"))) void DecideHiddenJobsAvx2(const FourMomentPixel* const* px,
  const double* lnLimits, const double* z, int8_t* decisions, int jobs)
{
  for (int j = 0; j < jobs; ++j)
  {
    const Constants4 k(*px[j], lnLimits[j] - kHiddenMargin, lnLimits[j] + kHiddenMargin);
    DecideFour(k, z + 4 * j, decisions + 4 * j);
  }
}

__attribute__((target("avx2"))) void DecideHiddenLanesAvx2(const FourMomentPixel* const* px,
  const double* lnLimits, const double* z, int8_t* decisions, int n)
{
  int i = 0;
  for (; i + 4 <= n; i += 4)
  {
    const Constants4 k(px + i, lnLimits + i);
    DecideFour(k, z + i, decisions + i);
  }
  for (; i < n; ++i)
  {
    decisions[i] =
      DecideLane(*px[i], lnLimits[i] - kHiddenMargin, lnLimits[i] + kHiddenMargin, z[i]);
  }
}

bool CpuHasAvx2()
{
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}
#endif

} // namespace

bool HasHiddenKernel(HiddenKernel kernel)
{
  switch (kernel)
  {
    case HiddenKernel::Best:
    case HiddenKernel::Scalar:
      return true;
    case HiddenKernel::Avx2:
#ifdef APC_HAVE_AVX2_HIDDEN
      return CpuHasAvx2();
#else
      return false;
#endif
  }
  return false;
}

void DecideHidden(const FourMomentPixel& px, double lnLimit, const double* z, int8_t* decisions,
  int n, HiddenKernel kernel)
{
  // Outside these bounds the exponential, as libm rounds it, is certainly on that side.
  const double low = lnLimit - kHiddenMargin;
  const double high = lnLimit + kHiddenMargin;
#ifdef APC_HAVE_AVX2_HIDDEN
  if (kernel != HiddenKernel::Scalar && CpuHasAvx2())
  {
    DecideHiddenAvx2(px, low, high, z, decisions, n);
    return;
  }
#endif
  (void)kernel;
  DecideHiddenScalar(px, low, high, z, decisions, n);
}

void DecideHiddenJobs(const FourMomentPixel* const* px, const double* lnLimits, const double* z,
  int8_t* decisions, int jobs, HiddenKernel kernel)
{
#ifdef APC_HAVE_AVX2_HIDDEN
  if (kernel != HiddenKernel::Scalar && CpuHasAvx2())
  {
    DecideHiddenJobsAvx2(px, lnLimits, z, decisions, jobs);
    return;
  }
#endif
  (void)kernel;
  for (int j = 0; j < jobs; ++j)
  {
    DecideHiddenScalar(*px[j], lnLimits[j] - kHiddenMargin, lnLimits[j] + kHiddenMargin, z + 4 * j,
      decisions + 4 * j, 4);
  }
}

void DecideHiddenLanes(const FourMomentPixel* const* px, const double* lnLimits, const double* z,
  int8_t* decisions, int n, HiddenKernel kernel)
{
#ifdef APC_HAVE_AVX2_HIDDEN
  if (kernel != HiddenKernel::Scalar && CpuHasAvx2())
  {
    DecideHiddenLanesAvx2(px, lnLimits, z, decisions, n);
    return;
  }
#endif
  (void)kernel;
  for (int i = 0; i < n; ++i)
  {
    decisions[i] =
      DecideLane(*px[i], lnLimits[i] - kHiddenMargin, lnLimits[i] + kHiddenMargin, z[i]);
  }
}

} // namespace apc
