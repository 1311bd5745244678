// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAPCPuzzleSource.h"

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkFloatArray.h"
#include "vtkIdTypeArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkUnstructuredGrid.h"

#include <algorithm>
#include <array>
#include <cmath>

vtkStandardNewMacro(vtkAPCPuzzleSource);

namespace
{
constexpr double Pi = 3.14159265358979323846;

// Hermite ramp from 0 at e0 to 1 at e1: keeps the sphere shells' edges smooth enough that
// trilinear interpolation of point values does not alias into staircases.
double SmoothStep(double e0, double e1, double x)
{
  const double t = std::min(1.0, std::max(0.0, (x - e0) / (e1 - e0)));
  return t * t * (3.0 - 2.0 * t);
}

double SpheresField(const std::array<double, 3>& p)
{
  const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  const double halfWidth = 0.025;
  const double core = 1.0 - SmoothStep(0.35 - halfWidth, 0.35 + halfWidth, r);
  const double shell = SmoothStep(0.6 - halfWidth, 0.6 + halfWidth, r) *
    (1.0 - SmoothStep(0.8 - halfWidth, 0.8 + halfWidth, r));
  return std::max(core, 0.5 * shell);
}

double SmoothField(const std::array<double, 3>& p)
{
  return 0.5 +
    0.25 * (std::sin(Pi * p[0]) * std::cos(Pi * p[1]) + std::sin(0.5 * Pi * (p[2] + p[0] * p[1])));
}

// Slabs are built in a frame (u, v, w) with w along the slab axis; a cyclic permutation to
// (x, y, z) keeps the hexahedra right-handed whatever the axis.
std::array<double, 3> ToWorld(int axis, double u, double v, double w)
{
  switch (axis)
  {
    case 0:
      return { w, u, v };
    case 1:
      return { v, w, u };
    default:
      return { u, v, w };
  }
}

// One slab's lattice: (res + 1)^2 points per layer, three point layers for its two cell layers.
struct SlabLattice
{
  vtkIdType Res;
  vtkIdType PointsPerLayer;
  double CellSize;
  double Thickness;
};

// The three point layers of a slab starting at depth w0, with the field's value at each point.
void AddSlabPoints(vtkPoints* points, vtkFloatArray* scalars, int axis, int field,
  double sandwichValue, double w0, const SlabLattice& lattice, vtkIdType& pointId)
{
  for (int k = 0; k < 3; ++k)
  {
    const double w = w0 + 0.5 * lattice.Thickness * k;
    for (vtkIdType j = 0; j <= lattice.Res; ++j)
    {
      const double v = -1.0 + lattice.CellSize * j;
      for (vtkIdType i = 0; i <= lattice.Res; ++i, ++pointId)
      {
        const double u = -1.0 + lattice.CellSize * i;
        const std::array<double, 3> p = ToWorld(axis, u, v, w);
        points->SetPoint(pointId, p.data());
        double value = sandwichValue;
        if (field == vtkAPCPuzzleSource::SPHERES)
        {
          value = SpheresField(p);
        }
        else if (field == vtkAPCPuzzleSource::SMOOTH)
        {
          value = SmoothField(p);
        }
        scalars->SetValue(pointId, static_cast<float>(value));
      }
    }
  }
}

// The slab's two layers of hexahedra on its points (from firstPoint), owned by puzzle piece pp.
void AddSlabCells(vtkIdType* conn, vtkIdTypeArray* offsets, vtkIntArray* owner, int pp,
  vtkIdType firstPoint, const SlabLattice& lattice, vtkIdType& cellId)
{
  const vtkIdType res = lattice.Res;
  for (vtkIdType k = 0; k < 2; ++k)
  {
    for (vtkIdType j = 0; j < res; ++j)
    {
      for (vtkIdType i = 0; i < res; ++i, ++cellId)
      {
        const vtkIdType p0 = firstPoint + k * lattice.PointsPerLayer + j * (res + 1) + i;
        const vtkIdType bottom[4] = { p0, p0 + 1, p0 + res + 2, p0 + res + 1 };
        for (int c = 0; c < 4; ++c)
        {
          conn[8 * cellId + c] = bottom[c];
          conn[8 * cellId + 4 + c] = bottom[c] + lattice.PointsPerLayer;
        }
        offsets->SetValue(cellId, 8 * cellId);
        owner->SetValue(cellId, pp);
      }
    }
  }
}
}

//------------------------------------------------------------------------------
vtkAPCPuzzleSource::vtkAPCPuzzleSource()
{
  this->SetNumberOfInputPorts(0);
}

//------------------------------------------------------------------------------
const char* vtkAPCPuzzleSource::GetFieldName() const
{
  switch (this->Field)
  {
    case SMOOTH:
      return "Smooth";
    case SANDWICH:
      return "Sandwich";
    default:
      return "Spheres";
  }
}

//------------------------------------------------------------------------------
vtkIdType vtkAPCPuzzleSource::GetNumberOfCellsPerPuzzlePiece() const
{
  const vtkIdType r = this->Resolution;
  return static_cast<vtkIdType>(this->SlabsPerPiece) * r * r * 2;
}

//------------------------------------------------------------------------------
int vtkAPCPuzzleSource::RequestInformation(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  outputVector->GetInformationObject(0)->Set(CAN_HANDLE_PIECE_REQUEST(), 1);
  return 1;
}

//------------------------------------------------------------------------------
int vtkAPCPuzzleSource::RequestData(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outInfo);
  if (!output)
  {
    vtkErrorMacro("Output is not a vtkUnstructuredGrid.");
    return 0;
  }

  int piece = 0;
  int numPieces = 1;
  if (outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER()))
  {
    piece = outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER());
    numPieces = outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES());
  }
  numPieces = std::max(numPieces, 1);
  if (piece < 0 || piece >= numPieces)
  {
    // Outside the requested range nothing is ours: an empty piece, not an error.
    return 1;
  }

  const int puzzlePieces = this->NumberOfPuzzlePieces > 0 ? this->NumberOfPuzzlePieces : numPieces;
  const int firstPuzzlePiece =
    static_cast<int>(static_cast<long long>(piece) * puzzlePieces / numPieces);
  const int endPuzzlePiece =
    static_cast<int>(static_cast<long long>(piece + 1) * puzzlePieces / numPieces);
  const int myPieces = endPuzzlePiece - firstPuzzlePiece;

  const vtkIdType res = this->Resolution;
  const vtkIdType slabs = static_cast<vtkIdType>(myPieces) * this->SlabsPerPiece;
  const vtkIdType pointsPerLayer = (res + 1) * (res + 1);
  const vtkIdType pointsPerSlab = pointsPerLayer * 3; // two cell layers need three point layers
  const vtkIdType cellsPerSlab = res * res * 2;
  const int totalSlabs = puzzlePieces * this->SlabsPerPiece;
  const double slabThickness = 2.0 / totalSlabs;
  const double cellSize = 2.0 / static_cast<double>(res);

  vtkNew<vtkPoints> points;
  points->SetDataTypeToFloat();
  points->SetNumberOfPoints(slabs * pointsPerSlab);
  vtkNew<vtkFloatArray> scalars;
  scalars->SetName(this->GetFieldName());
  scalars->SetNumberOfTuples(slabs * pointsPerSlab);
  vtkNew<vtkIdTypeArray> offsets;
  offsets->SetNumberOfTuples(slabs * cellsPerSlab + 1);
  vtkNew<vtkIdTypeArray> connectivity;
  connectivity->SetNumberOfTuples(slabs * cellsPerSlab * 8);
  vtkNew<vtkIntArray> owner;
  owner->SetName("PuzzlePiece");
  owner->SetNumberOfTuples(slabs * cellsPerSlab);

  const SlabLattice lattice{ res, pointsPerLayer, cellSize, slabThickness };
  vtkIdType pointId = 0;
  vtkIdType cellId = 0;
  vtkIdType* conn = connectivity->GetPointer(0);
  for (int pp = firstPuzzlePiece; pp < endPuzzlePiece; ++pp)
  {
    const double sandwichValue = static_cast<double>(pp) / std::max(puzzlePieces - 1, 1);
    for (int s = 0; s < this->SlabsPerPiece; ++s)
    {
      this->UpdateProgress(static_cast<double>(cellId) / (slabs * cellsPerSlab));
      const int globalSlab = s * puzzlePieces + pp; // round robin: the "gear teeth"
      const vtkIdType slabFirstPoint = pointId;
      AddSlabPoints(points, scalars, this->Axis, this->Field, sandwichValue,
        -1.0 + globalSlab * slabThickness, lattice, pointId);
      AddSlabCells(conn, offsets, owner, pp, slabFirstPoint, lattice, cellId);
    }
  }
  offsets->SetValue(cellId, 8 * cellId);

  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, connectivity);
  output->SetPoints(points);
  output->SetCells(VTK_HEXAHEDRON, cells);
  output->GetPointData()->SetScalars(scalars);
  output->GetCellData()->AddArray(owner);
  return 1;
}

//------------------------------------------------------------------------------
void vtkAPCPuzzleSource::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "NumberOfPuzzlePieces: " << this->NumberOfPuzzlePieces << "\n";
  os << indent << "SlabsPerPiece: " << this->SlabsPerPiece << "\n";
  os << indent << "Resolution: " << this->Resolution << "\n";
  os << indent << "Axis: " << this->Axis << "\n";
  os << indent << "Field: " << this->GetFieldName() << "\n";
}
