// SPDX-License-Identifier: BSD-3-Clause
// What every process must agree on before a frame's collectives, settled in one small
// allreduce: the union of the data bounds (depth warp, sample spacing, screen rectangle),
// the number of cells and their volume (with the bounds, the default sample spacing; summed
// exactly in a second, integer one),
// failures, the number of visible APC volumes and of moments, the viewport size, whether the
// frame is interactive, and the pass's settings (apcFrameSettings.h). A process that cannot
// render, has no volume while others have, or disagrees on a size or a setting makes every
// process skip the frame instead of waiting forever in a later collective.
#ifndef apcFrameAgreement_h
#define apcFrameAgreement_h

#include "apcExactSum.h"
#include "apcFrameSettings.h"

#include <string>
#include <vector>

class vtkAPCVolumeMapper;
class vtkObject;
class vtkVolumeProperty;

namespace apc
{
struct ProcessGroup;

// A volume's transfer functions as the mapper samples them (apcFrameInputsFromVTK.h).
struct TransferSignature
{
  double Colour = 0;  // checksum of the colour (or gray) table
  double Opacity = 0; // checksum of the opacity table and unit distance
  double Range[2] = { 0, 0 };
};

// This process's side of the agreement.
struct LocalFrame
{
  double Bounds[6]; // of this process's renderable cells; empty (min > max) if none
  double Cells = 0; // their number (the default sample distance is the mean cell size)
  ExactSum Volume;  // their total volume
  bool Failed = false;
  int Volumes = 0;    // visible APC volumes
  int MinMoments = 0; // over those volumes (0 and 0 if none)
  int MaxMoments = 0;
  int Width = 0;
  int Height = 0;
  bool ReportPending = false;    // an input report to say (apcInputReport.h)
  bool Interactive = false;      // this process's window asks for a fast frame
  bool StopsWhereOpaque = false; // a volume of this process has Stop Where Opaque on
  // A volume of this process weights the boundary's ends and its faces are not matched with
  // the other processes' yet (apcBoundaryExchange.h).
  bool NeedsSharedBoundary = false;
  bool Opaque = true;         // its last APC frame had a pixel at the stop's threshold
  FrameSettings Settings;     // the pass's
  TransferSignature Transfer; // of the visible volumes (combined)

  LocalFrame();
  // One visible APC volume: its number of moments, if it has cells their bounds, and its
  // transfer functions (TransferSignatureFromVTK), if given.
  void AddVolume(int moments, const double* bounds, vtkVolumeProperty* property = nullptr);
};

// The agreed frame, the same on every process.
struct FrameAgreement
{
  double Bounds[6];  // union over all processes; empty if no cells anywhere
  double Cells = 0;  // sum over all processes
  double Volume = 0; // the cells' volume, summed exactly over all processes, rounded once
  bool AnyFailed = false;
  // A volume of some process stops where opaque: every process then joins the profile's
  // allreduce, with volumes or without.
  bool AnyStopsWhereOpaque = false;
  // Then every process joins ShareBoundaryFaces (apcBoundaryExchange.h).
  bool AnyNeedsSharedBoundary = false;
  bool AnyOpaque = true;
  int MinVolumes = 0;
  int MaxVolumes = 0;
  int MinMoments = 0;
  int MaxMoments = 0;
  bool SizesDiffer = false;
  int Width = 0;
  int Height = 0;
  bool AnyReportPending = false; // then every process calls ShareInputReports
  // Interactive if any process's window says so.
  bool Interactive = false;
  // The settings by their rules (ForEachAgreed); SettingDiffers names the first setting that
  // must be the same everywhere but is not (empty if none).
  FrameSettings Settings;
  std::string SettingDiffers;
  // Transfer functions: the frame is rendered anyway (each process maps its own cells with
  // its own), but the picture mixes mappings, which the display process says.
  bool ColourDiffers = false;
  bool OpacityDiffers = false;
  double RangeLow[2] = { 0, 0 };  // smallest and largest lower end over the processes
  double RangeHigh[2] = { 0, 0 }; // smallest and largest upper end

  static FrameAgreement Agree(const ProcessGroup& group, const LocalFrame& local);

  bool NoVolumes() const { return this->MaxVolumes == 0; }
  bool HasCells() const;
  // Empty if the frame can be rendered; otherwise why every process skips it.
  std::string Problem() const;
  bool TransferFunctionsDiffer() const;
  // The warning for TransferFunctionsDiffer, naming the transfer functions of array.
  std::string TransferMismatch(const std::string& array) const;
};

// On the display process, says agreed.TransferMismatch (naming the first mapper's array) once
// while the processes disagree (warned remembers it; cleared when they agree again).
void WarnOnceIfTransferFunctionsDiffer(vtkObject* self, const ProcessGroup& group,
  const FrameAgreement& agreed, const std::vector<vtkAPCVolumeMapper*>& mappers, bool& warned);

} // namespace apc

#endif
