// What a data change costs before the first sample, part by part, on the bundled wind data (or
// --data FILE.pvtu/.vtu): the conversion to the ray marcher's mesh (CellMeshFromVTK, which
// ends with CellMesh::Finalize), Finalize alone, and the per-view binning (BinCells) at
// --size pixels, then pass 1 on a new ray marcher ("pass1_first": its memory is touched for
// the first time, as in a first frame) and on the same marcher again ("pass1_again", a later
// frame), with the sample cache at its default and off, one thread (as a rank under
// `mpirun -np 1`), ParaView's default linear opacity ramp over the scalar range and the default
// sample distance. Prints one CSV row per part: the smallest CPU time (all threads) and wall
// time over --repeats, and a checksum of the mesh, so that two builds run side by side show
// both their costs and that they make the same mesh. Uses only interfaces that older builds
// have, so the same source measures a baseline, but for "probe_bins_decimated" (a first
// frame's probe binning, and its bins derived from the frame's: DecimateBins).
//
// "boundary_first" is CellMesh::FindBoundaryPlanes (Sample End Weights = Boundary's matching)
// once after the conversion, as a first frame runs it (its memory new to the process), with its
// system CPU seconds and page faults; "boundary" the smallest of --repeats more; then a checksum
// of the boundary planes found. --piece K N converts piece K of N (a rank's share of the data
// on N ranks, as ParaView's reader splits it).
//
//   apcSetupBenchmark [--data FILE] [--array U_mag] [--size 1024] [--repeats 3] [--no-pass1]
//                     [--camera fill|overview] [--piece K N]

#include "apcCellMesh.h"
#include "apcCellMeshFromVTK.h"
#include "apcDefaultSpacing.h"
#include "apcDepthWarp.h"
#include "apcInputReport.h"
#include "apcRayCamera.h"
#include "apcTileBins.h"
#include "apcTransferTable.h"
#include "apcVolumeRayMarcher.h"

#include "vtkDataArray.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkUnstructuredGrid.h"
#include "vtkXMLPUnstructuredGridReader.h"
#include "vtkXMLUnstructuredGridReader.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <functional>
#include <memory>
#include <string>
#include <sys/resource.h>
#include <vector>

namespace
{
double CpuSeconds()
{
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

double WallSeconds()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// The smallest CPU and wall time of repeats runs of work.
void Time(
  const char* part, int repeats, const std::function<void()>& work, double& cpu, double& wall)
{
  cpu = wall = 1e300;
  for (int r = 0; r < repeats; ++r)
  {
    const double c0 = CpuSeconds();
    const double w0 = WallSeconds();
    work();
    cpu = std::min(cpu, CpuSeconds() - c0);
    wall = std::min(wall, WallSeconds() - w0);
  }
  std::printf("%s,%.4f,%.4f\n", part, cpu, wall);
  std::fflush(stdout);
}

void Mix(unsigned long long& hash, const void* data, size_t bytes)
{
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < bytes; ++i)
  {
    hash = (hash ^ p[i]) * 1099511628211ull;
  }
}

// Everything the marcher reads of the mesh.
unsigned long long Checksum(const apc::CellMesh& mesh)
{
  unsigned long long hash = 1469598103934665603ull;
  Mix(hash, mesh.Points.data(), mesh.Points.size() * sizeof(mesh.Points[0]));
  Mix(hash, mesh.PointScalars.data(), mesh.PointScalars.size() * sizeof(float));
  Mix(hash, mesh.CellScalars.data(), mesh.CellScalars.size() * sizeof(float));
  for (int64_t c = 0; c < mesh.GetNumberOfCells(); ++c)
  {
    const apc::CellShape shape = mesh.GetShape(c);
    Mix(hash, &shape, sizeof shape);
    Mix(hash, mesh.GetCellPoints(c), apc::NumberOfCorners(shape) * sizeof(int64_t));
    int count = 0;
    const apc::FacePlane* planes = mesh.GetPlanes(c, count);
    // The normal and offset (KeepsParallelRays follows from the normal: left out, so that the
    // checksum stays comparable with builds before it was stored).
    for (int f = 0; f < count; ++f)
    {
      Mix(hash, planes[f].Normal.data(), 3 * sizeof(float));
      Mix(hash, &planes[f].Offset, sizeof(double));
    }
    Mix(hash, mesh.GetCellBounds(c).data(), 6 * sizeof(double));
    Mix(hash, mesh.GetScalarRange(c).data(), 2 * sizeof(float));
  }
  // What Finalize summed (the default sample distance's input) and left out.
  const double volume = mesh.GetCellVolume().Value();
  Mix(hash, &volume, sizeof volume);
  const int64_t skipped[2] = { mesh.GetNumberOfNonFiniteCornerCells(),
    mesh.GetNumberOfFlatCells() };
  Mix(hash, skipped, sizeof skipped);
  return hash;
}

// Pass 1 on a new marcher (first) and on the same marcher again, cacheMiB of sample cache.
void TimePass1(const apc::CellMesh& mesh, const apc::RayCamera& camera, int cacheMiB)
{
  const auto& b = mesh.GetBounds();
  // The plain lattice's default: this marcher weights no ends.
  const double spacing = apc::DefaultSampleDistance(
    b.data(), static_cast<double>(mesh.GetNumberOfCells()), mesh.GetCellVolume().Value(), false);
  double lo = 1e300;
  double hi = -1e300;
  for (float v : mesh.PointScalars)
  {
    lo = std::min(lo, static_cast<double>(v));
    hi = std::max(hi, static_cast<double>(v));
  }
  constexpr int kEntries = 256;
  std::vector<std::array<float, 3>> colours(kEntries, { 1.0f, 1.0f, 1.0f });
  std::vector<double> alphas(kEntries);
  for (int i = 0; i < kEntries; ++i)
  {
    alphas[i] = static_cast<double>(i) / (kEntries - 1); // ParaView's default ramp
  }
  // ParaView's unit distance is about the mean cell length: the default spacing here.
  const apc::TransferTable table(lo, hi, colours, alphas, spacing, spacing);
  double tmin = 0;
  double tmax = 0;
  camera.DistanceRange(b, tmin, tmax);
  const apc::LogDepthWarp warp(tmin, tmax);
  std::vector<double> moments(static_cast<size_t>(camera.GetWidth()) * camera.GetHeight() * 5);
  auto marcher = std::make_unique<apc::VolumeRayMarcher>();
  auto pass1 = [&]
  {
    marcher->SetView(camera, nullptr);
    std::fill(moments.begin(), moments.end(), 0.0);
    marcher->AccumulateMoments<4>(table, warp, moments.data());
  };
  auto fresh = [&]
  {
    marcher = std::make_unique<apc::VolumeRayMarcher>();
    marcher->SetNumberOfThreads(1);
    marcher->SetMaxSampleCacheBytes(static_cast<size_t>(cacheMiB) << 20);
    marcher->SetMesh(&mesh);
  };
  const std::string suffix = cacheMiB > 0 ? "_cache" : "_nocache";
  double cpu, wall;
  // One repeat each: a repeat of "first" would need a new marcher, whose memory the allocator
  // may hand back already touched.
  fresh();
  Time(("pass1_first" + suffix).c_str(), 1, pass1, cpu, wall);
  Time(("pass1_again" + suffix).c_str(), 1, pass1, cpu, wall);
  std::printf("# pass 1%s: %lld samples, spacing %g\n", suffix.c_str(),
    static_cast<long long>(marcher->GetLastSampleCount()), spacing);
}
}

int main(int argc, char* argv[])
{
  std::string data = std::string(APC_SOURCE_DIR) + "/Data/windAroundBuildings/wind.pvtu";
  std::string arrayName = "U_mag";
  int size = 1024;
  int repeats = 3;
  int piece = 0;
  int pieces = 1;
  bool timePass1 = true;
  double factor = 1.0; // the camera's distance: 1 = the demo's view, 0.6 = "fill"
  for (int i = 1; i < argc; ++i)
  {
    const std::string option = argv[i];
    if (option == "--no-pass1")
    {
      timePass1 = false;
      continue;
    }
    if (i + 1 >= argc)
      break;
    if (option == "--piece" && i + 2 < argc)
    {
      piece = std::atoi(argv[i + 1]);
      pieces = std::max(1, std::atoi(argv[i + 2]));
      i += 2;
      continue;
    }
    if (option == "--data")
      data = argv[i + 1];
    else if (option == "--array")
      arrayName = argv[i + 1];
    else if (option == "--size")
      size = std::atoi(argv[i + 1]);
    else if (option == "--camera")
      factor = std::string(argv[i + 1]) == "fill" ? 0.6 : 1.0;
    else if (option == "--repeats")
      repeats = std::max(1, std::atoi(argv[i + 1]));
    ++i;
  }
  vtkSmartPointer<vtkUnstructuredGrid> grid;
  if (data.size() > 5 && data.compare(data.size() - 5, 5, ".pvtu") == 0)
  {
    vtkNew<vtkXMLPUnstructuredGridReader> reader;
    reader->SetFileName(data.c_str());
    reader->UpdatePiece(piece, pieces, 0);
    grid = reader->GetOutput();
  }
  else
  {
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    reader->SetFileName(data.c_str());
    reader->Update();
    grid = reader->GetOutput();
  }
  vtkDataArray* scalars = grid ? grid->GetPointData()->GetArray(arrayName.c_str()) : nullptr;
  if (!scalars)
  {
    std::fprintf(stderr, "error: no point array %s in %s\n", arrayName.c_str(), data.c_str());
    return 1;
  }
  std::printf("# %s: %lld cells, %lld points; part,cpu_s,wall_s\n", data.c_str(),
    static_cast<long long>(grid->GetNumberOfCells()),
    static_cast<long long>(grid->GetNumberOfPoints()));
  apc::ScalarSelection selection;
  selection.Array = scalars;
  apc::CellMesh mesh;
  apc::InputReport report;
  std::string error;
  double cpu, wall;
  bool ok = true;
  Time(
    "conversion", repeats,
    [&] { ok = apc::CellMeshFromVTK(grid, selection, mesh, report, error) && ok; }, cpu, wall);
  if (!ok)
  {
    std::fprintf(stderr, "error: %s\n", error.c_str());
    return 1;
  }
  Time(
    "finalize", repeats, [&] { mesh.Finalize(); }, cpu, wall);
  {
    rusage before;
    rusage after;
    getrusage(RUSAGE_SELF, &before);
    Time(
      "boundary_first", 1, [&] { mesh.FindBoundaryPlanes(); }, cpu, wall);
    getrusage(RUSAGE_SELF, &after);
    std::printf("# boundary_first: %.4f system s, %ld page faults\n",
      (after.ru_stime.tv_sec - before.ru_stime.tv_sec) +
        1e-6 * (after.ru_stime.tv_usec - before.ru_stime.tv_usec),
      after.ru_minflt - before.ru_minflt);
    Time(
      "boundary", repeats,
      [&]
      {
        mesh.ForgetBoundaryPlanes();
        mesh.FindBoundaryPlanes();
      },
      cpu, wall);
    unsigned long long hash = 1469598103934665603ull;
    int64_t planes = 0;
    for (int64_t c = 0; c < mesh.GetNumberOfCells(); ++c)
    {
      const uint8_t bits = mesh.GetBoundaryPlanes(c);
      Mix(hash, &bits, 1);
      planes += __builtin_popcount(bits);
    }
    // The faces sorted: which copy of a face three cells hold is listed may move it in the list.
    std::vector<apc::CellMesh::FaceCorners> faces;
    getrusage(RUSAGE_SELF, &before);
    Time(
      "boundary_faces_first", 1, [&] { faces = mesh.GetBoundaryFaces(); }, cpu, wall);
    getrusage(RUSAGE_SELF, &after);
    std::printf("# boundary_faces_first: %ld page faults\n", after.ru_minflt - before.ru_minflt);
    std::sort(faces.begin(), faces.end());
    Mix(hash, faces.data(), faces.size() * sizeof(faces[0]));
    std::printf("# boundary checksum %016llx, %lld boundary planes, %zu faces listed\n", hash,
      static_cast<long long>(planes), faces.size());
  }
  // The camera of first_frame.py and paraview_vs_apc.py, a square image.
  // --camera fill moves it to 0.6 x its focal distance (paraview_vs_apc.py's fill camera).
  const double focal[3] = { 155, 90, 40 };
  const double from[3] = { -120, -260, 420 };
  const apc::RayCamera camera(
    { focal[0] + factor * (from[0] - focal[0]), focal[1] + factor * (from[1] - focal[1]),
      focal[2] + factor * (from[2] - focal[2]) },
    { focal[0], focal[1], focal[2] }, { 0, 0, 1 }, 30.0, false, 1.0, size, size, 1.0, 2000.0);
  apc::TileBins bins;
  Time(
    "bins", repeats, [&] { apc::BinCells(&mesh, camera, 16, 0, bins); }, cpu, wall);
  int64_t onScreen = 0;
  for (const auto& r : bins.Rects)
  {
    onScreen += r[0] <= r[2] && r[1] <= r[3] ? 1 : 0;
  }
  // Everything the marcher reads of the bins: two builds that bin alike print the same sum.
  unsigned long long binsHash = 1469598103934665603ull;
  Mix(binsHash, bins.Rects.data(), bins.Rects.size() * sizeof(bins.Rects[0]));
  Mix(binsHash, bins.Near.data(), bins.Near.size() * sizeof(double));
  Mix(binsHash, bins.Far.data(), bins.Far.size() * sizeof(double));
  Mix(binsHash, bins.Start.data(), bins.Start.size() * sizeof(int64_t));
  Mix(binsHash, bins.Cells.data(), bins.Cells.size() * sizeof(int64_t));
  std::printf("# mesh checksum %016llx, %lld cells, %lld on screen, %zu tile entries, bins "
              "checksum %016llx\n",
    Checksum(mesh), static_cast<long long>(mesh.GetNumberOfCells()),
    static_cast<long long>(onScreen), bins.Cells.size(), binsHash);
  // A first frame's probe (every 8th ray, FrameSettings' default step): binning every cell
  // for its camera, as its marcher's SetView does, against its bins derived from the frame's
  // (DecimateBins, as SetDecimatedView does: this build's interface).
  const int step = 8;
  const apc::RayCamera coarse = camera.Decimated(step, step / 2);
  apc::TileBins probeBins;
  Time(
    "probe_bins", repeats, [&] { apc::BinCells(&mesh, coarse, 16, 0, probeBins); }, cpu, wall);
  const std::vector<int64_t> probeCells(probeBins.Cells.begin(), probeBins.Cells.end());
  Time(
    "probe_bins_decimated", repeats,
    [&]
    {
      apc::DecimateBins(
        bins, step, step / 2, coarse.GetWidth(), coarse.GetHeight(), 16, 0, probeBins);
    },
    cpu, wall);
  std::printf("# probe bins: %zu tile entries, %s\n", probeCells.size(),
    std::equal(probeCells.begin(), probeCells.end(), probeBins.Cells.begin(), probeBins.Cells.end())
      ? "the same derived"
      : "DIFFERENT derived");
  if (timePass1)
  {
    TimePass1(mesh, camera, 1024);
    TimePass1(mesh, camera, 0);
  }
  return 0;
}
