#include "apcCompositePassRenders.h"

#include "apcTestCompositePass.h"
#include "apcTestPuzzles.h"
#include "vtkAPCCompositePass.h"

#include "vtkActor.h"
#include "vtkAppendFilter.h"
#include "vtkDataArray.h"
#include "vtkExtractCells.h"
#include "vtkIdList.h"
#include "vtkImageData.h"
#include "vtkMPIController.h"
#include "vtkNew.h"
#include "vtkPlaneSource.h"
#include "vtkPointData.h"
#include "vtkPolyDataMapper.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkXMLUnstructuredGridReader.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace apctest
{
void ConfigureVolume(vtkVolume* volume, vtkAPCVolumeMapper* mapper, const Scene& scene)
{
  mapper->SetSampleDistance(scene.SampleDistance);
  mapper->SetNumberOfMoments(scene.Moments);
  mapper->SetLatticeJitter(scene.LatticeJitter);
  mapper->SetSampleEndWeights(scene.SampleEndWeights);
  volume->SetMapper(mapper);
  volume->SetProperty(MakeVolumeProperty(scene.TF));
}

void SetCamera(vtkRenderer* renderer, const Scene& scene, const double bounds[6])
{
  ApplyView(renderer, scene.Camera);
  renderer->ResetCameraClippingRange(bounds);
}

std::vector<PassFrame> RenderPassFrames(vtkMPIController* controller, const Scene& scene,
  vtkUnstructuredGrid* piece, const double bounds[6], const std::vector<View>& views,
  const PassFrameOptions& options)
{
  vtkNew<vtkAPCCompositePass> pass;
  if (options.ProbeStep >= 0)
  {
    pass->SetOpaqueProbeStep(options.ProbeStep);
  }
  if (options.MaxMessageBytes > 0)
  {
    pass->SetMaxMessageBytes(options.MaxMessageBytes);
  }
  vtkNew<vtkRenderWindow> window;
  vtkNew<vtkRenderer> renderer;
  SetUpCompositeWindow(window, renderer, options.Size, pass, controller);
  vtkNew<vtkAPCVolumeMapper> mapper;
  mapper->SetInputData(piece);
  mapper->SetStopWhereOpaque(options.Stop);
  mapper->SetNumberOfThreads(1);
  vtkNew<vtkVolume> volume;
  ConfigureVolume(volume, mapper, scene);
  pass->KeepLastImageOn();
  pass->AddVolume(volume);
  std::vector<PassFrame> frames;
  for (const View& view : views)
  {
    ApplyView(renderer, view);
    renderer->ResetCameraClippingRange(bounds);
    window->Render();
    frames.push_back({ ImageRGBA(pass->GetLastImage()), pass->GetLastTimings() });
  }
  return frames;
}

std::vector<float> RenderDistributed(vtkMPIController* controller, const Scene& scene,
  vtkUnstructuredGrid* piece, const double globalBounds[6], int size, bool plane,
  vtkAPCCompositePass* pass, bool withVolume, int resolve, std::vector<unsigned char>* shown,
  bool stopWhereOpaque)
{
  vtkNew<vtkRenderWindow> window;
  vtkNew<vtkRenderer> renderer;
  SetUpCompositeWindow(window, renderer, size, pass, controller);
  vtkNew<vtkAPCVolumeMapper> mapper;
  mapper->SetInputData(piece);
  mapper->SetResolveMode(resolve);
  mapper->SetStopWhereOpaque(stopWhereOpaque);
  vtkNew<vtkVolume> volume;
  ConfigureVolume(volume, mapper, scene);
  if (!shown)
  {
    pass->KeepLastImageOn(); // the image compared below
  }
  pass->RemoveAllVolumes();
  if (withVolume)
  {
    pass->AddVolume(volume);
  }
  vtkNew<vtkPlaneSource> source;
  vtkNew<vtkPolyDataMapper> planeMapper;
  vtkNew<vtkActor> actor;
  if (plane && controller->GetLocalProcessId() == 0)
  {
    // Opaque geometry through the middle of the data, on the display rank only (as after an
    // IceT composite).
    source->SetOrigin(globalBounds[0], globalBounds[2], 0.5 * (globalBounds[4] + globalBounds[5]));
    source->SetPoint1(globalBounds[1], globalBounds[2], 0.5 * (globalBounds[4] + globalBounds[5]));
    source->SetPoint2(globalBounds[0], 0.5 * (globalBounds[2] + globalBounds[3]),
      0.5 * (globalBounds[4] + globalBounds[5]));
    planeMapper->SetInputConnection(source->GetOutputPort());
    actor->SetMapper(planeMapper);
    renderer->AddActor(actor);
  }
  SetCamera(renderer, scene, globalBounds);
  window->Render();
  if (shown)
  {
    vtkNew<vtkUnsignedCharArray> pixels;
    window->GetPixelData(0, 0, size - 1, size - 1, 0, pixels);
    shown->assign(pixels->GetPointer(0), pixels->GetPointer(0) + 3 * size * size);
  }
  return ImageRGBA(pass->GetLastImage());
}

std::vector<float> RenderWhole(const Scene& scene, int size, bool plane, int mode)
{
  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->SetSize(size, size);
  vtkNew<vtkRenderer> renderer;
  window->AddRenderer(renderer);
  vtkNew<vtkAPCVolumeMapper> mapper;
  mapper->SetInputData(scene.Grid);
  mapper->SetMode(mode);
  vtkNew<vtkVolume> volume;
  ConfigureVolume(volume, mapper, scene);
  renderer->AddVolume(volume);
  double b[6];
  scene.Grid->GetBounds(b);
  vtkNew<vtkPlaneSource> source;
  vtkNew<vtkPolyDataMapper> planeMapper;
  vtkNew<vtkActor> actor;
  if (plane)
  {
    source->SetOrigin(b[0], b[2], 0.5 * (b[4] + b[5]));
    source->SetPoint1(b[1], b[2], 0.5 * (b[4] + b[5]));
    source->SetPoint2(b[0], 0.5 * (b[2] + b[3]), 0.5 * (b[4] + b[5]));
    planeMapper->SetInputConnection(source->GetOutputPort());
    actor->SetMapper(planeMapper);
    renderer->AddActor(actor);
  }
  SetCamera(renderer, scene, b);
  window->Render();
  return ImageRGBA(mapper->GetLastImage());
}

std::vector<float> ImageRGBA(vtkImageData* image)
{
  std::vector<float> rgba;
  vtkDataArray* array = image ? image->GetPointData()->GetArray("RGBA") : nullptr;
  if (array)
  {
    rgba.resize(array->GetNumberOfTuples() * 4);
    for (vtkIdType v = 0; v < array->GetNumberOfTuples() * 4; ++v)
    {
      rgba[v] = static_cast<float>(array->GetComponent(v / 4, v % 4));
    }
  }
  return rgba;
}

void GlobalBounds(vtkMPIController* controller, vtkUnstructuredGrid* piece, double bounds[6])
{
  double local[6] = { 1e300, -1e300, 1e300, -1e300, 1e300, -1e300 };
  if (piece->GetNumberOfCells() > 0)
  {
    piece->GetBounds(local);
  }
  double mins[3] = { local[0], local[2], local[4] };
  double maxs[3] = { local[1], local[3], local[5] };
  double gmins[3];
  double gmaxs[3];
  controller->AllReduce(mins, gmins, 3, vtkCommunicator::MIN_OP);
  controller->AllReduce(maxs, gmaxs, 3, vtkCommunicator::MAX_OP);
  for (int d = 0; d < 3; ++d)
  {
    bounds[2 * d] = gmins[d];
    bounds[2 * d + 1] = gmaxs[d];
  }
}

double MaxAbsDifference(const std::vector<float>& a, const std::vector<float>& b)
{
  double most = a.size() == b.size() && !a.empty() ? 0.0 : 1.0;
  for (size_t v = 0; v < std::min(a.size(), b.size()); ++v)
  {
    most = std::max(most, static_cast<double>(std::abs(a[v] - b[v])));
  }
  return most;
}

Scene MakeScene(
  vtkUnstructuredGrid* grid, const TransferFunction& tf, double spacing, const View& view)
{
  Scene scene;
  scene.Grid = grid;
  scene.TF = tf;
  scene.Camera = view;
  scene.SampleDistance = spacing;
  return scene;
}

vtkSmartPointer<vtkUnstructuredGrid> PuzzleShare(int piece, int pieces, int puzzlePieces, int field)
{
  return apctest::PuzzlePiece(field, puzzlePieces, 4, 12, piece, 2, pieces);
}

Scene PuzzleScene(int puzzlePieces)
{
  View oblique;
  oblique.Parallel = false;
  oblique.Position = { 2.5, 1.7, 3.1 };
  return MakeScene(PuzzleShare(0, 1, puzzlePieces), BlueToRedTF(0.0, 1.0, 0.2), 0.02, oblique);
}

vtkSmartPointer<vtkUnstructuredGrid> WindPieces(int rank, int ranks)
{
  vtkNew<vtkAppendFilter> append;
  for (int p = rank; p < 8; p += ranks)
  {
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    reader->SetFileName(
      (std::string(APC_DATA_DIR) + "/windAroundBuildings/wind_" + std::to_string(p) + ".vtu")
        .c_str());
    reader->Update();
    append->AddInputData(reader->GetOutput());
  }
  vtkSmartPointer<vtkUnstructuredGrid> grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  if (append->GetNumberOfInputConnections(0) > 0)
  {
    append->Update();
    grid->ShallowCopy(append->GetOutput());
    grid->GetPointData()->SetActiveScalars("U_mag");
  }
  return grid;
}

vtkSmartPointer<vtkUnstructuredGrid> DepthBlock(vtkUnstructuredGrid* grid, int rank, int ranks)
{
  double b[6];
  grid->GetBounds(b);
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    double cb[6];
    grid->GetCellBounds(c, cb);
    const double f = (0.5 * (cb[4] + cb[5]) - b[4]) / (b[5] - b[4]);
    if (std::min(ranks - 1, static_cast<int>(f * ranks)) == rank)
    {
      ids->InsertNextId(c);
    }
  }
  vtkNew<vtkExtractCells> extract;
  extract->SetInputData(grid);
  extract->SetCellList(ids);
  extract->Update();
  vtkSmartPointer<vtkUnstructuredGrid> piece = extract->GetOutput();
  return piece;
}

} // namespace apctest
