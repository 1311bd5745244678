// SPDX-License-Identifier: BSD-3-Clause
// Puts a vtkAPCCompositePass into a ParaView render view: one pass per view, shared by the
// APC volumes shown in it, installed as the view's image processing pass (after IceT's opaque
// z-composite, on every rank in lockstep) while at least one is visible; the pass it replaced
// comes back when the last one leaves.
#ifndef apcPassInstaller_h
#define apcPassInstaller_h

class vtkAPCCompositePass;
class vtkPVRenderView;
class vtkVolume;

namespace apc
{

// user: any key identifying the volume's owner (the representation); volume: what the pass
// renders. Returns the view's pass, or null where rendering does not happen on this process
// (a client connected to a remote server) or cannot (tile-display and CAVE modes, warned).
vtkAPCCompositePass* AttachVolume(vtkPVRenderView* view, const void* user, vtkVolume* volume);

// Takes user's volume out of every view's pass; uninstalls passes left without volumes.
void DetachVolume(const void* user, vtkVolume* volume);

// The pass user's volume is attached to, or null.
vtkAPCCompositePass* FindPass(const void* user);

} // namespace apc

#endif
