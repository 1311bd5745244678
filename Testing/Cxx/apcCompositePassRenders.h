// What the composite pass's MPI tests share: a distributed render of each rank's piece through
// vtkAPCCompositePass and the one-process render of the whole data it is checked against, the
// global bounds, and the scenes (the gear-teeth puzzle, the wind data's Scotch pieces).
#ifndef apcCompositePassRenders_h
#define apcCompositePassRenders_h

#include "apcTestScenes.h"
#include "vtkAPCCompositePass.h"
#include "vtkAPCPuzzleSource.h"
#include "vtkAPCVolumeMapper.h"

#include "vtkSmartPointer.h"

#include <vector>

class vtkImageData;
class vtkMPIController;
class vtkRenderer;
class vtkUnstructuredGrid;
class vtkVolume;

namespace apctest
{

// The display rank's float RGBA of the distributed render of each rank's piece (empty on the
// other ranks, and where the frame failed). `plane`: opaque geometry through the middle of the
// data on the display rank; `shown`: the window's RGB bytes, and no float image kept.
std::vector<float> RenderDistributed(vtkMPIController* controller, const Scene& scene,
  vtkUnstructuredGrid* piece, const double globalBounds[6], int size, bool plane,
  vtkAPCCompositePass* pass, bool withVolume = true, int resolve = vtkAPCVolumeMapper::RENORMALISED,
  std::vector<unsigned char>* shown = nullptr, bool stopWhereOpaque = true);

// One frame of a pass as the opaque stop's tests read it: the display rank's float image (empty
// on the other ranks) and the pass's timings of that frame on this rank.
struct PassFrame
{
  std::vector<float> RGBA;
  vtkAPCCompositePass::Timings Timings;
};

// How RenderPassFrames sets up its fresh pass and mapper (one thread per rank).
struct PassFrameOptions
{
  int Size = 96;                 // the window's width and height
  bool Stop = true;              // the mapper's Stop Where Opaque
  int ProbeStep = -1;            // the pass's OpaqueProbeStep; -1 leaves the pass's default
  vtkIdType MaxMessageBytes = 0; // the pass's MaxMessageBytes; 0 leaves the pass's default
};

// Renders each of views in turn through one fresh pass over each rank's piece (the first frame
// has no previous frame; each later one follows the frame before); every frame, in order.
std::vector<PassFrame> RenderPassFrames(vtkMPIController* controller, const Scene& scene,
  vtkUnstructuredGrid* piece, const double bounds[6], const std::vector<View>& views,
  const PassFrameOptions& options = PassFrameOptions());

// The scene's sample distance, moments, jitter and transfer function on mapper and volume.
void ConfigureVolume(vtkVolume* volume, vtkAPCVolumeMapper* mapper, const Scene& scene);
// The scene's camera, clipped to the data's global bounds.
void SetCamera(vtkRenderer* renderer, const Scene& scene, const double bounds[6]);

// The one-process image of the whole grid (the reference), MBOIT or EXACT.
std::vector<float> RenderWhole(
  const Scene& scene, int size, bool plane, int mode = vtkAPCVolumeMapper::MBOIT);

// The bounds of all ranks' pieces together (every rank joins).
void GlobalBounds(vtkMPIController* controller, vtkUnstructuredGrid* piece, double bounds[6]);

// An APC image's float RGBA (GetLastImage() of the pass or the mapper); empty without one.
std::vector<float> ImageRGBA(vtkImageData* image);
// The largest absolute difference of two images; 1 if their sizes differ or both are empty.
double MaxAbsDifference(const std::vector<float>& a, const std::vector<float>& b);

Scene MakeScene(
  vtkUnstructuredGrid* grid, const TransferFunction& tf, double spacing, const View& view);

// Piece `piece` of `pieces` (a rank's share) of the puzzle source's gear teeth (SANDWICH) or
// spheres cut in `puzzlePieces` puzzle pieces.
vtkSmartPointer<vtkUnstructuredGrid> PuzzleShare(
  int piece, int pieces, int puzzlePieces, int field = vtkAPCPuzzleSource::SPHERES);

// The spheres puzzle of `puzzlePieces` pieces seen obliquely, the whole data on one process:
// every piece's bounds overlap every other's.
Scene PuzzleScene(int puzzlePieces);

// The wind data's 8 Scotch pieces dealt round robin: rank r owns pieces r, r + N, ...
vtkSmartPointer<vtkUnstructuredGrid> WindPieces(int rank, int ranks);

// The cells of grid whose centres lie in this rank's share of the z extent: blocks of slabs
// along the gear teeth's slab axis, compact pieces as a spatial partitioner would make them.
vtkSmartPointer<vtkUnstructuredGrid> DepthBlock(vtkUnstructuredGrid* grid, int rank, int ranks);

} // namespace apctest

#endif
