// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAPCVolumeRepresentation.h"

#include "vtkAPCCompositePass.h"
#include "vtkAPCVolumeMapper.h"

#include "apcPassInstaller.h"

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

vtkStandardNewMacro(vtkAPCVolumeRepresentation);

//------------------------------------------------------------------------------
vtkAPCVolumeRepresentation::vtkAPCVolumeRepresentation()
  : Mapper(vtkSmartPointer<vtkAPCVolumeMapper>::New())
  , LocalPiece(vtkSmartPointer<vtkUnstructuredGrid>::New())
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
  this->LocalPiece = vtkSmartPointer<vtkUnstructuredGrid>::New();
  vtkDataObject* input = inputVector[0]->GetNumberOfInformationObjects()
    ? vtkDataObject::GetData(inputVector[0], 0)
    : nullptr;
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
    this->UpdateMapperArray();
    this->Attach(true);
  }
  return 1;
}

//------------------------------------------------------------------------------
void vtkAPCVolumeRepresentation::UpdateMapperArray()
{
  vtkInformation* info = this->GetInputArrayInformation(0);
  if (info && info->Has(vtkDataObject::FIELD_ASSOCIATION()) &&
    info->Has(vtkDataObject::FIELD_NAME()))
  {
    this->Mapper->SelectScalarArray(info->Get(vtkDataObject::FIELD_NAME()));
    this->Mapper->SetScalarMode(
      info->Get(vtkDataObject::FIELD_ASSOCIATION()) == vtkDataObject::FIELD_ASSOCIATION_CELLS
        ? VTK_SCALAR_MODE_USE_CELL_FIELD_DATA
        : VTK_SCALAR_MODE_USE_POINT_FIELD_DATA);
  }
  else
  {
    this->Mapper->SelectScalarArray(static_cast<const char*>(nullptr));
    this->Mapper->SetScalarMode(VTK_SCALAR_MODE_DEFAULT);
  }
  // Which values of a vector are rendered: the colour map's vector mode and component (what
  // ColorBy(display, ('POINTS', 'v', 'X')) sets), as ParaView's own volume representations
  // hand them to their mappers; with dependent components (Map Scalars off, or Multi
  // Components Mapping on) the first one, as they do.
  vtkColorTransferFunction* colours = this->Property->GetRGBTransferFunction(0);
  const bool independent = this->MapScalars && !this->MultiComponentsMapping;
  this->Mapper->SetVectorMode(
    independent && colours ? colours->GetVectorMode() : vtkScalarsToColors::COMPONENT);
  this->Mapper->SetVectorComponent(independent && colours ? colours->GetVectorComponent() : 0);
}

//------------------------------------------------------------------------------
void vtkAPCVolumeRepresentation::Attach(bool attach)
{
  if (!attach)
  {
    apc::DetachVolume(this, this->APCVolume);
    return;
  }
  if (vtkAPCCompositePass* pass = apc::AttachVolume(this->View, this, this->APCVolume))
  {
    pass->SetCompositeMode(this->Mode);
    pass->SetVerbosity(this->Verbosity);
    pass->SetImageFileName(this->ImageFileName.c_str());
    pass->SetInteractiveSampleDistanceFactor(this->InteractiveSampleDistanceFactor);
    pass->SetInteractiveImageReduction(this->InteractiveImageReduction);
    pass->SetMaxBandPixels(
      static_cast<vtkIdType>(std::max(1.0, std::ldexp(this->BandMegapixels, 20))));
  }
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

void vtkAPCVolumeRepresentation::SetMode(int mode)
{
  // The pass clamps it, where it is used: this only passes it on.
  if (this->Mode != mode)
  {
    this->Mode = mode;
    this->MarkModified();
  }
}

void vtkAPCVolumeRepresentation::SetImageFileName(const char* name)
{
  this->ImageFileName = name ? name : "";
  this->MarkModified();
}

void vtkAPCVolumeRepresentation::SetInteractiveSampleDistanceFactor(double factor)
{
  // The pass clamps and agrees on it: this only passes it on.
  this->InteractiveSampleDistanceFactor = factor;
  this->MarkModified();
}

void vtkAPCVolumeRepresentation::SetInteractiveImageReduction(int reduction)
{
  this->InteractiveImageReduction = reduction;
  this->MarkModified();
}

void vtkAPCVolumeRepresentation::SetBandMegapixels(double megapixels)
{
  this->BandMegapixels = megapixels;
  this->MarkModified();
}

void vtkAPCVolumeRepresentation::SetVerbosity(int verbosity)
{
  this->Verbosity = verbosity;
  this->MarkModified();
}

//------------------------------------------------------------------------------
double* vtkAPCVolumeRepresentation::GetLastTimings()
{
  std::fill(this->LastTimings, this->LastTimings + 15, 0.0);
  this->LastTimings[11] = -1;
  if (const vtkAPCCompositePass* pass = apc::FindPass(this))
  {
    const char* stages[] = { "agree", "depth", "pass1", "allreduce", "pass2", "reduce", "resolve",
      "blend" };
    for (int s = 0; s < 8; ++s)
    {
      this->LastTimings[s] = pass->GetLastStageSeconds(stages[s]);
    }
    this->LastTimings[8] = pass->GetLastStageSeconds(nullptr);
    this->LastTimings[9] = pass->GetLastBytesSent();
    this->LastTimings[10] = static_cast<double>(pass->GetLastCompositedPixels());
    this->LastTimings[11] = pass->GetLastCompositeMode();
    this->LastTimings[12] = static_cast<double>(pass->GetLastCoveredPixels());
    this->LastTimings[13] = pass->GetLastStageSeconds("tiles");
    this->LastTimings[14] = pass->GetLastImageReduction();
  }
  return this->LastTimings;
}

double* vtkAPCVolumeRepresentation::GetLastSegmentStatistics()
{
  std::fill(this->LastSegmentStatistics, this->LastSegmentStatistics + 7, 0.0);
  if (const vtkAPCCompositePass* pass = apc::FindPass(this))
  {
    const char* stages[] = { "segments", "exchange", "blend_segments", "gather" };
    for (int s = 0; s < 4; ++s)
    {
      this->LastSegmentStatistics[s] = pass->GetLastStageSeconds(stages[s]);
    }
    this->LastSegmentStatistics[4] = static_cast<double>(pass->GetLastMessagesSent());
    this->LastSegmentStatistics[5] = pass->GetLastAverageSegmentsPerPixel();
    this->LastSegmentStatistics[6] = static_cast<double>(pass->GetLastMaxSegmentsPerPixel());
  }
  return this->LastSegmentStatistics;
}

//------------------------------------------------------------------------------
void vtkAPCVolumeRepresentation::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Mode: " << this->Mode << " (vtkAPCCompositePass::CompositeModeType)\n";
  os << indent << "Verbosity: " << this->Verbosity << "\n";
  os << indent << "InteractiveSampleDistanceFactor: " << this->InteractiveSampleDistanceFactor
     << "\n";
  os << indent << "InteractiveImageReduction: " << this->InteractiveImageReduction << "\n";
  os << indent << "BandMegapixels: " << this->BandMegapixels << "\n";
}
