// SPDX-License-Identifier: BSD-3-Clause
#include "apcFrameStart.h"

#include "vtkAPCVolumeMapper.h"
#include "vtkObject.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkVolume.h"

#include "apcFrameAgreement.h"
#include "apcInputReport.h"
#include "apcScreenRect.h"

#include <algorithm>
#include <sstream>
#include <string>

namespace apc
{

namespace
{
// This process's visible APC volumes: their engines begin the frame with the volumes' settings
// (read once, at the VTK boundary) and take their inputs; their side of the agreement goes into
// local; mappers lists their mappers in order (the first says the input reports).
void CollectVolumes(const std::vector<VolumeEntry>& volumes, LocalFrame& local,
  CompositeFrame& frame, std::vector<vtkVolume*>& visible,
  std::vector<vtkAPCVolumeMapper*>& mappers, InputReport& reports, std::ostringstream& problem)
{
  for (const VolumeEntry& entry : volumes)
  {
    if (!entry.Volume->GetVisibility())
    {
      continue;
    }
    auto* mapper = vtkAPCVolumeMapper::SafeDownCast(entry.Volume->GetMapper());
    if (!mapper)
    {
      problem << "a volume without a vtkAPCVolumeMapper; ";
      local.Failed = true;
      continue;
    }
    // The engine reads no mapper: it gets the volume's settings and input.
    const VolumeSettings volumeSettings = mapper->GetVolumeSettings();
    FrameEngine* engine = entry.Engine.get();
    engine->BeginFrame(volumeSettings);
    if (!engine->UpdateInput(mapper->GetInput(), mapper))
    {
      problem << "unusable input (see the mapper's error); ";
      local.Failed = true;
    }
    local.ReportPending = engine->TakeNewInputReport() || local.ReportPending;
    reports.Add(engine->GetInputReport());
    double bounds[6];
    local.AddVolume(volumeSettings.Moments.Moments,
      engine->GetLocalBounds(bounds) ? bounds : nullptr, entry.Volume->GetProperty());
    local.Cells += static_cast<double>(engine->GetNumberOfCells());
    local.Volume.Add(engine->GetCellVolume());
    local.StopsWhereOpaque = local.StopsWhereOpaque || volumeSettings.StopWhereOpaque;
    local.NeedsSharedBoundary = local.NeedsSharedBoundary || engine->NeedsSharedBoundary();
    if (mappers.empty())
    {
      // The frame's moment settings: the first volume's beta, bias and resolve.
      frame.Moments = volumeSettings.Moments;
    }
    mappers.push_back(mapper);
    visible.push_back(entry.Volume);
    frame.Engines.push_back(engine);
  }
}

}

bool AgreeOnFrame(vtkObject* self, const ProcessGroup& group,
  const std::vector<VolumeEntry>& volumes, const FrameSettings& settings, vtkRenderer* ren,
  CompositeFrame& frame, std::vector<vtkVolume*>& visible, FrameRecord& record,
  bool& transferWarned, bool opaque)
{
  LocalFrame local;
  local.Settings = settings;
  local.Opaque = opaque;
  std::ostringstream problem;
  InputReport reports; // said once for all processes when any has news
  std::vector<vtkAPCVolumeMapper*> mappers;
  CollectVolumes(volumes, local, frame, visible, mappers, reports, problem);
  vtkObject* reporter = mappers.empty() ? static_cast<vtkObject*>(self) : mappers.front();
  // The screen rectangle and every image buffer derive from the viewport: sizes that differ
  // between processes would make their collectives disagree in length.
  ren->GetTiledSizeAndOrigin(&local.Width, &local.Height, &frame.X0, &frame.Y0);
  // Whether this frame may be cheap is the window's word (ParaView's and VTK's interactive
  // renders raise its desired update rate); how cheap is this pass's setting. Both are
  // agreed, so no process renders a different lattice or image size than the others.
  vtkRenderWindow* window = ren->GetRenderWindow();
  local.Interactive = window && window->GetDesiredUpdateRate() >= 1.0;
  const FrameAgreement agreed = FrameAgreement::Agree(group, local);
  if (agreed.AnyReportPending)
  {
    ShareInputReports(group, reports, reporter);
  }
  WarnOnceIfTransferFunctionsDiffer(self, group, agreed, mappers, transferWarned);
  record.Clock.Lap("agree");
  if (agreed.NoVolumes())
  {
    return false;
  }
  const std::string why = agreed.Problem();
  if (!why.empty())
  {
    record.Failed = true;
    if (!problem.str().empty())
    {
      vtkErrorWithObjectMacro(self, "APC on process " << group.Rank << ": " << problem.str());
    }
    if (group.IsDisplay())
    {
      vtkErrorWithObjectMacro(self, "APC frame skipped: " << why);
    }
    return false;
  }
  if (!agreed.HasCells() || agreed.Width < 1 || agreed.Height < 1)
  {
    return false; // nothing to draw anywhere (the same on every process)
  }
  frame.Renderer = ren;
  frame.ViewWidth = agreed.Width;
  frame.ViewHeight = agreed.Height;
  frame.Interactive = agreed.Interactive;
  frame.Settings = agreed.Settings;
  const int reduction = frame.Reduction();
  frame.Width = (agreed.Width + reduction - 1) / reduction;
  frame.Height = (agreed.Height + reduction - 1) / reduction;
  frame.Rect = ScreenRectOf(ren, agreed.Bounds, frame.Width, frame.Height, frame.Aspect());
  const ScreenRect& r = frame.Rect;
  frame.Tiles = r.Pixels() > 0 ? TileGrid(r.Width(), 0, 0, r.Width(), r.Height()) : TileGrid();
  frame.Moments.Moments = agreed.MaxMoments;
  frame.Volumes = agreed.MaxVolumes;
  frame.StopsWhereOpaque = agreed.AnyStopsWhereOpaque;
  frame.ShareBoundary = agreed.AnyNeedsSharedBoundary;
  // The double wire's sums may round differently on each process: no retry decided from them.
  frame.TryWithoutOpaqueStop = !agreed.AnyOpaque && !agreed.Settings.CompositeInDouble;
  std::copy(agreed.Bounds, agreed.Bounds + 6, frame.Bounds);
  frame.Cells = agreed.Cells;
  frame.CellVolume = agreed.Volume;
  return true;
}

} // namespace apc
