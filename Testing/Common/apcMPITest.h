// What every MPI test and benchmark does around its work: MPI up with a global controller,
// failures counted per rank, and one verdict for all ranks at the end.
#ifndef apcMPITest_h
#define apcMPITest_h

#include "vtkMPIController.h"
#include "vtkSmartPointer.h"

#include <cstdio>
#include <string>

namespace apctest
{

// VTK's parallel filters and passes find the controller through the global one.
inline vtkSmartPointer<vtkMPIController> StartMPI(int* argc, char*** argv)
{
  auto controller = vtkSmartPointer<vtkMPIController>::New();
  controller->Initialize(argc, argv);
  vtkMultiProcessController::SetGlobalController(controller);
  return controller;
}

inline int& RankFailures()
{
  static int failures = 0;
  return failures;
}

inline void Check(bool ok, int rank, const std::string& what)
{
  if (!ok)
  {
    std::fprintf(stderr, "rank %d: FAILED: %s\n", rank, what.c_str());
    ++RankFailures();
  }
}

// Every rank must agree on the verdict, so a failure anywhere fails the test; ends MPI and
// returns the exit code.
inline int FinishMPITest(vtkMPIController* controller)
{
  int globalFailures = 0;
  controller->AllReduce(&RankFailures(), &globalFailures, 1, vtkCommunicator::SUM_OP);
  if (controller->GetLocalProcessId() == 0)
  {
    std::printf("%s: %d failure(s) on %d ranks\n", globalFailures ? "FAILED" : "PASSED",
      globalFailures, controller->GetNumberOfProcesses());
  }
  controller->Finalize();
  return globalFailures == 0 ? 0 : 1;
}

} // namespace apctest

#endif
