// Weak scaling of vtkAPCCompositePass under MPI: every rank generates its own piece of the
// gear teeth (vtkAPCPuzzleSource, one puzzle piece per rank, 4 slabs each, so the work per
// rank is constant and every piece overlaps every other in depth) and renders it through the
// pass in both compositing modes, APC and the exact sort-last baseline SEGMENTS, from 4
// cameras on an orbit. Rank 0 appends one CSV row per mode and camera: the frame time (max
// over ranks, median over frames), the stage times (max over ranks, median over frames),
// bytes and messages summed over ranks, pixels composited, the segment statistics, and how
// far the distributed image is from one process rendering all pieces with the same mapper
// (MBOIT for APC, EXACT for SEGMENTS): the paper's "APC on N ranks = 1-process MBOIT"; then
// per stage with collectives its time, its wait for the slowest rank and its transfer after
// the last arrival (max over ranks), the compositing time and the wait in it (mean over
// ranks) and the render imbalance (slowest / mean).
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
// The stages with collectives, whose wait for the slowest rank and transfer after the last
// arrival the pass times apart (vtkAPCCompositePass::Timings): a column each (max over ranks),
// both modes.
const char* const CollectiveStages[] = { "agree", "depth", "tiles", "allreduce", "reduce",
  "exchange", "gather", "statistics", "ranks" };
constexpr int NumberOfCollectiveStages = 9;
// A mode's compositing: APC's tiles, allreduce and reduce; SEGMENTS' exchange and gather.
bool IsCompositing(const std::string& stage, bool apc)
{
  return apc ? stage == "tiles" || stage == "allreduce" || stage == "reduce"
             : stage == "exchange" || stage == "gather";
}

// This rank's last frame: every collective stage's time, wait and transfer, then the
// compositing time and the wait in it, and the render imbalance (the display rank's).
std::vector<double> CollectiveColumns(const vtkAPCCompositePass* pass, bool apc)
{
  const vtkAPCCompositePass::Timings t = pass->GetLastTimings();
  std::vector<double> values;
  double compositing = 0;
  double waiting = 0;
  for (const char* stage : CollectiveStages)
  {
    const std::string name(stage);
    double parts[3] = { 0, 0, 0 };
    vtkAPCCompositePass::ForEachTiming(t,
      [&](const char* field, double value)
      {
        parts[0] += name == field ? value : 0.0;
        parts[1] += name + "_wait" == field ? value : 0.0;
        parts[2] += name + "_transfer" == field ? value : 0.0;
      });
    values.insert(values.end(), parts, parts + 3);
    compositing += IsCompositing(name, apc) ? parts[0] : 0.0;
    waiting += IsCompositing(name, apc) ? parts[1] : 0.0;
  }
  values.push_back(compositing);
  values.push_back(waiting);
  values.push_back(t.RenderImbalance);
  return values;
}

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
      // Per frame: the collective columns, max over ranks and mean over ranks.
      std::vector<std::vector<double>> collectiveMax;
      std::vector<std::vector<double>> collectiveMean;
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
        const std::vector<double> columns = CollectiveColumns(pass, apc);
        std::vector<double> largest(columns.size());
        std::vector<double> sum(columns.size());
        const auto n = static_cast<vtkIdType>(columns.size());
        controller->AllReduce(columns.data(), largest.data(), n, vtkCommunicator::MAX_OP);
        controller->AllReduce(columns.data(), sum.data(), n, vtkCommunicator::SUM_OP);
        collectiveMax.resize(columns.size());
        collectiveMean.resize(columns.size());
        for (size_t v = 0; v < columns.size(); ++v)
        {
          collectiveMax[v].push_back(largest[v]);
          collectiveMean[v].push_back(sum[v] / ranks);
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
        std::snprintf(line, sizeof(line), ",%.3g", identity);
        rows << line;
        // The collective stages (max over ranks), the compositing time and its wait (mean
        // over ranks) and the imbalance; medians over frames.
        const size_t k = 3 * NumberOfCollectiveStages;
        for (size_t v = 0; v < k; ++v)
        {
          std::snprintf(line, sizeof(line), ",%.6f", apctest::Median(collectiveMax[v], 0));
          rows << line;
        }
        std::snprintf(line, sizeof(line), ",%.6f,%.6f,%.4f\n",
          apctest::Median(collectiveMean[k], 0), apctest::Median(collectiveMean[k + 1], 0),
          apctest::Median(collectiveMax[k + 2], 0));
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
               "max_abs_diff_vs_1process";
        for (const char* stage : CollectiveStages)
        {
          csv << ',' << stage << "_stage_s," << stage << "_wait_s," << stage << "_transfer_s";
        }
        csv << ",compositing_mean_s,compositing_wait_mean_s,render_imbalance\n";
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
