// Run under mpirun -np N. What the inputs' conversion finds is said once
// for all ranks, on the display rank, with the global counts: rank r's piece holds r + 1 flat
// cells and one triangle, so the display rank must say "N(N+1)/2 cells with no volume" and
// "N x vtkTriangle" once, and no other rank anything. A frame without a data change says
// nothing; a data change on one rank makes the display rank say the global counts again.

#include "apcMPITest.h"
#include "apcTestCompositePass.h"
#include "apcTestGrids.h"
#include "apcTestMessages.h"
#include "apcTestScenes.h"
#include "vtkAPCCompositePass.h"
#include "vtkAPCVolumeMapper.h"

#include "vtkImageData.h"
#include "vtkMPIController.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"

#include <cstdio>
#include <string>

namespace
{
using apctest::Check;
using apctest::MessageLog;

// A 2 x 2 x 2 block of hexahedra, `flat` tetrahedra over the four corners of one of its
// bottom faces (distinct and coplanar) and one triangle.
vtkSmartPointer<vtkUnstructuredGrid> Piece(int flat)
{
  auto grid =
    apctest::HexBlock(2, [](double x, double y, double z) { return 0.5 + 0.2 * x - 0.3 * y * z; });
  const vtkIdType bottom[4] = { 0, 1, 4, 3 }; // lattice points (0,0,0) (1,0,0) (1,1,0) (0,1,0)
  for (int i = 0; i < flat; ++i)
  {
    grid->InsertNextCell(VTK_TETRA, 4, bottom);
  }
  grid->InsertNextCell(VTK_TRIANGLE, 3, bottom);
  return grid;
}

// How many messages each rank's log holds that mention text, summed over the ranks.
int GlobalCount(
  vtkMPIController* controller, const std::vector<std::string>& messages, const std::string& text)
{
  const int mine = MessageLog::Count(messages, text);
  int all = 0;
  controller->AllReduce(&mine, &all, 1, vtkCommunicator::SUM_OP);
  return all;
}
}

int main(int argc, char* argv[])
{
  vtkSmartPointer<vtkMPIController> controller = apctest::StartMPI(&argc, &argv);
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  {
    vtkNew<vtkAPCCompositePass> pass;
    pass->KeepLastImageOn();
    vtkNew<vtkRenderWindow> window;
    vtkNew<vtkRenderer> renderer;
    apctest::SetUpCompositeWindow(window, renderer, 48, pass, controller);
    auto piece = Piece(rank + 1);
    vtkNew<vtkAPCVolumeMapper> mapper;
    mapper->SetInputData(piece);
    mapper->SetSampleDistance(0.05);
    vtkNew<vtkVolume> volume;
    volume->SetMapper(mapper);
    volume->SetProperty(apctest::MakeVolumeProperty(apctest::TransferFunction()));
    pass->AddVolume(volume);
    apctest::ApplyView(renderer, apctest::ObliqueView(48));
    renderer->ResetCameraClippingRange(-1, 1, -1, 1, -1, 1);
    vtkNew<MessageLog> log;
    log->Watch(mapper);
    log->Watch(pass);

    const int flat = ranks * (ranks + 1) / 2;
    const std::string flatText = std::to_string(flat) + " cells with no volume";
    const std::string triangleText = std::to_string(ranks) + " x vtkTriangle";
    const std::string summed =
      ranks > 1 ? "summed over " + std::to_string(ranks) + " processes" : std::string();

    window->Render();
    const int warnings = GlobalCount(controller, log->Warnings, "");
    const int errors = GlobalCount(controller, log->Errors, "");
    if (rank == 0)
    {
      std::printf("%d ranks, first frame: %s\n", ranks, log->All().c_str());
    }
    Check(warnings == 1, rank, "one warning on all ranks, got " + std::to_string(warnings));
    Check(errors == 1, rank, "one error on all ranks, got " + std::to_string(errors));
    if (rank == 0)
    {
      Check(MessageLog::Count(log->Warnings, flatText) == 1, rank, "the warning says " + flatText);
      Check(
        MessageLog::Count(log->Errors, triangleText) == 1, rank, "the error says " + triangleText);
      Check(MessageLog::Count(log->Warnings, summed) == 1, rank, "the warning says " + summed);
      vtkImageData* image = pass->GetLastImage();
      Check(image && image->GetNumberOfPoints() > 0, rank, "the frame was rendered");
    }

    // Nothing changed: nothing to say.
    log->Clear();
    window->Render();
    const int quiet =
      GlobalCount(controller, log->Warnings, "") + GlobalCount(controller, log->Errors, "");
    Check(quiet == 0, rank, "no data change, no message; got " + std::to_string(quiet));

    // The last rank's data change: the global counts again, once.
    log->Clear();
    if (rank == ranks - 1)
    {
      piece->Modified();
    }
    window->Render();
    const int again = GlobalCount(controller, log->Warnings, flatText);
    if (rank == 0)
    {
      std::printf("after a data change on rank %d: %s\n", ranks - 1, log->All().c_str());
    }
    Check(again == 1, rank, "after a data change on one rank, one warning with the global count");
    Check(GlobalCount(controller, log->Warnings, "") == 1, rank, "and no other warning");
  }
  return apctest::FinishMPITest(controller);
}
