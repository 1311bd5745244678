// SPDX-License-Identifier: BSD-3-Clause
// What apc::WindTracer hands to Catalyst: its pieces as one multiblock per rank, with the
// tracer, and the walls for context.
#include "apcWindTracer.h"

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkFloatArray.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

#include <algorithm>
#include <cmath>

namespace apc
{
namespace
{
constexpr double PlaneTolerance = 0.1; // m: snapping left the box's sides a few mm uneven
}

// Open faces on no side of the domain's box but the ground: the buildings' walls.
void WindTracer::BuildWalls()
{
  vtkNew<vtkPoints> points;
  vtkNew<vtkCellArray> polys;
  vtkNew<vtkUnsignedCharArray> patch;
  patch->SetName("patch");
  const double* b = this->Bounds.data();
  for (std::int64_t f = 0; f < static_cast<std::int64_t>(this->Neighbour.size()); ++f)
  {
    if (this->Neighbour[f] >= 0)
    {
      continue;
    }
    vtkUnstructuredGrid* grid = this->GridOfFace(f);
    bool side[6] = { true, true, true, true, true, true };
    vtkIdType ids[4];
    int count = 0;
    for (; count < 4 && this->FacePoints[f][count] >= 0; ++count)
    {
      const double* x = grid->GetPoint(this->FacePoints[f][count]);
      for (int s = 0; s < 6; ++s)
      {
        side[s] = side[s] && std::abs(x[s / 2] - b[s]) <= PlaneTolerance;
      }
      ids[count] = points->InsertNextPoint(x);
    }
    if (side[0] || side[1] || side[2] || side[3] || side[5])
    {
      continue; // inlet, outlet, the sides, the top
    }
    polys->InsertNextCell(count, ids);
    patch->InsertNextValue(side[4] ? 0 : 1);
  }
  this->Walls = vtkSmartPointer<vtkPolyData>::New();
  this->Walls->SetPoints(points);
  this->Walls->SetPolys(polys);
  this->Walls->GetCellData()->AddArray(patch);
}

void WindTracer::BuildMesh()
{
  this->Mesh = vtkSmartPointer<vtkMultiBlockDataSet>::New();
  this->Mesh->SetNumberOfBlocks(this->GetNumberOfPieces());
  for (std::size_t k = 0; k < this->Grids.size(); ++k)
  {
    vtkNew<vtkUnstructuredGrid> block;
    block->SetPoints(this->Grids[k]->GetPoints());
    block->SetCells(this->Grids[k]->GetCellTypesArray(), this->Grids[k]->GetCells());
    vtkNew<vtkFloatArray> tracer;
    tracer->SetName("tracer");
    tracer->SetNumberOfTuples(this->Grids[k]->GetNumberOfCells());
    block->GetCellData()->AddArray(tracer);
    this->Tracer.emplace_back(tracer);
    this->Mesh->SetBlock(this->Pieces[k], block);
  }
}

vtkMultiBlockDataSet* WindTracer::GetMesh()
{
  for (std::size_t k = 0; k < this->Tracer.size(); ++k)
  {
    float* out = this->Tracer[k]->GetPointer(0);
    for (std::int64_t c = this->LocalStart[k]; c < this->LocalStart[k + 1]; ++c)
    {
      out[c - this->LocalStart[k]] = static_cast<float>(this->C[c]);
    }
    this->Tracer[k]->Modified();
  }
  return this->Mesh;
}
}
