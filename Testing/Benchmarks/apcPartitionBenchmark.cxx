// SPDX-License-Identifier: BSD-3-Clause
// How long vtkAPCGraphPartition takes and how much memory each rank peaks at, METIS (the graph
// gathered on rank 0) against PT-Scotch (the graph distributed), one CSV line per run:
// - wind: the wind data (Data/, 332k cells), its pieces read distributed over the ranks;
// - tets: an n^3 image cut into 5 tetrahedra per voxel (625k cells at n = 50), generated on
//   rank 0 only (the "one file" case);
// - hexbox: an n^3 box of hexahedra (2.1M cells at n = 128), each rank generating only its own
//   slab of z layers, so no rank holds the whole mesh first (Testing/Common/apcHexBox.h).
// Memory: before each run every rank returns freed heap to the system (malloc_trim) and resets
// its peak resident size (/proc/self/clear_refs, "5"); after it, VmHWM is the run's peak,
// including the input mesh the rank holds. Gathered on rank 0 for the CSV (a few numbers).
//
//   apcPartitionBenchmark [--mesh wind|tets|hexbox|both] [--grid 50] [--box 128]
//                         [--k 2,4,8,16,64,256] [--repeats 3] [--label-only]
//                         [--partitioners metis,ptscotch] [--out file.csv]
// Not a test: run by Testing/Benchmarks/run-partition-benchmark.sh.

#include "apcHexBox.h"
#include "vtkAPCGraphPartition.h"

#include "vtkDataSetTriangleFilter.h"
#include "vtkImageData.h"
#include "vtkMPIController.h"
#include "vtkNew.h"
#include "vtkUnstructuredGrid.h"
#include "vtkXMLPUnstructuredGridReader.h"

#include <malloc.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace
{
vtkSmartPointer<vtkUnstructuredGrid> Wind(int rank, int ranks)
{
  vtkNew<vtkXMLPUnstructuredGridReader> reader;
  reader->SetFileName(APC_SOURCE_DIR "/Data/windAroundBuildings/wind.pvtu");
  reader->UpdatePiece(rank, ranks, 0);
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->ShallowCopy(reader->GetOutput());
  return grid;
}

vtkSmartPointer<vtkUnstructuredGrid> Tets(int n, bool here)
{
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  if (!here)
  {
    grid->SetPoints(vtkNew<vtkPoints>());
    return grid;
  }
  vtkNew<vtkImageData> image;
  image->SetDimensions(n + 1, n + 1, n + 1);
  image->SetSpacing(1.0 / n, 1.0 / n, 1.0 / n);
  vtkNew<vtkDataSetTriangleFilter> tets;
  tets->SetInputData(image);
  tets->Update();
  grid->ShallowCopy(tets->GetOutput());
  return grid;
}

// A field of /proc/self/status in MiB (VmHWM: peak resident size, VmRSS: current), 0 if absent.
double StatusMiB(const char* field)
{
  std::ifstream status("/proc/self/status");
  std::string line;
  const std::size_t length = std::strlen(field);
  while (std::getline(status, line))
  {
    if (line.compare(0, length, field) == 0 && line.size() > length && line[length] == ':')
    {
      return std::atof(line.c_str() + length + 1) / 1024.0;
    }
  }
  return 0;
}

// CPU seconds (user + system) of this process so far: the machine is shared, so wall time
// alone is not trusted. Includes MPI's busy polling while a rank waits in a collective.
double CpuSeconds()
{
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_utime.tv_sec + usage.ru_stime.tv_sec +
    1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

// Freed heap back to the system, then the peak reset to the current size; false where the
// kernel does not allow the reset (the peak is then the process's since it started).
bool ResetPeak()
{
  malloc_trim(0);
  std::ofstream clear("/proc/self/clear_refs");
  clear << "5";
  clear.close();
  return static_cast<bool>(clear);
}

std::vector<std::string> Split(const std::string& text)
{
  std::vector<std::string> items;
  std::stringstream list(text);
  std::string item;
  while (std::getline(list, item, ','))
  {
    items.push_back(item);
  }
  return items;
}

struct Options
{
  std::string Mesh = "both", Out;
  int Grid = 50, Box = 128, Repeats = 3;
  bool LabelOnly = false;
  std::vector<int> Ks{ 2, 4, 8, 16, 64, 256 };
  // METIS and PT-Scotch side by side in the same run (the machine is noisy).
  std::vector<std::string> Partitioners{ "metis", "ptscotch" };
};

Options Parse(int argc, char* argv[])
{
  Options o;
  for (int i = 1; i < argc; ++i)
  {
    const std::string a = argv[i];
    auto next = [&]() { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (a == "--mesh")
      o.Mesh = next();
    else if (a == "--grid")
      o.Grid = std::atoi(next().c_str());
    else if (a == "--box")
      o.Box = std::atoi(next().c_str());
    else if (a == "--repeats")
      o.Repeats = std::max(1, std::atoi(next().c_str()));
    else if (a == "--label-only")
      o.LabelOnly = true;
    else if (a == "--out")
      o.Out = next();
    else if (a == "--partitioners")
      o.Partitioners = Split(next());
    else if (a == "--k")
    {
      o.Ks.clear();
      for (const auto& k : Split(next()))
      {
        o.Ks.push_back(std::atoi(k.c_str()));
      }
    }
  }
  return o;
}

struct Measured
{
  double Seconds[4] = { 1e300, 1e300, 1e300, 1e300 }; // graph, partition, move, total
  vtkIdType Cut = 0;
  double Imbalance = 0;
  double CpuSeconds = 1e300; // this rank's, in the fastest repeat
  double PeakMiB = 0;        // this rank's, the largest over the repeats
  double BeforeMiB = 0;      // this rank's resident size before the first run
  bool PeakReset = true;
};

Measured Run(vtkMPIController* controller, vtkUnstructuredGrid* mesh,
  const std::string& partitioner, int k, const Options& o)
{
  Measured m;
  for (int r = 0; r < o.Repeats; ++r)
  {
    m.PeakReset = ResetPeak() && m.PeakReset;
    if (r == 0)
    {
      m.BeforeMiB = StatusMiB("VmRSS");
    }
    {
      vtkNew<vtkAPCGraphPartition> partition;
      partition->SetInputData(mesh);
      partition->SetNumberOfPartitions(k);
      partition->SetLabelOnly(o.LabelOnly);
      partition->SetPartitioner(partitioner == "metis" ? vtkAPCGraphPartition::METIS
          : partitioner == "ptscotch"                  ? vtkAPCGraphPartition::PTSCOTCH
                                                       : vtkAPCGraphPartition::AUTO);
      controller->Barrier();
      const double cpu = CpuSeconds();
      const auto start = std::chrono::steady_clock::now();
      partition->Update();
      const double cpuSpent = CpuSeconds() - cpu;
      controller->Barrier();
      const double total =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      // The fastest of the repeats: the machine is shared, the minimum is the least disturbed.
      if (total < m.Seconds[3])
      {
        m.Seconds[0] = partition->GetLastGraphSeconds();
        m.Seconds[1] = partition->GetLastPartitionSeconds();
        m.Seconds[2] = partition->GetLastExchangeSeconds();
        m.Seconds[3] = total;
        m.CpuSeconds = cpuSpent;
      }
      m.Cut = partition->GetLastEdgeCut();
      m.Imbalance = partition->GetLastImbalance();
      // The output is still held here: it is part of what a rank holds after the filter.
      m.PeakMiB = std::max(m.PeakMiB, StatusMiB("VmHWM"));
    }
  }
  return m;
}

// One CSV row on rank 0: times, cut, imbalance and every rank's peak memory.
void Report(vtkMPIController* controller, FILE* csv, const std::string& mesh, vtkIdType cells,
  const std::string& partitioner, int k, const Options& o, const Measured& m)
{
  const int ranks = controller->GetNumberOfProcesses();
  double move = m.Seconds[2];
  controller->AllReduce(&m.Seconds[2], &move, 1, vtkCommunicator::MAX_OP);
  constexpr int kValues = 4;
  double mine[kValues] = { m.PeakMiB, m.BeforeMiB, m.PeakReset ? 1.0 : 0.0, m.CpuSeconds };
  std::vector<double> all(kValues * static_cast<std::size_t>(ranks));
  controller->Gather(mine, all.data(), kValues, 0);
  if (!csv)
  {
    return;
  }
  double others = 0, before = 0, cpu = 0;
  bool reset = true;
  std::string peaks;
  for (int r = 0; r < ranks; ++r)
  {
    const double* at = all.data() + kValues * r;
    others = r > 0 ? std::max(others, at[0]) : others;
    before = std::max(before, at[1]);
    reset = reset && at[2] > 0;
    cpu = std::max(cpu, at[3]);
    peaks += (r ? ";" : "") + std::to_string(static_cast<long>(at[0] + 0.5));
  }
  std::fprintf(csv,
    "%s,%lld,%d,%d,%s,%s,%.4f,%.4f,%.4f,%.4f,%.3f,%.3f,%.0f,%lld,%.4f,%.0f,%.0f,%.3f,%.0f,%s,%d\n",
    mesh.c_str(), static_cast<long long>(cells), ranks, k, o.LabelOnly ? "label" : "move",
    partitioner.c_str(), m.Seconds[0], m.Seconds[1], move, m.Seconds[3], all[3], cpu,
    cells / m.Seconds[3], static_cast<long long>(m.Cut), m.Imbalance, all[0], others,
    ranks > 1 ? all[0] / others : 1.0, before, peaks.c_str(), reset ? 1 : 0);
  std::fflush(csv);
}
} // namespace

int main(int argc, char* argv[])
{
  vtkNew<vtkMPIController> controller;
  controller->Initialize(&argc, &argv);
  vtkMultiProcessController::SetGlobalController(controller);
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  const Options o = Parse(argc, argv);

  std::vector<std::pair<std::string, vtkSmartPointer<vtkUnstructuredGrid>>> meshes;
  if (o.Mesh == "wind" || o.Mesh == "both")
  {
    meshes.emplace_back("wind", Wind(rank, ranks));
  }
  if (o.Mesh == "tets" || o.Mesh == "both")
  {
    meshes.emplace_back("tets" + std::to_string(o.Grid), Tets(o.Grid, rank == 0));
  }
  if (o.Mesh == "hexbox")
  {
    meshes.emplace_back("hexbox" + std::to_string(o.Box), apctest::HexBoxSlab(o.Box, rank, ranks));
  }

  FILE* csv = nullptr;
  if (rank == 0)
  {
    FILE* existing = o.Out.empty() ? nullptr : std::fopen(o.Out.c_str(), "r");
    const bool fresh = !existing;
    if (existing)
    {
      std::fclose(existing);
    }
    csv = o.Out.empty() ? stdout : std::fopen(o.Out.c_str(), "a");
    if (fresh)
    {
      std::fprintf(csv,
        "mesh,cells,ranks,K,mode,partitioner,graph_s,partition_s,move_s,total_s,rank0_cpu_s,"
        "max_cpu_s,"
        "cells_per_s,edge_cut,imbalance,rank0_peak_mib,others_peak_mib,rank0_over_others,"
        "before_mib,peak_mib_per_rank,peak_reset\n");
    }
  }
  for (const auto& mesh : meshes)
  {
    vtkIdType local = mesh.second->GetNumberOfCells(), cells = 0;
    controller->AllReduce(&local, &cells, 1, vtkCommunicator::SUM_OP);
    for (const auto& partitioner : o.Partitioners)
    {
      for (const int k : o.Ks)
      {
        const Measured m = Run(controller, mesh.second, partitioner, k, o);
        Report(controller, csv, mesh.first, cells, partitioner, k, o, m);
      }
    }
  }
  if (csv && csv != stdout)
  {
    std::fclose(csv);
  }
  controller->Finalize();
  return 0;
}
