// SPDX-License-Identifier: BSD-3-Clause
// One APC volume's settings as one value. vtkAPCVolumeMapper stores its properties in it (so
// each default is written once, below) and hands a copy to the frame engine at the start of a
// frame, together with the scalar selection its vtkAbstractMapper base holds: the engine reads
// nothing back from the mapper. Internal to APC's rendering module.
#ifndef apcVolumeSettings_h
#define apcVolumeSettings_h

#include "apcMomentParameters.h"
#include "apcNodeThreads.h"

#include <cstddef>
#include <string>

namespace apc
{

// What the input renders: vtkAbstractMapper's scalar selection, read from the mapper each
// frame (VTK's defaults apply, not these), and which values of a vector.
struct ScalarChoice
{
  int ScalarMode = 0; // VTK_SCALAR_MODE_*
  int ArrayAccessMode = 0;
  int ArrayId = -1;
  std::string ArrayName;
  int VectorMode = 0; // vtkScalarsToColors::MAGNITUDE
  int VectorComponent = 0;
};

struct VolumeSettings
{
  ScalarChoice Scalars;
  bool Exact = false;          // vtkAPCVolumeMapper::EXACT; MBOIT otherwise
  MomentParameters Moments;    // MBOIT's number of moments, beta, bias and resolve
  double SampleDistance = 0.0; // world units; 0: from the cells (apcDefaultSpacing.h)
  bool LatticeJitter = false;
  // VolumeRayMarcher::EndWeightsMode: 0 off, 1 all ends, 2 the ends on the mesh's boundary
  // (the default: no lattice staircase on silhouettes at a few per cent of a frame).
  int SampleEndWeights = 2;
  // MBOIT stops a ray at VolumeRayMarcher::kRecommendedOpaqueAbsorbance of its own samples.
  bool StopWhereOpaque = true;
  int SampleCacheMiB = -1; // -1: the process's share of its node's memory (apcNodeThreads.h)
  int NumberOfThreads = 0; // 0: the process's share of its node (apcNodeThreads.h)
  bool ComputeSegmentCount = false;

  size_t SampleCacheBytes() const
  {
    return this->SampleCacheMiB < 0 ? DefaultSampleCacheBytes()
                                    : static_cast<size_t>(this->SampleCacheMiB) << 20;
  }
};

} // namespace apc

#endif
