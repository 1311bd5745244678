// Grid builders and comparisons shared by the invariance, error and thread tests of
// vtkAPCVolumeMapper: a mixed-cell block, shuffled copies, cell subsets that keep or renumber
// the points, and the puzzle source's output.
#ifndef apcTestGrids_h
#define apcTestGrids_h

#include "apcTestScenes.h"

#include "apcCellMesh.h"
#include "apcCellMeshFromVTK.h"
#include "apcRayCamera.h"
#include "vtkAPCPuzzleSource.h"
#include "vtkCellData.h"
#include "vtkDataSetAttributes.h"
#include "vtkExtractCells.h"
#include "vtkIdList.h"
#include "vtkPointData.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace apctest
{

// The puzzle source's whole output (all puzzle pieces in one grid).
inline vtkSmartPointer<vtkUnstructuredGrid> PuzzleGrid(
  int field, int pieces, int slabs, int resolution, int axis = 2)
{
  vtkNew<vtkAPCPuzzleSource> source;
  source->SetField(field);
  source->SetNumberOfPuzzlePieces(pieces);
  source->SetSlabsPerPiece(slabs);
  source->SetResolution(resolution);
  source->SetAxis(axis);
  source->Update();
  return source->GetOutput();
}

// One puzzle piece as a rank would generate it: the source's pipeline piece request.
inline vtkSmartPointer<vtkUnstructuredGrid> PuzzlePiece(
  int field, int pieces, int slabs, int resolution, int piece, int axis = 2)
{
  vtkNew<vtkAPCPuzzleSource> source;
  source->SetField(field);
  source->SetNumberOfPuzzlePieces(pieces);
  source->SetSlabsPerPiece(slabs);
  source->SetResolution(resolution);
  source->SetAxis(axis);
  source->UpdatePiece(piece, pieces, 0);
  return source->GetOutput();
}

// An n x n x n block on [-1,1]^3 whose lattice cells are, in turn, a hexahedron, two wedges,
// six tetrahedra (around the main diagonal) or six pyramids around an extra centre point.
// Point scalars f(x, y, z). With n a power of two every coordinate is a binary fraction, so
// the face planes of neighbouring cells of different types (a quad next to two triangles)
// come out identical and no lattice sample is counted twice or lost at those interfaces.
inline vtkSmartPointer<vtkUnstructuredGrid> MixedBlock(
  int n, const std::function<double(double, double, double)>& f)
{
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  vtkNew<vtkFloatArray> scalars;
  scalars->SetName("f");
  auto add = [&](double x, double y, double z)
  {
    scalars->InsertNextValue(static_cast<float>(f(x, y, z)));
    return points->InsertNextPoint(x, y, z);
  };
  for (int k = 0; k <= n; ++k)
  {
    for (int j = 0; j <= n; ++j)
    {
      for (int i = 0; i <= n; ++i)
      {
        add(-1 + 2.0 * i / n, -1 + 2.0 * j / n, -1 + 2.0 * k / n);
      }
    }
  }
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->SetPoints(points);
  grid->GetPointData()->SetScalars(scalars);
  auto id = [n](int i, int j, int k)
  { return static_cast<vtkIdType>((k * (n + 1) + j) * (n + 1) + i); };
  for (int k = 0; k < n; ++k)
  {
    for (int j = 0; j < n; ++j)
    {
      for (int i = 0; i < n; ++i)
      {
        const vtkIdType h[8] = { id(i, j, k), id(i + 1, j, k), id(i + 1, j + 1, k), id(i, j + 1, k),
          id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1) };
        switch ((i + 2 * j + 3 * k) % 4)
        {
          case 0:
            grid->InsertNextCell(VTK_HEXAHEDRON, 8, h);
            break;
          case 1:
          {
            // VTK's wedge: the normal of (0,1,2) points away from (3,4,5).
            const vtkIdType w0[6] = { h[0], h[2], h[1], h[4], h[6], h[5] };
            const vtkIdType w1[6] = { h[0], h[3], h[2], h[4], h[7], h[6] };
            grid->InsertNextCell(VTK_WEDGE, 6, w0);
            grid->InsertNextCell(VTK_WEDGE, 6, w1);
            break;
          }
          case 2:
          {
            const int tets[6][4] = { { 0, 1, 2, 6 }, { 0, 2, 3, 6 }, { 0, 3, 7, 6 }, { 0, 7, 4, 6 },
              { 0, 4, 5, 6 }, { 0, 5, 1, 6 } };
            for (const auto& t : tets)
            {
              const vtkIdType tet[4] = { h[t[0]], h[t[1]], h[t[2]], h[t[3]] };
              grid->InsertNextCell(VTK_TETRA, 4, tet);
            }
            break;
          }
          default:
          {
            double a[3];
            double b[3];
            points->GetPoint(h[0], a);
            points->GetPoint(h[6], b);
            const vtkIdType centre =
              add(0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2]));
            // Bases ordered so that their normals point at the centre (VTK's pyramid).
            const int faces[6][4] = { { 0, 1, 2, 3 }, { 4, 7, 6, 5 }, { 0, 4, 5, 1 },
              { 3, 2, 6, 7 }, { 0, 3, 7, 4 }, { 1, 5, 6, 2 } };
            for (const auto& q : faces)
            {
              const vtkIdType pyramid[5] = { h[q[0]], h[q[1]], h[q[2]], h[q[3]], centre };
              grid->InsertNextCell(VTK_PYRAMID, 5, pyramid);
            }
          }
        }
      }
    }
  }
  return grid;
}

// A copy of grid with the cells in random order and the points renumbered at random (same
// coordinates, scalars and cell data; each cell keeps its corner order).
inline vtkSmartPointer<vtkUnstructuredGrid> Shuffled(vtkUnstructuredGrid* grid, unsigned seed)
{
  std::mt19937 random(seed);
  const vtkIdType numPoints = grid->GetNumberOfPoints();
  const vtkIdType numCells = grid->GetNumberOfCells();
  std::vector<vtkIdType> newId(numPoints);
  std::iota(newId.begin(), newId.end(), 0);
  std::shuffle(newId.begin(), newId.end(), random);
  std::vector<vtkIdType> cellOrder(numCells);
  std::iota(cellOrder.begin(), cellOrder.end(), 0);
  std::shuffle(cellOrder.begin(), cellOrder.end(), random);

  auto out = vtkSmartPointer<vtkUnstructuredGrid>::New();
  vtkNew<vtkPoints> points;
  points->SetDataType(grid->GetPoints()->GetDataType());
  points->SetNumberOfPoints(numPoints);
  out->GetPointData()->CopyAllocate(grid->GetPointData(), numPoints);
  for (vtkIdType p = 0; p < numPoints; ++p)
  {
    points->SetPoint(newId[p], grid->GetPoint(p));
    out->GetPointData()->CopyData(grid->GetPointData(), p, newId[p]);
  }
  out->SetPoints(points);
  out->GetCellData()->CopyAllocate(grid->GetCellData(), numCells);
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < numCells; ++c)
  {
    const vtkIdType old = cellOrder[c];
    grid->GetCellPoints(old, ids);
    for (vtkIdType i = 0; i < ids->GetNumberOfIds(); ++i)
    {
      ids->SetId(i, newId[ids->GetId(i)]);
    }
    const vtkIdType cell = out->InsertNextCell(grid->GetCellType(old), ids);
    out->GetCellData()->CopyData(grid->GetCellData(), old, cell);
  }
  return out;
}

// The cells of grid for which keep(cell) holds, in their order, on the very same points
// (shared vtkPoints and point data, so every face plane is computed from the same ids).
inline vtkSmartPointer<vtkUnstructuredGrid> CellSubset(
  vtkUnstructuredGrid* grid, const std::function<bool(vtkIdType)>& keep)
{
  auto out = vtkSmartPointer<vtkUnstructuredGrid>::New();
  out->SetPoints(grid->GetPoints());
  out->GetPointData()->ShallowCopy(grid->GetPointData());
  out->GetCellData()->CopyAllocate(grid->GetCellData());
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    if (keep(c))
    {
      grid->GetCellPoints(c, ids);
      const vtkIdType cell = out->InsertNextCell(grid->GetCellType(c), ids);
      out->GetCellData()->CopyData(grid->GetCellData(), c, cell);
    }
  }
  return out;
}

// Centre of a cell's bounding box.
inline std::array<double, 3> CellCentre(vtkUnstructuredGrid* grid, vtkIdType cell)
{
  double b[6];
  grid->GetCellBounds(cell, b);
  return { 0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]), 0.5 * (b[4] + b[5]) };
}

// A render window, renderer, volume and mapper that stay alive between renders (for tests
// that render the same mapper several times or change its input in between).
struct Scene
{
  vtkNew<vtkRenderWindow> Window;
  vtkNew<vtkRenderer> Renderer;
  vtkNew<vtkAPCVolumeMapper> Mapper;
  vtkNew<vtkColorTransferFunction> Colour;
  vtkNew<vtkPiecewiseFunction> Opacity;
  vtkNew<vtkVolumeProperty> Property;
  vtkNew<vtkVolume> Volume;
  View Camera;

  explicit Scene(const TransferFunction& tf = {}, const View& view = {})
    : Camera(view)
  {
    this->Window->SetOffScreenRendering(1);
    this->Window->SetSize(view.Width, view.Height);
    this->Window->SetMultiSamples(0);
    this->Renderer->SetBackground(0, 0, 0);
    this->Window->AddRenderer(this->Renderer);
    for (const auto& c : tf.Colours)
    {
      this->Colour->AddRGBPoint(c[0], c[1], c[2], c[3]);
    }
    for (const auto& o : tf.Opacities)
    {
      this->Opacity->AddPoint(o[0], o[1]);
    }
    this->Property->SetColor(this->Colour);
    this->Property->SetScalarOpacity(this->Opacity);
    this->Property->SetScalarOpacityUnitDistance(tf.UnitDistance);
    this->Volume->SetMapper(this->Mapper);
    this->Volume->SetProperty(this->Property);
    this->Renderer->AddVolume(this->Volume);
    vtkCamera* camera = this->Renderer->GetActiveCamera();
    camera->SetPosition(view.Position.data());
    camera->SetFocalPoint(view.FocalPoint.data());
    camera->SetViewUp(view.ViewUp.data());
    camera->SetParallelProjection(view.Parallel);
    camera->SetParallelScale(view.ParallelScale);
    camera->SetViewAngle(view.ViewAngle);
    this->Renderer->ResetCameraClippingRange(-2, 2, -2, 2, -2, 2);
  }

  // Renders and returns the mapper's float images (RGBA, Moments, ColourSums, SegmentCount).
  Frame Render()
  {
    this->Window->Render();
    Frame frame;
    frame.Width = this->Camera.Width;
    frame.Height = this->Camera.Height;
    frame.SampleDistance = this->Mapper->GetLastSampleDistance();
    vtkImageData* image = this->Mapper->GetLastImage();
    auto copy = [image](const char* name, auto& out)
    {
      vtkDataArray* array = image->GetPointData()->GetArray(name);
      if (!array)
      {
        return;
      }
      const int nc = array->GetNumberOfComponents();
      const vtkIdType n = array->GetNumberOfTuples() * nc;
      out.resize(n);
      for (vtkIdType v = 0; v < n; ++v)
      {
        out[v] = static_cast<typename std::decay_t<decltype(out)>::value_type>(
          array->GetComponent(v / nc, v % nc));
      }
    };
    copy("RGBA", frame.RGBA);
    copy("Moments", frame.Moments);
    copy("ColourSums", frame.ColourSums);
    copy("SegmentCount", frame.SegmentCount);
    vtkNew<vtkUnsignedCharArray> pixels;
    this->Window->GetPixelData(0, 0, frame.Width - 1, frame.Height - 1, 0, pixels);
    frame.Window.assign(
      pixels->GetPointer(0), pixels->GetPointer(0) + 3 * frame.Width * frame.Height);
    return frame;
  }
};

// A well-mixed 32-bit hash of a cell id (splitmix64's finaliser).
inline uint32_t CellHash(vtkIdType cell)
{
  uint64_t x = static_cast<uint64_t>(cell) + 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return static_cast<uint32_t>(x ^ (x >> 31));
}

// max |a - b| over two equally long float images; +inf if the sizes differ.
template <class T>
double MaxAbsDiff(const std::vector<T>& a, const std::vector<T>& b)
{
  if (a.size() != b.size())
  {
    return std::numeric_limits<double>::infinity();
  }
  double d = 0;
  for (size_t v = 0; v < a.size(); ++v)
  {
    const double e = std::abs(static_cast<double>(a[v]) - static_cast<double>(b[v]));
    d = std::max(d, e == e ? e : std::numeric_limits<double>::infinity());
  }
  return d;
}

// Largest value of one channel of an interleaved image (e.g. alpha: channel 3 of 4).
inline double MaxChannel(const std::vector<float>& image, int channels, int channel)
{
  double m = 0;
  for (size_t v = channel; v < image.size(); v += channels)
  {
    m = std::max(m, static_cast<double>(image[v]));
  }
  return m;
}

// The grid cut into k pieces by cell: owner(c) in [0, k) picks cell c's piece. Each piece is
// extracted with vtkExtractCells, so it has its own, compacted point ids (as on a rank).
inline std::vector<vtkSmartPointer<vtkUnstructuredGrid>> SplitCells(
  vtkUnstructuredGrid* grid, int k, const std::function<int(vtkIdType)>& owner)
{
  std::vector<vtkNew<vtkIdList>> lists(k);
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    lists[owner(c)]->InsertNextId(c);
  }
  std::vector<vtkSmartPointer<vtkUnstructuredGrid>> pieces;
  for (int p = 0; p < k; ++p)
  {
    vtkNew<vtkExtractCells> extract;
    extract->SetInputData(grid);
    extract->SetCellList(lists[p]);
    extract->Update();
    pieces.push_back(extract->GetOutput());
  }
  return pieces;
}

// The ray marcher's copy of a grid with point scalars (a test failure if unusable).
inline apc::CellMesh ToMesh(vtkUnstructuredGrid* grid)
{
  apc::CellMesh mesh;
  std::string message;
  const bool ok =
    apc::CellMeshFromVTK(grid, grid->GetPointData()->GetScalars(), false, mesh, message);
  EXPECT_TRUE(ok) << message;
  EXPECT_TRUE(message.empty()) << message;
  return mesh;
}

// The core camera of ObliqueView (apcTestScenes.h), for tests that drive the ray marcher.
inline apc::RayCamera ObliqueCamera(int size)
{
  return apc::RayCamera(
    { 3.6, 2.5, 4.5 }, { 0, 0, 0 }, { 0, 1, 0 }, 35.0, false, 1.0, size, size, 0.1, 100.0);
}

} // namespace apctest

#endif
