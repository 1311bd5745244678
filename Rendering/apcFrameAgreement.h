// SPDX-License-Identifier: BSD-3-Clause
// What every process must agree on before a frame's collectives, settled in one small
// allreduce: the union of the data bounds (depth warp, sample spacing, screen rectangle),
// failures, the number of visible APC volumes and of moments, the viewport size, the
// compositing mode, the band size, and whether the frame is interactive and how much cheaper
// it is then. A
// process that cannot render, has no volume while others have, or disagrees on a size makes
// every process skip the frame instead of waiting forever in a later collective.
#ifndef apcFrameAgreement_h
#define apcFrameAgreement_h

#include <string>

namespace apc
{
struct ProcessGroup;

// This process's side of the agreement.
struct LocalFrame
{
  double Bounds[6]; // of this process's renderable cells; empty (min > max) if none
  bool Failed = false;
  int Volumes = 0;    // visible APC volumes
  int MinMoments = 0; // over those volumes (0 and 0 if none)
  int MaxMoments = 0;
  int Width = 0;
  int Height = 0;
  bool ReportPending = false;  // an input report to say (apcInputReport.h)
  bool Interactive = false;    // this process's window asks for a fast frame
  double SampleFactor = 1.0;   // interactive frames: factor on the sample distance (>= 1)
  int Reduction = 1;           // interactive frames: image reduction (>= 1)
  int Mode = 0;                // the pass's CompositeMode and wire precision: each mode runs
  bool InDouble = false;       // different collectives, so one process's odd setting would hang
  bool DepthComposited = true; // the pass's DisplayDepthComposited (depth broadcast or MIN)
  double BandPixels = 1;       // the pass's MaxBandPixels

  LocalFrame();
  // One visible APC volume: its number of moments and, if it has cells, their bounds.
  void AddVolume(int moments, const double* bounds);
};

// The agreed frame, the same on every process.
struct FrameAgreement
{
  double Bounds[6]; // union over all processes; empty if no cells anywhere
  bool AnyFailed = false;
  int MinVolumes = 0;
  int MaxVolumes = 0;
  int MinMoments = 0;
  int MaxMoments = 0;
  bool SizesDiffer = false;
  bool ModesDiffer = false; // CompositeMode, CompositeInDouble or DisplayDepthComposited
  int Width = 0;
  int Height = 0;
  bool AnyReportPending = false; // then every process calls ShareInputReports
  // Interactive if any process's window says so; then the largest factors any process asks
  // for apply (the same settings everywhere in ParaView, where they come from one proxy).
  bool Interactive = false;
  double SampleFactor = 1.0; // 1 for still frames
  int Reduction = 1;         // 1 for still frames
  double BandPixels = 1;     // the smallest MaxBandPixels of any process: the bands of a frame

  static FrameAgreement Agree(const ProcessGroup& group, const LocalFrame& local);

  bool NoVolumes() const { return this->MaxVolumes == 0; }
  bool HasCells() const;
  // Empty if the frame can be rendered; otherwise why every process skips it.
  std::string Problem() const;
};

} // namespace apc

#endif
