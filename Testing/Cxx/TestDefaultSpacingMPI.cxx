// Run under mpirun -np N. The default sample distance from the cells' own volume is agreed
// bit for bit: with the wind data's pieces dealt over N processes, every process gets the
// same cell volume and sample distance as one process holding the whole data, to the last
// bit (a floating-point sum of the volumes in another order would differ in its low bits).

#include "apcCellMesh.h"
#include "apcCellMeshFromVTK.h"
#include "apcCompositeFrame.h"
#include "apcCompositePassRenders.h"
#include "apcDefaultSpacing.h"
#include "apcFrameAgreement.h"
#include "apcMPITest.h"

#include "vtkMPIController.h"
#include "vtkPointData.h"
#include "vtkUnstructuredGrid.h"

#include <cstdio>
#include <cstring>
#include <string>

namespace
{
using apctest::Check;

bool Convert(vtkUnstructuredGrid* grid, apc::CellMesh& mesh)
{
  std::string error;
  return apc::CellMeshFromVTK(grid, grid->GetPointData()->GetArray("U_mag"), false, mesh, error);
}

bool SameBits(double a, double b)
{
  return std::memcmp(&a, &b, sizeof(double)) == 0;
}
}

int main(int argc, char* argv[])
{
  vtkSmartPointer<vtkMPIController> controller = apctest::StartMPI(&argc, &argv);
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  {
    // One process with the whole data: its own bounds, cells and volume.
    apc::CellMesh whole;
    Check(Convert(apctest::WindPieces(0, 1), whole), rank, "the whole wind data converts");
    const double wholeCells = static_cast<double>(whole.GetNumberOfCells());
    const double wholeVolume = whole.GetCellVolume().Value();
    const double wholeDistance =
      apc::DefaultSampleDistance(whole.GetBounds().data(), wholeCells, wholeVolume, true);

    // This process's pieces, agreed with the others' as the composite pass agrees them.
    apc::CellMesh mine;
    Check(Convert(apctest::WindPieces(rank, ranks), mine), rank, "the pieces convert");
    apc::LocalFrame local;
    local.AddVolume(4, mine.GetNumberOfCells() > 0 ? mine.GetBounds().data() : nullptr);
    local.Cells = static_cast<double>(mine.GetNumberOfCells());
    local.Volume = mine.GetCellVolume();
    const apc::FrameAgreement agreed =
      apc::FrameAgreement::Agree(apc::ProcessGroup(controller, 0), local);
    const double distance =
      apc::DefaultSampleDistance(agreed.Bounds, agreed.Cells, agreed.Volume, true);

    if (rank == 0)
    {
      std::printf("%d ranks: cells %.0f volume %.17g distance %.17g (one process: %.0f %.17g "
                  "%.17g)\n",
        ranks, agreed.Cells, agreed.Volume, distance, wholeCells, wholeVolume, wholeDistance);
    }
    Check(agreed.Cells == wholeCells, rank, "the cell count is the whole data's");
    Check(
      SameBits(agreed.Volume, wholeVolume), rank, "the volume is the whole data's, bit for bit");
    Check(SameBits(distance, wholeDistance), rank, "the distance is one process's, bit for bit");
    // The rule on the wind (Sample End Weights = Boundary, the default): 1.25 mean cell sizes
    // (its cells fill 98 % of the box), finer than the floor of kMinDefaultSamples along the
    // diagonal.
    const double meanCell = apc::MeanCellVolumeSize(agreed.Volume, agreed.Cells);
    Check(distance == apc::kDefaultSpacingPerCell * meanCell && meanCell > 3.3 && meanCell < 3.44,
      rank, "the wind's default is 1.25 mean cell sizes, " + std::to_string(distance));
    // Every process the same bits: the largest and smallest over the processes agree.
    double range[2] = { distance, -distance };
    double extreme[2] = { 0, 0 };
    controller->AllReduce(range, extreme, 2, vtkCommunicator::MAX_OP);
    Check(extreme[0] == -extreme[1], rank, "every process has the same distance");
  }
  return apctest::FinishMPITest(controller);
}
