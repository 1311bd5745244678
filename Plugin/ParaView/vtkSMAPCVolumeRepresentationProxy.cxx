// SPDX-License-Identifier: BSD-3-Clause
#include "vtkSMAPCVolumeRepresentationProxy.h"

#include "vtkObjectFactory.h"
#include "vtkPVSession.h"

vtkStandardNewMacro(vtkSMAPCVolumeRepresentationProxy);

//------------------------------------------------------------------------------
vtkSMAPCVolumeRepresentationProxy::vtkSMAPCVolumeRepresentationProxy() = default;
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
