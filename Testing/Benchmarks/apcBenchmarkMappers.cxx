// SPDX-License-Identifier: BSD-3-Clause
// Frame times of vtkAPCVolumeMapper (EXACT and MBOIT, 1 and 2 threads) against VTK's own
// unstructured-grid volume mappers (Bunyk ray casting, ZSweep, projected tetrahedra) on the
// same mesh, camera, transfer function and image size. Writes one CSV row per
// dataset x mapper x mode x threads and, per dataset, one PNG of what each mapper shows.
//
//   apcBenchmarkMappers [--size N] [--quick] [--repeats N] [--datasets gear,wind,flange]
//     [--out DIR] [--csv FILE] [--data DIR] [--threads 1,2] [--zsweep-max-cells N]
//     [--time-cap S] [--spacing-scale F] [--moments 4|6|8] [--mappers bunyk,exact,mboit,zsweep,pt]
//     [--no-images] [--setup benchmark|paraview] [--dolly F] [--no-compare]
//     [--linear-tolerance BINS] [--no-stop] [--lower60] [--field NAME] [--end-weights]
//     [--boundary-weights] [--no-end-weights] [--no-lanes] [--opaque-absorbance A[,B,...]]
//
// Mapper "sampler" times the core ray marcher alone (apcSamplerTiming.h): CPU nanoseconds per
// pass-1 sample and per pass-2 cached sample, the share of samples skipped behind opaque, and
// the resolved image's largest difference from the exact blend. --setup paraview renders as
// ParaView does by default: a linear opacity ramp over the data range, a cool-to-warm colour
// map, the opacity unit distance ParaView derives from the bounds (diagonal / cells^(1/3)) and
// APC's default sample distance and Sample End Weights (Boundary; --no-end-weights: Off), as the
// mapper takes them (apcDefaultSpacing.h; with --spacing-scale F, F times that distance); the
// sampler takes the same distance. --opaque-absorbance times the sampler with each of these
// thresholds of the opaque stop instead of the marcher's recommended one (a benchmark-only
// knob: the mapper always takes the recommended one), in turn within each repeat, one row each,
// with the image's PSNR and SSIM against the exact blend and its change from the first
// threshold's image (ln 10^4 = 9.21034, ln 10^3 = 6.90776, ln 10^2.5 = 5.75646,
// ln 255 = 5.54126).
//
// Run under an X server (xvfb-run); Testing/Benchmarks/run-benchmark.sh does everything.
#include "vtkAPCPuzzleSource.h"
#include "vtkAPCVolumeMapper.h"

#include "apcCellMesh.h"
#include "apcCellMeshFromVTK.h"
#include "apcDefaultSpacing.h"
#include "apcImageMetrics.h"
#include "apcSamplerTiming.h"
#include "apcTestImages.h"
#include "apcTestPuzzles.h"
#include "apcTestScenes.h"
#include "apcTestStatistics.h"

#include "vtkCallbackCommand.h"
#include "vtkCamera.h"
#include "vtkCellData.h"
#include "vtkDataArray.h"
#include "vtkDataSetTriangleFilter.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkProjectedTetrahedraMapper.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"
#include "vtkStaticCleanUnstructuredGrid.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"
#include "vtkUnstructuredGridBase.h"
#include "vtkUnstructuredGridPreIntegration.h"
#include "vtkUnstructuredGridVolumeRayCastMapper.h"
#include "vtkUnstructuredGridVolumeRayIntegrator.h"
#include "vtkUnstructuredGridVolumeZSweepMapper.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"
#include "vtkXMLPUnstructuredGridReader.h"
#include "vtkXMLUnstructuredGridReader.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#ifndef APC_SOURCE_DIR
#define APC_SOURCE_DIR "."
#endif

namespace
{

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start)
{
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// CPU seconds of all threads of this process (llvmpipe's GL threads included). Next to the
// wall clock it tells whether a frame had its cores to itself: on a shared machine the wall
// time grows, the CPU time much less.
double ProcessCpuSeconds()
{
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// Bunyk and ZSweep hand every ray's cell segments to a ray integrator, one segment per cell
// crossed; counting them gives these mappers' "samples", the number to set against APC's
// lattice samples. The wrapped integrator is the one the mappers pick by themselves for point
// scalars with independent components, so the work is the same as without the counter.
class CountingRayIntegrator : public vtkUnstructuredGridVolumeRayIntegrator
{
public:
  static CountingRayIntegrator* New();
  vtkTypeMacro(CountingRayIntegrator, vtkUnstructuredGridVolumeRayIntegrator);

  void Initialize(vtkVolume* volume, vtkDataArray* scalars) override
  {
    this->Inner->Initialize(volume, scalars);
  }
  void Integrate(vtkDoubleArray* lengths, vtkDataArray* nearValues, vtkDataArray* farValues,
    float color[4]) override
  {
    this->Segments.fetch_add(lengths->GetNumberOfTuples(), std::memory_order_relaxed);
    this->Inner->Integrate(lengths, nearValues, farValues, color);
  }
  int64_t TakeCount() { return this->Segments.exchange(0); }

protected:
  CountingRayIntegrator() = default;
  ~CountingRayIntegrator() override = default;

private:
  vtkNew<vtkUnstructuredGridPreIntegration> Inner;
  std::atomic<int64_t> Segments{ 0 };
};
vtkStandardNewMacro(CountingRayIntegrator);

struct Options
{
  int Size = 1024;
  int Repeats = 3;
  bool Quick = false;
  bool Images = true;
  std::vector<std::string> Datasets = { "gear", "wind", "flange" };
  std::vector<int> Threads = { 1, 2 };
  std::vector<std::string> Mappers = { "bunyk", "exact", "mboit", "zsweep", "pt" };
  std::string Out = "out/benchmark";
  std::string Csv;
  std::string Data = APC_SOURCE_DIR "/Data";
  // ZSweep took no frame within 300 s on 330k cells in an earlier probe; it is run only below
  // this many tetrahedra, and every VTK mapper's frame is aborted after TimeCap seconds.
  vtkIdType ZSweepMaxCells = 100000;
  double TimeCap = 120.0;
  double SpacingScale = 1.0;
  bool SpacingScaleGiven = false; // --setup paraview: APC's default distance times SpacingScale
  double LinearTolerance = NAN;   // sampler: the linear inverse's tolerance in bins (NaN: default)
  bool Lower60 = false;        // --setup paraview: the ramp with the lower 60 % of the range clear
  std::string WindField = "p"; // --field: the wind's point array (paraview_vs_apc.py: U_mag)
  bool Stop = true; // sampler: time with the recommended opaque stop (off: as ParaView renders)
  // APC and sampler: vtkAPCVolumeMapper::SetSampleEndWeights (2: boundary); -1: the mapper's
  // default with --setup paraview, off with --setup benchmark
  int EndWeights = -1;
  bool Lanes = true; // sampler: VolumeRayMarcher::SetSampleLanes (--no-lanes: scalar loops)
  int Moments = 4;   // APC's MBOIT moments
  std::string Setup = "benchmark"; // or "paraview": ParaView's default transfer function
  double Dolly = 1.0;              // times the data set's own dolly
  bool Compare = true; // the sampler's untimed exact and unstopped frames (errors, hidden share)
  // sampler: the opaque stop's thresholds (absorbance, each > 0, inf: no stop); empty: the
  // marcher's recommended one (or none with --no-stop)
  std::vector<double> OpaqueAbsorbances;
};

// A shared scene (its Grid: the original cells, what APC renders) plus what VTK's mappers
// need and how the camera frames the data (Camera.Position is only the direction from the
// focal point towards the eye: ResetCamera sets the distance).
struct MapperScene : apctest::Scene
{
  vtkSmartPointer<vtkUnstructuredGrid> Tets; // what Bunyk, ZSweep and PT render
  double TetSeconds = 0;
  std::string Field;
  double Azimuth = 30;
  double Elevation = 25;
  double Dolly = 1.0;
  std::string Note;
};

struct Row
{
  std::string Dataset;
  vtkIdType Cells = 0;
  std::string Image;
  std::string Mapper;
  std::string Mode;
  std::string Threads;
  double FirstFrame = NAN;
  double Frame = NAN;
  double Pass1 = NAN;
  double Pass2 = NAN;
  double Setup = NAN;
  double Cpu = NAN;
  double Samples = NAN;
  double RatioToBunyk = NAN;
  double Spacing = NAN;
  apcbench::SamplerTiming Sampler; // mapper "sampler" only
  std::string Note;
  int BunykThreads = 0; // which Bunyk row the ratio refers to
};

std::vector<std::string> Split(const std::string& text)
{
  std::vector<std::string> parts;
  std::stringstream stream(text);
  std::string part;
  while (std::getline(stream, part, ','))
  {
    if (!part.empty())
    {
      parts.push_back(part);
    }
  }
  return parts;
}

// Cell size whose cube fills the bounding box evenly: about the distance between cell faces
// along a ray, i.e. one APC sample per cell crossed, which is what Bunyk integrates.
double MeanCellSize(vtkDataSet* grid)
{
  double b[6];
  grid->GetBounds(b);
  const double volume = (b[1] - b[0]) * (b[3] - b[2]) * (b[5] - b[4]);
  return std::cbrt(volume / static_cast<double>(grid->GetNumberOfCells()));
}

// What vtkAPCVolumeMapper takes for sample distance 0 on grid alone (its cells' own volume),
// with or without weighted ends.
double MapperDefaultSpacing(vtkDataSet* grid, bool weightedEnds)
{
  auto* cells = vtkUnstructuredGridBase::SafeDownCast(grid);
  apc::CellMesh mesh;
  std::string error;
  if (!cells ||
    !apc::CellMeshFromVTK(cells, grid->GetPointData()->GetScalars(), false, mesh, error))
  {
    std::cerr << "error: the mapper's default spacing: " << error << "\n";
    std::exit(2);
  }
  return apc::DefaultSampleDistance(mesh.GetBounds().data(),
    static_cast<double>(mesh.GetNumberOfCells()), mesh.GetCellVolume().Value(), weightedEnds);
}

vtkSmartPointer<vtkUnstructuredGrid> ReadGrid(const std::string& path)
{
  vtkSmartPointer<vtkUnstructuredGrid> grid;
  if (path.size() > 5 && path.substr(path.size() - 5) == ".pvtu")
  {
    vtkNew<vtkXMLPUnstructuredGridReader> reader;
    reader->SetFileName(path.c_str());
    reader->Update();
    grid = reader->GetOutput();
  }
  else
  {
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    reader->SetFileName(path.c_str());
    reader->Update();
    grid = reader->GetOutput();
  }
  if (!grid || grid->GetNumberOfCells() == 0)
  {
    std::cerr << "error: could not read " << path << "\n";
    std::exit(2);
  }
  return grid;
}

// The same mesh with only the rendered point array (smaller tetrahedralisation, and no other
// array can be picked up as scalars by a mapper).
vtkSmartPointer<vtkUnstructuredGrid> KeepField(vtkUnstructuredGrid* in, const std::string& field)
{
  auto out = vtkSmartPointer<vtkUnstructuredGrid>::New();
  out->ShallowCopy(in);
  out->GetPointData()->Initialize();
  out->GetCellData()->Initialize();
  vtkDataArray* array = in->GetPointData()->GetArray(field.c_str());
  if (!array)
  {
    std::cerr << "error: no point array " << field << "\n";
    std::exit(2);
  }
  out->GetPointData()->SetScalars(array);
  return out;
}

// ParaView's default look for a freshly coloured volume: the cool-to-warm map and a linear
// opacity ramp over the data range, the opacity unit distance of ParaView's
// "approximate_cell_length" bounds domain and APC's default sample distance (0).
void UseParaViewDefaults(MapperScene& scene)
{
  double range[2];
  scene.Grid->GetPointData()->GetScalars()->GetRange(range);
  const double mid = 0.5 * (range[0] + range[1]);
  scene.TF.Colours = { { range[0], 0.23, 0.299, 0.754 }, { mid, 0.865, 0.865, 0.865 },
    { range[1], 0.706, 0.016, 0.15 } };
  scene.TF.Opacities = { { range[0], 0.0 }, { range[1], 1.0 } };
  double b[6];
  scene.Grid->GetBounds(b);
  const double diagonal = std::sqrt(
    (b[1] - b[0]) * (b[1] - b[0]) + (b[3] - b[2]) * (b[3] - b[2]) + (b[5] - b[4]) * (b[5] - b[4]));
  scene.TF.UnitDistance = diagonal / std::cbrt(static_cast<double>(scene.Grid->GetNumberOfCells()));
  scene.SampleDistance = 0.0;
  scene.Note += std::string(scene.Note.empty() ? "" : "; ") + "ParaView's default setup";
}

MapperScene MakeScene(const std::string& name, const Options& options, bool tetrahedra)
{
  MapperScene scene;
  scene.Name = name;
  scene.Camera.Position = { 0, 0, 1 };
  if (name == "gear")
  {
    // The APC paper's gear teeth: 4 pieces x 4 slabs x 64 x 64 x 2 hexahedra in [-1,1]^3,
    // a red core (1) inside a blue shell (0.5).
    vtkSmartPointer<vtkUnstructuredGrid> puzzle =
      apctest::PuzzleGrid(vtkAPCPuzzleSource::SPHERES, 4, 4, 64);
    scene.Field = puzzle->GetPointData()->GetScalars()->GetName();
    scene.Grid = KeepField(puzzle, scene.Field);
    scene.TF.Colours = { { 0.0, 0.2, 0.3, 1.0 }, { 0.5, 0.2, 0.4, 1.0 }, { 1.0, 1.0, 0.15, 0.1 } };
    scene.TF.Opacities = { { 0.0, 0.0 }, { 0.25, 0.0 }, { 0.5, 0.25 }, { 0.75, 0.05 },
      { 1.0, 0.8 } };
    scene.TF.UnitDistance = 0.1;
    scene.Dolly = 1.5; // the spheres, not the clear corners of the box
  }
  else if (name == "wind")
  {
    // Kinematic pressure around the buildings: stagnation on the windward walls (red) and
    // suction at the roof edges and in the wakes (blue); the near-zero free stream is clear.
    scene.Field = options.WindField;
    vtkSmartPointer<vtkUnstructuredGrid> raw =
      ReadGrid(options.Data + "/windAroundBuildings/wind.pvtu");
    // The 8 Scotch pieces each carry their interface points; merging the coincident ones
    // (identical values, see Data/README.md) gives one conforming mesh, so Bunyk and ZSweep
    // do not see internal boundary faces between pieces. The cells are unchanged.
    vtkNew<vtkStaticCleanUnstructuredGrid> clean;
    clean->SetInputData(KeepField(raw, scene.Field));
    clean->Update();
    scene.Grid = clean->GetOutput();
    scene.TF.Colours = { { -125.0, 0.1, 0.2, 0.9 }, { -20.0, 0.5, 0.7, 1.0 },
      { 0.0, 0.9, 0.9, 0.9 }, { 30.0, 1.0, 0.75, 0.4 }, { 196.0, 0.85, 0.05, 0.05 } };
    // About 3 % of the points on either side are visible (p percentiles: 5 % below -25,
    // 5 % above 62), so the upstream over-pressure does not hide the buildings.
    scene.TF.Opacities = { { -125.0, 0.9 }, { -30.0, 0.25 }, { -20.0, 0.0 }, { 60.0, 0.0 },
      { 100.0, 0.3 }, { 196.0, 0.9 } };
    scene.TF.UnitDistance = 4.0;
    scene.Camera.Position = { 0.0, -1.0, 0.0 };
    scene.Camera.ViewUp = { 0.0, 0.0, 1.0 };
    scene.Azimuth = -35;
    scene.Elevation = 35;
    scene.Dolly = 1.3; // the buildings sit low in the middle of the domain
    scene.Note = "points merged across the 8 pieces";
  }
  else if (name == "flange")
  {
    scene.Field = "T";
    scene.Grid = KeepField(ReadGrid(options.Data + "/flange/flange.vtu"), scene.Field);
    scene.TF.Colours = { { 273.0, 0.23, 0.3, 0.75 }, { 423.0, 0.87, 0.87, 0.87 },
      { 573.0, 0.7, 0.02, 0.15 } };
    scene.TF.Opacities = { { 273.0, 0.15 }, { 423.0, 0.02 }, { 573.0, 0.6 } };
    scene.TF.UnitDistance = 0.002;
    scene.Camera.Position = { 0.0, -1.0, 0.0 };
    scene.Camera.ViewUp = { 0.0, 0.0, 1.0 };
    scene.Azimuth = 35;
    scene.Elevation = 30;
    scene.Dolly = 1.6;
  }
  else
  {
    std::cerr << "error: unknown dataset " << name << " (gear, wind, flange)\n";
    std::exit(2);
  }
  scene.SampleDistance = options.SpacingScale * MeanCellSize(scene.Grid);
  scene.Dolly *= options.Dolly;
  if (options.Setup == "paraview")
  {
    UseParaViewDefaults(scene);
    if (options.Lower60)
    {
      // As paraview_vs_apc.py --opacity lower60: clear up to 60 % of the range, then 0 to 1.
      const double lo = scene.TF.Opacities.front()[0];
      const double hi = scene.TF.Opacities.back()[0];
      scene.TF.Opacities = { { lo, 0.0 }, { lo + 0.6 * (hi - lo), 0.0 }, { hi, 1.0 } };
      scene.Note += "; lower 60 % of the range transparent";
    }
    if (options.SpacingScaleGiven)
    {
      // F times what the mapper takes by default with these end weights (the box's mean cell
      // size, 3.458 on the wind, is not the mapper's default, 3.375 or 4.219 there).
      scene.SampleDistance =
        options.SpacingScale * MapperDefaultSpacing(scene.Grid, options.EndWeights != 0);
    }
  }

  // Bunyk assumes tetrahedra and ZSweep reads only the first three points of every face, so
  // VTK's mappers get VTK's own tetrahedralisation; APC renders the original cells.
  scene.Tets = vtkSmartPointer<vtkUnstructuredGrid>::New();
  if (!tetrahedra)
  {
    return scene;
  }
  const auto start = Clock::now();
  vtkNew<vtkDataSetTriangleFilter> tets;
  tets->SetInputData(scene.Grid);
  tets->Update();
  scene.Tets = tets->GetOutput();
  scene.TetSeconds = SecondsSince(start);
  return scene;
}

// One render window per mapper configuration, so that no state carries over between them.
struct Stage
{
  vtkNew<vtkRenderWindow> Window;
  vtkNew<vtkRenderer> Renderer;
  vtkNew<vtkVolume> Volume;
  vtkSmartPointer<vtkVolumeProperty> Property;
  Clock::time_point FrameStart = Clock::now();
  double TimeCap = 0;
  bool Aborted = false;
  double LastCpuSeconds = 0;

  Stage(const MapperScene& scene, int size, double timeCap)
    : TimeCap(timeCap)
  {
    this->Window->SetOffScreenRendering(1);
    this->Window->SetMultiSamples(0);
    this->Window->SetSize(size, size);
    this->Window->AddRenderer(this->Renderer);
    this->Renderer->SetBackground(0.32, 0.34, 0.43); // ParaView's default background
    this->Property = apctest::MakeVolumeProperty(scene.TF);
    this->Property->SetInterpolationTypeToLinear();
    this->Property->ShadeOff();
    this->Volume->SetProperty(this->Property);
    this->Renderer->AddVolume(this->Volume);

    // Bunyk and ZSweep poll the window while they work: that is the only way to stop a
    // frame that would take minutes.
    vtkNew<vtkCallbackCommand> abortCheck;
    abortCheck->SetClientData(this);
    abortCheck->SetCallback(
      [](vtkObject*, unsigned long, void* data, void*)
      {
        auto* stage = static_cast<Stage*>(data);
        if (SecondsSince(stage->FrameStart) > stage->TimeCap)
        {
          stage->Aborted = true;
          stage->Window->SetAbortRender(1);
        }
      });
    this->Window->AddObserver(vtkCommand::AbortCheckEvent, abortCheck);
  }

  void SetMapper(vtkAbstractVolumeMapper* mapper, const MapperScene& scene)
  {
    this->Volume->SetMapper(mapper);
    vtkCamera* camera = this->Renderer->GetActiveCamera();
    camera->SetFocalPoint(scene.Camera.FocalPoint.data());
    camera->SetPosition(scene.Camera.Position.data());
    camera->SetViewUp(scene.Camera.ViewUp.data());
    double bounds[6];
    scene.Grid->GetBounds(bounds);
    this->Renderer->ResetCamera(bounds);
    camera->Azimuth(scene.Azimuth);
    camera->Elevation(scene.Elevation);
    camera->OrthogonalizeViewUp();
    camera->Dolly(scene.Dolly); // ResetCamera fits the bounding sphere: loose for most data
    this->Renderer->ResetCameraClippingRange(bounds);
  }

  // Wall-clock seconds of one frame, GPU work included.
  double Render()
  {
    this->FrameStart = Clock::now();
    const double cpu = ProcessCpuSeconds();
    this->Aborted = false;
    this->Window->Render();
    this->Window->WaitForCompletion();
    this->LastCpuSeconds = ProcessCpuSeconds() - cpu;
    return SecondsSince(this->FrameStart);
  }

  std::vector<unsigned char> Pixels()
  {
    const int* size = this->Window->GetSize();
    vtkNew<vtkUnsignedCharArray> pixels;
    this->Window->GetPixelData(0, 0, size[0] - 1, size[1] - 1, 0, pixels);
    return std::vector<unsigned char>(
      pixels->GetPointer(0), pixels->GetPointer(0) + 3 * size[0] * size[1]);
  }
};

std::string Format(double value, int precision = 4)
{
  if (std::isnan(value))
  {
    return "";
  }
  std::ostringstream out;
  out << std::setprecision(precision) << value;
  return out.str();
}

std::string Quote(const std::string& text)
{
  if (text.find_first_of(",\"") == std::string::npos)
  {
    return text;
  }
  std::string quoted = "\"";
  for (char c : text)
  {
    quoted += c;
    if (c == '"')
    {
      quoted += '"';
    }
  }
  return quoted + "\"";
}

class Benchmark
{
public:
  explicit Benchmark(const Options& options)
    : Opt(options)
  {
  }

  void RunDataset(const std::string& name)
  {
    std::cerr << "== " << name << ": preparing\n";
    const MapperScene scene = MakeScene(
      name, this->Opt, this->Wants("bunyk") || this->Wants("zsweep") || this->Wants("pt"));
    std::cerr << "   " << scene.Grid->GetNumberOfCells() << " cells, "
              << scene.Tets->GetNumberOfCells() << " tetrahedra (" << Format(scene.TetSeconds, 3)
              << " s), spacing " << scene.SampleDistance << "\n";
    const size_t first = this->Rows.size();
    const int maxThreads = *std::max_element(this->Opt.Threads.begin(), this->Opt.Threads.end());

    for (int threads : this->Opt.Threads)
    {
      if (this->Wants("bunyk"))
      {
        this->RunBunyk(scene, threads, threads == maxThreads);
      }
    }
    for (int mode : { vtkAPCVolumeMapper::EXACT, vtkAPCVolumeMapper::MBOIT })
    {
      if (!this->Wants(mode == vtkAPCVolumeMapper::EXACT ? "exact" : "mboit"))
      {
        continue;
      }
      for (int threads : this->Opt.Threads)
      {
        this->RunAPC(scene, mode, threads, threads == maxThreads, scene.SampleDistance, "");
      }
    }
    // The mean-cell-size spacing takes one sample per original cell, but Bunyk integrates one
    // segment per tetrahedron (5-6 per hexahedron): also time MBOIT with about as many
    // samples as Bunyk has segments, the other reading of "comparable sampling".
    const double bunykSamples = this->FindSamples(first, "bunyk", "", maxThreads);
    // Bunyk integrates every segment, visible or not; APC skips the cells the transfer
    // function hides, so the match counts the lattice samples inside all cells.
    const double apcSamples =
      bunykSamples > 0 ? LatticeSamples(scene, this->Opt.Size, scene.SampleDistance) : NAN;
    if (bunykSamples > 0 && apcSamples > 0)
    {
      this->RunAPC(scene, vtkAPCVolumeMapper::MBOIT, maxThreads, true,
        scene.SampleDistance * apcSamples / bunykSamples, "mboit-matched");
    }
    for (int threads : this->Opt.Threads)
    {
      if (this->Wants("sampler"))
      {
        this->RunSampler(scene, threads);
      }
    }
    if (this->Wants("zsweep"))
    {
      this->RunZSweep(scene);
    }
    if (this->Wants("pt"))
    {
      this->RunPT(scene, maxThreads);
    }

    // Ratios against Bunyk with the same number of threads (PT against the most threads).
    std::map<int, double> bunyk;
    for (size_t r = first; r < this->Rows.size(); ++r)
    {
      if (this->Rows[r].Mapper == "bunyk")
      {
        bunyk[this->Rows[r].BunykThreads] = this->Rows[r].Frame;
      }
    }
    for (size_t r = first; r < this->Rows.size(); ++r)
    {
      Row& row = this->Rows[r];
      auto it = bunyk.find(row.BunykThreads);
      if (it != bunyk.end() && row.Frame > 0)
      {
        row.RatioToBunyk = it->second / row.Frame;
      }
    }
    this->CompareImages(scene);
  }

  static void WriteCsvHeader(std::ostream& out)
  {
    out
      << "dataset,cells,image,mapper,mode,threads,first_frame_s,frame_s,pass1_s,pass2_s,"
         "samples,samples_per_s,ratio_to_bunyk,note,setup_s,spacing,cpu_s,"
         "pass1_ns_per_sample,pass2_ns_per_cached_sample,hidden_share,all_samples,cache_share,"
         "error_vs_exact,stop_change,stop_change_share,error_vs_exact_unstopped,worse_share,"
         "mesh_s,finalize_s,linear_change,pass2_hidden_share,pass2_hidden_share_unstopped,"
         "opaque_absorbance,pass2_samples,psnr_vs_exact,ssim_vs_exact,psnr_vs_exact_unstopped,"
         "ssim_vs_exact_unstopped,change_from_first,worse_than_first_share,most_worse_than_first\n";
  }

  // Rows from index first on; written per data set so that a crash keeps what was measured.
  void WriteCsv(std::ostream& out, size_t first) const
  {
    for (size_t r = first; r < this->Rows.size(); ++r)
    {
      const Row& row = this->Rows[r];
      const double perSecond = row.Samples / row.Frame;
      out << row.Dataset << ',' << row.Cells << ',' << row.Image << ',' << row.Mapper << ','
          << row.Mode << ',' << row.Threads << ',' << Format(row.FirstFrame) << ','
          << Format(row.Frame) << ',' << Format(row.Pass1) << ',' << Format(row.Pass2) << ','
          << (std::isnan(row.Samples) ? "" : std::to_string(static_cast<int64_t>(row.Samples)))
          << ',' << Format(perSecond, 3) << ',' << Format(row.RatioToBunyk, 3) << ','
          << Quote(row.Note) << ',' << Format(row.Setup) << ',' << Format(row.Spacing) << ','
          << Format(row.Cpu) << ',';
      const apcbench::SamplerTiming& s = row.Sampler;
      if (s.Valid)
      {
        out << Format(s.Pass1NanosecondsPerSample()) << ',' << Format(s.Pass2NanosecondsPerSample())
            << ',' << Format(s.HiddenShare()) << ',' << s.AllSamples << ',' << Format(s.CacheShare)
            << ',' << Format(s.ErrorVsExact) << ',' << Format(s.StopChange) << ','
            << Format(s.StopChangeShare) << ',' << Format(s.ErrorVsExactAll) << ','
            << Format(s.WorseShare) << ',' << Format(s.MeshSeconds) << ','
            << Format(s.FinalizeSeconds) << ',' << Format(s.LinearChange) << ','
            << Format(s.Pass2HiddenShare) << ',' << Format(s.Pass2HiddenShareUnstopped) << ','
            << Format(s.OpaqueAbsorbance, 10) << ',' << s.Pass2Samples << ','
            << Format(s.PsnrVsExact, 6) << ',' << Format(s.SsimVsExact, 7) << ','
            << Format(s.PsnrVsExactAll, 6) << ',' << Format(s.SsimVsExactAll, 7) << ','
            << Format(s.ChangeFromFirst) << ',' << Format(s.WorseThanFirstShare) << ','
            << Format(s.MostWorseThanFirst);
      }
      else
      {
        out << ",,,,,,,,,,,,,,,,,,,,,,,";
      }
      out << '\n';
    }
    out.flush();
  }

  size_t GetNumberOfRows() const { return this->Rows.size(); }

private:
  bool Wants(const std::string& mapper) const
  {
    return std::find(this->Opt.Mappers.begin(), this->Opt.Mappers.end(), mapper) !=
      this->Opt.Mappers.end();
  }

  Row NewRow(const MapperScene& scene, vtkIdType cells, const std::string& mapper,
    const std::string& mode, const std::string& threads)
  {
    Row row;
    row.Dataset = scene.Name;
    row.Cells = cells;
    row.Image = std::to_string(this->Opt.Size) + "x" + std::to_string(this->Opt.Size);
    row.Mapper = mapper;
    row.Mode = mode;
    row.Threads = threads;
    return row;
  }

  std::string TetNote(const MapperScene& scene) const
  {
    return "tetrahedralized by vtkDataSetTriangleFilter (" + Format(scene.TetSeconds, 3) +
      " s, not timed)";
  }

  // Warm-up frame, then the timed ones; perFrame runs after each frame (timed or not) and
  // receives its index (-1 for the warm-up).
  void Time(Stage& stage, Row& row, const std::function<void(int)>& perFrame)
  {
    row.FirstFrame = stage.Render();
    if (stage.Aborted)
    {
      row.FirstFrame = NAN;
      row.Note = "skipped (no frame within " + Format(stage.TimeCap, 3) + " s time cap)";
      return;
    }
    perFrame(-1);
    // A frame of many seconds is measured once: repeats would not change the picture.
    const int repeats = row.FirstFrame > 20.0 ? 1 : this->Opt.Repeats;
    std::vector<double> frames;
    std::vector<double> cpu;
    for (int f = 0; f < repeats; ++f)
    {
      const double seconds = stage.Render();
      if (stage.Aborted)
      {
        row.Note = "timed frame hit the time cap";
        break;
      }
      frames.push_back(seconds);
      cpu.push_back(stage.LastCpuSeconds);
      perFrame(f);
    }
    row.Frame = apctest::Median(frames);
    row.Cpu = apctest::Median(cpu);
    if (repeats != this->Opt.Repeats)
    {
      row.Note += std::string(row.Note.empty() ? "" : "; ") + "1 timed frame (slow)";
    }
  }

  void Report(const Row& row)
  {
    std::cerr << "   " << std::left << std::setw(7) << row.Mapper << std::setw(6) << row.Mode
              << " threads " << std::setw(3) << row.Threads << " first " << std::setw(8)
              << Format(row.FirstFrame) << " frame " << std::setw(8) << Format(row.Frame) << " cpu "
              << std::setw(8) << Format(row.Cpu) << (row.Note.empty() ? "" : "  [" + row.Note + "]")
              << std::right << "\n";
  }

  void KeepImage(const MapperScene& scene, const std::string& tag, Stage& stage)
  {
    if (stage.Aborted)
    {
      return;
    }
    std::vector<unsigned char> pixels = stage.Pixels();
    if (this->Opt.Images)
    {
      apctest::WritePNG(this->Opt.Out + "/" + scene.Name + "_" + tag + ".png", pixels,
        this->Opt.Size, this->Opt.Size);
    }
    this->Images[tag] = std::move(pixels);
  }

  // Bunyk and ZSweep (no common base class with these setters): the tetrahedra, one ray per
  // pixel, and the integrated cell segments counted as their samples.
  template <class RayIntegratingMapper>
  void TimeCountingSegments(
    Stage& stage, Row& row, RayIntegratingMapper* mapper, const MapperScene& scene)
  {
    mapper->SetInputData(scene.Tets);
    mapper->AutoAdjustSampleDistancesOff();
    mapper->SetImageSampleDistance(1.0);
    vtkNew<CountingRayIntegrator> counter;
    mapper->SetRayIntegrator(counter);
    stage.SetMapper(mapper, scene);
    std::vector<double> samples;
    this->Time(stage, row,
      [&](int frame)
      {
        const int64_t count = counter->TakeCount();
        if (frame >= 0)
        {
          samples.push_back(static_cast<double>(count));
        }
      });
    row.Samples = apctest::Median(samples);
  }

  void RunBunyk(const MapperScene& scene, int threads, bool keepImage)
  {
    Row row = NewRow(scene, scene.Tets->GetNumberOfCells(), "bunyk", "", std::to_string(threads));
    row.BunykThreads = threads;
    Stage stage(scene, this->Opt.Size, this->Opt.TimeCap);
    vtkNew<vtkUnstructuredGridVolumeRayCastMapper> mapper;
    mapper->SetNumberOfThreads(threads);
    this->TimeCountingSegments(stage, row, mapper.GetPointer(), scene);
    row.Note += std::string(row.Note.empty() ? "" : "; ") + TetNote(scene) +
      "; samples = cell segments integrated (early ray termination at alpha 0.99)";
    if (keepImage)
    {
      this->KeepImage(scene, "bunyk", stage);
    }
    this->Report(row);
    this->Rows.push_back(row);
  }

  // Lattice samples inside the cells at this spacing, whatever the transfer function hides:
  // one untimed exact frame with a faint opacity everywhere, so that no cell is skipped.
  static double LatticeSamples(const MapperScene& scene, int size, double spacing)
  {
    MapperScene faint = scene;
    faint.TF.Opacities = { { faint.TF.Min, 1e-6 }, { faint.TF.Max, 1e-6 } };
    Stage stage(faint, size, 1e9);
    vtkNew<vtkAPCVolumeMapper> mapper;
    mapper->SetInputData(faint.Grid);
    mapper->SetMode(vtkAPCVolumeMapper::EXACT);
    mapper->SetSampleDistance(spacing);
    stage.SetMapper(mapper, faint);
    stage.Render();
    vtkDataArray* count = mapper->GetLastImage()->GetFieldData()->GetArray("SampleCount");
    return count ? count->GetTuple1(0) : NAN;
  }

  double FindSamples(
    size_t first, const std::string& mapper, const std::string& mode, int threads) const
  {
    for (size_t r = first; r < this->Rows.size(); ++r)
    {
      const Row& row = this->Rows[r];
      if (row.Mapper == mapper && row.Mode == mode && row.Threads == std::to_string(threads))
      {
        return row.Samples;
      }
    }
    return NAN;
  }

  // label: the mode column, if not the mode's own name.
  void RunAPC(const MapperScene& scene, int mode, int threads, bool keepImage, double spacing,
    const std::string& label)
  {
    const bool mboit = mode == vtkAPCVolumeMapper::MBOIT;
    const std::string modeName = label.empty() ? (mboit ? "mboit" : "exact") : label;
    Row row =
      NewRow(scene, scene.Grid->GetNumberOfCells(), "apc", modeName, std::to_string(threads));
    row.BunykThreads = threads;
    Stage stage(scene, this->Opt.Size, this->Opt.TimeCap);
    vtkNew<vtkAPCVolumeMapper> mapper;
    mapper->SetInputData(scene.Grid);
    mapper->SetMode(mode);
    mapper->SetNumberOfThreads(threads);
    mapper->SetSampleEndWeights(this->Opt.EndWeights);
    mapper->SetSampleDistance(spacing);
    mapper->SetNumberOfMoments(this->Opt.Moments);
    stage.SetMapper(mapper, scene);
    std::vector<double> pass1, pass2, setup, samples;
    double mesh = 0;
    this->Time(stage, row,
      [&](int frame)
      {
        if (frame < 0)
        {
          mesh = mapper->GetLastStageSeconds("mesh");
          return;
        }
        pass1.push_back(mapper->GetLastStageSeconds(mboit ? "moments" : "exact"));
        if (mboit)
        {
          pass2.push_back(mapper->GetLastStageSeconds("colour"));
        }
        setup.push_back(mapper->GetLastStageSeconds("setup"));
        vtkDataArray* count = mapper->GetLastImage()->GetFieldData()->GetArray("SampleCount");
        samples.push_back(count ? count->GetTuple1(0) : NAN);
      });
    row.Pass1 = apctest::Median(pass1);
    row.Pass2 = apctest::Median(pass2);
    row.Setup = apctest::Median(setup);
    row.Samples = apctest::Median(samples);
    row.Spacing = mapper->GetLastSampleDistance();
    std::ostringstream note;
    note << "original cells; mesh build " << Format(mesh, 3) << " s in first frame";
    if (!scene.Note.empty())
    {
      note << "; " << scene.Note;
    }
    row.Note += (row.Note.empty() ? "" : "; ") + note.str();
    if (keepImage)
    {
      this->KeepImage(scene, "apc_" + modeName, stage);
    }
    this->Report(row);
    this->Rows.push_back(row);
  }

  // The core marcher alone on this scene's mesh, camera and transfer function: one row, or
  // one per threshold of --opaque-absorbance.
  void RunSampler(const MapperScene& scene, int threads)
  {
    Stage stage(scene, this->Opt.Size, this->Opt.TimeCap);
    vtkNew<vtkAPCVolumeMapper> mapper; // only for the camera's placement
    mapper->SetInputData(scene.Grid);
    stage.SetMapper(mapper, scene);
    auto* grid = vtkUnstructuredGrid::SafeDownCast(scene.Grid);
    std::vector<apcbench::SamplerTiming> timings;
    if (this->Opt.OpaqueAbsorbances.empty())
    {
      timings.push_back(apcbench::TimeSampler(grid, stage.Renderer, stage.Property, this->Opt.Size,
        scene.SampleDistance, threads, this->Opt.Repeats, this->Opt.Compare,
        this->Opt.LinearTolerance, this->Opt.Stop, this->Opt.EndWeights, this->Opt.Lanes));
    }
    else
    {
      timings = apcbench::TimeSamplerThresholds(grid, stage.Renderer, stage.Property,
        this->Opt.Size, scene.SampleDistance, threads, this->Opt.Repeats, this->Opt.Compare,
        this->Opt.LinearTolerance, this->Opt.OpaqueAbsorbances, this->Opt.EndWeights,
        this->Opt.Lanes);
    }
    for (const apcbench::SamplerTiming& s : timings)
    {
      Row row =
        NewRow(scene, scene.Grid->GetNumberOfCells(), "sampler", "mboit", std::to_string(threads));
      row.BunykThreads = threads;
      row.Sampler = s;
      row.Pass1 = s.Pass1Seconds;
      row.Pass2 = s.Pass2Seconds;
      row.Frame = s.Pass1Seconds + s.Pass2Seconds;
      row.Cpu = s.Pass1Cpu + s.Pass2Cpu;
      row.Setup = s.ViewSeconds;
      row.Samples = static_cast<double>(s.Samples);
      row.Spacing = s.Spacing;
      row.Note = "core marcher alone: pass 1 + pass 2, CPU ns per sample; setup_s = binning";
      if (!scene.Note.empty())
      {
        row.Note += "; " + scene.Note;
      }
      std::cerr << "   sampler threads " << threads << " stop " << Format(s.OpaqueAbsorbance, 6)
                << ": pass 1 " << Format(s.Pass1NanosecondsPerSample()) << " ns/sample, pass 2 "
                << Format(s.Pass2NanosecondsPerSample()) << " ns/sample, " << s.Samples
                << " samples (pass 2 " << s.Pass2Samples << "), hidden " << Format(s.HiddenShare())
                << ", cached " << Format(s.CacheShare) << ", error vs exact "
                << Format(s.ErrorVsExact) << ", stop change " << Format(s.StopChange)
                << " (pixels over 1/255: " << Format(s.StopChangeShare) << "), unstopped error "
                << Format(s.ErrorVsExactAll) << ", pixels worse by 1/255 " << Format(s.WorseShare)
                << ", mesh " << Format(s.MeshSeconds) << " s (finalize "
                << Format(s.FinalizeSeconds) << " s), bin " << Format(s.ViewSeconds)
                << " s, linear change " << Format(s.LinearChange) << ", spacing "
                << Format(s.Spacing) << "\n";
      std::cerr << "   sampler pass 2: hidden " << Format(s.Pass2HiddenShare) << ", unstopped "
                << Format(s.Pass2HiddenShareUnstopped) << "; vs exact PSNR "
                << Format(s.PsnrVsExact, 6) << " dB SSIM " << Format(s.SsimVsExact, 7)
                << " (unstopped " << Format(s.PsnrVsExactAll, 6) << " dB, "
                << Format(s.SsimVsExactAll, 7) << "); change from the first threshold "
                << Format(s.ChangeFromFirst) << ", pixels worse than it by 1/255 "
                << Format(s.WorseThanFirstShare) << " (at most " << Format(s.MostWorseThanFirst)
                << " farther from exact)\n";
      // Pictures of each threshold's image (and the exact blend) over ParaView's background.
      const std::array<double, 3> background = { 0.32, 0.34, 0.43 };
      if (this->Opt.Images && !s.Image.empty())
      {
        apctest::WritePNG(this->Opt.Out + "/" + scene.Name + "_sampler_stop" +
            Format(s.OpaqueAbsorbance, 6) + ".png",
          s.Image, this->Opt.Size, this->Opt.Size, background);
      }
      if (this->Opt.Images && !s.ExactImage.empty())
      {
        apctest::WritePNG(this->Opt.Out + "/" + scene.Name + "_sampler_exact.png", s.ExactImage,
          this->Opt.Size, this->Opt.Size, background);
      }
      row.Sampler.Image = std::vector<float>();
      row.Sampler.ExactImage = std::vector<float>();
      this->Rows.push_back(row);
    }
  }

  void RunZSweep(const MapperScene& scene)
  {
    Row row = NewRow(scene, scene.Tets->GetNumberOfCells(), "zsweep", "", "1");
    row.BunykThreads = 1;
    if (scene.Tets->GetNumberOfCells() > this->Opt.ZSweepMaxCells)
    {
      row.Note = "skipped (" + std::to_string(scene.Tets->GetNumberOfCells()) +
        " tetrahedra > --zsweep-max-cells " + std::to_string(this->Opt.ZSweepMaxCells) +
        "; no frame in 300 s on the 330k-cell wind mesh in an earlier probe)";
      this->Report(row);
      this->Rows.push_back(row);
      return;
    }
    Stage stage(scene, this->Opt.Size, this->Opt.TimeCap);
    vtkNew<vtkUnstructuredGridVolumeZSweepMapper> mapper;
    this->TimeCountingSegments(stage, row, mapper.GetPointer(), scene);
    row.Note += std::string(row.Note.empty() ? "" : "; ") + TetNote(scene) +
      "; single-threaded; samples = cell segments integrated";
    this->KeepImage(scene, "zsweep", stage);
    this->Report(row);
    this->Rows.push_back(row);
  }

  void RunPT(const MapperScene& scene, int bunykThreads)
  {
    Row row = NewRow(scene, scene.Tets->GetNumberOfCells(), "pt", "", "gl");
    row.BunykThreads = bunykThreads;
    Stage stage(scene, this->Opt.Size, this->Opt.TimeCap);
    vtkSmartPointer<vtkProjectedTetrahedraMapper> mapper =
      vtkSmartPointer<vtkProjectedTetrahedraMapper>::Take(vtkProjectedTetrahedraMapper::New());
    mapper->SetInputData(scene.Tets);
    stage.SetMapper(mapper, scene);
    stage.Render(); // the GL context must exist before IsSupported can tell
    if (!mapper->IsSupported(stage.Window))
    {
      row.Note = "skipped (projected tetrahedra not supported by this OpenGL)";
      this->Report(row);
      this->Rows.push_back(row);
      return;
    }
    // That render built the context and the mapper's buffers: rebuild for a fair first frame.
    mapper->Modified();
    this->Time(stage, row, [](int) {});
    const char* lp = std::getenv("LP_NUM_THREADS");
    row.Note += std::string(row.Note.empty() ? "" : "; ") + TetNote(scene) + "; " +
      mapper->GetClassName() + ", CPU visibility sort + GL rasterisation (" +
      (lp ? "LP_NUM_THREADS=" + std::string(lp) : std::string("GL driver's threads")) +
      "); first frame after context creation";
    this->KeepImage(scene, "pt", stage);
    this->Report(row);
    this->Rows.push_back(row);
  }

  // How alike APC's images and Bunyk's are, as a viewer sees them (SSIM/PSNR of the 8-bit RGB
  // windows); goes into the note of the APC rows with the most threads.
  void CompareImages(const MapperScene& scene)
  {
    auto bunyk = this->Images.find("bunyk");
    if (bunyk == this->Images.end())
    {
      return;
    }
    const int n = this->Opt.Size;
    auto toFloat = [](const std::vector<unsigned char>& rgb)
    {
      std::vector<float> f(rgb.size());
      std::transform(rgb.begin(), rgb.end(), f.begin(), [](unsigned char c) { return c / 255.0f; });
      return f;
    };
    const std::vector<float> reference = toFloat(bunyk->second);
    const int maxThreads = *std::max_element(this->Opt.Threads.begin(), this->Opt.Threads.end());
    for (Row& row : this->Rows)
    {
      if (row.Dataset != scene.Name || row.Threads != std::to_string(maxThreads))
      {
        continue;
      }
      std::string tag;
      if (row.Mapper == "apc")
      {
        tag = "apc_" + row.Mode;
      }
      else if (row.Mapper == "zsweep" || row.Mapper == "pt")
      {
        tag = row.Mapper;
      }
      auto image = this->Images.find(tag);
      if (tag.empty() || image == this->Images.end() || n < apc::kSsimWindowSize)
      {
        continue;
      }
      const std::vector<float> test = toFloat(image->second);
      const apc::ImageComparison c =
        apc::CompareImages(test.data(), reference.data(), n, n, 3, 1.0, 0.1);
      std::ostringstream note;
      note << "vs bunyk image: SSIM " << std::fixed << std::setprecision(3) << c.Ssim << " PSNR "
           << std::setprecision(1) << c.Psnr << " dB, " << std::setprecision(2)
           << 100.0 * c.PixelsOverThreshold / (n * n) << "% pixels off by >0.1";
      row.Note += "; " + note.str();
    }
    this->Images.clear();
  }

  Options Opt;
  std::vector<Row> Rows;
  std::map<std::string, std::vector<unsigned char>> Images;
};

void Usage()
{
  std::cerr << "usage: apcBenchmarkMappers [--size N] [--quick] [--repeats N]\n"
               "  [--datasets gear,wind,flange] [--out DIR] [--csv FILE] [--data DIR]\n"
               "  [--threads 1,2] [--zsweep-max-cells N] [--time-cap SECONDS] [--spacing-scale F] "
               "[--moments 4|6|8]\n"
               "  [--mappers bunyk,exact,mboit,zsweep,pt]\n"
               "  [--no-images] [--setup benchmark|paraview] [--dolly F] [--no-compare]\n"
               "  [--linear-tolerance BINS] [--no-stop] [--lower60] [--field NAME] "
               "[--end-weights] [--boundary-weights] [--no-end-weights] [--no-lanes]\n"
               "  [--opaque-absorbance A[,B,...]]\n";
}

} // namespace

int main(int argc, char* argv[])
{
  Options options;
  bool sizeGiven = false;
  bool repeatsGiven = false;
  for (int a = 1; a < argc; ++a)
  {
    const std::string arg = argv[a];
    auto value = [&]() -> std::string
    {
      if (a + 1 >= argc)
      {
        Usage();
        std::exit(2);
      }
      return argv[++a];
    };
    if (arg == "--size")
    {
      options.Size = std::stoi(value());
      sizeGiven = true;
    }
    else if (arg == "--quick")
    {
      options.Quick = true;
    }
    else if (arg == "--repeats")
    {
      options.Repeats = std::max(1, std::stoi(value()));
      repeatsGiven = true;
    }
    else if (arg == "--datasets")
    {
      options.Datasets = Split(value());
    }
    else if (arg == "--threads")
    {
      options.Threads.clear();
      for (const std::string& t : Split(value()))
      {
        options.Threads.push_back(std::max(1, std::stoi(t)));
      }
    }
    else if (arg == "--out")
    {
      options.Out = value();
    }
    else if (arg == "--csv")
    {
      options.Csv = value();
    }
    else if (arg == "--data")
    {
      options.Data = value();
    }
    else if (arg == "--zsweep-max-cells")
    {
      options.ZSweepMaxCells = std::stoll(value());
    }
    else if (arg == "--time-cap")
    {
      options.TimeCap = std::stod(value());
    }
    else if (arg == "--mappers")
    {
      options.Mappers = Split(value());
    }
    else if (arg == "--moments")
    {
      options.Moments = std::stoi(value());
    }
    else if (arg == "--spacing-scale")
    {
      options.SpacingScale = std::stod(value());
      options.SpacingScaleGiven = true;
    }
    else if (arg == "--no-stop")
    {
      options.Stop = false;
    }
    else if (arg == "--end-weights")
    {
      options.EndWeights = 1;
    }
    else if (arg == "--boundary-weights")
    {
      options.EndWeights = 2;
    }
    else if (arg == "--no-end-weights")
    {
      options.EndWeights = 0;
    }
    else if (arg == "--no-lanes")
    {
      options.Lanes = false;
    }
    else if (arg == "--lower60")
    {
      options.Lower60 = true;
    }
    else if (arg == "--field")
    {
      options.WindField = value();
    }
    else if (arg == "--linear-tolerance")
    {
      options.LinearTolerance = std::stod(value());
    }
    else if (arg == "--setup")
    {
      options.Setup = value();
    }
    else if (arg == "--no-compare")
    {
      options.Compare = false;
    }
    else if (arg == "--dolly")
    {
      options.Dolly = std::stod(value());
    }
    else if (arg == "--no-images")
    {
      options.Images = false;
    }
    else if (arg == "--opaque-absorbance")
    {
      // Checked here, once: every threshold the sampler is given is a positive absorbance.
      for (const std::string& t : Split(value()))
      {
        const double absorbance = std::stod(t);
        if (!(absorbance > 0))
        {
          std::cerr << "error: --opaque-absorbance " << t << ": not a positive absorbance\n";
          return 2;
        }
        options.OpaqueAbsorbances.push_back(absorbance);
      }
    }
    else
    {
      Usage();
      return arg == "--help" || arg == "-h" ? 0 : 2;
    }
  }
  if (options.EndWeights < 0)
  {
    options.EndWeights = options.Setup == "paraview"
      ? vtkSmartPointer<vtkAPCVolumeMapper>::New()->GetSampleEndWeights()
      : vtkAPCVolumeMapper::END_WEIGHTS_OFF;
  }
  if (options.Quick)
  {
    options.Size = sizeGiven ? options.Size : 256;
    options.Repeats = repeatsGiven ? options.Repeats : 1;
  }
  if (options.Threads.empty() || options.Datasets.empty() || options.Size < 16)
  {
    Usage();
    return 2;
  }
  if (options.Csv.empty())
  {
    options.Csv = options.Out + "/mappers.csv";
  }

  std::error_code error;
  std::filesystem::create_directories(options.Out, error);
  const auto start = Clock::now();
  std::ofstream csv(options.Csv);
  if (!csv)
  {
    std::cerr << "error: cannot write " << options.Csv << "\n";
    return 1;
  }
  Benchmark::WriteCsvHeader(csv);
  Benchmark benchmark(options);
  for (const std::string& name : options.Datasets)
  {
    const size_t first = benchmark.GetNumberOfRows();
    benchmark.RunDataset(name);
    benchmark.WriteCsv(csv, first);
  }
  std::cerr << "wrote " << options.Csv << " (" << Format(SecondsSince(start), 3) << " s)\n";
  return 0;
}
