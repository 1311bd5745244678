// Exact ordered front-to-back compositing of discrete samples: the ground truth that the
// moment-based approximation of MBOIT (Münstermann et al. 2018, I3D) and APC (Huang, Usher
// et al., arXiv 2501.12581) are measured against.
#ifndef apcOrderedReference_h
#define apcOrderedReference_h

#include "apcResolve.h"

#include <vector>

namespace apc
{

struct Sample
{
  double Depth = 0.0; // any monotone depth (view distance or warped z)
  double Alpha = 0.0;
  RGB Colour{ 0.0, 0.0, 0.0 }; // straight (not premultiplied)
};

// Sorts a copy by depth and blends front to back into premultiplied RGBA. Samples at equal
// depth are ordered by (alpha, colour) so that the result does not depend on the input
// order. Alpha is clamped to [0,1]; samples with NaN depth or alpha are skipped.
RGBA CompositeOrdered(std::vector<Sample> samples);

// prod over samples with Depth < depth of (1 - alpha): the light reaching `depth` from the
// front, excluding samples at exactly that depth. Same clamping and skipping as above.
double ExactTransmittance(const std::vector<Sample>& samples, double depth);

} // namespace apc

#endif
