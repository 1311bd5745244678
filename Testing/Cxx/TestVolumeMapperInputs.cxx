// Inputs a user meets that used to give a silently wrong picture, each held to
// the picture it must give: one component of a vector renders like a scalar array equal to
// that component (point and cell arrays); flat cells render like no cell at all; an infinite
// scalar like a NaN one (transparent); quadratic cells like the tetrahedra
// vtkDataSetTriangleFilter makes of them (what ParaView's Volume renders); a polyhedron like
// its tetrahedra and like the hexahedron it describes. What was skipped is said once per data
// change.

#include "apcTestGrids.h"
#include "apcTestImages.h"
#include "apcTestMessages.h"
#include "apcTestRender.h"

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkFloatArray.h"
#include "vtkScalarsToColors.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <string>
#include <utility>

namespace
{
using apctest::Frame;
using apctest::MessageLog;

const int kModes[] = { vtkAPCVolumeMapper::MBOIT, vtkAPCVolumeMapper::EXACT };

const char* ModeName(int mode)
{
  return mode == vtkAPCVolumeMapper::EXACT ? "EXACT" : "MBOIT";
}

// Colour and opacity both change over [0, 1], so that a wrong value shows.
apctest::TransferFunction RampTF()
{
  apctest::TransferFunction tf;
  tf.Colours = { { 0.0, 0.1, 0.2, 1.0 }, { 0.5, 0.9, 0.9, 0.9 }, { 1.0, 1.0, 0.2, 0.1 } };
  tf.Opacities = { { 0.0, 0.05 }, { 1.0, 0.8 } };
  return tf;
}

// Renders grid's array `name` (point or cell) with the mapper in `mode`; more settings in
// `extra`. Messages go to log.
Frame RenderArray(vtkDataSet* grid, const char* name, bool cellData, int mode, MessageLog* log,
  const std::function<void(vtkAPCVolumeMapper*)>& extra = {},
  const apctest::View& view = apctest::ObliqueView(64))
{
  return apctest::Render(
    grid,
    [&](vtkAPCVolumeMapper* m)
    {
      log->Watch(m);
      m->SetMode(mode);
      m->SetSampleDistance(0.02);
      if (cellData)
      {
        m->SetScalarModeToUseCellFieldData();
      }
      else
      {
        m->SetScalarModeToUsePointFieldData();
      }
      m->SelectScalarArray(name);
      if (extra)
      {
        extra(m);
      }
    },
    RampTF(), view);
}

vtkSmartPointer<vtkFloatArray> Array(const char* name, int components, vtkIdType tuples)
{
  auto a = vtkSmartPointer<vtkFloatArray>::New();
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(tuples);
  return a;
}

// A vector array `prefix`v (3 components) on points or cells, and scalar arrays equal to its
// components (`prefix`vx, vy, vz) and to its magnitude (`prefix`vmag), computed as the mapper
// does (double from the float components, rounded to float).
void AddVectors(vtkDataSetAttributes* data, vtkIdType tuples,
  const std::function<std::array<double, 3>(vtkIdType)>& v, const std::string& prefix)
{
  auto vector = Array((prefix + "v").c_str(), 3, tuples);
  auto x = Array((prefix + "vx").c_str(), 1, tuples);
  auto y = Array((prefix + "vy").c_str(), 1, tuples);
  auto z = Array((prefix + "vz").c_str(), 1, tuples);
  auto magnitude = Array((prefix + "vmag").c_str(), 1, tuples);
  for (vtkIdType t = 0; t < tuples; ++t)
  {
    const std::array<double, 3> value = v(t);
    double sum = 0;
    for (int c = 0; c < 3; ++c)
    {
      const float f = static_cast<float>(value[c]);
      vector->SetTypedComponent(t, c, f);
      sum += static_cast<double>(f) * f;
    }
    x->SetValue(t, vector->GetTypedComponent(t, 0));
    y->SetValue(t, vector->GetTypedComponent(t, 1));
    z->SetValue(t, vector->GetTypedComponent(t, 2));
    magnitude->SetValue(t, static_cast<float>(std::sqrt(sum)));
  }
  for (vtkFloatArray* a : { vector.Get(), x.Get(), y.Get(), z.Get(), magnitude.Get() })
  {
    data->AddArray(a);
  }
}

vtkSmartPointer<vtkUnstructuredGrid> VectorBlock()
{
  auto grid = apctest::HexBlock(6, [](double, double, double) { return 0.0; });
  auto field = [](const double* p) -> std::array<double, 3> {
    return { 0.5 + 0.4 * p[0] * p[1], 0.5 + 0.3 * p[2], 0.2 - 0.1 * p[0] };
  };
  AddVectors(
    grid->GetPointData(), grid->GetNumberOfPoints(),
    [&](vtkIdType p) { return field(grid->GetPoint(p)); }, "");
  AddVectors(
    grid->GetCellData(), grid->GetNumberOfCells(),
    [&](vtkIdType c) { return field(apctest::CellCentre(grid, c).data()); }, "c");
  return grid;
}

// Sets the vector mode and component.
std::function<void(vtkAPCVolumeMapper*)> Vector(int mode, int component = 0)
{
  return [mode, component](vtkAPCVolumeMapper* m)
  {
    m->SetVectorMode(mode);
    m->SetVectorComponent(component);
  };
}
}

//------------------------------------------------------------------------------
TEST(VolumeMapperInputs, VectorComponentRendersThatComponent)
{
  auto grid = VectorBlock();
  for (bool cellData : { false, true })
  {
    const std::string p = cellData ? "c" : "";
    const char* where = cellData ? "cell array" : "point array";
    for (int mode : kModes)
    {
      vtkNew<MessageLog> log;
      const Frame x = RenderArray(
        grid, (p + "v").c_str(), cellData, mode, log, Vector(vtkScalarsToColors::COMPONENT, 0));
      const Frame y = RenderArray(
        grid, (p + "v").c_str(), cellData, mode, log, Vector(vtkScalarsToColors::COMPONENT, 1));
      const Frame magnitude = RenderArray(grid, (p + "v").c_str(), cellData, mode, log);
      const Frame scalarX = RenderArray(grid, (p + "vx").c_str(), cellData, mode, log);
      const Frame scalarY = RenderArray(grid, (p + "vy").c_str(), cellData, mode, log);
      const Frame scalarMagnitude = RenderArray(grid, (p + "vmag").c_str(), cellData, mode, log);
      const double dx = apctest::MaxAbsDiff(x.RGBA, scalarX.RGBA);
      const double dy = apctest::MaxAbsDiff(y.RGBA, scalarY.RGBA);
      const double dm = apctest::MaxAbsDiff(magnitude.RGBA, scalarMagnitude.RGBA);
      const double apart = apctest::MaxAbsDiff(x.RGBA, magnitude.RGBA);
      std::cout << where << ", " << ModeName(mode) << ": max |v X - vx| " << dx << ", |v Y - vy| "
                << dy << ", |v magnitude - vmag| " << dm << "; |v X - v magnitude| " << apart
                << ", max alpha " << apctest::MaxChannel(x.RGBA, 4, 3) << "\n";
      EXPECT_LE(dx, 1e-6) << where << " " << ModeName(mode);
      EXPECT_LE(dy, 1e-6) << where << " " << ModeName(mode);
      EXPECT_LE(dm, 1e-6) << where << " " << ModeName(mode);
      EXPECT_GT(apart, 0.05) << where << " " << ModeName(mode) << ": X must not be the magnitude";
      EXPECT_GT(apctest::MaxChannel(x.RGBA, 4, 3), 0.3) << where;
      EXPECT_TRUE(log->Errors.empty() && log->Warnings.empty()) << log->All();
    }
  }
}

TEST(VolumeMapperInputs, VectorModeEdges)
{
  auto grid = VectorBlock();
  const int mode = vtkAPCVolumeMapper::MBOIT;
  // RGBCOLORS (direct colours) cannot be volume rendered: the magnitude, with a warning.
  {
    vtkNew<MessageLog> log;
    const Frame rgb =
      RenderArray(grid, "v", false, mode, log, Vector(vtkScalarsToColors::RGBCOLORS));
    vtkNew<MessageLog> quiet;
    const Frame magnitude = RenderArray(grid, "vmag", false, mode, quiet);
    std::cout << "RGBCOLORS: " << log->All() << "\n";
    EXPECT_LE(apctest::MaxAbsDiff(rgb.RGBA, magnitude.RGBA), 1e-6);
    EXPECT_EQ(MessageLog::Count(log->Warnings, "RGBCOLORS"), 1) << log->All();
  }
  // A component that does not exist: the last one, with a warning (VTK's lookup tables clamp).
  {
    vtkNew<MessageLog> log;
    const Frame seven =
      RenderArray(grid, "v", false, mode, log, Vector(vtkScalarsToColors::COMPONENT, 7));
    vtkNew<MessageLog> quiet;
    const Frame z = RenderArray(grid, "vz", false, mode, quiet);
    std::cout << "component 7 of 3: " << log->All() << "\n";
    EXPECT_LE(apctest::MaxAbsDiff(seven.RGBA, z.RGBA), 1e-6);
    EXPECT_EQ(MessageLog::Count(log->Warnings, "does not exist"), 1) << log->All();
  }
  // A single-component array renders its value in every mode.
  {
    vtkNew<MessageLog> log;
    const Frame component =
      RenderArray(grid, "vy", false, mode, log, Vector(vtkScalarsToColors::COMPONENT, 2));
    const Frame plain = RenderArray(grid, "vy", false, mode, log);
    EXPECT_EQ(apctest::MaxAbsDiff(component.RGBA, plain.RGBA), 0.0);
    EXPECT_TRUE(log->Warnings.empty()) << log->All();
  }
  // Switching the component of a live mapper rebuilds its copy of the data.
  {
    apctest::LiveWindow live(RampTF(), apctest::ObliqueView(64));
    live.Mapper->SetInputData(grid);
    live.Mapper->SetScalarModeToUsePointFieldData();
    live.Mapper->SelectScalarArray("v");
    live.Mapper->SetSampleDistance(0.02);
    Vector(vtkScalarsToColors::COMPONENT, 0)(live.Mapper);
    const Frame x = live.Render();
    Vector(vtkScalarsToColors::COMPONENT, 1)(live.Mapper);
    const Frame y = live.Render();
    vtkNew<MessageLog> quiet;
    EXPECT_LE(apctest::MaxAbsDiff(x.RGBA, RenderArray(grid, "vx", false, mode, quiet).RGBA), 1e-6);
    EXPECT_LE(apctest::MaxAbsDiff(y.RGBA, RenderArray(grid, "vy", false, mode, quiet).RGBA), 1e-6);
  }
}

//------------------------------------------------------------------------------
namespace
{
// One hexahedron on [-1,1]^3, and the same with flat cells of every shape lying on its bottom
// face (z = -1): a tetrahedron over its four corners (the case), a pyramid with its
// apex in that plane, a wedge whose top triangle lies on its bottom one (other points), a
// hexahedron over the face's corners and four points inside it.
std::pair<vtkSmartPointer<vtkUnstructuredGrid>, vtkSmartPointer<vtkUnstructuredGrid>> HexAndFlat()
{
  auto f = [](double x, double y, double z) { return 0.5 + 0.3 * x * y - 0.2 * z; };
  auto hex = apctest::HexBlock(1, f);
  auto flat = apctest::HexBlock(1, f);
  auto* points = flat->GetPoints();
  auto* s = vtkFloatArray::SafeDownCast(flat->GetPointData()->GetScalars());
  auto add = [&](double x, double y)
  {
    s->InsertNextValue(static_cast<float>(f(x, y, -1)));
    return points->InsertNextPoint(x, y, -1);
  };
  const vtkIdType tetra[4] = { 0, 1, 2, 3 };
  flat->InsertNextCell(VTK_TETRA, 4, tetra);
  const vtkIdType pyramid[5] = { 0, 1, 2, 3, add(0.2, 0.1) };
  flat->InsertNextCell(VTK_PYRAMID, 5, pyramid);
  const vtkIdType wedge[6] = { 0, 1, 3, add(-0.5, -0.4), add(0.3, -0.6), add(-0.6, 0.2) };
  flat->InsertNextCell(VTK_WEDGE, 6, wedge);
  const vtkIdType hexahedron[8] = { 0, 1, 2, 3, add(-0.5, -0.5), add(0.5, -0.5), add(0.5, 0.5),
    add(-0.5, 0.5) };
  flat->InsertNextCell(VTK_HEXAHEDRON, 8, hexahedron);
  return { hex, flat };
}
}

TEST(VolumeMapperInputs, FlatCellsRenderLikeNoCell)
{
  const auto grids = HexAndFlat();
  apctest::View below = apctest::ObliqueView(64);
  below.Position = { 2.5, -3.0, -4.0 };
  for (const apctest::View& view : { apctest::ObliqueView(64), below })
  {
    for (int mode : kModes)
    {
      vtkNew<MessageLog> log;
      const Frame withFlat = RenderArray(grids.second, "f", false, mode, log, {}, view);
      vtkNew<MessageLog> quiet;
      const Frame alone = RenderArray(grids.first, "f", false, mode, quiet, {}, view);
      const double diff = apctest::MaxAbsDiff(withFlat.RGBA, alone.RGBA);
      std::cout << ModeName(mode) << ", eye at z = " << view.Position[2]
                << ": max |hexahedron + 4 flat cells - hexahedron| = " << diff << ", max alpha "
                << apctest::MaxChannel(alone.RGBA, 4, 3) << "; " << log->All() << "\n";
      EXPECT_LE(diff, 1e-6) << ModeName(mode);
      EXPECT_GT(apctest::MaxChannel(alone.RGBA, 4, 3), 0.3);
      EXPECT_EQ(log->Warnings.size(), 1u) << log->All();
      EXPECT_EQ(MessageLog::Count(log->Warnings, "4 cells with no volume"), 1) << log->All();
      EXPECT_TRUE(log->Errors.empty()) << log->All();
    }
  }
}

TEST(VolumeMapperInputs, SaidOncePerDataChange)
{
  const auto grids = HexAndFlat();
  apctest::LiveWindow live(RampTF(), apctest::ObliqueView(32));
  vtkNew<MessageLog> log;
  log->Watch(live.Mapper);
  live.Mapper->SetInputData(grids.second);
  live.Render();
  EXPECT_EQ(log->Warnings.size(), 1u) << log->All();
  live.Render();
  live.Render();
  EXPECT_EQ(log->Warnings.size(), 1u) << "no data change, nothing new to say: " << log->All();
  grids.second->Modified();
  live.Render();
  EXPECT_EQ(log->Warnings.size(), 2u) << "the data changed: " << log->All();
  live.Mapper->SetInputData(grids.first);
  live.Render();
  EXPECT_EQ(log->Warnings.size(), 2u) << "nothing to say about the hexahedron: " << log->All();
}

//------------------------------------------------------------------------------
TEST(VolumeMapperInputs, InfiniteScalarsAreTransparentLikeNaN)
{
  auto f = [](double x, double y, double z) { return 0.5 + 0.3 * x - 0.2 * y * z; };
  const float inf = std::numeric_limits<float>::infinity();
  auto with = [&](float bad)
  {
    auto grid = apctest::HexBlock(6, f);
    auto* s = vtkFloatArray::SafeDownCast(grid->GetPointData()->GetScalars());
    for (vtkIdType p = 0; p < s->GetNumberOfTuples(); p += 29)
    {
      s->SetValue(p, bad);
    }
    // Cell scalars with the same bad cells.
    auto cells = Array("g", 1, grid->GetNumberOfCells());
    for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
    {
      const auto centre = apctest::CellCentre(grid, c);
      cells->SetValue(c, c % 7 == 3 ? bad : static_cast<float>(f(centre[0], centre[1], centre[2])));
    }
    grid->GetCellData()->AddArray(cells);
    return grid;
  };
  auto nanGrid = with(std::nanf(""));
  auto plus = with(inf);
  auto minus = with(-inf);
  auto full = apctest::HexBlock(6, f);
  for (bool cellData : { false, true })
  {
    const char* name = cellData ? "g" : "f";
    for (int mode : kModes)
    {
      vtkNew<MessageLog> nanLog;
      const Frame nan = RenderArray(nanGrid, name, cellData, mode, nanLog);
      vtkNew<MessageLog> plusLog;
      const Frame p = RenderArray(plus, name, cellData, mode, plusLog);
      vtkNew<MessageLog> minusLog;
      const Frame m = RenderArray(minus, name, cellData, mode, minusLog);
      double lost = 0;
      if (!cellData)
      {
        vtkNew<MessageLog> quiet;
        const Frame reference = RenderArray(full, name, false, mode, quiet);
        for (size_t i = 3; i < reference.RGBA.size(); i += 4)
        {
          lost = std::max(lost, static_cast<double>(reference.RGBA[i] - nan.RGBA[i]));
        }
      }
      const double dp = apctest::MaxAbsDiff(p.RGBA, nan.RGBA);
      const double dm = apctest::MaxAbsDiff(m.RGBA, nan.RGBA);
      std::cout << (cellData ? "cell" : "point") << " scalars, " << ModeName(mode)
                << ": max |+inf - NaN| " << dp << ", |-inf - NaN| " << dm << ", alpha lost to NaN "
                << lost << "; " << plusLog->All() << "\n";
      EXPECT_EQ(dp, 0.0) << ModeName(mode);
      EXPECT_EQ(dm, 0.0) << ModeName(mode);
      if (!cellData)
      {
        EXPECT_GT(lost, 0.01) << "the bad cells must be visibly transparent";
      }
      EXPECT_GT(apctest::MaxChannel(p.RGBA, 4, 3), 0.3);
      for (MessageLog* log : { nanLog.Get(), plusLog.Get(), minusLog.Get() })
      {
        EXPECT_EQ(MessageLog::Count(log->Warnings, "NaN or infinite scalar are transparent"), 1)
          << log->All();
      }
    }
  }
}

//------------------------------------------------------------------------------
namespace
{
// The grid's linear cells made quadratic: a midside node on every edge (shared between the
// cells that share the edge) whose scalar is q at that point, not the mean of the corners.
vtkSmartPointer<vtkUnstructuredGrid> Quadratic(
  vtkUnstructuredGrid* linear, const std::function<double(double, double, double)>& q)
{
  static const int tetEdges[6][2] = { { 0, 1 }, { 1, 2 }, { 2, 0 }, { 0, 3 }, { 1, 3 }, { 2, 3 } };
  static const int hexEdges[12][2] = { { 0, 1 }, { 1, 2 }, { 2, 3 }, { 3, 0 }, { 4, 5 }, { 5, 6 },
    { 6, 7 }, { 7, 4 }, { 0, 4 }, { 1, 5 }, { 2, 6 }, { 3, 7 } };
  vtkNew<vtkPoints> points;
  points->DeepCopy(linear->GetPoints());
  vtkNew<vtkFloatArray> s;
  s->SetName("f");
  for (vtkIdType p = 0; p < points->GetNumberOfPoints(); ++p)
  {
    const double* x = points->GetPoint(p);
    s->InsertNextValue(static_cast<float>(q(x[0], x[1], x[2])));
  }
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->SetPoints(points);
  grid->GetPointData()->SetScalars(s);
  std::map<std::pair<vtkIdType, vtkIdType>, vtkIdType> midpoints;
  for (vtkIdType c = 0; c < linear->GetNumberOfCells(); ++c)
  {
    vtkIdType n;
    const vtkIdType* ids;
    linear->GetCellPoints(c, n, ids);
    const bool tet = linear->GetCellType(c) == VTK_TETRA;
    const int edges = tet ? 6 : 12;
    std::vector<vtkIdType> quadratic(ids, ids + n);
    for (int e = 0; e < edges; ++e)
    {
      const vtkIdType a = ids[tet ? tetEdges[e][0] : hexEdges[e][0]];
      const vtkIdType b = ids[tet ? tetEdges[e][1] : hexEdges[e][1]];
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = midpoints.find(key);
      if (it == midpoints.end())
      {
        double pa[3];
        double pb[3];
        points->GetPoint(a, pa);
        points->GetPoint(b, pb);
        const double m[3] = { 0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1]), 0.5 * (pa[2] + pb[2]) };
        it = midpoints.emplace(key, points->InsertNextPoint(m)).first;
        s->InsertNextValue(static_cast<float>(q(m[0], m[1], m[2])));
      }
      quadratic.push_back(it->second);
    }
    grid->InsertNextCell(tet ? VTK_QUADRATIC_TETRA : VTK_QUADRATIC_HEXAHEDRON,
      static_cast<vtkIdType>(quadratic.size()), quadratic.data());
  }
  return grid;
}

// Every hexahedron of grid written as a VTK_POLYHEDRON with its six faces.
vtkSmartPointer<vtkUnstructuredGrid> AsPolyhedra(vtkUnstructuredGrid* hexahedra)
{
  static const int faces[6][4] = { { 0, 4, 7, 3 }, { 1, 2, 6, 5 }, { 0, 1, 5, 4 }, { 3, 7, 6, 2 },
    { 0, 3, 2, 1 }, { 4, 5, 6, 7 } };
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->SetPoints(hexahedra->GetPoints());
  grid->GetPointData()->ShallowCopy(hexahedra->GetPointData());
  for (vtkIdType c = 0; c < hexahedra->GetNumberOfCells(); ++c)
  {
    vtkIdType n;
    const vtkIdType* ids;
    hexahedra->GetCellPoints(c, n, ids);
    std::vector<vtkIdType> stream;
    for (const auto& face : faces)
    {
      stream.push_back(4);
      for (int i : face)
      {
        stream.push_back(ids[i]);
      }
    }
    grid->InsertNextCell(VTK_POLYHEDRON, n, ids, 6, stream.data());
  }
  return grid;
}
}

TEST(VolumeMapperInputs, QuadraticCellsRenderLikeTheirTetrahedra)
{
  auto q = [](double x, double y, double z) { return 0.45 + 0.5 * x * x - 0.3 * y * z + 0.1 * z; };
  auto linearHex = apctest::HexBlock(2, q);
  auto linearTets = apctest::Tetrahedralized(linearHex);
  for (auto* linear : { linearTets.Get(), linearHex.Get() })
  {
    auto quadratic = Quadratic(linear, q);
    // What ParaView's Volume renders of it.
    auto reference = apctest::Tetrahedralized(quadratic);
    const char* what = linear == linearHex.Get() ? "quadratic hexahedra" : "quadratic tetrahedra";
    for (int mode : kModes)
    {
      vtkNew<MessageLog> log;
      const Frame frame = RenderArray(quadratic, "f", false, mode, log);
      vtkNew<MessageLog> referenceLog;
      const Frame expected = RenderArray(reference, "f", false, mode, referenceLog);
      vtkNew<MessageLog> linearLog;
      const Frame corners = RenderArray(linear, "f", false, mode, linearLog);
      const double diff = apctest::MaxAbsDiff(frame.RGBA, expected.RGBA);
      const double midside = apctest::MaxAbsDiff(frame.RGBA, corners.RGBA);
      std::cout << what << " (" << quadratic->GetNumberOfCells() << " cells, "
                << reference->GetNumberOfCells() << " tetrahedra), " << ModeName(mode)
                << ": max |APC - APC of vtkDataSetTriangleFilter| " << diff
                << ", |quadratic - corners only| " << midside << "; " << log->All() << "\n";
      EXPECT_LE(diff, 1e-6) << what << " " << ModeName(mode);
      EXPECT_GT(midside, 0.01) << what << ": the midside nodes must count";
      EXPECT_GT(apctest::MaxChannel(frame.RGBA, 4, 3), 0.3) << what;
      EXPECT_TRUE(log->Errors.empty() && log->Warnings.empty()) << log->All();
    }
  }
}

TEST(VolumeMapperInputs, PolyhedraRenderLikeTheirTetrahedra)
{
  // A linear field: hexahedra and any tetrahedra of them interpolate it the same. On the
  // plain lattice: Sample End Weights = Boundary's middle samples in boundary cells with no
  // lattice point depend on how the block is cut into cells (docs/sampler.md).
  const auto plain = [](vtkAPCVolumeMapper* m)
  { m->SetSampleEndWeights(vtkAPCVolumeMapper::END_WEIGHTS_OFF); };
  auto f = [](double x, double y, double z) { return 0.5 + 0.3 * x - 0.2 * y + 0.1 * z; };
  auto hexahedra = apctest::HexBlock(2, f);
  auto polyhedra = AsPolyhedra(hexahedra);
  auto tetrahedra = apctest::Tetrahedralized(polyhedra);
  ASSERT_GT(tetrahedra->GetNumberOfCells(), 8 * 5 - 1);
  for (int mode : kModes)
  {
    vtkNew<MessageLog> log;
    const Frame frame = RenderArray(polyhedra, "f", false, mode, log, plain);
    vtkNew<MessageLog> quiet;
    const Frame tets = RenderArray(tetrahedra, "f", false, mode, quiet, plain);
    const Frame hexes = RenderArray(hexahedra, "f", false, mode, quiet, plain);
    const double diffTets = apctest::MaxAbsDiff(frame.RGBA, tets.RGBA);
    const double diffHexes = apctest::MaxAbsDiff(frame.RGBA, hexes.RGBA);
    std::cout << "8 hexahedra as polyhedra (" << tetrahedra->GetNumberOfCells() << " tetrahedra), "
              << ModeName(mode) << ": max |APC - APC of vtkDataSetTriangleFilter| " << diffTets
              << ", |APC - the hexahedra| " << diffHexes << "; " << log->All() << "\n";
    EXPECT_LE(diffTets, 1e-6) << ModeName(mode);
    // Tetrahedra and hexahedra clip a ray with different planes (two triangles for a quad)
    // and interpolate in different ways: equal to float rounding of the sample positions.
    EXPECT_LE(diffHexes, 1e-4) << ModeName(mode);
    EXPECT_GT(apctest::MaxChannel(frame.RGBA, 4, 3), 0.3);
    EXPECT_TRUE(log->Errors.empty() && log->Warnings.empty()) << log->All();
  }
}
