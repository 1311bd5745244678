// SPDX-License-Identifier: BSD-3-Clause
// The first step of vtkAPCCompositePass's frame: this process's visible APC volumes begin the
// frame (their engines take the volumes' settings, read once at the VTK boundary, and their
// inputs), every process agrees on the frame (apcFrameAgreement), and the agreed frame is laid
// out: the screen rectangle, its tiles, the moments and whether the opaque stop may be tried
// without.
#ifndef apcFrameStart_h
#define apcFrameStart_h

#include "vtkSmartPointer.h"
#include "vtkVolume.h"

#include "apcCompositeFrame.h"
#include "apcFrameEngine.h"
#include "apcFrameSettings.h"

#include <memory>
#include <vector>

class vtkObject;
class vtkRenderer;

namespace apc
{

// A volume the pass renders, with the engine that runs its frames (the pass's own: the mapper
// gives its settings, vtkAPCVolumeMapper::GetVolumeSettings, and its input, nothing else).
struct VolumeEntry
{
  vtkSmartPointer<vtkVolume> Volume;
  std::unique_ptr<apc::FrameEngine> Engine;
};

// This process's visible volumes and its side of the agreement, then the agreement itself
// into frame (visible: the volumes drawn; opaque: the last APC frame had a pixel at the stop's
// threshold). False if the frame is skipped on every process (failures reported through self).
bool AgreeOnFrame(vtkObject* self, const ProcessGroup& group,
  const std::vector<VolumeEntry>& volumes, const FrameSettings& settings, vtkRenderer* ren,
  CompositeFrame& frame, std::vector<vtkVolume*>& visible, FrameRecord& record,
  bool& transferWarned, bool opaque);

} // namespace apc

#endif
