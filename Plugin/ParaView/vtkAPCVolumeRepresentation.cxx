// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAPCVolumeRepresentation.h"

#include "vtkAPCCompositePass.h"
#include "vtkAPCVolumeMapper.h"

#include "apcPassInstaller.h"
#include "apcSettingChecks.h"

#include "vtkAlgorithmOutput.h"
#include "vtkAppendFilter.h"
#include "vtkColorTransferFunction.h"
#include "vtkCompositeDataIterator.h"
#include "vtkCompositeDataSet.h"
#include "vtkDataObject.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPVRenderView.h"
#include "vtkUnstructuredGrid.h"
#include "vtkUnstructuredGridBase.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <algorithm>
#include <cmath>
#include <sstream>

vtkStandardNewMacro(vtkAPCVolumeRepresentation);

namespace
{
// When data last changed: a composite's own time or any leaf's.
vtkMTimeType DataTime(vtkDataObject* data)
{
  vtkMTimeType time = data ? data->GetMTime() : 0;
  if (auto* composite = vtkCompositeDataSet::SafeDownCast(data))
  {
    vtkSmartPointer<vtkCompositeDataIterator> it;
    it.TakeReference(composite->NewIterator());
    for (it->InitTraversal(); !it->IsDoneWithTraversal(); it->GoToNextItem())
    {
      time = std::max(time, it->GetCurrentDataObject()->GetMTime());
    }
  }
  return time;
}

// The Band Size property's range (APCRepresentation.xml says the same).
constexpr double kMinBandMegapixels = 0.01;
constexpr double kMaxBandMegapixels = 1024.0;
}

//------------------------------------------------------------------------------
vtkAPCVolumeRepresentation::vtkAPCVolumeRepresentation()
  : Mapper(vtkSmartPointer<vtkAPCVolumeMapper>::New())
  , LocalPiece(vtkSmartPointer<vtkUnstructuredGrid>::New())
  , ViewRequest(new apc::ViewRequest)
{
  this->APCVolume = vtkSmartPointer<vtkVolume>::New();
  this->APCVolume->SetMapper(this->Mapper);
  this->APCVolume->SetProperty(this->Property);
}

vtkAPCVolumeRepresentation::~vtkAPCVolumeRepresentation()
{
  this->Attach(false);
}

vtkAPCVolumeMapper* vtkAPCVolumeRepresentation::GetMapper()
{
  return this->Mapper;
}

//------------------------------------------------------------------------------
int vtkAPCVolumeRepresentation::FillInputPortInformation(int, vtkInformation* info)
{
  info->Append(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkUnstructuredGridBase");
  info->Append(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkCompositeDataSet");
  info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  return 1;
}

//------------------------------------------------------------------------------
int vtkAPCVolumeRepresentation::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  // This rank's cells, as one grid: composite inputs (OpenFOAM, Exodus readers) have their
  // unstructured leaves appended here, locally; nothing crosses ranks.
  vtkDataObject* input = inputVector[0]->GetNumberOfInformationObjects()
    ? vtkDataObject::GetData(inputVector[0], 0)
    : nullptr;
  // A display property's change re-executes this (MarkModified) with the same data: the piece
  // is kept, so that the mapper sees no new data (its input warnings follow data changes only).
  const vtkMTimeType inputTime = DataTime(input);
  if (input && input == this->PieceSource && inputTime == this->PieceSourceTime)
  {
    return this->Superclass::RequestData(request, inputVector, outputVector);
  }
  this->PieceSource = input;
  this->PieceSourceTime = inputTime;
  this->LocalPiece = vtkSmartPointer<vtkUnstructuredGrid>::New();
  vtkNew<vtkAppendFilter> append;
  if (auto* grid = vtkUnstructuredGridBase::SafeDownCast(input))
  {
    append->AddInputData(grid);
  }
  else if (auto* composite = vtkCompositeDataSet::SafeDownCast(input))
  {
    vtkSmartPointer<vtkCompositeDataIterator> it;
    it.TakeReference(composite->NewIterator());
    for (it->InitTraversal(); !it->IsDoneWithTraversal(); it->GoToNextItem())
    {
      if (auto* leaf = vtkUnstructuredGridBase::SafeDownCast(it->GetCurrentDataObject()))
      {
        if (leaf->GetNumberOfCells() > 0)
        {
          append->AddInputData(leaf);
        }
      }
    }
  }
  if (append->GetNumberOfInputConnections(0) > 0)
  {
    append->Update();
    this->LocalPiece->ShallowCopy(append->GetOutput());
  }
  this->DataSize = this->LocalPiece->GetActualMemorySize();
  this->LocalPiece->GetBounds(this->DataBounds);
  return this->Superclass::RequestData(request, inputVector, outputVector);
}

//------------------------------------------------------------------------------
int vtkAPCVolumeRepresentation::ProcessViewRequest(
  vtkInformationRequestKey* request_type, vtkInformation* inInfo, vtkInformation* outInfo)
{
  if (!this->Superclass::ProcessViewRequest(request_type, inInfo, outInfo))
  {
    return 0; // invisible
  }
  if (request_type == vtkPVView::REQUEST_UPDATE())
  {
    // The piece stays on its rank: no ordered compositing, so no redistribution; and the
    // view must render in parallel (remotely) whatever the data size.
    vtkPVView::SetPiece(inInfo, this, this->LocalPiece, this->DataSize);
    vtkPVRenderView::SetGeometryBounds(inInfo, this, this->DataBounds);
    vtkPVRenderView::SetRequiresDistributedRendering(inInfo, this, true);
  }
  else if (request_type == vtkPVView::REQUEST_UPDATE_LOD())
  {
    vtkPVRenderView::SetRequiresDistributedRenderingLOD(inInfo, this, true);
  }
  else if (request_type == vtkPVView::REQUEST_RENDER())
  {
    vtkDataObject* piece = vtkPVView::GetDeliveredPiece(inInfo, this);
    this->Mapper->SetInputDataObject(piece ? piece : this->LocalPiece.Get());
    if (!this->UpdateMapperArray())
    {
      // Solid Color: no array to render. Nothing is drawn (on every rank alike: they share the
      // setting), and that is said once until an array is chosen.
      this->Attach(false);
      if (!this->SaidNoArray && apc::SaysMessages())
      {
        vtkWarningMacro("APC Volume renders the values of an array: choose one in Coloring "
                        "(Solid Color has none). Nothing is drawn until then.");
      }
      this->SaidNoArray = true;
      return 1;
    }
    this->SaidNoArray = false;
    this->Attach(true);
  }
  return 1;
}

//------------------------------------------------------------------------------
bool vtkAPCVolumeRepresentation::UpdateMapperArray()
{
  vtkInformation* info = this->GetInputArrayInformation(0);
  const char* name = info && info->Has(vtkDataObject::FIELD_ASSOCIATION())
    ? info->Get(vtkDataObject::FIELD_NAME())
    : nullptr;
  if (!name || !*name)
  {
    return false; // Solid Color
  }
  this->Mapper->SelectScalarArray(name);
  this->Mapper->SetScalarMode(
    info->Get(vtkDataObject::FIELD_ASSOCIATION()) == vtkDataObject::FIELD_ASSOCIATION_CELLS
      ? VTK_SCALAR_MODE_USE_CELL_FIELD_DATA
      : VTK_SCALAR_MODE_USE_POINT_FIELD_DATA);
  // Which values of a vector are rendered: the colour map's vector mode and component (what
  // ColorBy(display, ('POINTS', 'v', 'X')) sets), as ParaView's own volume representations
  // hand them to their mappers; with dependent components (Map Scalars off, or Multi
  // Components Mapping on) the first one, as they do.
  vtkColorTransferFunction* colours = this->Property->GetRGBTransferFunction(0);
  const bool independent = this->MapScalars && !this->MultiComponentsMapping;
  this->Mapper->SetVectorMode(
    independent && colours ? colours->GetVectorMode() : vtkScalarsToColors::COMPONENT);
  this->Mapper->SetVectorComponent(independent && colours ? colours->GetVectorComponent() : 0);
  return true;
}

//------------------------------------------------------------------------------
void vtkAPCVolumeRepresentation::Attach(bool attach)
{
  if (!attach)
  {
    apc::DetachVolume(this, this->APCVolume);
    return;
  }
  apc::AttachVolume(this->View, this, this->APCVolume, *this->ViewRequest);
}

//------------------------------------------------------------------------------
bool vtkAPCVolumeRepresentation::AddToView(vtkView* view)
{
  // The volume is deliberately not added to the renderer: IceT must not render it.
  this->View = vtkPVRenderView::SafeDownCast(view);
  return this->View ? this->Superclass::AddToView(view) : false;
}

bool vtkAPCVolumeRepresentation::RemoveFromView(vtkView* view)
{
  this->Attach(false);
  this->View = nullptr;
  return this->Superclass::RemoveFromView(view);
}

void vtkAPCVolumeRepresentation::SetVisibility(bool visible)
{
  if (!visible)
  {
    this->Attach(false);
  }
  this->Superclass::SetVisibility(visible);
}

//------------------------------------------------------------------------------
void vtkAPCVolumeRepresentation::SetSampleDistance(double distance)
{
  this->Mapper->SetSampleDistance(distance);
  this->MarkModified();
}

void vtkAPCVolumeRepresentation::SetNumberOfMoments(int moments)
{
  this->Mapper->SetNumberOfMoments(moments);
  this->MarkModified();
}

void vtkAPCVolumeRepresentation::SetLatticeJitter(bool jitter)
{
  this->Mapper->SetLatticeJitter(jitter);
  this->MarkModified();
}

void vtkAPCVolumeRepresentation::SetSampleEndWeights(int mode)
{
  this->Mapper->SetSampleEndWeights(mode);
  this->MarkModified();
}

void vtkAPCVolumeRepresentation::SetStopWhereOpaque(bool stop)
{
  this->Mapper->SetStopWhereOpaque(stop);
  this->MarkModified();
}

void vtkAPCVolumeRepresentation::SetSampleCacheSize(int megabytes)
{
  this->Mapper->SetSampleCacheSize(megabytes);
  this->MarkModified();
}

void vtkAPCVolumeRepresentation::SetOverestimation(double beta)
{
  this->Mapper->SetOverestimation(beta);
  this->MarkModified();
}

void vtkAPCVolumeRepresentation::SetResolveMode(int mode)
{
  this->Mapper->SetResolveMode(mode);
  this->MarkModified();
}

// The view settings enter here: checked once (the pass then gets valid values), kept for the
// view's pass (apcPassInstaller.h).
void vtkAPCVolumeRepresentation::SetMode(int mode)
{
  mode = apc::CheckedSetting(this, "APC Mode", mode, 0, 3,
    "0 APC, 1 Exact (segments), "
    "2 Local exact, 3 Auto");
  if (this->ViewRequest->Frame.CompositeMode != mode)
  {
    this->ViewRequest->Frame.CompositeMode = mode;
    this->MarkModified();
  }
}

int vtkAPCVolumeRepresentation::GetMode() const
{
  return this->ViewRequest->Frame.CompositeMode;
}

void vtkAPCVolumeRepresentation::SetImageFileName(const char* name)
{
  this->ViewRequest->ImageFileName = name ? name : "";
  this->MarkModified();
}

const char* vtkAPCVolumeRepresentation::GetImageFileName() const
{
  return this->ViewRequest->ImageFileName.c_str();
}

void vtkAPCVolumeRepresentation::SetInteractiveSampleDistanceFactor(double factor)
{
  this->ViewRequest->Frame.InteractiveSampleDistanceFactor =
    apc::CheckedSetting(this, "Interactive Sample Distance Factor", factor, 1.0,
      apc::FrameSettings::MaxSampleDistanceFactor, "1 switches it off");
  this->MarkModified();
}

double vtkAPCVolumeRepresentation::GetInteractiveSampleDistanceFactor() const
{
  return this->ViewRequest->Frame.InteractiveSampleDistanceFactor;
}

void vtkAPCVolumeRepresentation::SetInteractiveImageReduction(int reduction)
{
  this->ViewRequest->Frame.InteractiveImageReduction =
    apc::CheckedSetting(this, "Interactive Image Reduction", reduction, 1,
      apc::FrameSettings::MaxImageReduction, "1 switches it off");
  this->MarkModified();
}

int vtkAPCVolumeRepresentation::GetInteractiveImageReduction() const
{
  return this->ViewRequest->Frame.InteractiveImageReduction;
}

void vtkAPCVolumeRepresentation::SetBandMegapixels(double megapixels)
{
  megapixels = apc::CheckedSetting(this, "Band Size (megapixels)", megapixels, kMinBandMegapixels,
    kMaxBandMegapixels, "units of 2^20 pixels");
  this->ViewRequest->Frame.MaxBandPixels = static_cast<vtkIdType>(std::ldexp(megapixels, 20));
  this->MarkModified();
}

double vtkAPCVolumeRepresentation::GetBandMegapixels() const
{
  return std::ldexp(static_cast<double>(this->ViewRequest->Frame.MaxBandPixels), -20);
}

void vtkAPCVolumeRepresentation::SetVerbosity(int verbosity)
{
  this->ViewRequest->Verbosity =
    apc::CheckedSetting(this, "Compositing Verbosity", verbosity, 0, 1);
  this->MarkModified();
}

int vtkAPCVolumeRepresentation::GetVerbosity() const
{
  return this->ViewRequest->Verbosity;
}

//------------------------------------------------------------------------------
double* vtkAPCVolumeRepresentation::GetLastTimings()
{
  static_assert(sizeof(this->LastTimings) / sizeof(double) == vtkAPCCompositePass::NumberOfTimings,
    "one value per field of vtkAPCCompositePass::Timings (and VTK_SIZEHINT in the header)");
  static_assert(
    sizeof(vtkAPCCompositePass::Timings) == sizeof(double) * vtkAPCCompositePass::NumberOfTimings,
    "NumberOfTimings counts every field of vtkAPCCompositePass::Timings");
  const vtkAPCCompositePass* pass = apc::FindPass(this);
  const vtkAPCCompositePass::Timings timings =
    pass ? pass->GetLastTimings() : vtkAPCCompositePass::Timings();
  int field = 0;
  vtkAPCCompositePass::ForEachTiming(
    timings, [&](const char*, double value) { this->LastTimings[field++] = value; });
  return this->LastTimings;
}

const char* vtkAPCVolumeRepresentation::GetLastTimingNames()
{
  this->LastTimingNames.clear();
  const vtkAPCCompositePass::Timings timings;
  vtkAPCCompositePass::ForEachTiming(timings,
    [&](const char* name, double)
    { this->LastTimingNames += (this->LastTimingNames.empty() ? "" : " ") + std::string(name); });
  return this->LastTimingNames.c_str();
}

const char* vtkAPCVolumeRepresentation::GetLastRankRenderSeconds()
{
  const vtkAPCCompositePass* pass = apc::FindPass(this);
  std::ostringstream list;
  list.precision(17);
  for (const double seconds : pass ? pass->GetLastRankRenderSeconds() : std::vector<double>())
  {
    list << (list.tellp() > 0 ? " " : "") << seconds;
  }
  this->LastRankRenderSeconds = list.str();
  return this->LastRankRenderSeconds.c_str();
}

//------------------------------------------------------------------------------
void vtkAPCVolumeRepresentation::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  const apc::ViewRequest& request = *this->ViewRequest;
  os << indent << "Mode: " << request.Frame.CompositeMode
     << " (vtkAPCCompositePass::CompositeModeType)\n";
  os << indent << "Verbosity: " << request.Verbosity << "\n";
  os << indent
     << "InteractiveSampleDistanceFactor: " << request.Frame.InteractiveSampleDistanceFactor
     << "\n";
  os << indent << "InteractiveImageReduction: " << request.Frame.InteractiveImageReduction << "\n";
  os << indent << "BandMegapixels: " << this->GetBandMegapixels() << "\n";
}
