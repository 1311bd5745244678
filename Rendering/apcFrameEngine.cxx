// SPDX-License-Identifier: BSD-3-Clause
#include "apcFrameEngine.h"

#include "apcDefaultSpacing.h"
#include "apcTestFailures.h"

#include "vtkAbstractMapper.h"
#include "vtkCamera.h"
#include "vtkCellArray.h"
#include "vtkDataArray.h"
#include "vtkPoints.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"
#include "vtkUnstructuredGridBase.h"
#include "vtkVolumeProperty.h"

#include "apcCellMeshFromVTK.h"
#include "apcDepthWarp.h"
#include "apcFrameInputsFromVTK.h"
#include "apcParallel.h"
#include "apcRayCamera.h"
#include "apcTransferTable.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <sstream>
#include <utility>
#include <vector>

namespace apc
{

ImageSetup ImageSetup::FullQuality(vtkRenderer* ren)
{
  ImageSetup image;
  ren->GetTiledSizeAndOrigin(&image.Width, &image.Height, &image.X0, &image.Y0);
  image.Aspect = image.Height > 0 ? static_cast<double>(image.Width) / image.Height : 1.0;
  return image;
}

namespace
{
// Mixes an array's bytes into hash, eight at a time (FNV-1a steps on 64-bit words).
void HashBytes(const void* data, size_t bytes, unsigned long long& hash)
{
  const auto* p = static_cast<const unsigned char*>(data);
  size_t i = 0;
  for (; i + 8 <= bytes; i += 8)
  {
    unsigned long long word;
    std::memcpy(&word, p + i, 8);
    hash = (hash ^ word) * 1099511628211ull;
  }
  for (; i < bytes; ++i)
  {
    hash = (hash ^ p[i]) * 1099511628211ull;
  }
  hash = (hash ^ bytes) * 1099511628211ull;
}

void HashArray(vtkDataArray* array, unsigned long long& hash)
{
  if (array)
  {
    HashBytes(array->GetVoidPointer(0),
      static_cast<size_t>(array->GetNumberOfValues()) * array->GetDataTypeSize(), hash);
  }
  hash = (hash ^ (array ? array->GetDataType() : 0)) * 1099511628211ull;
}

// What a new time step of the same mesh keeps: points, cells, ghost flags. Their content,
// not their arrays' identity: pipelines (ParaView's append of a rank's blocks, Catalyst's
// producers) hand over fresh copies every step. 0 for grids that are not plain
// vtkUnstructuredGrid (no raw arrays to read): those are converted every time.
unsigned long long GeometryKey(vtkUnstructuredGridBase* input)
{
  auto* grid = vtkUnstructuredGrid::SafeDownCast(input);
  if (!grid || !grid->GetPoints() || !grid->GetCells())
  {
    return 0;
  }
  unsigned long long hash = 1469598103934665603ull;
  HashArray(grid->GetPoints()->GetData(), hash);
  HashArray(grid->GetCells()->GetOffsetsArray(), hash);
  HashArray(grid->GetCells()->GetConnectivityArray(), hash);
  HashArray(grid->GetCellTypesArray(), hash);
  HashArray(grid->GetCellGhostArray(), hash);
  HashArray(grid->GetFaces(), hash); // polyhedra
  HashArray(grid->GetFaceLocations(), hash);
  return hash == 0 ? 1 : hash;
}
}

FrameEngine::FrameEngine() = default;
FrameEngine::~FrameEngine() = default;

namespace
{
// vtkAbstractVolumeMapper::GetScalarModeAsString's names, for the message.
const char* ScalarModeName(int mode)
{
  switch (mode)
  {
    case VTK_SCALAR_MODE_USE_CELL_DATA:
      return "UseCellData";
    case VTK_SCALAR_MODE_USE_POINT_DATA:
      return "UsePointData";
    case VTK_SCALAR_MODE_USE_POINT_FIELD_DATA:
      return "UsePointFieldData";
    case VTK_SCALAR_MODE_USE_CELL_FIELD_DATA:
      return "UseCellFieldData";
    default:
      return "Default";
  }
}

// The data a mesh is made of: the arrays of points, cells and ghosts with their modification
// times. ParaView hands the mapper a new shallow copy of the same piece after a display
// property's change: a new data set, but the same arrays, and no new data.
std::string DataKey(vtkUnstructuredGridBase* input)
{
  std::ostringstream key;
  auto add = [&key](vtkObject* object)
  { key << object << ' ' << (object ? object->GetMTime() : 0) << ' '; };
  auto* grid = vtkUnstructuredGrid::SafeDownCast(input);
  if (!grid)
  {
    add(input); // another kind of unstructured grid: the data set itself
    return key.str();
  }
  add(grid->GetPoints() ? grid->GetPoints()->GetData() : nullptr);
  add(grid->GetCells());
  add(grid->GetCellTypesArray());
  add(grid->GetFaces());
  add(grid->GetCellGhostArray());
  return key.str();
}
}

//------------------------------------------------------------------------------
bool FrameEngine::UpdateInput(vtkUnstructuredGridBase* input, vtkObject* reporter)
{
  if (!input || input->GetNumberOfCells() == 0)
  {
    // An empty piece renders nothing, silently: in parallel that is a normal rank.
    this->Mesh = CellMesh();
    this->Mesh.Finalize();
    this->MeshValid = true;
    this->MeshKey.clear();
    this->MeshGeometryKey = 0;
    this->Report = InputReport();
    this->ReportPending = false;
    return true;
  }
  const ScalarChoice& choice = this->Settings.Scalars;
  int cellFlag = 0;
  vtkDataArray* scalars = vtkAbstractMapper::GetScalars(input, choice.ScalarMode,
    choice.ArrayAccessMode, choice.ArrayId, choice.ArrayName.c_str(), cellFlag);
  if (!scalars)
  {
    vtkErrorWithObjectMacro(reporter,
      "The input has no scalars to render (ScalarMode "
        << ScalarModeName(choice.ScalarMode) << ", array "
        << (choice.ArrayName.empty() ? "<none>" : choice.ArrayName.c_str()) << ").");
    this->MeshValid = false;
    return false;
  }
  ScalarSelection selection;
  selection.Array = scalars;
  selection.CellData = cellFlag == 1;
  selection.VectorMode = choice.VectorMode;
  selection.VectorComponent = choice.VectorComponent;
  // Rebuild the ray marcher's mesh (and say its report again) only when the data or the scalar
  // selection changed.
  std::ostringstream selectionKey;
  selectionKey << cellFlag << ' ' << selection.VectorMode << ' ' << selection.VectorComponent;
  std::ostringstream key;
  key << DataKey(input) << ' ' << scalars << ' ' << scalars->GetMTime() << ' '
      << selectionKey.str();
  // The same data set modified (Modified() after editing values in place) is a change too.
  const bool modified = input == this->MeshData && input->GetMTime() > this->MeshDataTime;
  this->MeshData = input;
  this->MeshDataTime = input->GetMTime();
  // A mesh that borrows its input's cells (apcGridCells.h) is made again once they moved or
  // changed, whatever the keys say.
  const bool cellsIntact = this->Mesh.CellsIntact();
  if (this->MeshValid && this->MeshKey == key.str() && !modified && cellsIntact)
  {
    return true;
  }
  const unsigned long long geometry = GeometryKey(input);
  std::string error;
  if (this->MeshValid && cellsIntact && geometry != 0 && geometry == this->MeshGeometryKey &&
    this->MeshSelectionKey == selectionKey.str() && this->Mesh.GetNumberOfCells() > 0)
  {
    // Only the values changed: the cells, their checks and planes stay.
    ++this->ScalarRefreshes;
    this->MeshValid =
      RefreshScalarsFromVTK(input, selection, this->MeshSources, this->Mesh, this->Report, error);
  }
  else
  {
    ++this->MeshConversions;
    this->MeshValid =
      CellMeshFromVTK(input, selection, this->Mesh, this->Report, error, &this->MeshSources);
  }
  this->ReportPending = this->MeshValid && !this->Report.Empty();
  if (!this->MeshValid)
  {
    // The input cannot be rendered at all: said at once, by every process it happens on.
    this->Report.Emit(reporter);
    vtkErrorWithObjectMacro(reporter, << error);
    this->Report = InputReport();
  }
  this->MeshKey = key.str();
  this->MeshSelectionKey = selectionKey.str();
  this->MeshGeometryKey = this->MeshValid ? geometry : 0;
  this->Clock.Lap("mesh");
  return this->MeshValid;
}

//------------------------------------------------------------------------------
bool FrameEngine::TakeNewInputReport()
{
  const bool news = this->ReportPending;
  this->ReportPending = false;
  return news;
}

//------------------------------------------------------------------------------
bool FrameEngine::GetLocalBounds(double bounds[6]) const
{
  if (!this->MeshValid || this->Mesh.GetNumberOfCells() == 0)
  {
    return false;
  }
  const auto& b = this->Mesh.GetBounds();
  std::copy(b.begin(), b.end(), bounds);
  return true;
}

//------------------------------------------------------------------------------
int FrameEngine::GetThreads() const
{
  return ConcurrencyFor(this->Settings.NumberOfThreads);
}

//------------------------------------------------------------------------------
void FrameEngine::BeginFrame(const VolumeSettings& settings)
{
  this->Settings = settings;
  this->OpaqueStopActive = true;
  this->Clock.Restart();
  this->Ready = false;
}

//------------------------------------------------------------------------------
bool FrameEngine::Prepare(vtkRenderer* ren, vtkVolumeProperty* property, const double* globalBounds,
  double globalCells, double globalVolume, const float* depthBuffer, const ImageSetup& image)
{
  this->Ready = false;
  this->Crop = image.Crop.value_or(ScreenRect{ 0, 0, image.Width, image.Height });
  const int width = this->GetWidth();
  const int height = this->GetHeight();
  this->X0 = image.X0;
  this->Y0 = image.Y0;
  if (width < 1 || height < 1 || !this->MeshValid)
  {
    return false;
  }

  // Everything that must agree between processes comes from the global bounds, cell count
  // and cell volume: the sample spacing (the lattice) and the depth range of the warp (the moments'
  // axis).
  std::array<double, 6> bounds = this->Mesh.GetBounds();
  double cells = static_cast<double>(this->Mesh.GetNumberOfCells());
  double volume = this->Mesh.GetCellVolume().Value();
  if (globalBounds)
  {
    std::copy(globalBounds, globalBounds + 6, bounds.begin());
    cells = globalCells;
    volume = globalVolume;
  }
  if (!(bounds[0] <= bounds[1] && bounds[2] <= bounds[3] && bounds[4] <= bounds[5]))
  {
    return false; // no cells anywhere
  }
  const double diagonal = BoundsDiagonal(bounds.data());
  const double distance = this->Settings.SampleDistance;
  this->DefaultWeighted = this->WeightsEnds() && !image.PlainLattice;
  this->Spacing = image.SampleFactor *
    (distance > 0 ? distance
                  : DefaultSampleDistance(bounds.data(), cells, volume, this->DefaultWeighted));
  if (!(this->Spacing > 0))
  {
    return false; // a mesh with no extent
  }
  this->CapSpacing(distance, diagonal);
  this->Table = TransferTableFromVTK(property, this->Spacing);
  this->Camera.reset(new RayCamera(RayCameraFromVTK(ren, image.Width, image.Height, image.Aspect)
                                     ->Cropped(this->Crop.I0, this->Crop.J0, width, height)));
  double clip[2];
  ren->GetActiveCamera()->GetClippingRange(clip);
  double tmin = 0;
  double tmax = 0;
  this->Camera->DistanceRange(bounds, tmin, tmax);
  this->Warp.reset(new LogDepthWarp(std::max(tmin, clip[0]), tmax));

  // Rays end at the opaque geometry: the given depth buffer, or this window's, read into the
  // ends' own buffer and turned into distances in place (one image-sized buffer written, not two).
  std::vector<float> rayEnds;
  if (depthBuffer)
  {
    rayEnds.assign(depthBuffer, depthBuffer + this->GetPixels());
  }
  else
  {
    rayEnds.assign(this->GetPixels(), 1.0f);
    const int x0 = this->X0 + this->Crop.I0;
    const int y0 = this->Y0 + this->Crop.J0;
    ren->GetRenderWindow()->GetZbufferData(x0, y0, x0 + width - 1, y0 + height - 1, rayEnds.data());
  }
  for (int j = 0; j < height; ++j)
  {
    for (int i = 0; i < width; ++i)
    {
      const size_t p = static_cast<size_t>(j) * width + i;
      rayEnds[p] = static_cast<float>(this->Camera->DistanceFromDepth(i, j, rayEnds[p]));
    }
  }
  this->Marcher.SetNumberOfThreads(this->Settings.NumberOfThreads);
  this->Marcher.SetLatticeJitter(this->Settings.LatticeJitter);
  this->Marcher.SetEndWeightsMode(this->EndWeightsMode());
  this->SetOpaqueStopActive(this->OpaqueStopActive);
  this->Marcher.SetMaxSampleCacheBytes(this->Settings.SampleCacheBytes());
  if (this->RendersBoundaryWeights()) // once per data change
  {
    this->Mesh.FindBoundaryPlanes();
  }
  this->Marcher.SetMesh(&this->Mesh);
  this->Marcher.SetView(*this->Camera, std::move(rayEnds));
  this->Samples = 0;
  this->ColourSamples = 0;
  this->ReplayedSamples = 0;
  this->HiddenSamples = 0;
  this->CutSamples = 0;
  this->UnstoppedTiles = 0;
  this->Ready = true;
  this->Clock.Lap("setup");
  return true;
}

//------------------------------------------------------------------------------
VolumeRayMarcher::EndWeightsMode FrameEngine::EndWeightsMode() const
{
  // Hybrid is the exact blend on one process (its own samples' product, T_others = 1), and
  // the exact modes keep the plain lattice: its moments and its own product keep it too, or
  // one process's Hybrid would blend other samples than the exact image.
  if (this->Settings.Moments.Resolve == ResolveMode::Hybrid)
  {
    return VolumeRayMarcher::EndWeightsMode::Off;
  }
  return static_cast<VolumeRayMarcher::EndWeightsMode>(this->Settings.SampleEndWeights);
}

bool FrameEngine::WeightsEnds() const
{
  // The exact blend keeps the plain lattice whatever the setting (VolumeRayMarcher).
  return !this->Settings.Exact && this->EndWeightsMode() != VolumeRayMarcher::EndWeightsMode::Off;
}

bool FrameEngine::RendersBoundaryWeights() const
{
  return this->EndWeightsMode() == VolumeRayMarcher::EndWeightsMode::Boundary;
}

//------------------------------------------------------------------------------
void FrameEngine::CapSpacing(double distance, double diagonal)
{
  const double finest = diagonal / kMaxSamplesPerRay;
  if (this->Spacing >= finest)
  {
    return;
  }
  // Said once per setting and data extent, not every frame (nor again when an interactive
  // frame's coarser lattice happens to stay under the limit).
  if (distance != this->CappedDistance || diagonal != this->CappedDiagonal)
  {
    std::ostringstream note;
    if (distance > 0)
    {
      note << "Sample Distance " << distance;
    }
    else
    {
      note << "The default Sample Distance (" << this->Spacing
           << ", from the data's mean cell size)";
    }
    note << " would take up to " << static_cast<long long>(diagonal / this->Spacing)
         << " samples along a ray through the data (its bounding-box diagonal is " << diagonal
         << "); the limit is " << static_cast<long long>(kMaxSamplesPerRay) << ", so " << finest
         << " is used. " << (distance > 0 ? "Raise" : "Set") << " Sample Distance to at least "
         << finest << " (0 picks "
         << (this->DefaultWeighted ? kDefaultSpacingPerCell : kPlainSpacingPerCell)
         << " times the mean cell size, at least diagonal / "
         << static_cast<long long>(
              this->DefaultWeighted ? kMinDefaultSamples : kPlainMinDefaultSamples)
         << ").";
    this->SpacingNote = note.str();
    this->CappedDistance = distance;
    this->CappedDiagonal = diagonal;
  }
  this->Spacing = finest;
}

std::string FrameEngine::TakeSpacingNote()
{
  return std::exchange(this->SpacingNote, std::string());
}

//------------------------------------------------------------------------------
void FrameEngine::RenderMoments(
  const MomentParameters& parameters, double* moments, const RowBand& band, const uint8_t* bound)
{
  if (!this->Ready)
  {
    return;
  }
  ThrowIfFailingForTesting(FailurePoint::PassOne);
  // Hybrid's pass 2 needs this volume's own moments next to the global ones.
  const bool hybrid = parameters.Resolve == ResolveMode::Hybrid;
  this->Marcher.SetOpaqueBound(bound);
  DispatchMoments(parameters.Moments,
    [&](auto n)
    { this->Marcher.AccumulateMoments<n()>(*this->Table, *this->Warp, moments, hybrid, band); });
  this->Marcher.SetOpaqueBound(nullptr);
  this->Samples += this->Marcher.GetLastSampleCount(); // summed over the frame's bands
  this->UnstoppedTiles += this->Marcher.GetLastUnstoppedTileCount();
  this->Clock.Lap("moments");
}

//------------------------------------------------------------------------------
bool FrameEngine::StopsWhereOpaque(const MomentParameters& parameters) const
{
  // Hybrid's pass 1 marches every sample (its own transmittance is exact).
  return this->Settings.StopWhereOpaque && this->OpaqueStopActive &&
    parameters.Resolve != ResolveMode::Hybrid;
}

void FrameEngine::SetOpaqueStopActive(bool active)
{
  this->OpaqueStopActive = active;
  this->Marcher.SetOpaqueAbsorbance(this->Settings.StopWhereOpaque && active
      ? VolumeRayMarcher::kRecommendedOpaqueAbsorbance
      : std::numeric_limits<double>::infinity());
}

VolumeRayMarcher::OpaqueProfile FrameEngine::GetOpaqueProfile() const
{
  return this->Ready ? this->Marcher.GetOpaqueProfile() : VolumeRayMarcher::OpaqueProfile{};
}

uint16_t* FrameEngine::GetOpaqueProfileToSum(size_t values)
{
  return this->Ready && this->Marcher.GetOpaqueProfile().size() == values
    ? this->Marcher.GetOpaqueProfileToSum()
    : nullptr;
}

void FrameEngine::ApplyOpaqueCut(
  const MomentParameters& parameters, const uint16_t* profile, double* moments, const RowBand& band)
{
  if (!this->Ready)
  {
    return;
  }
  DispatchMoments(parameters.Moments,
    [&](auto n)
    { this->Marcher.ApplyOpaqueCut<n()>(*this->Table, *this->Warp, profile, moments, band); });
  this->CutSamples += this->Marcher.GetLastCutSampleCount();
  this->Clock.Lap("cut");
}

void FrameEngine::RedoOpaqueTiles(const MomentParameters& parameters, const uint8_t* unresolved,
  double* moments, const RowBand& band)
{
  if (!this->Ready)
  {
    return;
  }
  DispatchMoments(parameters.Moments,
    [&](auto n)
    { this->Marcher.RedoOpaqueTiles<n()>(*this->Table, *this->Warp, unresolved, moments, band); });
  this->Samples += this->Marcher.GetLastRedoSampleCount();
  this->Clock.Lap("moments");
}

int64_t FrameEngine::ProbeOpaqueProfile(
  const MomentParameters& parameters, int step, int offset, uint16_t* profile)
{
  if (!this->Ready || !this->StopsWhereOpaque(parameters))
  {
    return 0;
  }
  // The very rays of those pixels, with their ray ends, on the frame's lattice, warp and bins
  // (they follow from the camera and the data, not from the image's resolution).
  const RayCamera coarse = this->Camera->Decimated(step, offset);
  const int width = this->Camera->GetWidth();
  const std::vector<float>& ends = this->Marcher.GetRayEnds();
  std::vector<float> coarseEnds(static_cast<size_t>(coarse.GetWidth()) * coarse.GetHeight());
  for (int j = 0; j < coarse.GetHeight(); ++j)
  {
    for (int i = 0; i < coarse.GetWidth(); ++i)
    {
      const size_t fine = static_cast<size_t>(j * step + offset) * width + (i * step + offset);
      coarseEnds[static_cast<size_t>(j) * coarse.GetWidth() + i] =
        fine < ends.size() ? ends[fine] : std::numeric_limits<float>::infinity();
    }
  }
  ThrowIfFailingForTesting(FailurePoint::Probe);
  // A marcher of its own (the frame's keeps its view and cache for the frame's passes), freed
  // on return, also when the probe throws.
  const std::unique_ptr<VolumeRayMarcher> marcher(new VolumeRayMarcher);
  VolumeRayMarcher& probe = *marcher;
  probe.SetNumberOfThreads(this->Settings.NumberOfThreads);
  probe.SetLatticeJitter(this->Settings.LatticeJitter);
  probe.SetEndWeightsMode(this->EndWeightsMode());
  probe.SetOpaqueAbsorbance(VolumeRayMarcher::kRecommendedOpaqueAbsorbance);
  probe.SetMaxSampleCacheBytes(0);
  if (this->RendersBoundaryWeights())
  {
    this->Mesh.FindBoundaryPlanes();
  }
  probe.SetMesh(&this->Mesh);
  probe.SetDecimatedView(this->Marcher, step, offset, std::move(coarseEnds));
  std::vector<double> moments(
    static_cast<size_t>(coarse.GetWidth()) * coarse.GetHeight() * (parameters.Moments + 1), 0.0);
  DispatchMoments(parameters.Moments,
    [&](auto n) { probe.AccumulateMoments<n()>(*this->Table, *this->Warp, moments.data()); });
  const VolumeRayMarcher::OpaqueProfile own = probe.GetOpaqueProfile();
  AddProfiles(profile, own.data(), own.size());
  const int64_t samples = probe.GetLastSampleCount();
  this->Clock.Lap("opaque_prepass");
  return samples;
}

//------------------------------------------------------------------------------
void FrameEngine::RenderColour(const MomentParameters& parameters, const double* moments,
  double* colourSums, const RowBand& band)
{
  if (!this->Ready)
  {
    return;
  }
  ThrowIfFailingForTesting(FailurePoint::PassTwo);
  DispatchMoments(parameters.Moments,
    [&](auto n)
    {
      this->Marcher.AccumulateColour<n()>(*this->Table, *this->Warp, moments,
        parameters.Settings<n()>(), colourSums, parameters.Resolve == ResolveMode::Hybrid, band);
    });
  this->ColourSamples += this->Marcher.GetLastSampleCount();
  this->ReplayedSamples += this->Marcher.GetLastReplayedCount();
  this->HiddenSamples += this->Marcher.GetLastHiddenCount();
  this->Clock.Lap("colour");
}

//------------------------------------------------------------------------------
void FrameEngine::RenderExact(float* rgba)
{
  if (!this->Ready)
  {
    return;
  }
  this->Marcher.RenderExact(*this->Table, rgba);
  this->Samples = this->Marcher.GetLastSampleCount();
  this->Clock.Lap("exact");
}

//------------------------------------------------------------------------------
void FrameEngine::CountSegments(int* counts)
{
  if (!this->Ready)
  {
    return;
  }
  this->Marcher.CountSegments(counts);
  this->Clock.Lap("segments");
}

//------------------------------------------------------------------------------
void FrameEngine::RenderSegments(SegmentImage& segments)
{
  if (!this->Ready)
  {
    segments.Reset(this->GetWidth(), this->GetHeight());
    return;
  }
  this->Marcher.RenderSegments(*this->Table, segments);
  this->Samples = this->Marcher.GetLastSampleCount();
  this->Clock.Lap("segments");
}

} // namespace apc
