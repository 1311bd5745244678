// The constants of the alpha-beta-gamma compositing model (scaling_model.py), measured on this
// machine with plain MPI: latency alpha and inverse bandwidth beta from a ping-pong between
// ranks 0 and 1 over message sizes, the per-byte reduction cost gamma from MPI_Allreduce and
// MPI_Reduce of float and double sums (the operations vtkAPCCompositePass runs), and, in one
// process, the memory bandwidth of a copy and of a local sum (what packing segments and
// summing images cost). The other ranks take part in every timed operation or wait in a
// barrier, so an oversubscribed run (more ranks than cores) is measured under the same
// contention as the compositing benchmarks it is held against.
//
//   mpirun -np N apcCommBenchmark [--out comm.csv] [--max-bytes B] [--repetitions R]
//                                 [--budget S]
//
// Rank 0 appends one CSV row per operation, type and size (writing the header when the file
// is new): ranks, op, type, bytes (per rank's buffer; ping-pong: one message), repetitions,
// min_s, median_s (ping-pong: half the round trip; collectives: the max over ranks of one
// call, each call started after a barrier), load1 (the 1-minute load average at the end).
// Times are wall clock; take min or median: this machine is shared. Last, the barrier the
// pass enters every collective through against MPI_Barrier (see Barriers). Not run by ctest;
// see run-evaluation.sh.

#include "apcCollectiveTimes.h"

#include "vtkMPIController.h"
#include "vtkNew.h"

#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

namespace
{
double Now()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct Timing
{
  int Repetitions = 0;
  double Min = 0;
  double Median = 0;
};

Timing Summarise(std::vector<double> times)
{
  Timing t;
  t.Repetitions = static_cast<int>(times.size());
  if (times.empty())
  {
    return t;
  }
  std::sort(times.begin(), times.end());
  t.Min = times.front();
  t.Median = times[times.size() / 2];
  return t;
}

// Repeats `once` (which returns the seconds of one repetition, the same on every rank) at
// least `minimum` and at most `maximum` times, stopping after `budget` seconds. Rank 0 decides
// when to stop so that every rank runs the same number of repetitions.
template <class Once>
Timing Repeat(Once once, int minimum, int maximum, double budget)
{
  std::vector<double> times;
  const double start = MPI_Wtime();
  for (int r = 0; r < maximum; ++r)
  {
    times.push_back(once());
    int more = r + 1 < minimum || MPI_Wtime() - start < budget;
    MPI_Bcast(&more, 1, MPI_INT, 0, MPI_COMM_WORLD);
    if (!more)
    {
      break;
    }
  }
  return Summarise(times);
}

// The slowest rank's time of one call of `call`, every rank starting after a barrier.
template <class Call>
double Collective(Call call)
{
  MPI_Barrier(MPI_COMM_WORLD);
  const double start = MPI_Wtime();
  call();
  double mine = MPI_Wtime() - start;
  double slowest = 0;
  MPI_Allreduce(&mine, &slowest, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return slowest;
}

double ThreadSeconds()
{
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// 4. The barrier vtkAPCCompositePass enters every collective through (apc::WaitForAll:
// MPI_Ibarrier tested with yields, then sleeps growing to 1 ms) against MPI_Barrier: rows
// "barrier" (one call, the ranks together: its cost per collective), "late_overshoot" (the last
// rank arrives kLate late: how long after its arrival rank 0 leaves) and "late_cpu_share" (the
// share of its wait rank 0 spends on a core: MPI_Barrier polls, the polled barrier sleeps).
template <class Row>
void Barriers(vtkMPIController* controller, int rank, int ranks, int minimum, int repetitions,
  double budget, Row row)
{
  constexpr double kLate = 0.02;
  for (const bool polled : { false, true })
  {
    const char* type = polled ? "polled" : "blocking";
    auto wait = [&]
    {
      if (polled)
      {
        apc::WaitForAll(controller);
      }
      else
      {
        MPI_Barrier(MPI_COMM_WORLD);
      }
    };
    row("barrier", type, 0, Repeat([&] { return Collective(wait); }, minimum, repetitions, budget));
    // The clock is the machine's monotonic one, the same in every process: rank 0's exit
    // against the last arrival, whatever the ranks' skew leaving the barrier before.
    std::vector<double> cpuShare;
    const Timing overshoot = Repeat(
      [&]
      {
        MPI_Barrier(MPI_COMM_WORLD);
        if (rank == ranks - 1)
        {
          std::this_thread::sleep_for(std::chrono::duration<double>(kLate));
        }
        const double arrival = Now();
        const double startCPU = ThreadSeconds();
        wait();
        const double exit = Now();
        double last = 0;
        MPI_Allreduce(&arrival, &last, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
        double mine[2] = { exit - last, (ThreadSeconds() - startCPU) / (exit - arrival) };
        MPI_Bcast(mine, 2, MPI_DOUBLE, 0, MPI_COMM_WORLD);
        cpuShare.push_back(mine[1]);
        return mine[0];
      },
      minimum, repetitions, budget);
    row("late_overshoot", type, 0, overshoot);
    row("late_cpu_share", type, 0, Summarise(cpuShare));
  }
}

void Usage(const char* program)
{
  std::fprintf(stderr,
    "usage: mpirun -np N %s [--out comm.csv] [--max-bytes B] [--repetitions R] [--budget S]\n",
    program);
}
}

int main(int argc, char* argv[])
{
  MPI_Init(&argc, &argv);
  vtkNew<vtkMPIController> controller; // for the pass's barrier, apc::WaitForAll
  controller->Initialize(&argc, &argv, 1);
  int rank = 0;
  int ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);

  std::string out = "comm.csv";
  long long maxBytes = 64LL << 20;
  int repetitions = 30;
  double budget = 2.0; // seconds per operation and size
  for (int a = 1; a < argc; ++a)
  {
    const bool hasValue = a + 1 < argc;
    if (!std::strcmp(argv[a], "--out") && hasValue)
    {
      out = argv[++a];
    }
    else if (!std::strcmp(argv[a], "--max-bytes") && hasValue)
    {
      maxBytes = std::atoll(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--repetitions") && hasValue)
    {
      repetitions = std::atoi(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--budget") && hasValue)
    {
      budget = std::atof(argv[++a]);
    }
    else
    {
      if (rank == 0)
      {
        Usage(argv[0]);
      }
      MPI_Finalize();
      return 2;
    }
  }
  if (maxBytes < 8 || repetitions < 1)
  {
    if (rank == 0)
    {
      Usage(argv[0]);
    }
    MPI_Finalize();
    return 2;
  }

  // Sizes 8 B, 32 B, ... (x4), and maxBytes itself: the model needs latency (small) and
  // bandwidth (the MB-sized images of compositing).
  std::vector<long long> sizes;
  for (long long b = 8; b < maxBytes; b *= 4)
  {
    sizes.push_back(b);
  }
  sizes.push_back(maxBytes);

  std::vector<char> send(static_cast<size_t>(maxBytes), 1);
  std::vector<char> receive(static_cast<size_t>(maxBytes), 0);
  std::vector<std::string> rows;
  auto row = [&](const char* op, const char* type, long long bytes, const Timing& t)
  {
    char line[256];
    std::snprintf(line, sizeof(line), "%d,%s,%s,%lld,%d,%.9g,%.9g", ranks, op, type, bytes,
      t.Repetitions, t.Min, t.Median);
    rows.push_back(line);
    if (rank == 0)
    {
      std::printf("%-10s %-6s %10lld B: min %.3g s, median %.3g s (%d repetitions)\n", op, type,
        bytes, t.Min, t.Median, t.Repetitions);
      std::fflush(stdout);
    }
  };
  const int minimum = std::min(5, repetitions);

  // 1. Ping-pong between ranks 0 and 1 (the others wait in the barrier): a round trip of one
  // message each way, repeated `inner` times per sample so that small messages are timed over
  // ~1 ms rather than at the clock's resolution.
  if (ranks >= 2)
  {
    for (long long bytes : sizes)
    {
      const int inner = static_cast<int>(std::max(1LL, std::min(100LL, (1LL << 20) / bytes)));
      const int count = static_cast<int>(bytes);
      Timing t = Repeat(
        [&]
        {
          MPI_Barrier(MPI_COMM_WORLD);
          double seconds = 0;
          if (rank <= 1)
          {
            const double start = MPI_Wtime();
            for (int k = 0; k < inner; ++k)
            {
              if (rank == 0)
              {
                MPI_Send(send.data(), count, MPI_BYTE, 1, 1, MPI_COMM_WORLD);
                MPI_Recv(receive.data(), count, MPI_BYTE, 1, 2, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
              }
              else
              {
                MPI_Recv(receive.data(), count, MPI_BYTE, 0, 1, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
                MPI_Send(send.data(), count, MPI_BYTE, 0, 2, MPI_COMM_WORLD);
              }
            }
            seconds = (MPI_Wtime() - start) / (2.0 * inner);
          }
          MPI_Bcast(&seconds, 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
          return seconds;
        },
        minimum, repetitions, budget);
      row("pingpong", "byte", bytes, t);
    }
  }

  // 2. The collectives of APC's compositing, sums in float and double. The buffers hold
  // small values so that sums stay finite.
  std::vector<float> sendFloat(static_cast<size_t>(maxBytes / 4), 0.5f);
  std::vector<float> receiveFloat(sendFloat.size());
  std::vector<double> sendDouble(static_cast<size_t>(maxBytes / 8), 0.5);
  std::vector<double> receiveDouble(sendDouble.size());
  for (int op = 0; op < 2; ++op)
  {
    const bool everywhere = op == 0;
    for (int type = 0; type < 2; ++type)
    {
      const bool isFloat = type == 0;
      const int element = isFloat ? 4 : 8;
      for (long long bytes : sizes)
      {
        if (bytes < element)
        {
          continue;
        }
        const int count = static_cast<int>(bytes / element);
        void* in = isFloat ? static_cast<void*>(sendFloat.data()) : sendDouble.data();
        void* outBuffer = isFloat ? static_cast<void*>(receiveFloat.data()) : receiveDouble.data();
        MPI_Datatype datatype = isFloat ? MPI_FLOAT : MPI_DOUBLE;
        Timing t = Repeat(
          [&]
          {
            return Collective(
              [&]
              {
                if (everywhere)
                {
                  MPI_Allreduce(in, outBuffer, count, datatype, MPI_SUM, MPI_COMM_WORLD);
                }
                else
                {
                  MPI_Reduce(in, outBuffer, count, datatype, MPI_SUM, 0, MPI_COMM_WORLD);
                }
              });
          },
          minimum, repetitions, budget);
        row(everywhere ? "allreduce" : "reduce", isFloat ? "float" : "double",
          static_cast<long long>(count) * element, t);
      }
    }
  }

  // 3. One process's memory work per byte, on rank 0 while the others wait in the barrier
  // (as they would in the collective): a copy (packing segments, packing tiles) and an
  // in-place sum (the reduction operator), in float and double, at the largest size.
  {
    const long long bytes = maxBytes;
    auto local = [&](auto body)
    {
      return Repeat(
        [&]
        {
          MPI_Barrier(MPI_COMM_WORLD);
          double seconds = 0;
          if (rank == 0)
          {
            const double start = Now();
            body();
            seconds = Now() - start;
          }
          MPI_Bcast(&seconds, 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
          return seconds;
        },
        minimum, repetitions, budget);
    };
    row("copy", "byte", bytes, local([&] { std::memcpy(receive.data(), send.data(), bytes); }));
    row("sum", "float", bytes,
      local(
        [&]
        {
          for (size_t i = 0; i < sendFloat.size(); ++i)
          {
            receiveFloat[i] += sendFloat[i];
          }
        }));
    row("sum", "double", bytes,
      local(
        [&]
        {
          for (size_t i = 0; i < sendDouble.size(); ++i)
          {
            receiveDouble[i] += sendDouble[i];
          }
        }));
    // Keep the sums observable so the loops are not optimised away.
    if (rank == 0 && receiveFloat[0] + receiveDouble[0] < 0)
    {
      std::printf("unreachable\n");
    }
  }

  if (ranks > 1)
  {
    Barriers(controller, rank, ranks, minimum, repetitions, budget, row);
  }

  if (rank == 0)
  {
    double load[1] = { 0 };
    std::ifstream loadavg("/proc/loadavg");
    loadavg >> load[0];
    const bool exists = std::ifstream(out).good();
    std::ofstream file(out, std::ios::app);
    if (!exists)
    {
      file << "ranks,op,type,bytes,repetitions,min_s,median_s,load1\n";
    }
    for (const std::string& line : rows)
    {
      file << line << "," << load[0] << "\n";
    }
    if (!file)
    {
      std::fprintf(stderr, "error: cannot write %s\n", out.c_str());
      MPI_Abort(MPI_COMM_WORLD, 1);
    }
    std::printf("wrote %zu rows to %s (load average %.2f)\n", rows.size(), out.c_str(), load[0]);
  }
  controller->Finalize(1);
  MPI_Finalize();
  return 0;
}
