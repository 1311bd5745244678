// Shared scene builders and a render harness for the vtkAPCVolumeMapper tests.
#ifndef apcTestScenes_h
#define apcTestScenes_h

#include "vtkAPCVolumeMapper.h"

#include "vtkActor.h"
#include "vtkCamera.h"
#include "vtkCellArray.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataSetTriangleFilter.h"
#include "vtkFloatArray.h"
#include "vtkIdList.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPNGWriter.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <array>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

namespace apctest
{

// An n x n x n block of hexahedra on [-1,1]^3 with point scalars f(x, y, z).
inline vtkSmartPointer<vtkUnstructuredGrid> HexBlock(
  int n, const std::function<double(double, double, double)>& f)
{
  vtkNew<vtkPoints> points;
  vtkNew<vtkFloatArray> scalars;
  scalars->SetName("f");
  for (int k = 0; k <= n; ++k)
  {
    for (int j = 0; j <= n; ++j)
    {
      for (int i = 0; i <= n; ++i)
      {
        const double x = -1 + 2.0 * i / n;
        const double y = -1 + 2.0 * j / n;
        const double z = -1 + 2.0 * k / n;
        points->InsertNextPoint(x, y, z);
        scalars->InsertNextValue(static_cast<float>(f(x, y, z)));
      }
    }
  }
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->SetPoints(points);
  grid->GetPointData()->SetScalars(scalars);
  auto id = [n](int i, int j, int k)
  { return static_cast<vtkIdType>((k * (n + 1) + j) * (n + 1) + i); };
  for (int k = 0; k < n; ++k)
  {
    for (int j = 0; j < n; ++j)
    {
      for (int i = 0; i < n; ++i)
      {
        const vtkIdType hex[8] = { id(i, j, k), id(i + 1, j, k), id(i + 1, j + 1, k),
          id(i, j + 1, k), id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1),
          id(i, j + 1, k + 1) };
        grid->InsertNextCell(VTK_HEXAHEDRON, 8, hex);
      }
    }
  }
  return grid;
}

// The same block cut into tetrahedra by VTK.
inline vtkSmartPointer<vtkUnstructuredGrid> Tetrahedralized(vtkUnstructuredGrid* grid)
{
  vtkNew<vtkDataSetTriangleFilter> tets;
  tets->SetInputData(grid);
  tets->Update();
  return tets->GetOutput();
}

struct TransferFunction
{
  double Min = 0.0;
  double Max = 1.0;
  // (scalar, r, g, b) and (scalar, alpha) nodes.
  std::vector<std::array<double, 4>> Colours = { { 0.0, 1.0, 0.5, 0.25 }, { 1.0, 1.0, 0.5, 0.25 } };
  std::vector<std::array<double, 2>> Opacities = { { 0.0, 0.2 }, { 1.0, 0.2 } };
  double UnitDistance = 1.0;
};

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

// The paper's picture for the Spheres field: a red core seen through a translucent blue shell.
inline TransferFunction SpheresTF()
{
  TransferFunction tf;
  tf.Colours = { { 0.0, 0.0, 0.0, 0.0 }, { 0.5, 0.15, 0.3, 1.0 }, { 1.0, 1.0, 0.15, 0.1 } };
  tf.Opacities = { { 0.0, 0.0 }, { 0.2, 0.0 }, { 0.5, 0.12 }, { 0.75, 0.05 }, { 1.0, 0.95 } };
  tf.UnitDistance = 0.1;
  return tf;
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

// The real wind data (U_mag): the buildings' wakes (nearly still air) in blue, the fast
// stream above in red.
inline TransferFunction WindTF()
{
  TransferFunction tf;
  tf.Min = 0;
  tf.Max = 20;
  tf.Colours = { { 0.0, 0.23, 0.30, 0.75 }, { 10.0, 0.87, 0.87, 0.87 },
    { 20.0, 0.71, 0.02, 0.15 } };
  tf.Opacities = { { 0.0, 0.5 }, { 2.0, 0.15 }, { 5.0, 0.0 }, { 12.0, 0.0 }, { 16.0, 0.03 },
    { 20.0, 0.2 } };
  tf.UnitDistance = 5.0;
  return tf;
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
  // Ray (origin, unit direction) of pixel (i, j), computed by VTK's own camera transforms.
  std::vector<std::array<double, 6>> Rays;
};

// The VTK volume property of a transfer function.
inline vtkSmartPointer<vtkVolumeProperty> MakeVolumeProperty(const TransferFunction& tf)
{
  vtkNew<vtkColorTransferFunction> colour;
  for (const auto& c : tf.Colours)
  {
    colour->AddRGBPoint(c[0], c[1], c[2], c[3]);
  }
  vtkNew<vtkPiecewiseFunction> opacity;
  for (const auto& o : tf.Opacities)
  {
    opacity->AddPoint(o[0], o[1]);
  }
  vtkNew<vtkVolumeProperty> property;
  property->SetColor(colour);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(tf.UnitDistance);
  return property;
}

// Renders grid with a configured mapper in an off-screen window; extra actors (opaque
// geometry) optional.
inline Frame Render(vtkDataSet* grid, const std::function<void(vtkAPCVolumeMapper*)>& configure,
  const TransferFunction& tf = {}, const View& view = {}, const std::vector<vtkActor*>& actors = {})
{
  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->SetSize(view.Width, view.Height);
  window->SetMultiSamples(0);
  vtkNew<vtkRenderer> renderer;
  renderer->SetBackground(0, 0, 0);
  window->AddRenderer(renderer);

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

  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetPosition(view.Position.data());
  camera->SetFocalPoint(view.FocalPoint.data());
  camera->SetViewUp(view.ViewUp.data());
  camera->SetParallelProjection(view.Parallel);
  camera->SetParallelScale(view.ParallelScale);
  camera->SetViewAngle(view.ViewAngle);
  double bounds[6];
  grid->GetBounds(bounds);
  renderer->ResetCameraClippingRange(bounds);
  window->Render();

  Frame frame;
  frame.Width = view.Width;
  frame.Height = view.Height;
  frame.SampleDistance = mapper->GetLastSampleDistance();
  vtkImageData* image = mapper->GetLastImage();
  auto copy = [image](const char* name, auto& out)
  {
    vtkDataArray* array = image->GetPointData()->GetArray(name);
    if (!array)
    {
      return;
    }
    const vtkIdType n = array->GetNumberOfTuples() * array->GetNumberOfComponents();
    out.resize(n);
    for (vtkIdType v = 0; v < n; ++v)
    {
      out[v] = static_cast<typename std::decay_t<decltype(out)>::value_type>(array->GetComponent(
        v / array->GetNumberOfComponents(), v % array->GetNumberOfComponents()));
    }
  };
  copy("RGBA", frame.RGBA);
  copy("Moments", frame.Moments);
  copy("ColourSums", frame.ColourSums);
  copy("SegmentCount", frame.SegmentCount);
  vtkNew<vtkUnsignedCharArray> pixels;
  window->GetPixelData(0, 0, view.Width - 1, view.Height - 1, 0, pixels);
  frame.Window.assign(pixels->GetPointer(0), pixels->GetPointer(0) + 3 * view.Width * view.Height);

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

// Length of a ray inside the box [-1,1]^3 (slab method), independent of the mapper.
inline double LengthInUnitBox(const std::array<double, 6>& ray, double halfSize = 1.0)
{
  double t0 = -1e300;
  double t1 = 1e300;
  for (int d = 0; d < 3; ++d)
  {
    if (std::abs(ray[3 + d]) < 1e-15)
    {
      if (std::abs(ray[d]) > halfSize)
      {
        return 0.0;
      }
      continue;
    }
    double a = (-halfSize - ray[d]) / ray[3 + d];
    double b = (halfSize - ray[d]) / ray[3 + d];
    if (a > b)
    {
      std::swap(a, b);
    }
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  return t1 > t0 ? t1 - t0 : 0.0;
}

// Premultiplied RGBA over a background, as 8-bit RGB, written as PNG (for looking at).
inline void WritePNG(const std::string& path, const std::vector<float>& rgba, int width, int height,
  const std::array<double, 3>& background = { 1.0, 1.0, 1.0 })
{
  vtkNew<vtkImageData> image;
  image->SetDimensions(width, height, 1);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* out = static_cast<unsigned char*>(image->GetScalarPointer());
  for (int p = 0; p < width * height; ++p)
  {
    for (int c = 0; c < 3; ++c)
    {
      const double v = rgba[4 * p + c] + (1.0 - rgba[4 * p + 3]) * background[c];
      out[3 * p + c] =
        static_cast<unsigned char>(std::lround(255.0 * std::min(1.0, std::max(0.0, v))));
    }
  }
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(path.c_str());
  writer->SetInputData(image);
  writer->Write();
}

// Where tests put images for people to look at: $APC_TEST_OUTPUT or the working directory.
inline std::string OutputPath(const std::string& name)
{
  const char* dir = std::getenv("APC_TEST_OUTPUT");
  return (dir ? std::string(dir) + "/" : std::string()) + name;
}

} // namespace apctest

#endif
