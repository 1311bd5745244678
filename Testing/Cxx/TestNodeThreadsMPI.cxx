// Run under mpirun -np N, bound or not. Threads per process: after a frame through
// vtkAPCCompositePass a process renders with twice its share of the cores of its affinity
// mask (each core divided among the processes whose masks hold it; at least one thread, at
// most its mask), and a thread count set on the mapper still overrides the default. Every
// process of this test runs on one machine, so the processes on the node are all of them.

#include "apcMPITest.h"
#include "apcParallel.h"
#include "apcTestCompositePass.h"
#include "apcTestGrids.h"
#include "apcTestScenes.h"
#include "vtkAPCCompositePass.h"
#include "vtkAPCVolumeMapper.h"

#include "vtkMPI.h"
#include "vtkMPIController.h"
#include "vtkNew.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"

#include <tbb/task_arena.h>
#include <tbb/task_scheduler_observer.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <sched.h>
#include <set>
#include <string>
#include <thread>
#include <unistd.h>
#include <vector>

namespace
{
using apctest::Check;

// The distinct TBB worker threads that joined any arena while it watched.
class WorkerWatch : public tbb::task_scheduler_observer
{
public:
  WorkerWatch() { this->observe(true); }
  ~WorkerWatch() override { this->observe(false); }
  void on_scheduler_entry(bool worker) override
  {
    if (worker)
    {
      std::lock_guard<std::mutex> lock(this->Mutex);
      this->Workers.insert(std::this_thread::get_id());
    }
  }
  size_t Count()
  {
    std::lock_guard<std::mutex> lock(this->Mutex);
    return this->Workers.size();
  }

private:
  std::mutex Mutex;
  std::set<std::thread::id> Workers;
};

// The arena size apc::ParallelFor gives a request, seen from inside its tasks.
int ArenaSize(int requested)
{
  std::atomic<int> size{ 0 };
  apc::ParallelFor(requested, 64, 1,
    [&size](int64_t, int64_t) { size = tbb::this_task_arena::max_concurrency(); });
  return size;
}
}

int main(int argc, char* argv[])
{
  vtkSmartPointer<vtkMPIController> controller = apctest::StartMPI(&argc, &argv);
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  const int cores = static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN));
  cpu_set_t set;
  CPU_ZERO(&set);
  sched_getaffinity(0, sizeof set, &set);
  const int mask = CPU_COUNT(&set);
  const bool bound = mask < cores;
  // What this process should run by default, from the rule in the header's words, with every
  // process's mask gathered here.
  std::vector<cpu_set_t> sets(static_cast<size_t>(ranks));
  MPI_Allgather(&set, sizeof set, MPI_BYTE, sets.data(), sizeof set, MPI_BYTE, MPI_COMM_WORLD);
  double share = 0;
  for (int core = 0; core < CPU_SETSIZE; ++core)
  {
    if (CPU_ISSET(core, &set))
    {
      const auto sharing = std::count_if(
        sets.begin(), sets.end(), [core](const cpu_set_t& s) { return CPU_ISSET(core, &s); });
      share += 1.0 / static_cast<double>(sharing);
    }
  }
  const int expected = std::min(mask, 2 * std::max(1, static_cast<int>(std::floor(share + 1e-9))));
  Check(apc::GetDefaultThreads() == 0, rank, "no default before the first frame");
  {
    vtkNew<vtkAPCCompositePass> pass;
    vtkNew<vtkRenderWindow> window;
    vtkNew<vtkRenderer> renderer;
    apctest::SetUpCompositeWindow(window, renderer, 64, pass, controller);
    auto piece = apctest::HexBlock(
      4, [rank](double x, double y, double z) { return 0.2 + 0.1 * rank + 0.3 * x * y - 0.2 * z; });
    vtkNew<vtkAPCVolumeMapper> mapper;
    mapper->SetInputData(piece);
    mapper->SetSampleDistance(0.02);
    vtkNew<vtkVolume> volume;
    volume->SetMapper(mapper);
    volume->SetProperty(apctest::MakeVolumeProperty(apctest::TransferFunction()));
    pass->AddVolume(volume);
    apctest::ApplyView(renderer, apctest::ObliqueView(64));
    renderer->ResetCameraClippingRange(-1, 1, -1, 1, -1, 1);

    size_t workers = 0;
    {
      WorkerWatch watch;
      window->Render();
      workers = watch.Count();
    }
    const int byDefault = ArenaSize(0);
    std::printf("rank %d of %d: %d cores, affinity mask %d (%s): default %d threads, "
                "arena %d, %zu TBB workers joined the frame\n",
      rank, ranks, cores, mask, bound ? "bound" : "unbound", apc::GetDefaultThreads(), byDefault,
      workers);
    Check(byDefault == expected, rank,
      "a default arena of " + std::to_string(byDefault) + " threads, not " +
        std::to_string(expected));
    Check(apc::GetDefaultThreads() == expected, rank, "the node's share as the default");
    Check(static_cast<int>(workers) <= expected - 1, rank,
      std::to_string(workers) + " worker threads in a frame that may use " +
        std::to_string(expected) + " threads");

    // The mapper's setting overrides the default: it reaches the marcher's arenas as it is.
    mapper->SetNumberOfThreads(2);
    window->Render();
    Check(ArenaSize(2) == 2, rank, "a requested count of 2 gives an arena of 2");
    Check(apc::ThreadsFor(2) == 2 && apc::ThreadsFor(0) == expected, rank,
      "a request overrides the default, 0 takes it");
  }
  return apctest::FinishMPITest(controller);
}
