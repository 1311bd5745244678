// What exact sort-last compositing of segments would move, against APC's payload, in one
// process: for each configuration the ranks' pieces are rendered one after the other into
// their segment lists, exactly as vtkAPCCompositePass's SEGMENTS mode renders them on each
// rank (same mapper stage API, global bounds, sample lattice and screen rectangle), and
// apc::CountSegmentTransfer counts direct send to the strip owners and binary swap (computed:
// the paper's table, "average number of segments transferred per non-empty pixel"), per rank
// as well as in total (the busiest rank sets the time in scaling_model.py's alpha-beta model),
// and the 8 x 8 tiles of the screen rectangle that some rank covers (APC's compact wire).
//
//   apcSegmentAnalysis --out DIR [--data DIR] [--size S] [--wind-size W H]
//                      [--gear-ranks 1,2,4,8] [--gear-large-size S] [--gear-large-cameras C]
//                      [--wind-ranks 2,4,8] [--wind-distances 0.6,1,1.6]
//                      [--flange-size S] [--flange-ranks 2,4]
//                      [--partition-ranks 2,4,...,256] [--partition-size S]
//                      [--partition-meshes wind,flange] [--partition-distances 1]
//
// Configurations:
// - the gear teeth of apcScalingBenchmark (one piece per rank, 4 orbit cameras). Up to 8
//   ranks exactly the benchmark's frames. Beyond 8 the box stays [-1,1]^3, so its 4N slabs
//   thin as 1/N: the sample distance shrinks to 0.08/N to keep the ~6 samples across a slab
//   that the paper's fixed-thickness slabs have (otherwise slabs fall between samples and the
//   segments stop growing as 4N); such ranks counts use --gear-large-size pixels and the first
//   --gear-large-cameras cameras (the cost grows as N: every piece is rendered here);
// - the real meshes (wind: 8 Scotch pieces; flange: 4 pieces) shared out to the ranks as
//   ParaView's reader does; the wind from the camera of paraview_vs_apc.py moved to each
//   distance factor along its line of sight, the flange from apcBenchmarkMappers' camera
//   (--wind-ranks, --flange-ranks: at most the stored pieces);
// - the same meshes cut into N pieces by the graph partitioner (vtkAPCGraphPartition,
//   label-only, K = N, split by PartitionId) at --partition-size pixels, cases wind-metis-<d>
//   (the wind at --partition-distances) and flange-metis (--partition-ranks). The switch is the
//   filter's header: without it (before the graph-partition branch is merged) these runs are
//   skipped with a message.
// Writes (creating DIR) DIR/segment_transfer.csv and, for the first camera of each configuration,
// the per-pixel segment count over all ranks as DIR/heatmap_<case>_np<N>.pgm (16-bit binary PGM,
// top row first). apc_bytes is the pass's payload on main before the compact wire: every rank
// sends (moments + 1 + 4 colour) doubles per pixel of the rectangle, the display rank also
// 4 bytes of depth; scaling_model.py derives the compact wire's bytes from the tile columns.
// Not run by ctest; run-evaluation.sh runs it.

#include "apcFrameEngine.h"
#include "apcGearTeethScene.h"
#include "apcSegmentTransfer.h"
#include "apcTestScenes.h"
#include "vtkAPCCompositePass.h"
#include "vtkAPCVolumeMapper.h"

#include "vtkCamera.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkXMLPUnstructuredGridReader.h"

// The graph partitioner lives on its own branch until it is merged; the mesh runs it feeds
// switch on with its header.
#if __has_include("vtkAPCGraphPartition.h")
#include "vtkAPCGraphPartition.h"
#include "vtkCellData.h"
#include "vtkDataArray.h"
#include "vtkExtractCells.h"
#include "vtkIdList.h"
#define APC_HAVE_GRAPH_PARTITION 1
#else
#define APC_HAVE_GRAPH_PARTITION 0
#endif

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#ifndef APC_SOURCE_DIR
#define APC_SOURCE_DIR "."
#endif

namespace
{
constexpr bool kHaveGraphPartition = APC_HAVE_GRAPH_PARTITION != 0;

// Bytes of one segment on the wire (vtkAPCCompositePass's WireSegment).
constexpr int kSegmentBytes = 24;

std::vector<double> ParseList(const char* text)
{
  std::vector<double> values;
  std::stringstream s(text);
  std::string item;
  while (std::getline(s, item, ','))
  {
    values.push_back(std::atof(item.c_str()));
  }
  return values;
}

struct Config
{
  std::string Case;
  int Ranks = 1;
  std::string Camera;
  bool Heatmap = false;
};

// Renders each rank's segments with the pass's frame set-up and counts the transfers.
class Analysis
{
public:
  Analysis(int width, int height)
    : Width(width)
    , Height(height)
  {
    this->Window->SetOffScreenRendering(1);
    this->Window->SetSize(width, height);
    this->Window->AddRenderer(this->Renderer);
    this->Window->Render(); // a GL context for the mapper's set-up
  }

  vtkRenderer* GetRenderer() { return this->Renderer; }

  // pieces[r]: rank r's cells; volume carries the transfer function.
  std::string Run(const Config& config,
    const std::vector<vtkSmartPointer<vtkUnstructuredGrid>>& pieces, vtkVolume* volume,
    vtkAPCVolumeMapper* mapper, const double bounds[6], const std::string& out)
  {
    const auto start = std::chrono::steady_clock::now();
    std::vector<float> depth(static_cast<size_t>(this->Width) * this->Height, 1.0f);
    std::vector<apc::SegmentImage> images(pieces.size());
    double cells = 0; // of all pieces, as the pass agrees them (the default sample distance)
    for (const auto& piece : pieces)
    {
      cells += static_cast<double>(piece->GetNumberOfCells());
    }
    // Every piece's engine takes its input first: the default sample distance needs all
    // pieces' volume, as the pass agrees it.
    std::vector<apc::FrameEngine> engines(pieces.size());
    std::vector<bool> usable(pieces.size());
    apc::ExactSum volumeSum;
    for (size_t r = 0; r < pieces.size(); ++r)
    {
      mapper->SetInputData(pieces[r]);
      engines[r].BeginFrame(mapper->GetVolumeSettings());
      usable[r] = engines[r].UpdateInput(mapper->GetInput(), mapper);
      volumeSum.Add(engines[r].GetCellVolume());
    }
    const double cellVolume = volumeSum.Value();
    // The lattice the pass's SEGMENTS frames sample at sample distance 0 (the plain lattice's
    // default), so that the counts are the distributed compositing's.
    apc::ImageSetup image = apc::ImageSetup::FullQuality(this->Renderer);
    image.PlainLattice = vtkAPCCompositePass::SamplesPlainLattice(vtkAPCCompositePass::SEGMENTS);
    for (size_t r = 0; r < pieces.size(); ++r)
    {
      mapper->SetInputData(pieces[r]);
      apc::FrameEngine& engine = engines[r];
      if (usable[r] &&
        engine.Prepare(
          this->Renderer, volume->GetProperty(), bounds, cells, cellVolume, depth.data(), image))
      {
        engine.RenderSegments(images[r]);
      }
      if (images[r].Width != this->Width || images[r].Height != this->Height)
      {
        images[r].Reset(this->Width, this->Height); // an empty rank
      }
    }
    std::vector<const apc::SegmentImage*> ranks;
    for (const auto& image : images)
    {
      ranks.push_back(&image);
    }
    int rect[4];
    vtkAPCCompositePass::GetScreenRectangle(
      this->Renderer, bounds, this->Width, this->Height, rect);
    const apc::SegmentTransferCounts c =
      apc::CountSegmentTransfer(ranks, rect[1], rect[3], rect[0], rect[2]);
    if (!Consistent(c))
    {
      std::cerr << "error: per-rank segment counts do not add up to the totals\n";
      std::exit(1);
    }
    const long long rectPixels =
      static_cast<long long>(rect[2] - rect[0]) * static_cast<long long>(rect[3] - rect[1]);
    const int n = config.Ranks;
    const double apcBytes =
      n > 1 ? rectPixels * (8.0 * n * (mapper->GetNumberOfMoments() + 1 + 4) + 4.0) : 0.0;

    std::string heatmap;
    if (config.Heatmap)
    {
      heatmap = "heatmap_" + config.Case + "_np" + std::to_string(n) + ".pgm";
      WriteHeatmap(out + "/" + heatmap, apc::SegmentCountImage(ranks));
    }
    const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    char line[1024];
    std::snprintf(line, sizeof(line),
      "%s,%d,%s,%d,%d,%lld,%lld,%lld,%.4f,%lld,%lld,%lld,%lld,%.0f,%.0f,%.0f,%s,"
      "%.6g,%lld,%lld,%lld,%lld,%lld,%lld,%lld,%lld,%.1f\n",
      config.Case.c_str(), n, config.Camera.c_str(), this->Width, this->Height, rectPixels,
      static_cast<long long>(c.NonEmptyPixels), static_cast<long long>(c.Segments),
      c.PerNonEmptyPixel(c.Segments), static_cast<long long>(c.MaxSegmentsPerPixel),
      static_cast<long long>(c.DirectSend), static_cast<long long>(c.BinarySwap),
      static_cast<long long>(c.BinarySwapUnmerged), apcBytes,
      static_cast<double>(kSegmentBytes) * c.DirectSend,
      c.BinarySwap < 0 ? -1.0 : static_cast<double>(kSegmentBytes) * c.BinarySwap, heatmap.c_str(),
      mapper->GetSampleDistance(), static_cast<long long>(c.Tiles),
      static_cast<long long>(c.CoveredTiles), static_cast<long long>(c.CoveredTilePixels),
      static_cast<long long>(c.DirectSendMaxSent()),
      static_cast<long long>(c.DirectSendMaxReceived()),
      static_cast<long long>(c.DirectSendPairwiseCritical()),
      static_cast<long long>(c.DirectSendMessages()),
      static_cast<long long>(c.BinarySwapCritical()), seconds);
    std::printf("%s %d ranks, camera %s, %dx%d: %.2f segments per non-empty pixel (max %lld); "
                "transferred per non-empty pixel: direct send %.2f, binary swap %.2f; "
                "%lld of %lld tiles covered; %.1f s\n",
      config.Case.c_str(), n, config.Camera.c_str(), this->Width, this->Height,
      c.PerNonEmptyPixel(c.Segments), static_cast<long long>(c.MaxSegmentsPerPixel),
      c.PerNonEmptyPixel(c.DirectSend), c.BinarySwap < 0 ? -1.0 : c.PerNonEmptyPixel(c.BinarySwap),
      static_cast<long long>(c.CoveredTiles), static_cast<long long>(c.Tiles), seconds);
    std::fflush(stdout);
    return line;
  }

private:
  // The per-rank counts must add up to the totals the paper's table is made of.
  static bool Consistent(const apc::SegmentTransferCounts& c)
  {
    int64_t offDiagonal = 0;
    for (int p = 0; p < c.Ranks; ++p)
    {
      for (int o = 0; o < c.Ranks; ++o)
      {
        offDiagonal += p == o ? 0 : c.DirectSendMatrix[static_cast<size_t>(p) * c.Ranks + o];
      }
    }
    int64_t swapped = 0;
    for (int64_t sent : c.BinarySwapSent)
    {
      swapped += sent;
    }
    return offDiagonal == c.DirectSend && (c.BinarySwap < 0 || swapped == c.BinarySwap);
  }

  void WriteHeatmap(const std::string& path, const std::vector<int32_t>& counts) const
  {
    std::ofstream f(path, std::ios::binary);
    f << "P5\n" << this->Width << " " << this->Height << "\n65535\n";
    for (int j = this->Height - 1; j >= 0; --j)
    {
      for (int i = 0; i < this->Width; ++i)
      {
        const int32_t v =
          std::min<int32_t>(counts[static_cast<size_t>(j) * this->Width + i], 65535);
        const unsigned char bytes[2] = { static_cast<unsigned char>(v >> 8),
          static_cast<unsigned char>(v & 255) };
        f.write(reinterpret_cast<const char*>(bytes), 2);
      }
    }
  }

  int Width;
  int Height;
  vtkNew<vtkRenderWindow> Window;
  vtkNew<vtkRenderer> Renderer;
};

void Usage(const char* program)
{
  std::fprintf(stderr,
    "usage: %s --out DIR [--data DIR] [--size S] [--wind-size W H] [--gear-ranks 1,2,4,8]\n"
    "          [--gear-large-size S] [--gear-large-cameras C] [--wind-ranks 2,4,8]\n"
    "          [--wind-distances 0.6,1,1.6] [--flange-size S] [--flange-ranks 2,4]\n"
    "          [--partition-ranks 2,4,...] [--partition-size S] [--partition-meshes wind,flange]\n"
    "          [--partition-distances 1]\n",
    program);
}

// The gear teeth's sample distance: the scaling benchmark's up to 8 ranks; beyond, ~6 samples
// across each of the thinning slabs (see the file comment).
double GearSampleDistance(int ranks)
{
  return std::min(apcbench::kGearSampleDistance, 8 * apcbench::kGearSampleDistance / ranks);
}

// The pieces of a .pvtu shared out to n ranks as vtkXMLPUnstructuredGridReader does, with
// field as active scalars, and their common bounds. Empty when the field is missing or the
// mesh has fewer pieces than ranks (an empty rank would not model a partition into n parts).
std::vector<vtkSmartPointer<vtkUnstructuredGrid>> ReaderPieces(
  const std::string& path, const char* field, int n, double bounds[6])
{
  std::vector<vtkSmartPointer<vtkUnstructuredGrid>> pieces;
  for (int d = 0; d < 3; ++d)
  {
    bounds[2 * d] = 1e300;
    bounds[2 * d + 1] = -1e300;
  }
  for (int r = 0; r < n; ++r)
  {
    vtkNew<vtkXMLPUnstructuredGridReader> reader;
    reader->SetFileName(path.c_str());
    reader->UpdateInformation();
    if (reader->GetNumberOfPieces() < n)
    {
      std::cerr << "error: " << path << " has " << reader->GetNumberOfPieces()
                << " pieces, fewer than " << n
                << " ranks (more need the graph partitioner, not on this branch yet)\n";
      return {};
    }
    reader->UpdatePiece(r, n, 0);
    vtkSmartPointer<vtkUnstructuredGrid> piece = reader->GetOutput();
    if (!piece || !piece->GetPointData()->GetArray(field))
    {
      std::cerr << "error: could not read " << field << " from " << path << "\n";
      return {};
    }
    piece->GetPointData()->SetActiveScalars(field);
    double b[6];
    piece->GetBounds(b);
    for (int d = 0; d < 3; ++d)
    {
      bounds[2 * d] = std::min(bounds[2 * d], b[2 * d]);
      bounds[2 * d + 1] = std::max(bounds[2 * d + 1], b[2 * d + 1]);
    }
    pieces.push_back(piece);
  }
  return pieces;
}

// The whole mesh of a .pvtu (all pieces in one grid) with field as active scalars.
vtkSmartPointer<vtkUnstructuredGrid> ReadWhole(const std::string& path, const char* field)
{
  vtkNew<vtkXMLPUnstructuredGridReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkSmartPointer<vtkUnstructuredGrid> grid = reader->GetOutput();
  if (!grid || !grid->GetPointData()->GetArray(field))
  {
    std::cerr << "error: could not read " << field << " from " << path << "\n";
    return nullptr;
  }
  grid->GetPointData()->SetActiveScalars(field);
  return grid;
}

// The whole mesh cut into n pieces by the graph partitioner in this one process (label-only,
// K = n, METIS on the cell dual graph: jagged, interleaved pieces as a CFD code writes them),
// split by PartitionId; and their common bounds. Empty when the partitioner is not built.
std::vector<vtkSmartPointer<vtkUnstructuredGrid>> PartitionPieces(
  vtkUnstructuredGrid* whole, int n, double bounds[6])
{
  std::vector<vtkSmartPointer<vtkUnstructuredGrid>> pieces;
  whole->GetBounds(bounds);
#if APC_HAVE_GRAPH_PARTITION
  vtkNew<vtkAPCGraphPartition> partition;
  partition->SetController(nullptr); // one process: every cell is here
  partition->SetNumberOfPartitions(n);
  partition->LabelOnlyOn();
  partition->SetInputData(whole);
  partition->Update();
  vtkUnstructuredGrid* labelled = vtkUnstructuredGrid::SafeDownCast(partition->GetOutput());
  vtkDataArray* ids = labelled
    ? labelled->GetCellData()->GetArray(vtkAPCGraphPartition::GetPartitionIdArrayName())
    : nullptr;
  if (!ids)
  {
    std::cerr << "error: the graph partitioner gave no PartitionId\n";
    return pieces;
  }
  std::vector<vtkSmartPointer<vtkIdList>> cells(n);
  for (auto& list : cells)
  {
    list = vtkSmartPointer<vtkIdList>::New();
  }
  for (vtkIdType c = 0; c < labelled->GetNumberOfCells(); ++c)
  {
    const int part = static_cast<int>(ids->GetTuple1(c));
    if (part >= 0 && part < n)
    {
      cells[part]->InsertNextId(c);
    }
  }
  for (int part = 0; part < n; ++part)
  {
    vtkNew<vtkExtractCells> extract;
    extract->SetInputData(labelled);
    extract->SetCellList(cells[part]);
    extract->Update();
    vtkSmartPointer<vtkUnstructuredGrid> piece = extract->GetOutput();
    piece->GetPointData()->SetActiveScalars(whole->GetPointData()->GetScalars()->GetName());
    pieces.push_back(piece);
  }
  std::printf("graph partition into %d pieces: edge cut %lld, imbalance %.3f, %.1f s\n", n,
    static_cast<long long>(partition->GetLastEdgeCut()), partition->GetLastImbalance(),
    partition->GetLastGraphSeconds() + partition->GetLastPartitionSeconds());
#else
  (void)n;
  std::cerr << "error: vtkAPCGraphPartition is not in this build\n";
#endif
  return pieces;
}

enum class MeshKind
{
  Wind,
  Flange
};

const char* MeshName(MeshKind kind)
{
  return kind == MeshKind::Wind ? "wind" : "flange";
}

struct Mesh
{
  std::string Path;
  std::string Field;
  apctest::TransferFunction TF;
};

// The wind (U_mag, paraview_vs_apc.py's transfer function) and the flange (T, with
// apcBenchmarkMappers' transfer function).
Mesh LoadMesh(MeshKind kind, const std::string& data)
{
  Mesh mesh;
  if (kind == MeshKind::Wind)
  {
    mesh.Path = data + "/windAroundBuildings/wind.pvtu";
    mesh.Field = "U_mag";
    mesh.TF = apctest::WindTF();
    return mesh;
  }
  mesh.Path = data + "/flange/flange.pvtu";
  mesh.Field = "T";
  mesh.TF.Colours = { { 273.0, 0.23, 0.3, 0.75 }, { 423.0, 0.87, 0.87, 0.87 },
    { 573.0, 0.7, 0.02, 0.15 } };
  mesh.TF.Opacities = { { 273.0, 0.15 }, { 423.0, 0.02 }, { 573.0, 0.6 } };
  mesh.TF.UnitDistance = 0.002;
  return mesh;
}

// paraview_vs_apc.py's wind camera moved to `distance` times its focal distance along its
// line of sight.
void SetWindCamera(
  vtkRenderer* renderer, const double bounds[6], double distance, int width, int height)
{
  const apctest::View view = apctest::WindView(width, height);
  vtkCamera* camera = renderer->GetActiveCamera();
  double position[3];
  for (int k = 0; k < 3; ++k)
  {
    position[k] = view.FocalPoint[k] + distance * (view.Position[k] - view.FocalPoint[k]);
  }
  camera->SetFocalPoint(view.FocalPoint.data());
  camera->SetPosition(position);
  camera->SetViewUp(view.ViewUp.data());
  camera->SetViewAngle(view.ViewAngle);
  camera->ParallelProjectionOff();
  renderer->ResetCameraClippingRange(bounds);
}

// apcBenchmarkMappers' flange camera: from -y, azimuth 35, elevation 30, dolly 1.6.
void SetFlangeCamera(vtkRenderer* renderer, const double bounds[6])
{
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetFocalPoint(0, 0, 0);
  camera->SetPosition(0, -1, 0);
  camera->SetViewUp(0, 0, 1);
  camera->ParallelProjectionOff();
  renderer->ResetCamera(bounds);
  camera->Azimuth(35);
  camera->Elevation(30);
  camera->OrthogonalizeViewUp();
  camera->Dolly(1.6);
  renderer->ResetCameraClippingRange(bounds);
}
}

int main(int argc, char* argv[])
{
  std::string out;
  std::string data = std::string(APC_SOURCE_DIR) + "/Data";
  int size = 512;
  int largeSize = -1; // the gear teeth beyond 8 ranks; -1: size
  int largeCameras = 4;
  int windWidth = 1024;
  int windHeight = 1024;
  int flangeSize = 512;
  std::vector<double> gearRanks = { 1, 2, 4, 8 };
  std::vector<double> windRanks = { 2, 4, 8 };
  std::vector<double> distances = { 0.6, 1.0, 1.6 };
  std::vector<double> flangeRanks;
  std::vector<double> partitionRanks;
  std::set<std::string> partitionMeshes = { "wind", "flange" };
  int partitionSize = 512;
  std::vector<double> partitionDistances = { 1.0 };
  for (int a = 1; a < argc; ++a)
  {
    const bool hasValue = a + 1 < argc;
    if (!std::strcmp(argv[a], "--out") && hasValue)
    {
      out = argv[++a];
    }
    else if (!std::strcmp(argv[a], "--data") && hasValue)
    {
      data = argv[++a];
    }
    else if (!std::strcmp(argv[a], "--size") && hasValue)
    {
      size = std::atoi(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--gear-large-size") && hasValue)
    {
      largeSize = std::atoi(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--gear-large-cameras") && hasValue)
    {
      largeCameras = std::atoi(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--wind-size") && a + 2 < argc)
    {
      windWidth = std::atoi(argv[++a]);
      windHeight = std::atoi(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--flange-size") && hasValue)
    {
      flangeSize = std::atoi(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--gear-ranks") && hasValue)
    {
      gearRanks = ParseList(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--wind-ranks") && hasValue)
    {
      windRanks = ParseList(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--wind-distances") && hasValue)
    {
      distances = ParseList(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--flange-ranks") && hasValue)
    {
      flangeRanks = ParseList(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--partition-ranks") && hasValue)
    {
      partitionRanks = ParseList(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--partition-size") && hasValue)
    {
      partitionSize = std::atoi(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--partition-distances") && hasValue)
    {
      partitionDistances = ParseList(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--partition-meshes") && hasValue)
    {
      partitionMeshes.clear();
      std::stringstream list(argv[++a]);
      std::string item;
      while (std::getline(list, item, ','))
      {
        partitionMeshes.insert(item);
      }
    }
    else
    {
      Usage(argv[0]);
      return 2;
    }
  }
  largeSize = largeSize < 0 ? size : largeSize;
  if (out.empty() || size < 1 || largeSize < 1 || windWidth < 1 || windHeight < 1 ||
    flangeSize < 1 || partitionSize < 1 || largeCameras < 1 || largeCameras > 4)
  {
    Usage(argv[0]);
    return 2;
  }
  std::error_code made;
  std::filesystem::create_directories(out, made);
  if (made)
  {
    std::cerr << "error: cannot create " << out << ": " << made.message() << "\n";
    return 1;
  }

  std::ostringstream rows;
  rows << "case,ranks,camera,width,height,rect_pixels,nonempty_pixels,segments,"
          "avg_segments_per_pixel,max_segments_per_pixel,direct_send_segments,"
          "binary_swap_segments,binary_swap_unmerged_segments,apc_bytes,direct_send_bytes,"
          "binary_swap_bytes,heatmap,sample_distance,tiles,covered_tiles,covered_tile_pixels,"
          "ds_max_sent_segments,ds_max_received_segments,ds_pairwise_critical_segments,"
          "ds_messages,bs_critical_segments,seconds\n";
  // Written after every configuration, so that a long run killed part way keeps its rows.
  const std::string csv = out + "/segment_transfer.csv";
  auto save = [&]
  {
    std::ofstream file(csv);
    file << rows.str();
    return static_cast<bool>(file);
  };

  // The gear teeth, as apcScalingBenchmark renders them (beyond 8 ranks, see above).
  for (double value : gearRanks)
  {
    const int n = static_cast<int>(value);
    const bool large = n > 8;
    Analysis analysis(large ? largeSize : size, large ? largeSize : size);
    std::vector<vtkSmartPointer<vtkUnstructuredGrid>> pieces;
    for (int r = 0; r < n; ++r)
    {
      pieces.push_back(apcbench::GearTeethPiece(r, n));
    }
    vtkNew<vtkAPCVolumeMapper> mapper;
    vtkNew<vtkVolume> volume;
    apcbench::ConfigureGearTeethVolume(volume, mapper, n);
    mapper->SetSampleDistance(GearSampleDistance(n));
    for (int camera = 0; camera < (large ? largeCameras : 4); ++camera)
    {
      apcbench::SetGearTeethCamera(analysis.GetRenderer(), camera);
      rows << analysis.Run({ "gearteeth", n, std::to_string(camera), camera == 0 }, pieces, volume,
        mapper, apcbench::kGearBounds, out);
      if (!save())
      {
        std::cerr << "error: cannot write " << csv << "\n";
        return 1;
      }
    }
  }

  // The real meshes: the reader's pieces (case wind-<distance>, flange) and, where the graph
  // partitioner is built, its pieces (wind-metis-<distance>, flange-metis).
  struct MeshRuns
  {
    MeshKind Kind;
    bool Partitioned;
    std::vector<double> Ranks;
    int Width;
    int Height;
  };
  const MeshRuns runs[] = { { MeshKind::Wind, false, windRanks, windWidth, windHeight },
    { MeshKind::Flange, false, flangeRanks, flangeSize, flangeSize },
    { MeshKind::Wind, true, partitionRanks, partitionSize, partitionSize },
    { MeshKind::Flange, true, partitionRanks, partitionSize, partitionSize } };
  for (const MeshRuns& run : runs)
  {
    if (run.Ranks.empty() || (run.Partitioned && !partitionMeshes.count(MeshName(run.Kind))))
    {
      continue;
    }
    if (run.Partitioned && !kHaveGraphPartition)
    {
      std::printf("skipping %s cut by the graph partitioner: vtkAPCGraphPartition is not in "
                  "this build\n",
        MeshName(run.Kind));
      continue;
    }
    Analysis analysis(run.Width, run.Height);
    const Mesh mesh = LoadMesh(run.Kind, data);
    vtkSmartPointer<vtkUnstructuredGrid> whole;
    for (double value : run.Ranks)
    {
      const int n = static_cast<int>(value);
      double bounds[6];
      std::vector<vtkSmartPointer<vtkUnstructuredGrid>> pieces;
      if (run.Partitioned)
      {
        if (!whole)
        {
          whole = ReadWhole(mesh.Path, mesh.Field.c_str());
        }
        pieces = whole ? PartitionPieces(whole, n, bounds) : pieces;
      }
      else
      {
        pieces = ReaderPieces(mesh.Path, mesh.Field.c_str(), n, bounds);
      }
      if (pieces.empty())
      {
        return 1;
      }
      vtkNew<vtkAPCVolumeMapper> mapper;
      vtkNew<vtkVolume> volume;
      volume->SetMapper(mapper);
      volume->SetProperty(apctest::MakeVolumeProperty(mesh.TF));
      const std::string prefix =
        std::string(MeshName(run.Kind)) + (run.Partitioned ? "-metis" : "");
      const std::vector<double> views = run.Kind == MeshKind::Wind
        ? (run.Partitioned ? partitionDistances : distances)
        : std::vector<double>{ 0 };
      for (size_t v = 0; v < views.size(); ++v)
      {
        char label[32];
        std::snprintf(label, sizeof(label), "%g", views[v]);
        std::string name = prefix;
        if (run.Kind == MeshKind::Wind)
        {
          SetWindCamera(analysis.GetRenderer(), bounds, views[v], run.Width, run.Height);
          name += "-" + std::string(label);
        }
        else
        {
          SetFlangeCamera(analysis.GetRenderer(), bounds);
        }
        rows << analysis.Run({ name, n, label, true }, pieces, volume, mapper, bounds, out);
        if (!save())
        {
          std::cerr << "error: cannot write " << csv << "\n";
          return 1;
        }
      }
    }
  }

  if (!save())
  {
    std::cerr << "error: cannot write " << csv << "\n";
    return 1;
  }
  std::printf("wrote %s\n", csv.c_str());
  return 0;
}
