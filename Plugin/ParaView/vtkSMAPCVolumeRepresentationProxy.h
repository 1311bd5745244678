// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkSMAPCVolumeRepresentationProxy
 * @brief   The server-manager proxy of the "APC Volume" representation: reads its
 *          information properties (the last frame's timings) where the frame was rendered.
 *
 * The representation lives on the client and on the servers. vtkSMSessionClient pulls a
 * proxy's information from the client whenever the proxy has an object there, but in a
 * client-server session the client's object never renders: the vtkAPCCompositePass, and so
 * every timing, lives on the render server, whose root is the display rank. This proxy pulls
 * its information properties (APCLastTimings, APCLastTimingNames) from the render server's
 * root instead; in builtin sessions and pvbatch that is the local process. Pushing
 * APCRefreshTimings (the panel's "Refresh Timings" button) pulls them, so that the panel shows
 * the last frame's timings.
 */
#ifndef vtkSMAPCVolumeRepresentationProxy_h
#define vtkSMAPCVolumeRepresentationProxy_h

#include "APCParaViewModule.h" // for export macro
#include "vtkSMRepresentationProxy.h"

class APCPARAVIEW_EXPORT vtkSMAPCVolumeRepresentationProxy : public vtkSMRepresentationProxy
{
public:
  static vtkSMAPCVolumeRepresentationProxy* New();
  vtkTypeMacro(vtkSMAPCVolumeRepresentationProxy, vtkSMRepresentationProxy);
  void PrintSelf(ostream& os, vtkIndent indent) override;

protected:
  vtkSMAPCVolumeRepresentationProxy();
  ~vtkSMAPCVolumeRepresentationProxy() override;

  void UpdatePropertyInformationInternal(vtkSMProperty* prop = nullptr) override;

  // After "Refresh Timings" (APCRefreshTimings) was pushed: pulls the timings.
  void OnPropertyUpdated(vtkObject* caller, unsigned long event, void* name);

private:
  vtkSMAPCVolumeRepresentationProxy(const vtkSMAPCVolumeRepresentationProxy&) = delete;
  void operator=(const vtkSMAPCVolumeRepresentationProxy&) = delete;
};

#endif
