// The hidden depth's test T(z) <= limit (MomentTransmittance<4>::HiddenDepth) for several depths
// at once, on vector arithmetic, deciding exactly as the scalar query does. Internal to the core.
//
// Why it gives the same answers: the scalar Query is compiled for the baseline x86-64 (no FMA,
// so no product and sum is fused), and this file is compiled with contraction off; each lane
// does Query's operations in Query's order (std::min as b < a ? b : a, copysign by the sign
// bit, the Christoffel kernel as (d0 + y1 y1 d1) + y2 y2 d2), so a lane's absorbance A, and
// every test Query makes on the way, are Query's to the bit. Only the exponential is not
// computed: T = exp(-b0 A) <= limit is decided by comparing -b0 A with ln(limit) (one libm log a
// pixel), and only where it lies more than kHiddenMargin away, far beyond the error of libm's
// exp and log (below 1e-15 relative); a lane closer to the limit, and every lane where Query
// would leave its fast path (degree drop, discriminant <= 0, zero or non-finite root), is left
// undecided and asked of Query itself.
#ifndef apcHiddenDecisions_h
#define apcHiddenDecisions_h

#include <cstdint>

namespace apc
{

struct FourMomentPixel;

// A lane's answer: hidden (T <= limit), visible, or not decided here (ask Query).
enum : int8_t
{
  kHiddenUndecided = -1,
  kHiddenNo = 0,
  kHiddenYes = 1
};

// |-b0 A - ln(limit)| below this: undecided (1e-9 relative in T).
constexpr double kHiddenMargin = 1e-9;

// The limits for which the log comparison is sound: limit in [kLowestHiddenLimit, 1). Below, exp
// nears the subnormals; at 1 and above, T's clamp to 1 decides instead of exp.
constexpr double kLowestHiddenLimit = 1e-300;

// Which arithmetic decides: the widest the CPU runs (Best: AVX2 where the CPU has it, else the
// scalar lanes), or one named, so that tests can hold them against each other. Both give the
// same answers to the bit.
enum class HiddenKernel
{
  Best,
  Scalar,
  Avx2
};

// True if this build has the kernel and the CPU runs it.
bool HasHiddenKernel(HiddenKernel kernel);

// decisions[i] for depths z[i] in [-1, 1], i < n: whether T(z[i]) <= exp(lnLimit) for the pixel
// px (a valid 4-moment pixel), where lnLimit = std::log(limit), limit in
// [kLowestHiddenLimit, 1).
void DecideHidden(const FourMomentPixel& px, double lnLimit, const double* z, int8_t* decisions,
  int n, HiddenKernel kernel = HiddenKernel::Best);

// DecideHidden for several pixels' depths in one call, four depths a job: job j decides
// z[4 j, 4 j + 4) for the pixel *px[j] and its lnLimits[j] into decisions[4 j, 4 j + 4), the
// same answers as DecideHidden(*px[j], lnLimits[j], z + 4 j, decisions + 4 j, 4) gives. The
// jobs' chains of dependent operations overlap where DecideHidden's calls, each waited on by
// its pixel's next step, followed one another.
void DecideHiddenJobs(const FourMomentPixel* const* px, const double* lnLimits, const double* z,
  int8_t* decisions, int jobs, HiddenKernel kernel = HiddenKernel::Best);

// DecideHidden for depths each of its own pixel: z[i] for *px[i] and lnLimits[i] into
// decisions[i], i < n, the same answers as DecideHidden(*px[i], lnLimits[i], z + i,
// decisions + i, 1) gives. For the one point of many pixels that would otherwise each take a
// job of four lanes.
void DecideHiddenLanes(const FourMomentPixel* const* px, const double* lnLimits, const double* z,
  int8_t* decisions, int n, HiddenKernel kernel = HiddenKernel::Best);

} // namespace apc

#endif
