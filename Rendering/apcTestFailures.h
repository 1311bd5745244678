// SPDX-License-Identifier: BSD-3-Clause
// Failures a test injects where a process's own work between two collectives could throw (its
// memory ran out), to check that every process learns of it and leaves the frame at the same
// point (apcStageAgreement.h) instead of waiting in the next collective. One count-down per
// point, in this process only: a test arms it on one rank. Internal to APC's rendering module
// and its tests.
#ifndef apcTestFailures_h
#define apcTestFailures_h

#include "APCRenderingModule.h" // for export macro

namespace apc
{

/// The points a test can make throw, each before the work it names allocates or marches.
enum class FailurePoint
{
  Probe,            ///< Stop Where Opaque's first-frame probe (FrameEngine::ProbeOpaqueProfile)
  PassOne,          ///< pass 1 of a volume (FrameEngine::RenderMoments)
  PassTwo,          ///< pass 2 of a volume (FrameEngine::RenderColour)
  BandBuffers,      ///< a band's buffers, held before its pass 1
  OpaqueRedo,       ///< the unresolved tiles marched again (a predicted cut's replay)
  OpaqueCut,        ///< the agreed cut applied to a volume's moments
  Segments,         ///< the exact segments mode's own segments
  SegmentPacking,   ///< the same, packed for their owners
  SegmentBlend,     ///< the same, an owner's strip blended
  LocalExact,       ///< the local exact mode's image
  BoundarySetUp,    ///< Sample End Weights = Boundary: the exchange's set-up
  BoundaryExchange, ///< the same: the exchange itself, before it sends
  Count
};

/// Tests only: the next count times this process reaches point, it throws std::bad_alloc.
APCRENDERING_EXPORT void FailForTesting(FailurePoint point, int count);

/// Throws std::bad_alloc if a test asked point to fail, counting that failure down.
APCRENDERING_EXPORT void ThrowIfFailingForTesting(FailurePoint point);

} // namespace apc

#endif
