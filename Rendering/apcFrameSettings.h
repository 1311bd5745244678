// SPDX-License-Identifier: BSD-3-Clause
// The settings of vtkAPCCompositePass that every process must agree on, as one value. The pass
// stores its properties in it (so each default is written once, below) and hands it to the
// frame agreement (apcFrameAgreement.h), which settles it in the frame's one allreduce: each
// setting is either the same on every process (a difference skips the frame, naming the
// setting, instead of letting the processes run different collectives and hang) or the
// smallest or largest value any process asks for applies. To add a setting: a member here and
// one line in ForEachAgreed. Internal to APC's rendering module.
#ifndef apcFrameSettings_h
#define apcFrameSettings_h

#include "vtkType.h"

namespace apc
{

struct FrameSettings
{
  int CompositeMode = 0; // vtkAPCCompositePass::CompositeModeType: APC
  bool CompositeInDouble = false;
  bool DisplayDepthComposited = true;
  // APC mode composites a larger screen rectangle band by band (>= 1448^2 by default).
  vtkIdType MaxBandPixels = vtkIdType(1) << 21;
  // APC mode's wire travels in MPI messages of at most this many bytes.
  vtkIdType MaxMessageBytes = vtkIdType(8) << 20;
  // Interactive frames only: the factor on the sample distance and the image reduction.
  double InteractiveSampleDistanceFactor = 2.0;
  int InteractiveImageReduction = 4;
  // Stop Where Opaque on several processes: a frame with no previous cut first probes the
  // rays of every this-many-th pixel in each direction for its bound (0: no probe).
  int OpaqueProbeStep = 8;

  // The largest interactive factors the setters accept (vtkAPCCompositePass's and ParaView's
  // APC Volume's); the smallest is 1, which switches either off.
  static constexpr double MaxSampleDistanceFactor = 16.0;
  static constexpr int MaxImageReduction = 16;
  static constexpr int MaxOpaqueProbeStep = 64;
};

// How the processes' values of a setting become the frame's.
enum class AgreementRule
{
  Same,     // every process must have the same value
  Smallest, // the smallest value applies (a memory bound: the tightest one)
  Largest   // the largest value applies (how much cheaper an interactive frame may be)
};

// Calls f(name, member, rule) for every setting of settings (const or not), always in the same
// order: the agreement packs and unpacks them in this order.
template <class Settings, class F>
void ForEachAgreed(Settings& settings, F&& f)
{
  f("CompositeMode", settings.CompositeMode, AgreementRule::Same);
  f("CompositeInDouble", settings.CompositeInDouble, AgreementRule::Same);
  f("DisplayDepthComposited", settings.DisplayDepthComposited, AgreementRule::Same);
  f("MaxBandPixels", settings.MaxBandPixels, AgreementRule::Smallest);
  f("MaxMessageBytes", settings.MaxMessageBytes, AgreementRule::Smallest);
  f("InteractiveSampleDistanceFactor", settings.InteractiveSampleDistanceFactor,
    AgreementRule::Largest);
  f("InteractiveImageReduction", settings.InteractiveImageReduction, AgreementRule::Largest);
  f("OpaqueProbeStep", settings.OpaqueProbeStep, AgreementRule::Same);
}

} // namespace apc

#endif
