// Weak scaling of vtkAPCCompositePass under MPI: every rank generates its own piece of the
// gear teeth (vtkAPCPuzzleSource, one puzzle piece per rank, 4 slabs each, so the work per
// rank is constant and every piece overlaps every other in depth) and renders it through the
// pass in both compositing modes, APC and the exact sort-last baseline SEGMENTS, from 4
// cameras on an orbit. Rank 0 appends one CSV row per mode and camera: the frame time (max
// over ranks, median over frames), the stage times (max over ranks, median over frames),
// bytes and messages summed over ranks, pixels composited and the segment statistics.
//
//   mpirun -np N apcScalingBenchmark [--size S] [--frames F] [--out scaling.csv]
//
// Not run by ctest; see run-scaling.sh.

#include "vtkAPCCompositePass.h"
#include "vtkAPCPuzzleSource.h"
#include "vtkAPCVolumeMapper.h"

#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkMPIController.h"
#include "vtkNew.h"
#include "vtkPiecewiseFunction.h"
#include "vtkRenderStepsPass.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace
{
const char* const APCStages[] = { "pass1", "allreduce", "pass2", "reduce", "resolve" };
const char* const SegmentStages[] = { "segments", "exchange", "blend_segments", "gather" };
constexpr int NumberOfAPCStages = 5;
constexpr int NumberOfSegmentStages = 4;

double Median(std::vector<double> values)
{
  if (values.empty())
  {
    return 0;
  }
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

// One colour per puzzle piece (the Sandwich field is piece / max(pieces - 1, 1)), all fairly
// opaque, as TestVolumeMapperQuality's SandwichTF.
void ConfigureVolume(vtkVolume* volume, vtkAPCVolumeMapper* mapper, int pieces)
{
  static const double palette[8][3] = { { 0.9, 0.1, 0.1 }, { 0.1, 0.8, 0.1 }, { 0.1, 0.2, 0.9 },
    { 0.9, 0.8, 0.1 }, { 0.8, 0.1, 0.8 }, { 0.1, 0.8, 0.8 }, { 0.9, 0.5, 0.1 }, { 0.6, 0.6, 0.6 } };
  vtkNew<vtkColorTransferFunction> colour;
  const double denominator = std::max(pieces - 1, 1);
  for (int p = 0; p < pieces; ++p)
  {
    const double* c = palette[p % 8];
    colour->AddRGBPoint(p / denominator, c[0], c[1], c[2]);
  }
  vtkNew<vtkPiecewiseFunction> opacity;
  opacity->AddPoint(0.0, 0.6);
  opacity->AddPoint(1.0, 0.6);
  vtkNew<vtkVolumeProperty> property;
  property->SetColor(colour);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(0.1);
  mapper->SetSampleDistance(0.01);
  volume->SetMapper(mapper);
  volume->SetProperty(property);
}

void SetCamera(vtkRenderer* renderer, double azimuthDegrees)
{
  const double distance = 4.5;
  const double pi = 3.14159265358979323846;
  const double azimuth = azimuthDegrees * pi / 180;
  const double elevation = 30 * pi / 180;
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->ParallelProjectionOff();
  camera->SetFocalPoint(0, 0, 0);
  camera->SetPosition(distance * std::cos(elevation) * std::sin(azimuth),
    distance * std::sin(elevation), distance * std::cos(elevation) * std::cos(azimuth));
  camera->SetViewUp(0, 1, 0);
  camera->SetViewAngle(30);
  const double bounds[6] = { -1, 1, -1, 1, -1, 1 };
  renderer->ResetCameraClippingRange(bounds);
}

double Seconds()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

void Usage(const char* program)
{
  std::fprintf(
    stderr, "usage: mpirun -np N %s [--size S] [--frames F] [--out file.csv]\n", program);
}
}

int main(int argc, char* argv[])
{
  vtkNew<vtkMPIController> controller;
  controller->Initialize(&argc, &argv);
  vtkMultiProcessController::SetGlobalController(controller);
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();

  int size = 512;
  int frames = 5;
  std::string out = "scaling.csv";
  for (int a = 1; a < argc; ++a)
  {
    const bool hasValue = a + 1 < argc;
    if (!std::strcmp(argv[a], "--size") && hasValue)
    {
      size = std::atoi(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--frames") && hasValue)
    {
      frames = std::atoi(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--out") && hasValue)
    {
      out = argv[++a];
    }
    else
    {
      if (rank == 0)
      {
        Usage(argv[0]);
      }
      controller->Finalize();
      return 2;
    }
  }
  if (size < 1 || frames < 1)
  {
    if (rank == 0)
    {
      Usage(argv[0]);
    }
    controller->Finalize();
    return 2;
  }

  // This rank's piece: one puzzle piece per rank, constant work per rank.
  vtkNew<vtkAPCPuzzleSource> source;
  source->SetNumberOfPuzzlePieces(0);
  source->SetSlabsPerPiece(4);
  source->SetResolution(32);
  source->SetField(vtkAPCPuzzleSource::SANDWICH);
  source->UpdatePiece(rank, ranks, 0);
  vtkSmartPointer<vtkUnstructuredGrid> piece = source->GetOutput();

  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->SetSize(size, size);
  vtkNew<vtkRenderer> renderer;
  window->AddRenderer(renderer);
  vtkNew<vtkAPCCompositePass> pass;
  vtkNew<vtkRenderStepsPass> opaque;
  pass->SetDelegatePass(opaque);
  pass->SetController(controller);
  renderer->SetPass(pass);
  vtkNew<vtkAPCVolumeMapper> mapper;
  mapper->SetInputData(piece);
  vtkNew<vtkVolume> volume;
  ConfigureVolume(volume, mapper, ranks);
  pass->AddVolume(volume);

  std::ostringstream rows;
  int failedFrames = 0;
  const double azimuths[4] = { 0, 90, 180, 270 };
  for (int mode : { vtkAPCCompositePass::APC, vtkAPCCompositePass::SEGMENTS })
  {
    const bool apc = mode == vtkAPCCompositePass::APC;
    const char* const* stages = apc ? APCStages : SegmentStages;
    const int numberOfStages = apc ? NumberOfAPCStages : NumberOfSegmentStages;
    pass->SetCompositeMode(mode);
    // One untimed frame per mode: shader compilation and first-touch allocations.
    SetCamera(renderer, azimuths[0]);
    window->Render();
    for (int camera = 0; camera < 4; ++camera)
    {
      SetCamera(renderer, azimuths[camera]);
      // Per frame: the max over ranks of the frame time and of every stage's time.
      std::vector<std::vector<double>> maxima(1 + numberOfStages);
      for (int f = 0; f < frames; ++f)
      {
        controller->Barrier();
        const double start = Seconds();
        window->Render();
        std::vector<double> local(1 + numberOfStages);
        local[0] = Seconds() - start;
        for (int s = 0; s < numberOfStages; ++s)
        {
          local[1 + s] = pass->GetLastStageSeconds(stages[s]);
        }
        std::vector<double> global(local.size());
        controller->AllReduce(local.data(), global.data(), static_cast<vtkIdType>(local.size()),
          vtkCommunicator::MAX_OP);
        for (size_t v = 0; v < global.size(); ++v)
        {
          maxima[v].push_back(global[v]);
        }
        failedFrames += pass->GetLastFrameFailed() ? 1 : 0;
      }
      // Bytes and messages of the last frame (the same every frame for a fixed camera).
      double sent[2] = { pass->GetLastBytesSent(),
        static_cast<double>(pass->GetLastMessagesSent()) };
      double totals[2] = { 0, 0 };
      controller->Reduce(sent, totals, 2, vtkCommunicator::SUM_OP, 0);
      if (rank == 0)
      {
        char line[1024];
        std::snprintf(line, sizeof(line), "%d,%s,%d,%g,%d,%d,%.6f", ranks, apc ? "APC" : "SEGMENTS",
          camera, azimuths[camera], size, frames, Median(maxima[0]));
        rows << line;
        // Stage columns: the APC ones, then the SEGMENTS ones; the other mode's are empty.
        for (int s = 0; s < NumberOfAPCStages; ++s)
        {
          rows << ',';
          if (apc)
          {
            std::snprintf(line, sizeof(line), "%.6f", Median(maxima[1 + s]));
            rows << line;
          }
        }
        for (int s = 0; s < NumberOfSegmentStages; ++s)
        {
          rows << ',';
          if (!apc)
          {
            std::snprintf(line, sizeof(line), "%.6f", Median(maxima[1 + s]));
            rows << line;
          }
        }
        std::snprintf(line, sizeof(line), ",%.0f,%.0f,%lld", totals[0], totals[1],
          static_cast<long long>(pass->GetLastCompositedPixels()));
        rows << line;
        if (apc)
        {
          rows << ",,";
        }
        else
        {
          std::snprintf(line, sizeof(line), ",%.4f,%lld", pass->GetLastAverageSegmentsPerPixel(),
            static_cast<long long>(pass->GetLastMaxSegmentsPerPixel()));
          rows << line;
        }
        rows << '\n';
      }
    }
  }

  int globalFailed = 0;
  controller->AllReduce(&failedFrames, &globalFailed, 1, vtkCommunicator::SUM_OP);
  int status = 0;
  if (rank == 0)
  {
    bool header = true;
    {
      std::ifstream existing(out);
      header = !existing.good() || existing.peek() == std::ifstream::traits_type::eof();
    }
    std::ofstream csv(out, std::ios::app);
    if (!csv)
    {
      std::fprintf(stderr, "error: cannot write %s\n", out.c_str());
      status = 1;
    }
    else
    {
      if (header)
      {
        csv << "ranks,mode,camera,azimuth,size,frames,frame_s,pass1_s,allreduce_s,pass2_s,"
               "reduce_s,resolve_s,segments_s,exchange_s,blend_segments_s,gather_s,bytes_sent,"
               "messages,pixels_composited,avg_segments_per_pixel,max_segments_per_pixel\n";
      }
      csv << rows.str();
    }
    if (globalFailed > 0)
    {
      std::fprintf(stderr, "error: %d frame(s) failed (summed over ranks)\n", globalFailed);
      status = 1;
    }
    std::printf(
      "%d ranks: %s %s\n", ranks, status ? "FAILED, rows in" : "rows appended to", out.c_str());
  }
  controller->Broadcast(&status, 1, 0);
  controller->Finalize();
  return status;
}
