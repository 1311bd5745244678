// The weak-scaling scene shared by apcScalingBenchmark (run under MPI) and apcSegmentAnalysis
// (which models the same frames' traffic in one process): the gear teeth, one puzzle piece of
// 4 slabs of 32 x 32 x 2 hexahedra per rank, every piece overlapping every other in depth,
// seen from 4 cameras on an orbit.
#ifndef apcGearTeethScene_h
#define apcGearTeethScene_h

#include "apcTestPuzzles.h"
#include "apcTestTransferFunctions.h"
#include "vtkAPCPuzzleSource.h"
#include "vtkAPCVolumeMapper.h"

#include "vtkCamera.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"

#include <cmath>

namespace apcbench
{
constexpr double kGearAzimuths[4] = { 0, 90, 180, 270 };
constexpr double kGearSampleDistance = 0.01;
constexpr double kGearBounds[6] = { -1, 1, -1, 1, -1, 1 };

// Piece `piece` of `pieces` (one per rank); numberOfPieces = 1 gives all `pieces` in one grid.
inline vtkSmartPointer<vtkUnstructuredGrid> GearTeethPiece(
  int piece, int pieces, int numberOfPieces = -1)
{
  return apctest::PuzzlePiece(vtkAPCPuzzleSource::SANDWICH, pieces, 4, 32, piece, 2,
    numberOfPieces < 0 ? pieces : numberOfPieces);
}

// One colour per puzzle piece, as TestVolumeMapperQuality's gear teeth.
inline void ConfigureGearTeethVolume(vtkVolume* volume, vtkAPCVolumeMapper* mapper, int pieces)
{
  mapper->SetSampleDistance(kGearSampleDistance);
  volume->SetMapper(mapper);
  volume->SetProperty(apctest::MakeVolumeProperty(apctest::SandwichTF(pieces)));
}

// Camera `camera` (0-3) of the orbit: 30 degrees above the equator, azimuth kGearAzimuths.
inline void SetGearTeethCamera(vtkRenderer* renderer, int camera)
{
  const double distance = 4.5;
  const double pi = 3.14159265358979323846;
  const double azimuth = kGearAzimuths[camera] * pi / 180;
  const double elevation = 30 * pi / 180;
  vtkCamera* c = renderer->GetActiveCamera();
  c->ParallelProjectionOff();
  c->SetFocalPoint(0, 0, 0);
  c->SetPosition(distance * std::cos(elevation) * std::sin(azimuth), distance * std::sin(elevation),
    distance * std::cos(elevation) * std::cos(azimuth));
  c->SetViewUp(0, 1, 0);
  c->SetViewAngle(30);
  renderer->ResetCameraClippingRange(kGearBounds);
}
} // namespace apcbench

#endif
