// SPDX-License-Identifier: BSD-3-Clause
#include "apcPassInstaller.h"

#include "vtkAPCCompositePass.h"
#include "vtkCallbackCommand.h"
#include "vtkCommand.h"
#include "vtkFloatArray.h"
#include "vtkIceTSynchronizedRenderers.h"
#include "vtkLogger.h"
#include "vtkMultiProcessController.h"
#include "vtkOpenGLFXAAPass.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkOpenGLState.h"
#include "vtkPVRenderView.h"
#include "vtkPVSession.h"
#include "vtkPVSynchronizedRenderer.h"
#include "vtkProcessModule.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"
#include "vtkWeakPointer.h"
#include "vtk_glew.h"

#include <algorithm>
#include <map>
#include <sstream>
#include <utility>
#include <vector>

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
  // A representation can outlive its view (pvbatch deletes the view first at exit): what
  // is left of a dead view is only forgotten.
  vtkWeakPointer<vtkPVRenderView> View;
  vtkSmartPointer<vtkAPCCompositePass> Pass;
  vtkSmartPointer<vtkImageProcessingPass> Previous;
  // The representations whose volumes the pass renders and the settings they ask for, in the
  // order they were first shown: the first one's are the view's.
  std::vector<std::pair<const void*, ViewRequest>> Users;
  std::string ConflictSaid; // the differences last warned about, so that they are said once
  vtkSmartPointer<vtkCallbackCommand> BeforeRender;
  unsigned long BeforeRenderTag = 0;
  vtkSmartPointer<vtkCallbackCommand> AfterIceT;
  bool IceTPasted = true; // IceT's DisplayRGBAResults before the pass was installed
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

// Runs at the start of every render of the view's renderer, after vtkPVRenderView has set
// up the frame (ordered compositing, FXAA) and before any pass runs.
void BeforeRender(vtkObject*, unsigned long, void* clientData, void*)
{
  auto* view = static_cast<vtkPVRenderView*>(clientData);
  const auto found = Installations().find(view);
  if (found == Installations().end())
  {
    return;
  }
  vtkAPCCompositePass* pass = found->second.Pass;
  // Without IceT (one process), vtkPVSynchronizedRenderer wraps an image processing pass in
  // an FXAA pass (anti-aliasing the final picture, the APC volume included), but vtkPVRenderView
  // also leaves the renderer's own FXAA on, which smooths the geometry once before the pass.
  // IceT runs get the final FXAA only (their composited image has sharp outlines), so one
  // process differed from N on a one-pixel rim along every silhouette of opaque geometry.
  // The renderer's FXAA goes off for the frame; vtkPVRenderView sets it again every render.
  vtkRenderer* renderer = view->GetRenderer();
  auto* fxaa = vtkOpenGLFXAAPass::SafeDownCast(renderer->GetPass());
  if (fxaa && fxaa->GetDelegatePass() == pass)
  {
    renderer->SetUseFXAA(false);
  }
  // IceT composites depth only when no representation needs ordered compositing (ParaView's
  // Volume, translucent surfaces); then it blends colours alone and has no depth to paste
  // back into the display process's framebuffer (asking for it prints "Tile viewport size
  // ... does not match captured depth image (0)" every frame). The pass then composites the
  // processes' own depth buffers itself.
  const bool ordered = view->GetUseOrderedCompositing();
  vtkPVSynchronizedRenderer* sync = ViewAccess::SynchronizedRenderer(view);
  sync->SetUseDepthBuffer(!ordered);
  pass->SetDisplayDepthComposited(!ordered);
  // IceT pastes its image with vtkRawImage::PushToViewport, which clears the viewport's depth
  // too: the display process's own opaque geometry would be gone before the pass reads it.
  // Under ordered compositing AfterIceT pastes the same image without clearing instead.
  if (auto* icet = vtkIceTSynchronizedRenderers::SafeDownCast(sync->GetParallelSynchronizer()))
  {
    icet->GetIceTCompositePass()->SetDisplayRGBAResults(!ordered);
  }
}

// Runs when the pass's delegate (IceT) has rendered. On the display process IceT keeps the
// composited depth it read back as floats: the very values a one-process render reads from
// its depth buffer. The copy IceT pasted into the framebuffer went through a depth texture
// and back, which moves a few values by one step of the 24-bit buffer; rays stopping at
// opaque geometry that coincides with a sample then differ from one process at a few pixels.
void AfterIceT(vtkObject* caller, unsigned long, void* clientData, void* callData)
{
  auto* pass = static_cast<vtkAPCCompositePass*>(caller);
  auto* view = static_cast<vtkPVRenderView*>(clientData);
  auto* renderer = static_cast<vtkRenderer*>(callData);
  auto* icet = vtkIceTSynchronizedRenderers::SafeDownCast(
    ViewAccess::SynchronizedRenderer(view)->GetParallelSynchronizer());
  if (!icet || !renderer)
  {
    return;
  }
  if (!pass->GetDisplayDepthComposited())
  {
    // Ordered compositing: IceT's image replaces the colours (premultiplied, over black, as
    // IceT's own paste leaves them) and the depth buffer keeps this process's geometry.
    vtkSynchronizedRenderers::vtkRawImage tile;
    icet->GetIceTCompositePass()->GetLastRenderedTile(tile);
    auto* window = vtkOpenGLRenderWindow::SafeDownCast(renderer->GetRenderWindow());
    if (tile.IsValid() && window)
    {
      // DrawPixels turns the depth and scissor tests off and leaves them so.
      vtkOpenGLState* state = window->GetState();
      vtkOpenGLState::ScopedglEnableDisable depthTest(state, GL_DEPTH_TEST);
      vtkOpenGLState::ScopedglEnableDisable scissorTest(state, GL_SCISSOR_TEST);
      vtkOpenGLState::ScopedglDepthMask depthMask(state);
      state->vtkglDepthMask(GL_FALSE);
      tile.PushToFrameBuffer(renderer, /*blend=*/false);
    }
    return;
  }
  vtkIceTCompositePass* composite = icet->GetIceTCompositePass();
  int width = 0;
  int height = 0;
  renderer->GetTiledSize(&width, &height);
  vtkFloatArray* depth = composite->GetLastRenderedDepths();
  if (depth && composite->GetImageReductionFactor() == 1 &&
    depth->GetNumberOfTuples() == static_cast<vtkIdType>(width) * height)
  {
    pass->SetDelegateDepth(depth);
  }
}

// The view's settings onto its pass: the first representation's request; the others' differing
// requests are said once (until they change).
void ApplyRequests(Installation& installation)
{
  const ViewRequest& governing = installation.Users.front().second;
  std::string differences;
  for (const auto& user : installation.Users)
  {
    const std::string d = governing.Differences(user.second);
    if (!d.empty() && differences.find(d) == std::string::npos)
    {
      differences += (differences.empty() ? "" : ", ") + d;
    }
  }
  // Every rank asks the same (ParaView sets the properties everywhere): the display rank says it.
  if (SaysMessages() && !differences.empty() && differences != installation.ConflictSaid)
  {
    vtkLog(WARNING,
      "The APC volumes of one view ask for different view settings ("
        << differences
        << "). They are the view's, not each volume's: the view uses those of the APC volume "
           "shown first. Set them alike on every APC volume of the view.");
  }
  installation.ConflictSaid = differences;
  vtkAPCCompositePass* pass = installation.Pass;
  pass->SetCompositeMode(governing.Frame.CompositeMode);
  pass->SetMaxBandPixels(governing.Frame.MaxBandPixels);
  pass->SetInteractiveSampleDistanceFactor(governing.Frame.InteractiveSampleDistanceFactor);
  pass->SetInteractiveImageReduction(governing.Frame.InteractiveImageReduction);
  pass->SetCompositeInDouble(governing.Frame.CompositeInDouble);
  pass->SetVerbosity(governing.Verbosity);
  pass->SetImageFileName(governing.ImageFileName.c_str());
}
}

std::string ViewRequest::Differences(const ViewRequest& other) const
{
  std::ostringstream names;
  const char* separator = "";
  auto differ = [&](bool different, const char* name)
  {
    if (different)
    {
      names << separator << name;
      separator = ", ";
    }
  };
  differ(this->Frame.CompositeMode != other.Frame.CompositeMode, "APC Mode");
  differ(this->Frame.MaxBandPixels != other.Frame.MaxBandPixels, "Band Size");
  differ(this->Frame.InteractiveSampleDistanceFactor != other.Frame.InteractiveSampleDistanceFactor,
    "Interactive Sample Distance Factor");
  differ(this->Frame.InteractiveImageReduction != other.Frame.InteractiveImageReduction,
    "Interactive Image Reduction");
  differ(this->Frame.CompositeInDouble != other.Frame.CompositeInDouble, "Composite In Double");
  differ(this->Verbosity != other.Verbosity, "Compositing Verbosity");
  differ(this->ImageFileName != other.ImageFileName, "Float Image File");
  return names.str();
}

vtkAPCCompositePass* AttachVolume(
  vtkPVRenderView* view, const void* user, vtkVolume* volume, const ViewRequest& request)
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
  if (installation.Pass && !installation.View)
  {
    installation = Installation(); // a dead view's, at the same address
  }
  if (!installation.Pass)
  {
    vtkPVSynchronizedRenderer* sync = ViewAccess::SynchronizedRenderer(view);
    installation.View = view;
    installation.Previous = sync->GetImageProcessingPass();
    if (auto* icet = vtkIceTSynchronizedRenderers::SafeDownCast(sync->GetParallelSynchronizer()))
    {
      installation.IceTPasted = icet->GetIceTCompositePass()->GetDisplayRGBAResults();
    }
    installation.Pass = vtkSmartPointer<vtkAPCCompositePass>::New();
    installation.Pass->SetController(vtkMultiProcessController::GetGlobalController());
    sync->SetImageProcessingPass(installation.Pass);
    // IceT then leaves the composited depth in the display rank's framebuffer (renewed
    // before every render by BeforeRender, which knows whether IceT composites depth).
    sync->SetUseDepthBuffer(true);
    installation.BeforeRender = vtkSmartPointer<vtkCallbackCommand>::New();
    installation.BeforeRender->SetCallback(BeforeRender);
    installation.BeforeRender->SetClientData(view);
    installation.BeforeRenderTag =
      view->GetRenderer()->AddObserver(vtkCommand::StartEvent, installation.BeforeRender);
    installation.AfterIceT = vtkSmartPointer<vtkCallbackCommand>::New();
    installation.AfterIceT->SetCallback(AfterIceT);
    installation.AfterIceT->SetClientData(view);
    installation.Pass->AddObserver(
      vtkAPCCompositePass::DelegateRenderedEvent, installation.AfterIceT);
  }
  auto& users = installation.Users;
  const auto found = std::find_if(
    users.begin(), users.end(), [user](const auto& entry) { return entry.first == user; });
  if (found == users.end())
  {
    users.emplace_back(user, request);
  }
  else
  {
    found->second = request;
  }
  installation.Pass->AddVolume(volume);
  ApplyRequests(installation);
  return installation.Pass;
}

void DetachVolume(const void* user, vtkVolume* volume)
{
  auto& installations = Installations();
  for (auto it = installations.begin(); it != installations.end();)
  {
    Installation& installation = it->second;
    auto& users = installation.Users;
    const auto found = std::find_if(
      users.begin(), users.end(), [user](const auto& entry) { return entry.first == user; });
    if (found != users.end())
    {
      users.erase(found);
      installation.Pass->RemoveVolume(volume);
      if (installation.Users.empty())
      {
        if (vtkPVRenderView* view = installation.View)
        {
          view->GetRenderer()->RemoveObserver(installation.BeforeRenderTag);
          vtkPVSynchronizedRenderer* sync = ViewAccess::SynchronizedRenderer(view);
          sync->SetImageProcessingPass(installation.Previous);
          sync->SetUseDepthBuffer(installation.Previous != nullptr);
          // BeforeRender may have left IceT's own paste off (ordered compositing); without
          // the pass nothing else would put IceT's image on the screen.
          if (auto* icet =
                vtkIceTSynchronizedRenderers::SafeDownCast(sync->GetParallelSynchronizer()))
          {
            icet->GetIceTCompositePass()->SetDisplayRGBAResults(installation.IceTPasted);
          }
        }
        it = installations.erase(it);
        continue;
      }
      ApplyRequests(installation); // the next one shown may now be first
    }
    ++it;
  }
}

bool SaysMessages()
{
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  return RendersHere() && (!controller || controller->GetLocalProcessId() == 0);
}

vtkAPCCompositePass* FindPass(const void* user)
{
  for (const auto& entry : Installations())
  {
    const auto& users = entry.second.Users;
    if (std::any_of(users.begin(), users.end(), [user](const auto& u) { return u.first == user; }))
    {
      return entry.second.Pass;
    }
  }
  return nullptr;
}

} // namespace apc
