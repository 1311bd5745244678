// SPDX-License-Identifier: BSD-3-Clause
#include "apcPartitionInput.h"

#include "vtkDataSetAttributes.h"
#include "vtkInformation.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkNew.h"
#include "vtkPartitionedDataSet.h"
#include "vtkPartitionedDataSetCollection.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

namespace apc
{
namespace partition
{
namespace
{
// An empty part stands for a leaf absent on this rank, so every rank sees the same units.
std::string AddParts(vtkPartitionedDataSet* pds, Unit& unit, const std::string& where)
{
  if (!pds)
  {
    return {};
  }
  for (unsigned int i = 0; i < pds->GetNumberOfPartitions(); ++i)
  {
    vtkDataObject* part = pds->GetPartitionAsDataObject(i);
    if (!part)
    {
      continue;
    }
    auto* ug = vtkUnstructuredGrid::SafeDownCast(part);
    if (!ug)
    {
      return where + " partition " + std::to_string(i) + " is a " + part->GetClassName() +
        ", not a vtkUnstructuredGrid";
    }
    unit.Parts.push_back(ug);
  }
  return {};
}

void InstallPartitions(vtkPartitionedDataSet* out, const UGrids& pieces)
{
  out->SetNumberOfPartitions(static_cast<unsigned int>(pieces.size()));
  for (std::size_t i = 0; i < pieces.size(); ++i)
  {
    out->SetPartition(static_cast<unsigned int>(i), pieces[i]);
  }
}

// A vtkPartitionedDataSet as one unit whose pieces become the partitions of out.
std::string AddPartitionedUnit(vtkPartitionedDataSet* in, vtkPartitionedDataSet* out,
  std::vector<Unit>& units, const std::string& where)
{
  Unit unit;
  unit.Partitioned = true;
  const std::string error = AddParts(in, unit, where);
  if (!error.empty())
  {
    return error;
  }
  unit.Install = [out](const UGrids& pieces) { InstallPartitions(out, pieces); };
  units.push_back(std::move(unit));
  return {};
}

std::string CollectTree(
  vtkDataObject* in, vtkDataObject* out, std::vector<Unit>& units, const std::string& where);

// Block i of a multiblock: a leaf unit, a partitioned unit, or a multiblock walked in turn.
std::string CollectBlock(vtkMultiBlockDataSet* inMb, vtkMultiBlockDataSet* outMb, unsigned int i,
  std::vector<Unit>& units, const std::string& where)
{
  vtkDataObject* child = inMb->GetBlock(i);
  const std::string childWhere = where + " block " + std::to_string(i);
  if (!child || vtkUnstructuredGrid::SafeDownCast(child))
  {
    Unit unit;
    if (child)
    {
      unit.Parts.push_back(vtkUnstructuredGrid::SafeDownCast(child));
    }
    unit.Install = [outMb, i](const UGrids& pieces) { outMb->SetBlock(i, pieces[0]); };
    units.push_back(std::move(unit));
    return {};
  }
  if (auto* childPds = vtkPartitionedDataSet::SafeDownCast(child))
  {
    vtkSmartPointer<vtkPartitionedDataSet> outChild;
    outChild.TakeReference(childPds->NewInstance());
    outMb->SetBlock(i, outChild);
    return AddPartitionedUnit(childPds, outChild, units, childWhere);
  }
  if (vtkMultiBlockDataSet::SafeDownCast(child))
  {
    vtkNew<vtkMultiBlockDataSet> outChild;
    outMb->SetBlock(i, outChild);
    return CollectTree(child, outChild, units, childWhere);
  }
  return childWhere + " is a " + child->GetClassName() + ", not a vtkUnstructuredGrid";
}

std::string CollectMultiBlock(vtkMultiBlockDataSet* inMb, vtkMultiBlockDataSet* outMb,
  std::vector<Unit>& units, const std::string& where)
{
  outMb->SetNumberOfBlocks(inMb->GetNumberOfBlocks());
  for (unsigned int i = 0; i < inMb->GetNumberOfBlocks(); ++i)
  {
    if (inMb->HasMetaData(i))
    {
      outMb->GetMetaData(i)->Copy(inMb->GetMetaData(i));
    }
    const std::string error = CollectBlock(inMb, outMb, i, units, where);
    if (!error.empty())
    {
      return error;
    }
  }
  return {};
}

std::string CollectCollection(vtkPartitionedDataSetCollection* inPdc,
  vtkPartitionedDataSetCollection* outPdc, std::vector<Unit>& units, const std::string& where)
{
  outPdc->SetNumberOfPartitionedDataSets(inPdc->GetNumberOfPartitionedDataSets());
  outPdc->SetDataAssembly(inPdc->GetDataAssembly());
  for (unsigned int i = 0; i < inPdc->GetNumberOfPartitionedDataSets(); ++i)
  {
    if (inPdc->HasMetaData(i))
    {
      outPdc->GetMetaData(i)->Copy(inPdc->GetMetaData(i));
    }
    vtkNew<vtkPartitionedDataSet> outChild;
    outPdc->SetPartitionedDataSet(i, outChild);
    const std::string error = AddPartitionedUnit(inPdc->GetPartitionedDataSet(i), outChild, units,
      where + " partitioned dataset " + std::to_string(i));
    if (!error.empty())
    {
      return error;
    }
  }
  return {};
}

// Walks a composite input in a fixed order (the same on every rank when the structure is),
// building the output tree and one unit per mesh.
std::string CollectTree(
  vtkDataObject* in, vtkDataObject* out, std::vector<Unit>& units, const std::string& where)
{
  if (auto* inMb = vtkMultiBlockDataSet::SafeDownCast(in))
  {
    return CollectMultiBlock(inMb, vtkMultiBlockDataSet::SafeDownCast(out), units, where);
  }
  if (auto* inPdc = vtkPartitionedDataSetCollection::SafeDownCast(in))
  {
    return CollectCollection(
      inPdc, vtkPartitionedDataSetCollection::SafeDownCast(out), units, where);
  }
  if (auto* inPds = vtkPartitionedDataSet::SafeDownCast(in))
  {
    return AddPartitionedUnit(inPds, vtkPartitionedDataSet::SafeDownCast(out), units, where);
  }
  return std::string("the input is a ") + (in ? in->GetClassName() : "null data object") +
    ": vtkAPCGraphPartition needs a vtkUnstructuredGrid or a multiblock / partitioned "
    "dataset (collection) of them";
}
} // namespace

//------------------------------------------------------------------------------
std::string CollectUnits(vtkDataObject* input, vtkDataObject* output, std::vector<Unit>& units)
{
  if (auto* ug = vtkUnstructuredGrid::SafeDownCast(input))
  {
    Unit unit;
    unit.Parts.push_back(ug);
    unit.Install = [output](const UGrids& pieces) { output->ShallowCopy(pieces[0]); };
    units.push_back(std::move(unit));
    return {};
  }
  // Composite inputs are walked; anything else only gets its error message from there.
  return CollectTree(input, output, units, "input");
}

//------------------------------------------------------------------------------
LocalCells KeptCells(const Unit& unit)
{
  LocalCells cells;
  for (vtkUnstructuredGrid* part : unit.Parts)
  {
    std::vector<vtkIdType> kept;
    const vtkIdType n = part->GetNumberOfCells();
    kept.reserve(static_cast<std::size_t>(n));
    vtkUnsignedCharArray* ghosts = part->GetCellGhostArray();
    for (vtkIdType c = 0; c < n; ++c)
    {
      if (!ghosts || !(ghosts->GetValue(c) & vtkDataSetAttributes::DUPLICATECELL))
      {
        kept.push_back(c);
      }
    }
    cells.Count += static_cast<vtkIdType>(kept.size());
    cells.Kept.push_back(std::move(kept));
  }
  return cells;
}

} // namespace partition
} // namespace apc
