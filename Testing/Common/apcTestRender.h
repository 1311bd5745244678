// Renders with vtkAPCVolumeMapper in an off-screen window and hands back everything a test
// checks: the mapper's float images, the window's pixels and the rays VTK's camera casts.
#ifndef apcTestRender_h
#define apcTestRender_h

#include "apcTestScenes.h"
#include "vtkAPCVolumeMapper.h"

#include "vtkActor.h"
#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkVolume.h"

#include <array>
#include <cmath>
#include <functional>
#include <type_traits>
#include <vector>

namespace apctest
{

struct Frame
{
  int Width = 0;
  int Height = 0;
  std::vector<float> RGBA;    // the volume alone, premultiplied
  std::vector<float> Moments; // MBOIT mode only
  std::vector<float> ColourSums;
  std::vector<int> SegmentCount;
  std::vector<unsigned char> Window; // what the window shows, RGB 8-bit
  double SampleDistance = 0;
  int RenderedPixels = 0; // the mapper's buffers: the pixels whose rays can meet the data
  // Ray (origin, unit direction) of pixel (i, j), computed by VTK's own camera transforms.
  std::vector<std::array<double, 6>> Rays;
};

// Black background and no multisampling, so that the window's pixels are the volume's.
inline void SetUpWindow(vtkRenderWindow* window, vtkRenderer* renderer, const View& view)
{
  window->SetOffScreenRendering(1);
  window->SetSize(view.Width, view.Height);
  window->SetMultiSamples(0);
  renderer->SetBackground(0, 0, 0);
  window->AddRenderer(renderer);
}

// The mapper's float images and the window's pixels after a render.
inline Frame ReadFrame(vtkRenderWindow* window, vtkAPCVolumeMapper* mapper, const View& view)
{
  Frame frame;
  frame.Width = view.Width;
  frame.Height = view.Height;
  frame.SampleDistance = mapper->GetLastSampleDistance();
  frame.RenderedPixels = static_cast<int>(mapper->GetLastRenderedPixels());
  vtkImageData* image = mapper->GetLastImage();
  auto copy = [image](const char* name, auto& out)
  {
    vtkDataArray* array = image->GetPointData()->GetArray(name);
    if (!array)
    {
      return;
    }
    const int nc = array->GetNumberOfComponents();
    const vtkIdType n = array->GetNumberOfTuples() * nc;
    out.resize(n);
    for (vtkIdType v = 0; v < n; ++v)
    {
      out[v] = static_cast<typename std::decay_t<decltype(out)>::value_type>(
        array->GetComponent(v / nc, v % nc));
    }
  };
  copy("RGBA", frame.RGBA);
  copy("Moments", frame.Moments);
  copy("ColourSums", frame.ColourSums);
  copy("SegmentCount", frame.SegmentCount);
  vtkNew<vtkUnsignedCharArray> pixels;
  window->GetPixelData(0, 0, view.Width - 1, view.Height - 1, 0, pixels);
  frame.Window.assign(pixels->GetPointer(0), pixels->GetPointer(0) + 3 * view.Width * view.Height);
  return frame;
}

// Renders grid with a configured mapper in an off-screen window; extra actors (opaque
// geometry) optional.
inline Frame Render(vtkDataSet* grid, const std::function<void(vtkAPCVolumeMapper*)>& configure,
  const TransferFunction& tf = {}, const View& view = {}, const std::vector<vtkActor*>& actors = {})
{
  vtkNew<vtkRenderWindow> window;
  vtkNew<vtkRenderer> renderer;
  SetUpWindow(window, renderer, view);

  vtkNew<vtkAPCVolumeMapper> mapper;
  mapper->SetInputData(grid);
  configure(mapper);
  vtkNew<vtkVolume> volume;
  volume->SetMapper(mapper);
  volume->SetProperty(MakeVolumeProperty(tf));
  renderer->AddVolume(volume);
  for (vtkActor* actor : actors)
  {
    renderer->AddActor(actor);
  }

  ApplyView(renderer, view);
  double bounds[6];
  grid->GetBounds(bounds);
  renderer->ResetCameraClippingRange(bounds);
  window->Render();

  Frame frame = ReadFrame(window, mapper, view);
  for (int j = 0; j < view.Height; ++j)
  {
    for (int i = 0; i < view.Width; ++i)
    {
      double near[4];
      double far[4];
      renderer->SetDisplayPoint(i + 0.5, j + 0.5, 0.0);
      renderer->DisplayToWorld();
      renderer->GetWorldPoint(near);
      renderer->SetDisplayPoint(i + 0.5, j + 0.5, 1.0);
      renderer->DisplayToWorld();
      renderer->GetWorldPoint(far);
      std::array<double, 6> ray;
      double length = 0;
      for (int d = 0; d < 3; ++d)
      {
        near[d] /= near[3];
        far[d] /= far[3];
        ray[3 + d] = far[d] - near[d];
        length += ray[3 + d] * ray[3 + d];
      }
      length = std::sqrt(length);
      for (int d = 0; d < 3; ++d)
      {
        ray[3 + d] /= length;
        ray[d] = near[d];
      }
      frame.Rays.push_back(ray);
    }
  }
  return frame;
}

// A window, renderer, volume and mapper kept alive between renders, for tests that render
// the same mapper several times or change its input in between.
struct LiveWindow
{
  vtkNew<vtkRenderWindow> Window;
  vtkNew<vtkRenderer> Renderer;
  vtkNew<vtkAPCVolumeMapper> Mapper;
  vtkNew<vtkVolume> Volume;
  View Camera;

  explicit LiveWindow(const TransferFunction& tf = {}, const View& view = {})
    : Camera(view)
  {
    SetUpWindow(this->Window, this->Renderer, view);
    this->Volume->SetMapper(this->Mapper);
    this->Volume->SetProperty(MakeVolumeProperty(tf));
    this->Renderer->AddVolume(this->Volume);
    ApplyView(this->Renderer, view);
    this->Renderer->ResetCameraClippingRange(-2, 2, -2, 2, -2, 2);
  }

  Frame Render()
  {
    this->Window->Render();
    return ReadFrame(this->Window, this->Mapper, this->Camera);
  }
};

} // namespace apctest

#endif
