// SPDX-License-Identifier: BSD-3-Clause
// Puts a vtkAPCCompositePass into a ParaView render view: one pass per view, shared by the
// APC volumes shown in it, installed as the view's image processing pass (after IceT's opaque
// z-composite, on every rank in lockstep) while at least one is visible; the pass it replaced
// comes back when the last one leaves.
//
// The pass's settings are the view's, not a representation's: every APC representation asks
// for them (its properties), the first one shown in the view is the one the view follows, and
// when the others ask for something else that is said once, naming the settings.
#ifndef apcPassInstaller_h
#define apcPassInstaller_h

#include "apcFrameSettings.h"

#include <string>

class vtkAPCCompositePass;
class vtkPVRenderView;
class vtkVolume;

namespace apc
{

// What a representation asks of its view's pass: the settings every rank must agree on (but
// DisplayDepthComposited, which the installer sets from the view's compositing) and the display
// rank's own. The defaults are the pass's.
struct ViewRequest
{
  FrameSettings Frame;
  int Verbosity = 0;
  std::string ImageFileName;

  // The names of the settings in which the two requests differ, comma-separated; empty if none.
  std::string Differences(const ViewRequest& other) const;
};

// user: any key identifying the volume's owner (the representation); volume: what the pass
// renders; request: the view settings it asks for. Returns the view's pass, or null where
// rendering does not happen on this process (a client connected to a remote server) or cannot
// (tile-display and CAVE modes, warned).
vtkAPCCompositePass* AttachVolume(
  vtkPVRenderView* view, const void* user, vtkVolume* volume, const ViewRequest& request);

// Takes user's volume out of every view's pass; uninstalls passes left without volumes.
void DetachVolume(const void* user, vtkVolume* volume);

// The pass user's volume is attached to, or null.
vtkAPCCompositePass* FindPass(const void* user);

// Whether this process says what concerns every rank once: the display rank (rank 0) of the
// processes that render (not a client connected to a remote server, which renders nothing).
bool SaysMessages();

} // namespace apc

#endif
