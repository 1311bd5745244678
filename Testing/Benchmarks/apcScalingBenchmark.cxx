// Weak scaling of vtkAPCCompositePass under MPI: every rank generates its own piece of the
// gear teeth (vtkAPCPuzzleSource, one puzzle piece per rank, 4 slabs each, so the work per
// rank is constant and every piece overlaps every other in depth) and renders it through the
// pass in both compositing modes, APC and the exact sort-last baseline SEGMENTS, from 4
// cameras on an orbit. Rank 0 appends one CSV row per mode and camera: the frame time (max
// over ranks, median over frames), the stage times (max over ranks, median over frames),
// bytes and messages summed over ranks, pixels composited, the segment statistics, and how
// far the distributed image is from one process rendering all pieces with the same mapper
// (MBOIT for APC, EXACT for SEGMENTS): the paper's "APC on N ranks = 1-process MBOIT".
//
//   mpirun -np N apcScalingBenchmark [--size S] [--frames F] [--out scaling.csv]
//
// Not run by ctest; see run-scaling.sh.

#include "apcGearTeethScene.h"
#include "apcMPITest.h"
#include "apcTestCompositePass.h"
#include "apcTestStatistics.h"
#include "vtkAPCCompositePass.h"
#include "vtkAPCVolumeMapper.h"

#include "vtkDataArray.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkMPIController.h"
#include "vtkNew.h"
#include "vtkPointData.h"
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
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace
{
const char* const APCStages[] = { "pass1", "allreduce", "pass2", "reduce", "resolve" };
const char* const SegmentStages[] = { "segments", "exchange", "blend_segments", "gather" };
constexpr int NumberOfAPCStages = 5;
constexpr int NumberOfSegmentStages = 4;

// Rank 0's one-process render of all pieces (its own window, no pass) in the given mode.
vtkSmartPointer<vtkFloatArray> OneProcessImage(int pieces, int size, int camera, int mode)
{
  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->SetSize(size, size);
  vtkNew<vtkRenderer> renderer;
  window->AddRenderer(renderer);
  vtkNew<vtkAPCVolumeMapper> mapper;
  mapper->SetInputData(apcbench::GearTeethPiece(0, pieces, 1));
  mapper->SetMode(mode);
  vtkNew<vtkVolume> volume;
  apcbench::ConfigureGearTeethVolume(volume, mapper, pieces);
  renderer->AddVolume(volume);
  apcbench::SetGearTeethCamera(renderer, camera);
  window->Render();
  vtkNew<vtkFloatArray> rgba;
  rgba->DeepCopy(mapper->GetLastImage()->GetPointData()->GetArray("RGBA"));
  return rgba;
}

double MaxAbsDiff(vtkDataArray* a, vtkDataArray* b)
{
  if (!a || !b || a->GetNumberOfValues() != b->GetNumberOfValues())
  {
    return std::numeric_limits<double>::infinity();
  }
  double worst = 0;
  for (vtkIdType v = 0; v < a->GetNumberOfValues(); ++v)
  {
    worst = std::max(
      worst, std::abs(a->GetVariantValue(v).ToDouble() - b->GetVariantValue(v).ToDouble()));
  }
  return worst;
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
  vtkSmartPointer<vtkMPIController> controller = apctest::StartMPI(&argc, &argv);
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
  vtkSmartPointer<vtkUnstructuredGrid> piece = apcbench::GearTeethPiece(rank, ranks);

  vtkNew<vtkRenderWindow> window;
  vtkNew<vtkRenderer> renderer;
  vtkNew<vtkAPCCompositePass> pass;
  pass->KeepLastImageOn(); // compared with one process's image
  apctest::SetUpCompositeWindow(window, renderer, size, pass, controller);
  vtkNew<vtkAPCVolumeMapper> mapper;
  mapper->SetInputData(piece);
  vtkNew<vtkVolume> volume;
  apcbench::ConfigureGearTeethVolume(volume, mapper, ranks);
  pass->AddVolume(volume);

  std::ostringstream rows;
  int failedFrames = 0;
  for (int mode : { vtkAPCCompositePass::APC, vtkAPCCompositePass::SEGMENTS })
  {
    const bool apc = mode == vtkAPCCompositePass::APC;
    const char* const* stages = apc ? APCStages : SegmentStages;
    const int numberOfStages = apc ? NumberOfAPCStages : NumberOfSegmentStages;
    pass->SetCompositeMode(mode);
    // One untimed frame per mode: shader compilation and first-touch allocations.
    apcbench::SetGearTeethCamera(renderer, 0);
    window->Render();
    for (int camera = 0; camera < 4; ++camera)
    {
      apcbench::SetGearTeethCamera(renderer, camera);
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
      double identity = 0;
      if (rank == 0)
      {
        auto reference = OneProcessImage(
          ranks, size, camera, apc ? vtkAPCVolumeMapper::MBOIT : vtkAPCVolumeMapper::EXACT);
        identity = MaxAbsDiff(pass->GetLastImage()->GetPointData()->GetArray("RGBA"), reference);
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
          camera, apcbench::kGearAzimuths[camera], size, frames, apctest::Median(maxima[0], 0));
        rows << line;
        // Stage columns: the APC ones, then the SEGMENTS ones; the other mode's are empty.
        for (int s = 0; s < NumberOfAPCStages; ++s)
        {
          rows << ',';
          if (apc)
          {
            std::snprintf(line, sizeof(line), "%.6f", apctest::Median(maxima[1 + s], 0));
            rows << line;
          }
        }
        for (int s = 0; s < NumberOfSegmentStages; ++s)
        {
          rows << ',';
          if (!apc)
          {
            std::snprintf(line, sizeof(line), "%.6f", apctest::Median(maxima[1 + s], 0));
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
        std::snprintf(line, sizeof(line), ",%.3g\n", identity);
        rows << line;
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
               "messages,pixels_composited,avg_segments_per_pixel,max_segments_per_pixel,"
               "max_abs_diff_vs_1process\n";
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
