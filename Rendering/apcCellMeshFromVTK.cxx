// SPDX-License-Identifier: BSD-3-Clause
#include "apcCellMeshFromVTK.h"

#include "apcCellMesh.h"

#include "vtkCellType.h"
#include "vtkCellTypes.h"
#include "vtkDataArray.h"
#include "vtkDataSetAttributes.h"
#include "vtkIdList.h"
#include "vtkNew.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGridBase.h"

#include <cmath>
#include <map>
#include <sstream>

namespace apc
{
namespace
{
bool ShapeOf(int vtkType, CellShape& shape)
{
  switch (vtkType)
  {
    case VTK_TETRA:
      shape = CellShape::Tetra;
      return true;
    case VTK_PYRAMID:
      shape = CellShape::Pyramid;
      return true;
    case VTK_WEDGE:
      shape = CellShape::Wedge;
      return true;
    case VTK_HEXAHEDRON:
    case VTK_VOXEL:
      shape = CellShape::Hexahedron;
      return true;
    default:
      return false;
  }
}

double ScalarValue(vtkDataArray* array, vtkIdType tuple)
{
  const int components = array->GetNumberOfComponents();
  if (components == 1)
  {
    return array->GetComponent(tuple, 0);
  }
  // Multi-component arrays render their magnitude, ParaView's default for vectors.
  double sum = 0;
  for (int c = 0; c < components; ++c)
  {
    const double v = array->GetComponent(tuple, c);
    sum += v * v;
  }
  return std::sqrt(sum);
}
}

bool CellMeshFromVTK(vtkUnstructuredGridBase* input, vtkDataArray* scalars, bool cellData,
  CellMesh& mesh, std::string& message)
{
  mesh = CellMesh();
  message.clear();
  if (!input || !scalars)
  {
    message = "no input grid or no scalars";
    return false;
  }
  const vtkIdType numPoints = input->GetNumberOfPoints();
  mesh.Points.resize(numPoints);
  for (vtkIdType p = 0; p < numPoints; ++p)
  {
    input->GetPoint(p, mesh.Points[p].data());
  }
  if (!cellData)
  {
    mesh.PointScalars.resize(numPoints);
    for (vtkIdType p = 0; p < numPoints; ++p)
    {
      mesh.PointScalars[p] = static_cast<float>(ScalarValue(scalars, p));
    }
  }

  vtkUnsignedCharArray* ghosts = input->GetCellGhostArray();
  const unsigned char skipMask =
    vtkDataSetAttributes::DUPLICATECELL | vtkDataSetAttributes::HIDDENCELL;
  std::map<int, vtkIdType> unsupported;
  vtkNew<vtkIdList> cellPoints;
  const vtkIdType numCells = input->GetNumberOfCells();
  for (vtkIdType c = 0; c < numCells; ++c)
  {
    if (ghosts && (ghosts->GetValue(c) & skipMask))
    {
      continue;
    }
    const int type = input->GetCellType(c);
    CellShape shape;
    if (!ShapeOf(type, shape))
    {
      ++unsupported[type];
      continue;
    }
    input->GetCellPoints(c, cellPoints);
    const vtkIdType* ids = cellPoints->GetPointer(0);
    int64_t corners[8];
    for (int i = 0; i < NumberOfCorners(shape); ++i)
    {
      corners[i] = type == VTK_VOXEL ? ids[kVoxelToHexahedron[i]] : ids[i];
    }
    mesh.AddCell(shape, corners);
    if (cellData)
    {
      mesh.CellScalars.push_back(static_cast<float>(ScalarValue(scalars, c)));
    }
  }
  if (!unsupported.empty())
  {
    std::ostringstream text;
    text << "Skipped cells of types the APC ray marcher does not support (it renders "
            "tetrahedra, pyramids, wedges, hexahedra and voxels; decompose polyhedra and "
            "quadratic cells first, e.g. with the OpenFOAM reader's 'Decompose polyhedra'):";
    for (const auto& entry : unsupported)
    {
      text << ' ' << entry.second << " x " << vtkCellTypes::GetClassNameFromTypeId(entry.first);
    }
    message = text.str();
  }
  std::string error;
  const bool usable = mesh.Finalize(&error);
  if (usable && mesh.GetNumberOfSkippedCells() > 0)
  {
    message += (message.empty() ? "" : "; ") + std::to_string(mesh.GetNumberOfSkippedCells()) +
      " cells with non-finite or collapsed corners skipped";
  }
  if (!usable)
  {
    message += (message.empty() ? "" : "; ") + std::string("unusable mesh: ") + error;
    return false;
  }
  return true;
}
}
