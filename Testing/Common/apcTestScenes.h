// What a test or benchmark renders and from where: the data set, its transfer function, the
// camera and the mapper's sample distance, and the cameras that several of them share.
#ifndef apcTestScenes_h
#define apcTestScenes_h

#include "apcTestTransferFunctions.h"

#include "vtkCamera.h"
#include "vtkDataSet.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"

#include <array>
#include <string>

namespace apctest
{

struct View
{
  std::array<double, 3> Position = { 0, 0, 5 };
  std::array<double, 3> FocalPoint = { 0, 0, 0 };
  std::array<double, 3> ViewUp = { 0, 1, 0 };
  bool Parallel = true;
  double ParallelScale = 1.5;
  double ViewAngle = 30.0;
  int Width = 64;
  int Height = 64;
};

struct Scene
{
  std::string Name;
  vtkSmartPointer<vtkDataSet> Grid;
  TransferFunction TF;
  View Camera;
  double SampleDistance = 0.0;
  int Moments = 4; // the MBOIT order, for tests that vary it
  bool LatticeJitter = false;
  int SampleEndWeights = 0; // vtkAPCVolumeMapper::SetSampleEndWeights: 0 off, 1 all, 2 boundary
};

// Points the renderer's camera as view says; the clipping range is left to the caller, who
// knows what else is in the picture.
inline void ApplyView(vtkRenderer* renderer, const View& view)
{
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetPosition(view.Position.data());
  camera->SetFocalPoint(view.FocalPoint.data());
  camera->SetViewUp(view.ViewUp.data());
  camera->SetParallelProjection(view.Parallel);
  camera->SetParallelScale(view.ParallelScale);
  camera->SetViewAngle(view.ViewAngle);
}

// A perspective view of [-1,1]^3 from an oblique corner, size x size pixels.
inline View ObliqueView(int size)
{
  View view;
  view.Parallel = false;
  view.Position = { 3.6, 2.5, 4.5 };
  view.ViewAngle = 35;
  view.Width = view.Height = size;
  return view;
}

// Above the wind domain, looking at the buildings from the south-west.
inline View WindView(int width, int height)
{
  View view;
  view.Parallel = false;
  view.FocalPoint = { 155, 90, 40 };
  view.Position = { -120, -260, 420 };
  view.ViewUp = { 0, 0, 1 };
  view.ViewAngle = 30;
  view.Width = width;
  view.Height = height;
  return view;
}

} // namespace apctest

#endif
