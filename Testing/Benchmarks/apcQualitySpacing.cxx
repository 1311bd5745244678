// The default sample distance against the exact picture (apcQualitySweep --spacing).
//
// Each scene is set up as ParaView sets up a freshly coloured volume: the point array's range,
// the cool-to-warm map, a linear opacity ramp from 0 to 1 over the range and the opacity unit
// distance of ParaView's "approximate_cell_length" domain (diagonal / cells^(1/3)). The
// reference is vtkAPCVolumeMapper's EXACT mode (ordered blending) at a quarter of the finest
// spacing compared. Against it: MBOIT at the mapper's defaults (beta, moments, resolve) on the
// plain lattice at the old default spacing (bounding-box diagonal / 256), at multiples of the
// mean cell size (apcDefaultSpacing.h), with and without Lattice Jitter; EXACT at some of them
// (the lattice's own error, without the moments'); Sample End Weights = Boundary (the
// default) at the previous default, at 1 to 3 mean cell sizes and at 128 / 96 / 64 samples
// along the diagonal, with and without jitter; All at a few; the mapper's default (sample
// distance 0 and every setting at its default, what a user gets), also with Sample End
// Weights Off and in EXACT mode (their own default distance); and VTK's projected tetrahedra
// (ParaView's default Volume mapper) on VTK's tetrahedralisation. Premultiplied RGB over black,
// compared by apc::CompareImages; CPU time of the process (all threads) for one frame after a first
// one (mesh conversion excluded).
#include "apcQualitySpacing.h"

#include "apcCellMesh.h"
#include "apcCellMeshFromVTK.h"
#include "apcDefaultSpacing.h"
#include "apcImageMetrics.h"
#include "apcTestImages.h"
#include "apcTestPuzzles.h"
#include "apcTestRender.h"
#include "apcTestScenes.h"

#include "vtkAPCPuzzleSource.h"
#include "vtkAPCVolumeMapper.h"
#include "vtkDataArray.h"
#include "vtkDataSetTriangleFilter.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkProjectedTetrahedraMapper.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"
#include "vtkUnstructuredGridBase.h"
#include "vtkVolume.h"
#include "vtkXMLPUnstructuredGridReader.h"
#include "vtkXMLUnstructuredGridReader.h"

#include <cmath>
#include <ctime>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace apcbench
{
namespace
{

double CpuSeconds()
{
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// ParaView's look for a freshly coloured volume (see the top of the file).
apctest::TransferFunction ParaViewDefaults(vtkDataSet* grid)
{
  double range[2];
  grid->GetPointData()->GetScalars()->GetRange(range);
  apctest::TransferFunction tf;
  tf.Min = range[0];
  tf.Max = range[1];
  const double mid = 0.5 * (range[0] + range[1]);
  tf.Colours = { { range[0], 0.23, 0.299, 0.754 }, { mid, 0.865, 0.865, 0.865 },
    { range[1], 0.706, 0.016, 0.15 } };
  tf.Opacities = { { range[0], 0.0 }, { range[1], 1.0 } };
  double b[6];
  grid->GetBounds(b);
  tf.UnitDistance =
    apc::BoundsDiagonal(b) / std::cbrt(static_cast<double>(grid->GetNumberOfCells()));
  return tf;
}

// A perspective camera that frames the bounds from azimuth / elevation (degrees, from -y).
apctest::View FitView(const double b[6], double azimuth, double elevation, double zoom, int size)
{
  apctest::View view;
  view.Parallel = false;
  view.ViewAngle = 30;
  view.Width = view.Height = size;
  view.ViewUp = { 0, 0, 1 };
  const double pi = std::acos(-1.0);
  const double a = azimuth * pi / 180;
  const double e = elevation * pi / 180;
  const double distance =
    0.5 * apc::BoundsDiagonal(b) / std::sin(0.5 * view.ViewAngle * pi / 180) / zoom;
  for (int d = 0; d < 3; ++d)
  {
    view.FocalPoint[d] = 0.5 * (b[2 * d] + b[2 * d + 1]);
  }
  view.Position = { view.FocalPoint[0] + distance * std::cos(e) * std::sin(a),
    view.FocalPoint[1] - distance * std::cos(e) * std::cos(a),
    view.FocalPoint[2] + distance * std::sin(e) };
  return view;
}

vtkSmartPointer<vtkDataSet> ReadPoints(const std::string& path, const char* field)
{
  vtkSmartPointer<vtkDataSet> grid;
  if (path.size() > 5 && path.substr(path.size() - 5) == ".pvtu")
  {
    vtkNew<vtkXMLPUnstructuredGridReader> reader;
    reader->SetFileName(path.c_str());
    reader->Update();
    grid = reader->GetOutputAsDataSet();
  }
  else
  {
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    reader->SetFileName(path.c_str());
    reader->Update();
    grid = reader->GetOutputAsDataSet();
  }
  if (!grid || grid->GetNumberOfCells() == 0 || !grid->GetPointData()->GetArray(field))
  {
    std::cerr << "error: could not read point array " << field << " from " << path << "\n";
    std::exit(2);
  }
  grid->GetPointData()->SetActiveScalars(field);
  return grid;
}

std::vector<apctest::Scene> SpacingScenes(const std::string& data, int size)
{
  std::vector<apctest::Scene> scenes;
  auto add = [&](const std::string& name, vtkSmartPointer<vtkDataSet> grid, apctest::View view) {
    scenes.push_back({ name, grid, ParaViewDefaults(grid), view, 0.0 });
  };
  auto wind = ReadPoints(data + "/windAroundBuildings/wind.pvtu", "U_mag");
  add("wind", wind, apctest::WindView(size, size));
  // Closer (0.6 of the focal distance, as paraview_vs_apc.py's closest camera): the data
  // fills the view and the buildings' walls graze the rays.
  apctest::View close = apctest::WindView(size, size);
  for (int d = 0; d < 3; ++d)
  {
    close.Position[d] = close.FocalPoint[d] + 0.6 * (close.Position[d] - close.FocalPoint[d]);
  }
  add("wind-close", wind, close);
  auto flange = ReadPoints(data + "/flange/flange.vtu", "T");
  double b[6];
  flange->GetBounds(b);
  add("flange", flange, FitView(b, 35, 30, 1.3, size));
  const double cube[6] = { -1, 1, -1, 1, -1, 1 };
  add("spheres", apctest::PuzzleGrid(vtkAPCPuzzleSource::SPHERES, 4, 4, 32),
    FitView(cube, 35, 25, 1.2, size));
  add("gearteeth", apctest::PuzzleGrid(vtkAPCPuzzleSource::SANDWICH, 4, 4, 24),
    FitView(cube, 35, 25, 1.2, size));
  return scenes;
}

struct Picture
{
  std::vector<float> RGB; // premultiplied, over black
  double CpuSeconds = 0;  // of the frame (for projected tetra its second)
  double Spacing = 0;     // the one the mapper used
};

// A window for a scene, its camera and transfer function.
struct Stage
{
  vtkNew<vtkRenderWindow> Window;
  vtkNew<vtkRenderer> Renderer;
  vtkNew<vtkVolume> Volume;

  Stage(const apctest::Scene& scene, vtkAbstractVolumeMapper* mapper)
  {
    const apctest::View& view = scene.Camera;
    this->Window->SetOffScreenRendering(1);
    this->Window->SetSize(view.Width, view.Height);
    this->Window->SetMultiSamples(0);
    this->Renderer->SetBackground(0, 0, 0);
    this->Window->AddRenderer(this->Renderer);
    this->Volume->SetMapper(mapper);
    this->Volume->SetProperty(apctest::MakeVolumeProperty(scene.TF));
    this->Renderer->AddVolume(this->Volume);
    apctest::ApplyView(this->Renderer, view);
    double bounds[6];
    scene.Grid->GetBounds(bounds);
    this->Renderer->ResetCameraClippingRange(bounds);
  }

  double TimedRender()
  {
    const double start = CpuSeconds();
    this->Window->Render();
    return CpuSeconds() - start;
  }
};

// One mapper for all APC cases of a scene: the mesh is converted once (in the first frame,
// untimed), each case then costs one frame.
class APCStage
{
public:
  explicit APCStage(const apctest::Scene& scene)
    : Scene(scene)
    , View(scene, this->Mapper)
  {
    this->Mapper->SetInputData(scene.Grid);
    this->Mapper->SetSampleDistance(0);
    this->View.Window->Render();
  }

  // endWeights -1: the mapper's default.
  Picture Render(int mode, double spacing, bool jitter, int endWeights = 0)
  {
    endWeights = endWeights < 0 ? this->DefaultEndWeights : endWeights;
    this->Mapper->SetMode(mode);
    this->Mapper->SetSampleDistance(spacing);
    this->Mapper->SetLatticeJitter(jitter);
    this->Mapper->SetSampleEndWeights(endWeights);
    if (endWeights != this->LastEndWeights)
    {
      // An untimed frame: the first with Boundary matches the mesh's boundary faces (once per
      // data change), which is not a frame's cost.
      this->View.Window->Render();
      this->LastEndWeights = endWeights;
    }
    Picture picture;
    picture.CpuSeconds = this->View.TimedRender();
    const apctest::Frame frame =
      apctest::ReadFrame(this->View.Window, this->Mapper, this->Scene.Camera);
    picture.RGB =
      apc::CompositeOverBackground(frame.RGBA.data(), frame.Width, frame.Height, { 0, 0, 0 });
    picture.Spacing = this->Mapper->GetLastSampleDistance();
    return picture;
  }

  const int DefaultEndWeights = vtkNew<vtkAPCVolumeMapper>()->GetSampleEndWeights();

private:
  const apctest::Scene& Scene;
  vtkNew<vtkAPCVolumeMapper> Mapper;
  Stage View;
  int LastEndWeights = -1;
};

// VTK's projected tetrahedra on VTK's tetrahedralisation: what the window shows over black,
// and the CPU time of a second frame (the first sorts nothing it can reuse either, but sets up).
Picture RenderProjectedTetra(const apctest::Scene& scene)
{
  vtkNew<vtkDataSetTriangleFilter> tets;
  tets->SetInputData(scene.Grid);
  tets->Update();
  vtkNew<vtkProjectedTetrahedraMapper> mapper;
  mapper->SetInputData(tets->GetOutput());
  Stage stage(scene, mapper);
  stage.Window->Render();
  Picture picture;
  picture.CpuSeconds = stage.TimedRender();
  const int w = scene.Camera.Width;
  const int h = scene.Camera.Height;
  vtkNew<vtkUnsignedCharArray> pixels;
  stage.Window->GetPixelData(0, 0, w - 1, h - 1, 0, pixels);
  picture.RGB.resize(static_cast<size_t>(3) * w * h);
  for (size_t v = 0; v < picture.RGB.size(); ++v)
  {
    picture.RGB[v] = pixels->GetValue(static_cast<vtkIdType>(v)) / 255.0f;
  }
  return picture;
}

void WritePicture(const std::vector<float>& rgb, int w, int h, const std::string& path)
{
  std::vector<float> rgba(static_cast<size_t>(4) * w * h);
  for (size_t p = 0; p < static_cast<size_t>(w) * h; ++p)
  {
    std::copy_n(&rgb[3 * p], 3, &rgba[4 * p]);
    rgba[4 * p + 3] = 1.0f;
  }
  apctest::WritePNG(path, rgba, w, h);
}

struct Case
{
  std::string Name;
  int Mode = vtkAPCVolumeMapper::MBOIT;
  double Spacing = 0; // 0: the mapper's default
  bool Jitter = false;
  // vtkAPCVolumeMapper::SetSampleEndWeights (0 off, 1 all, 2 boundary); -1: the mapper's default
  int EndWeights = 0;
};

constexpr int kOff = vtkAPCVolumeMapper::END_WEIGHTS_OFF;
constexpr int kBoundary = vtkAPCVolumeMapper::END_WEIGHTS_BOUNDARY;

// previous: the default before Sample End Weights = Boundary chose its own (one mean cell size,
// at least diagonal / 128, apc::DefaultSampleDistance's plain-lattice rule).
std::vector<Case> Cases(double diagonal, double cell, double previous)
{
  std::vector<Case> cases;
  const double old = diagonal / 256;
  for (int mode : { vtkAPCVolumeMapper::MBOIT, vtkAPCVolumeMapper::EXACT })
  {
    const std::string m = mode == vtkAPCVolumeMapper::EXACT ? "exact" : "mboit";
    cases.push_back({ m + "-diag256", mode, old, false });
    // Fixed numbers of samples along the diagonal: where a sparse mesh needs its floor.
    for (int n : { 96, 128, 160, 192 })
    {
      if (mode == vtkAPCVolumeMapper::MBOIT)
      {
        cases.push_back({ m + "-diag" + std::to_string(n), mode, diagonal / n, false });
      }
    }
    for (double f : { 0.5, 0.75, 1.0, 1.25, 1.5, 2.0 })
    {
      std::ostringstream name;
      name << m << "-cell" << f;
      if (mode == vtkAPCVolumeMapper::MBOIT || f == 1.0 || f == 1.25 || f == 2.0)
      {
        cases.push_back({ name.str(), mode, f * cell, false });
      }
      if (mode == vtkAPCVolumeMapper::MBOIT && f >= 1)
      {
        cases.push_back({ name.str() + "-jitter", mode, f * cell, true });
      }
    }
  }
  // What a user gets: every setting at the mapper's default (Sample End Weights = Boundary),
  // and the default of the plain lattice's modes (Sample End Weights Off; EXACT).
  cases.push_back({ "mboit-default", vtkAPCVolumeMapper::MBOIT, 0.0, false, -1 });
  cases.push_back({ "mboit-default-off", vtkAPCVolumeMapper::MBOIT, 0.0, false, kOff });
  cases.push_back({ "exact-default", vtkAPCVolumeMapper::EXACT, 0.0, false, -1 });
  // Boundary (the default end weights) at the previous default, at multiples of the mean cell
  // size and at fixed numbers of samples along the diagonal, with and without Lattice Jitter.
  cases.push_back(
    { "mboit-previous-boundary", vtkAPCVolumeMapper::MBOIT, previous, false, kBoundary });
  for (bool jitter : { false, true })
  {
    const std::string j = jitter ? "-jitter" : "";
    for (double f : { 1.0, 1.25, 1.5, 2.0, 3.0 })
    {
      std::ostringstream name;
      name << "mboit-cell" << f << "-boundary" << j;
      cases.push_back({ name.str(), vtkAPCVolumeMapper::MBOIT, f * cell, jitter, kBoundary });
    }
    for (int n : { 128, 96, 64 })
    {
      cases.push_back({ "mboit-diag" + std::to_string(n) + "-boundary" + j,
        vtkAPCVolumeMapper::MBOIT, diagonal / n, jitter, kBoundary });
    }
  }
  // Every cell's ends weighted (All) at the default and at coarser spacings.
  cases.push_back({ "mboit-default-weights", vtkAPCVolumeMapper::MBOIT, 0.0, false, 1 });
  for (double f : { 1.0, 1.25, 1.5, 2.0 })
  {
    std::ostringstream name;
    name << "cell" << f << "-weights";
    cases.push_back({ "mboit-" + name.str(), vtkAPCVolumeMapper::MBOIT, f * cell, false, 1 });
  }
  return cases;
}
} // namespace

int SpacingStudy(const std::string& data, const std::string& out, int size,
  const std::string& wanted, const std::string& wantedCases)
{
  std::ofstream csv(out + "/spacing.csv");
  const std::string header =
    "scene,case,mode,jitter,spacing,spacing_per_cell,"
    "samples_per_diagonal,ssim,psnr,max_abs_diff,cpu_s,mean_cell,end_weights";
  csv << header << "\n";
  std::cout << header << std::endl;
  for (const apctest::Scene& scene : SpacingScenes(data, size))
  {
    if (!wanted.empty() && ("," + wanted + ",").find("," + scene.Name + ",") == std::string::npos)
    {
      continue;
    }
    double b[6];
    scene.Grid->GetBounds(b);
    const double diagonal = apc::BoundsDiagonal(b);
    // The mean cell size as the mapper takes it: from the cells' own volume.
    apc::CellMesh mesh;
    std::string error;
    auto* grid = vtkUnstructuredGridBase::SafeDownCast(scene.Grid);
    if (!grid ||
      !apc::CellMeshFromVTK(grid, grid->GetPointData()->GetScalars(), false, mesh, error))
    {
      std::cerr << "error: " << scene.Name << ": " << error << "\n";
      return 1;
    }
    const double cells = static_cast<double>(mesh.GetNumberOfCells());
    const double cell = apc::MeanCellVolumeSize(mesh.GetCellVolume().Value(), cells);
    const double previous =
      apc::DefaultSampleDistance(b, cells, mesh.GetCellVolume().Value(), false);
    const std::vector<Case> cases = Cases(diagonal, cell, previous);
    double finest = previous;
    for (const Case& c : cases)
    {
      finest = c.Spacing > 0 ? std::min(finest, c.Spacing) : finest;
    }
    APCStage stage(scene);
    const Picture exact = stage.Render(vtkAPCVolumeMapper::EXACT, finest / 4, false);
    WritePicture(exact.RGB, size, size, out + "/spacing_" + scene.Name + "_reference.png");
    auto row = [&](const std::string& name, const char* mode, bool jitter, const Picture& p,
                 int endWeights = 0)
    {
      const apc::ImageComparison c =
        apc::CompareImages(p.RGB.data(), exact.RGB.data(), size, size, 3, 1.0, 16.0 / 255);
      std::ostringstream line;
      line.precision(6);
      line << scene.Name << "," << name << "," << mode << "," << (jitter ? 1 : 0) << ","
           << p.Spacing << "," << (p.Spacing > 0 ? p.Spacing / cell : 0) << ","
           << (p.Spacing > 0 ? diagonal / p.Spacing : 0) << "," << c.Ssim << "," << c.Psnr << ","
           << c.MaxAbsDiff << "," << p.CpuSeconds << "," << cell << "," << endWeights;
      csv << line.str() << std::endl;
      std::cout << line.str() << std::endl;
      WritePicture(p.RGB, size, size, out + "/spacing_" + scene.Name + "_" + name + ".png");
    };
    row("reference", "exact", false, exact);
    for (const Case& c : cases)
    {
      if (!wantedCases.empty() &&
        ("," + wantedCases + ",").find("," + c.Name + ",") == std::string::npos)
      {
        continue;
      }
      row(c.Name, c.Mode == vtkAPCVolumeMapper::EXACT ? "exact" : "mboit", c.Jitter,
        stage.Render(c.Mode, c.Spacing, c.Jitter, c.EndWeights),
        c.EndWeights < 0 ? stage.DefaultEndWeights : c.EndWeights);
    }
    if (wantedCases.empty() ||
      ("," + wantedCases + ",").find(",projected-tetra,") != std::string::npos)
    {
      row("projected-tetra", "pt", false, RenderProjectedTetra(scene));
    }
  }
  return csv ? 0 : 1;
}

} // namespace apcbench
