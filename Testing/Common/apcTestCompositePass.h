// A window rendered through vtkAPCCompositePass as ParaView would set it up: opaque geometry
// by VTK's standard steps first, then the volumes composited across the ranks.
#ifndef apcTestCompositePass_h
#define apcTestCompositePass_h

#include "vtkAPCCompositePass.h"

#include "vtkMultiProcessController.h"
#include "vtkNew.h"
#include "vtkRenderStepsPass.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"

namespace apctest
{

inline void SetUpCompositeWindow(vtkRenderWindow* window, vtkRenderer* renderer, int size,
  vtkAPCCompositePass* pass, vtkMultiProcessController* controller)
{
  window->SetOffScreenRendering(1);
  window->SetSize(size, size);
  window->AddRenderer(renderer);
  vtkNew<vtkRenderStepsPass> opaque;
  pass->SetDelegatePass(opaque);
  pass->SetController(controller);
  renderer->SetPass(pass);
}

} // namespace apctest

#endif
