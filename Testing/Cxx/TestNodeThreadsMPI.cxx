// Run under mpirun -np N, bound or not. Threads per process: after a frame through
// vtkAPCCompositePass an unbound process renders with its share of the node's cores
// (cores / processes on the node, at least one), a bound one with its affinity mask (TBB's
// choice), and a thread count set on the mapper still overrides the default. Every process
// of this test runs on one machine, so the processes on the node are all of them.

#include "apcMPITest.h"
#include "apcParallel.h"
#include "apcTestCompositePass.h"
#include "apcTestGrids.h"
#include "apcTestScenes.h"
#include "vtkAPCCompositePass.h"
#include "vtkAPCVolumeMapper.h"

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
#include <cstdio>
#include <mutex>
#include <sched.h>
#include <set>
#include <string>
#include <thread>
#include <unistd.h>

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
  // What this process should run by default, from the rule in the header's words.
  const int expected = bound ? mask : std::min(cores, 2 * std::max(1, cores / ranks));
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
    Check(bound || apc::GetDefaultThreads() == expected, rank, "the node's share as the default");
    Check(static_cast<int>(workers) <= expected - 1, rank,
      std::to_string(workers) + " worker threads in a frame that may use " +
        std::to_string(expected) + " threads");

    // The mapper's setting overrides the default: it reaches the marcher's arenas as it is.
    mapper->SetNumberOfThreads(2);
    window->Render();
    Check(ArenaSize(2) == 2, rank, "a requested count of 2 gives an arena of 2");
    Check(apc::ThreadsFor(2) == 2 && (bound || apc::ThreadsFor(0) == expected), rank,
      "a request overrides the default, 0 takes it");
  }
  return apctest::FinishMPITest(controller);
}
