// SPDX-License-Identifier: BSD-3-Clause
// The in-situ example: an MPI mini-application (apc::WindTracer: a tracer carried by the wind
// through the buildings of the bundled OpenFOAM case, each rank advancing its own pieces of the
// graph-partitioned mesh) that hands every time step to ParaView Catalyst
// (apc::CatalystAdaptor); the Catalyst script renders it with APC Volume.
//
//   mpirun -np 4 apcCatalystMiniApp --script apc_catalyst_tracer.py --steps 400 --every 100
//
// Options the script reads (the mini-app puts them in its own environment, APC_CATALYST_*):
// --output DIR, --every N, --representation "APC Volume" | Volume, --size W H; --plugin gives
// the APC plugin's path (APC_PLUGIN). --data-ranks R leaves the ranks from R on without cells.
// --csv FILE: rank 0 appends one line per processed step and per rank's peak memory.
#include "apcCatalystAdaptor.h"
#include "apcWindTracer.h"

#include "vtkMultiBlockDataSet.h"
#include "vtkPolyData.h"

#include <mpi.h>
#include <sys/resource.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#ifndef APC_DEFAULT_DATA
#define APC_DEFAULT_DATA ""
#endif
#ifndef APC_DEFAULT_PLUGIN
#define APC_DEFAULT_PLUGIN ""
#endif

namespace
{
struct Options
{
  std::string Data = APC_DEFAULT_DATA;
  std::string Script;
  std::string Plugin = APC_DEFAULT_PLUGIN;
  std::string Output = "catalyst-out";
  std::string Representation = "APC Volume";
  std::string Csv;
  std::string Size = "640 400";
  double TimeStep = 0.05; // s: about the explicit limit of the smallest 5 % of the cells
  long Steps = 400;
  long Every = 100;
  int DataRanks = 0;
};

bool Parse(int argc, char* argv[], Options& o, std::string& error)
{
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    const bool more = i + 1 < argc;
    if (arg == "--data" && more)
      o.Data = argv[++i];
    else if (arg == "--script" && more)
      o.Script = argv[++i];
    else if (arg == "--plugin" && more)
      o.Plugin = argv[++i];
    else if (arg == "--output" && more)
      o.Output = argv[++i];
    else if (arg == "--representation" && more)
      o.Representation = argv[++i];
    else if (arg == "--csv" && more)
      o.Csv = argv[++i];
    else if (arg == "--steps" && more)
      o.Steps = std::atol(argv[++i]);
    else if (arg == "--every" && more)
      o.Every = std::atol(argv[++i]);
    else if (arg == "--dt" && more)
      o.TimeStep = std::atof(argv[++i]);
    else if (arg == "--data-ranks" && more)
      o.DataRanks = std::atoi(argv[++i]);
    else if (arg == "--size" && i + 2 < argc)
    {
      o.Size = std::string(argv[i + 1]) + " " + argv[i + 2];
      i += 2;
    }
    else
    {
      error = "unknown or incomplete option " + arg;
      return false;
    }
  }
  if (o.Script.empty() || o.Steps < 0 || o.Every < 1 || !(o.TimeStep > 0))
  {
    error = "usage: apcCatalystMiniApp --script FILE [--data FILE.pvtu] [--steps N] [--every N] "
            "[--output DIR] [--representation NAME] [--size W H] [--plugin FILE] "
            "[--dt S] [--data-ranks R] [--csv FILE]";
    return false;
  }
  return true;
}

double MaxOverRanks(double value)
{
  double all = 0;
  MPI_Allreduce(&value, &all, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return all;
}

// Peak resident memory of every rank (MB), on rank 0.
std::vector<double> PeakMemory()
{
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  double mine = usage.ru_maxrss / 1024.0; // kB on Linux
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  std::vector<double> all(size);
  MPI_Gather(&mine, 1, MPI_DOUBLE, all.data(), 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  return all;
}

int Run(const Options& o, int rank, int size)
{
  // The script's settings: a simulation would read them from its input deck.
  setenv("APC_CATALYST_OUTPUT", o.Output.c_str(), 1);
  setenv("APC_CATALYST_EVERY", std::to_string(o.Every).c_str(), 1);
  setenv("APC_CATALYST_REPRESENTATION", o.Representation.c_str(), 1);
  setenv("APC_CATALYST_SIZE", o.Size.c_str(), 1);
  setenv("APC_PLUGIN", o.Plugin.c_str(), 1);

  apc::WindTracer sim;
  std::string error;
  const double setupStart = MPI_Wtime();
  if (!sim.Initialize(o.Data, MPI_COMM_WORLD, o.DataRanks, o.TimeStep, error))
  {
    if (rank == 0)
      std::fprintf(stderr, "apcCatalystMiniApp: %s\n", error.c_str());
    return 1;
  }
  const double setup = MaxOverRanks(MPI_Wtime() - setupStart);
  apc::CatalystAdaptor catalyst;
  if (!catalyst.Initialize(o.Script, { "mesh", "walls" }, error))
  {
    if (rank == 0)
      std::fprintf(stderr, "apcCatalystMiniApp: %s\n", error.c_str());
    return 1;
  }
  if (rank == 0)
    std::printf("apcCatalystMiniApp: %d ranks, %d pieces, dt %.4g s, set-up %.2f s; "
                "%ld steps, Catalyst output every %ld with %s\n",
      size, sim.GetNumberOfPieces(), sim.GetTimeStep(), setup, o.Steps, o.Every,
      o.Representation.c_str());
  std::ofstream csv;
  if (rank == 0 && !o.Csv.empty())
    csv.open(o.Csv, std::ios::app);
  auto provider = [&sim](const std::string& channel) -> vtkDataObject*
  { return channel == "mesh" ? static_cast<vtkDataObject*>(sim.GetMesh()) : sim.GetWalls(); };
  double solver = 0;
  for (long step = 0; step <= o.Steps; ++step)
  {
    double start = MPI_Wtime();
    if (step > 0)
      sim.Advance();
    solver += MPI_Wtime() - start;
    start = MPI_Wtime();
    const int done = catalyst.CoProcess(step * sim.GetTimeStep(), step, step == o.Steps, provider);
    const double took = MaxOverRanks(MPI_Wtime() - start);
    if (done < 0)
    {
      if (rank == 0)
        std::fprintf(
          stderr, "apcCatalystMiniApp: the Catalyst pipeline failed at step %ld\n", step);
      return 1;
    }
    if (done == 0)
      continue;
    const double tracer = sim.GetTracerVolume();
    const double solved = MaxOverRanks(solver);
    if (rank == 0)
    {
      std::printf("step %5ld  t %7.2f s  tracer %9.1f m3  solver %6.3f s  catalyst (%s) %7.3f s\n",
        step, step * sim.GetTimeStep(), tracer, solved, o.Representation.c_str(), took);
      std::fflush(stdout);
      if (csv)
        csv << "step," << o.Representation << "," << size << "," << step << "," << took << ","
            << solved << "\n";
    }
    solver = 0;
  }
  catalyst.Finalize();
  const std::vector<double> memory = PeakMemory();
  for (int r = 0; rank == 0 && r < size; ++r)
  {
    std::printf("rank %d peak memory %.1f MB\n", r, memory[r]);
    if (csv)
      csv << "memory," << o.Representation << "," << size << "," << r << "," << memory[r] << ",\n";
  }
  return 0;
}
}

int main(int argc, char* argv[])
{
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  Options options;
  std::string error;
  int status = 2;
  if (!Parse(argc, argv, options, error))
  {
    if (rank == 0)
      std::fprintf(stderr, "apcCatalystMiniApp: %s\n", error.c_str());
  }
  else
  {
    status = Run(options, rank, size);
  }
  if (rank == 0)
    std::printf("apcCatalystMiniApp: %s\n", status == 0 ? "done" : "stopped");
  MPI_Finalize();
  return status;
}
