// SPDX-License-Identifier: BSD-3-Clause
#include "vtkSMAPCVolumeRepresentationProxy.h"

#include "vtkCommand.h"
#include "vtkObjectFactory.h"
#include "vtkPVSession.h"

#include <cstring>

vtkStandardNewMacro(vtkSMAPCVolumeRepresentationProxy);

//------------------------------------------------------------------------------
vtkSMAPCVolumeRepresentationProxy::vtkSMAPCVolumeRepresentationProxy()
{
  // The panel's "Refresh Timings" button pushes APCRefreshTimings (the server side has
  // nothing to do: every frame keeps its timings); what the user asks for is the information
  // properties pulled from where the frame was rendered, which the panel then shows.
  this->AddObserver(
    vtkCommand::UpdatePropertyEvent, this, &vtkSMAPCVolumeRepresentationProxy::OnPropertyUpdated);
}

void vtkSMAPCVolumeRepresentationProxy::OnPropertyUpdated(vtkObject*, unsigned long, void* name)
{
  if (name && strcmp(static_cast<const char*>(name), "APCRefreshTimings") == 0)
  {
    this->UpdatePropertyInformation();
  }
}

vtkSMAPCVolumeRepresentationProxy::~vtkSMAPCVolumeRepresentationProxy() = default;

//------------------------------------------------------------------------------
void vtkSMAPCVolumeRepresentationProxy::UpdatePropertyInformationInternal(vtkSMProperty* prop)
{
  // Every information property of this proxy describes a rendered frame, which exists only
  // where rendering happens. The pull targets one location, the client first if the proxy
  // lives there (vtkSMSessionClient::PullState); only for this pull, name the render
  // server's root, which a session without a separate render server maps to the data
  // server's root, and a builtin session to itself.
  const vtkTypeUInt32 location = this->Location;
  if ((location & (vtkPVSession::RENDER_SERVER | vtkPVSession::RENDER_SERVER_ROOT)) != 0)
  {
    this->Location = vtkPVSession::RENDER_SERVER_ROOT;
  }
  this->Superclass::UpdatePropertyInformationInternal(prop);
  this->Location = location;
}

//------------------------------------------------------------------------------
void vtkSMAPCVolumeRepresentationProxy::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
}
