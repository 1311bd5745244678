// SPDX-License-Identifier: BSD-3-Clause
#include "apcPassInstaller.h"

#include "vtkAPCCompositePass.h"
#include "vtkLogger.h"
#include "vtkMultiProcessController.h"
#include "vtkPVRenderView.h"
#include "vtkPVSession.h"
#include "vtkPVSynchronizedRenderer.h"
#include "vtkProcessModule.h"
#include "vtkSmartPointer.h"

#include <map>
#include <set>

namespace apc
{
namespace
{
// vtkPVRenderView keeps its vtkPVSynchronizedRenderer protected, and only a view subclass
// (like the Eye-Dome-Lighting view) is meant to install an image processing pass. Naming the
// member through a derived class is the one standard-conforming way to reach it, and it
// lets "APC Volume" work in the standard Render View instead of a view of its own.
struct ViewAccess : public vtkPVRenderView
{
  static vtkPVSynchronizedRenderer* SynchronizedRenderer(vtkPVRenderView* view)
  {
    return view->*(&ViewAccess::SynchronizedRenderers);
  }
};

struct Installation
{
  vtkSmartPointer<vtkAPCCompositePass> Pass;
  vtkSmartPointer<vtkImageProcessingPass> Previous;
  std::set<const void*> Users;
};

std::map<vtkPVRenderView*, Installation>& Installations()
{
  static std::map<vtkPVRenderView*, Installation> installations;
  return installations;
}

// Rendering happens where the render server lives: on the pvserver / pvbatch ranks and in
// builtin sessions, not on a client connected to a remote server (it shows the server's
// image).
bool RendersHere()
{
  vtkProcessModule* pm = vtkProcessModule::GetProcessModule();
  auto* session = pm ? vtkPVSession::SafeDownCast(pm->GetActiveSession()) : nullptr;
  return !session || session->HasProcessRole(vtkPVSession::RENDER_SERVER);
}
}

vtkAPCCompositePass* AttachVolume(vtkPVRenderView* view, const void* user, vtkVolume* volume)
{
  if (!view || !RendersHere())
  {
    return nullptr;
  }
  if (view->InTileDisplayMode() || view->InCaveDisplayMode())
  {
    vtkLog(WARNING, "APC Volume does not render in tile-display or CAVE mode.");
    return nullptr;
  }
  Installation& installation = Installations()[view];
  if (!installation.Pass)
  {
    vtkPVSynchronizedRenderer* sync = ViewAccess::SynchronizedRenderer(view);
    installation.Previous = sync->GetImageProcessingPass();
    installation.Pass = vtkSmartPointer<vtkAPCCompositePass>::New();
    installation.Pass->SetController(vtkMultiProcessController::GetGlobalController());
    sync->SetImageProcessingPass(installation.Pass);
    // IceT then leaves the composited depth in the display rank's framebuffer.
    sync->SetUseDepthBuffer(true);
  }
  installation.Users.insert(user);
  installation.Pass->AddVolume(volume);
  return installation.Pass;
}

void DetachVolume(const void* user, vtkVolume* volume)
{
  auto& installations = Installations();
  for (auto it = installations.begin(); it != installations.end();)
  {
    Installation& installation = it->second;
    if (installation.Users.erase(user))
    {
      installation.Pass->RemoveVolume(volume);
      if (installation.Users.empty())
      {
        vtkPVSynchronizedRenderer* sync = ViewAccess::SynchronizedRenderer(it->first);
        sync->SetImageProcessingPass(installation.Previous);
        sync->SetUseDepthBuffer(installation.Previous != nullptr);
        it = installations.erase(it);
        continue;
      }
    }
    ++it;
  }
}

vtkAPCCompositePass* FindPass(const void* user)
{
  for (const auto& entry : Installations())
  {
    if (entry.second.Users.count(user))
    {
      return entry.second.Pass;
    }
  }
  return nullptr;
}

} // namespace apc
