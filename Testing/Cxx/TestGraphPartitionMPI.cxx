// SPDX-License-Identifier: BSD-3-Clause
// Run under mpirun -np N: vtkAPCGraphPartition on the real wind data (read as the .pvtu's
// pieces, distributed over the ranks) and on the flange made of polyhedra.
// - every cell ends up in exactly one piece, on the rank owning that piece, with its own
//   arrays (a per-cell id and centroid are carried and checked);
// - PartitionId covers 0..K-1 and the pieces are within METIS's balance (1.03 mean + 1);
// - label-only mode moves nothing and gives the same labels as the moving mode;
// - the dual graph through polyhedron faces equals the one through the linear cells' faces;
// - multiblock and partitioned inputs are partitioned per block;
// - bad inputs (no cells, K < 0, image data, on every rank or on one) fail on every rank
//   with an error and nobody hangs;
// - on one rank, the pieces are jagged: more overlapping bounding boxes than a kd-tree split.

#include "apcMPITest.h"
#include "vtkAPCGraphPartition.h"

#include "vtkAppendFilter.h"
#include "vtkCellData.h"
#include "vtkCommand.h"
#include "vtkDataSetAttributes.h"
#include "vtkDoubleArray.h"
#include "vtkExecutive.h"
#include "vtkGenericCell.h"
#include "vtkIdTypeArray.h"
#include "vtkImageData.h"
#include "vtkIntArray.h"
#include "vtkMPIController.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkMultiPieceDataSet.h"
#include "vtkNew.h"
#include "vtkPartitionedDataSet.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkUnstructuredGrid.h"
#include "vtkXMLPUnstructuredGridReader.h"
#include "vtkXMLUnstructuredGridReader.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <vector>

namespace
{
using apctest::Check;

class ErrorCounter : public vtkCommand
{
public:
  static ErrorCounter* New() { return new ErrorCounter; }
  void Execute(vtkObject*, unsigned long, void* data) override
  {
    ++this->Count;
    this->Last += data ? static_cast<const char*>(data) : ""; // all of them: the filter's first
  }
  int Count = 0;
  std::string Last;
};

vtkSmartPointer<vtkUnstructuredGrid> ReadWindPiece(int rank, int ranks)
{
  vtkNew<vtkXMLPUnstructuredGridReader> reader;
  reader->SetFileName(APC_DATA_DIR "/windAroundBuildings/wind.pvtu");
  reader->UpdatePiece(rank, ranks, 0);
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->ShallowCopy(reader->GetOutput());
  return grid;
}

vtkSmartPointer<vtkUnstructuredGrid> ReadFlangePiece(int piece)
{
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(
    (std::string(APC_DATA_DIR) + "/flange/flange_" + std::to_string(piece) + ".vtu").c_str());
  reader->Update();
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->ShallowCopy(reader->GetOutput());
  return grid;
}

std::array<double, 3> Centroid(vtkUnstructuredGrid* grid, vtkIdType c)
{
  vtkNew<vtkIdList> ids;
  grid->GetCellPoints(c, ids); // polyhedra: the unique points
  std::array<double, 3> sum{ 0, 0, 0 };
  double x[3];
  for (vtkIdType i = 0; i < ids->GetNumberOfIds(); ++i)
  {
    grid->GetPoint(ids->GetId(i), x);
    for (int d = 0; d < 3; ++d)
    {
      sum[d] += x[d] / ids->GetNumberOfIds();
    }
  }
  return sum;
}

// Tags every cell with a global id (rank offset + local index) and its centroid, so that the
// output can be checked cell by cell.
void Tag(vtkMPIController* controller, vtkUnstructuredGrid* grid)
{
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  const vtkIdType n = grid->GetNumberOfCells();
  std::vector<vtkIdType> counts(static_cast<std::size_t>(ranks));
  controller->AllGather(&n, counts.data(), 1);
  const vtkIdType offset = std::accumulate(counts.begin(), counts.begin() + rank, vtkIdType(0));
  vtkNew<vtkIdTypeArray> id;
  id->SetName("OriginalCell");
  vtkNew<vtkDoubleArray> centroid;
  centroid->SetName("Centroid");
  centroid->SetNumberOfComponents(3);
  for (vtkIdType c = 0; c < n; ++c)
  {
    id->InsertNextValue(offset + c);
    centroid->InsertNextTuple(Centroid(grid, c).data());
  }
  grid->GetCellData()->AddArray(id);
  grid->GetCellData()->AddArray(centroid);
}

// Rank r of R owns pieces [r*K/R, (r+1)*K/R).
bool Owns(int rank, int ranks, int piece, int pieces)
{
  return static_cast<long long>(rank) * pieces / ranks <= piece &&
    piece < static_cast<long long>(rank + 1) * pieces / ranks;
}

// (OriginalCell, PartitionId) of every cell of every rank, on rank 0, sorted by cell.
std::vector<std::pair<vtkIdType, int>> GatherLabels(
  vtkMPIController* controller, vtkUnstructuredGrid* grid)
{
  vtkNew<vtkIdTypeArray> local;
  auto* id = vtkIdTypeArray::SafeDownCast(grid->GetCellData()->GetArray("OriginalCell"));
  auto* part = vtkIntArray::SafeDownCast(grid->GetCellData()->GetArray("PartitionId"));
  for (vtkIdType c = 0; id && part && c < grid->GetNumberOfCells(); ++c)
  {
    local->InsertNextValue(id->GetValue(c));
    local->InsertNextValue(part->GetValue(c));
  }
  vtkNew<vtkIdTypeArray> all;
  controller->GatherV(local, all, 0);
  std::vector<std::pair<vtkIdType, int>> labels;
  for (vtkIdType i = 0; i + 1 < all->GetNumberOfValues(); i += 2)
  {
    labels.emplace_back(all->GetValue(i), static_cast<int>(all->GetValue(i + 1)));
  }
  std::sort(labels.begin(), labels.end());
  return labels;
}

// The checks of a moved partition of `input` (tagged) into `pieces`.
void CheckMoved(vtkMPIController* controller, const char* what, vtkUnstructuredGrid* input,
  vtkUnstructuredGrid* output, int pieces)
{
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  const std::string w = std::string(what) + ": ";
  vtkIdType inCells = input->GetNumberOfCells(), totalIn = 0;
  controller->AllReduce(&inCells, &totalIn, 1, vtkCommunicator::SUM_OP);

  auto* part = vtkIntArray::SafeDownCast(output->GetCellData()->GetArray("PartitionId"));
  Check(part != nullptr, rank, w + "PartitionId is an int cell array");
  Check(output->GetCellData()->GetArray(vtkDataSetAttributes::GhostArrayName()) == nullptr, rank,
    w + "no ghost array");
  for (int a = 0; a < input->GetPointData()->GetNumberOfArrays(); ++a)
  {
    const char* name = input->GetPointData()->GetArrayName(a);
    Check(output->GetPointData()->GetArray(name) != nullptr, rank,
      w + "point array " + name + " carried over");
  }
  for (int a = 0; a < input->GetCellData()->GetNumberOfArrays(); ++a)
  {
    const char* name = input->GetCellData()->GetArrayName(a);
    Check(output->GetCellData()->GetArray(name) != nullptr, rank,
      w + "cell array " + name + " carried over");
  }
  if (!part)
  {
    return;
  }
  // Each cell sits on the rank of its piece and still has its own centroid.
  std::vector<vtkIdType> sizes(static_cast<std::size_t>(pieces), 0);
  auto* centroid = vtkDoubleArray::SafeDownCast(output->GetCellData()->GetArray("Centroid"));
  bool owned = true, sameCells = centroid != nullptr, inRange = true;
  for (vtkIdType c = 0; c < output->GetNumberOfCells(); ++c)
  {
    const int p = part->GetValue(c);
    if (p < 0 || p >= pieces)
    {
      inRange = false;
      continue;
    }
    ++sizes[p];
    owned = owned && Owns(rank, ranks, p, pieces);
    if (centroid)
    {
      const auto x = Centroid(output, c);
      double expected[3];
      centroid->GetTuple(c, expected);
      for (int d = 0; d < 3; ++d)
      {
        sameCells = sameCells && std::abs(x[d] - expected[d]) <= 1e-9 * (1 + std::abs(x[d]));
      }
    }
  }
  Check(inRange, rank, w + "PartitionId in [0, K)");
  Check(owned, rank, w + "every cell is on the rank owning its piece");
  Check(sameCells, rank, w + "every cell keeps its geometry and cell data");

  std::vector<vtkIdType> totalSizes(sizes.size());
  controller->AllReduce(sizes.data(), totalSizes.data(), pieces, vtkCommunicator::SUM_OP);
  const auto labels = GatherLabels(controller, output);
  if (rank == 0)
  {
    bool once = static_cast<vtkIdType>(labels.size()) == totalIn;
    for (std::size_t i = 0; once && i < labels.size(); ++i)
    {
      once = labels[i].first == static_cast<vtkIdType>(i);
    }
    Check(once, 0, w + "every input cell is in exactly one piece");
    const double mean = static_cast<double>(totalIn) / pieces;
    const vtkIdType largest = *std::max_element(totalSizes.begin(), totalSizes.end());
    const vtkIdType smallest = *std::min_element(totalSizes.begin(), totalSizes.end());
    std::printf("%s: %lld cells, K=%d on %d ranks: pieces %lld..%lld (mean %.1f, max/mean %.4f)\n",
      what, static_cast<long long>(totalIn), pieces, ranks, static_cast<long long>(smallest),
      static_cast<long long>(largest), mean, largest / mean);
    Check(smallest > 0, 0, w + "PartitionId covers 0..K-1 (no empty piece)");
    Check(largest <= 1.03 * mean + 1, 0, w + "largest piece within 1.03 x mean + 1");
  }
}

// --- wind: move and label ------------------------------------------------------------------
void WindCases(vtkMPIController* controller)
{
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  auto wind = ReadWindPiece(rank, ranks);
  Tag(controller, wind);
  const vtkIdType before = wind->GetNumberOfCells();
  const vtkMTimeType inputTime = wind->GetMTime();

  std::vector<std::pair<vtkIdType, int>> movedLabels;
  for (const int k : { 0, 3 * ranks + 1 })
  {
    vtkNew<vtkAPCGraphPartition> partition;
    partition->SetInputData(wind);
    partition->SetNumberOfPartitions(k);
    partition->SetSeed(7);
    partition->Update();
    auto* out = vtkUnstructuredGrid::SafeDownCast(partition->GetOutput());
    const int pieces = k > 0 ? k : ranks;
    CheckMoved(controller, k > 0 ? "wind, K = 3 ranks + 1" : "wind, K = ranks", wind, out, pieces);
    if (rank == 0)
    {
      std::printf("wind K=%d: edge cut %lld, imbalance %.4f, graph %.3f s, METIS %.3f s, "
                  "move %.3f s\n",
        pieces, static_cast<long long>(partition->GetLastEdgeCut()), partition->GetLastImbalance(),
        partition->GetLastGraphSeconds(), partition->GetLastPartitionSeconds(),
        partition->GetLastExchangeSeconds());
    }
    Check((pieces == 1 || partition->GetLastEdgeCut() > 0) && partition->GetLastImbalance() >= 1.0,
      rank, "edge cut and imbalance reported");
    if (k > 0)
    {
      movedLabels = GatherLabels(controller, out);
    }
  }
  Check(wind->GetNumberOfCells() == before && wind->GetMTime() == inputTime &&
      !wind->GetCellData()->GetArray("PartitionId"),
    rank, "the input is not modified");

  // Label only: nothing moves, the same labels as when moving.
  vtkNew<vtkAPCGraphPartition> label;
  label->SetInputData(wind);
  label->SetNumberOfPartitions(3 * ranks + 1);
  label->SetSeed(7);
  label->LabelOnlyOn();
  label->Update();
  auto* labelled = vtkUnstructuredGrid::SafeDownCast(label->GetOutput());
  Check(labelled->GetNumberOfCells() == before, rank, "label only: this rank keeps its cells");
  auto* id = vtkIdTypeArray::SafeDownCast(labelled->GetCellData()->GetArray("OriginalCell"));
  bool sameOrder = id != nullptr;
  for (vtkIdType c = 0; sameOrder && c < before; ++c)
  {
    sameOrder = id->GetValue(c) ==
      vtkIdTypeArray::SafeDownCast(wind->GetCellData()->GetArray("OriginalCell"))->GetValue(c);
  }
  Check(sameOrder, rank, "label only: the same cells in the same order");
  Check(labelled->GetPoints() == wind->GetPoints(), rank, "label only: points shared, not copied");
  Check(labelled->GetCellData()->GetArray("PartitionId") != nullptr, rank,
    "label only: PartitionId present");
  const auto labels = GatherLabels(controller, labelled);
  if (rank == 0)
  {
    Check(labels == movedLabels, 0, "label only gives the labels the moving mode moved by");
  }
}

// --- polyhedra: the same flange as VTK_POLYHEDRON cells -----------------------------------------
vtkSmartPointer<vtkUnstructuredGrid> AsPolyhedra(vtkUnstructuredGrid* grid)
{
  auto poly = vtkSmartPointer<vtkUnstructuredGrid>::New();
  poly->SetPoints(grid->GetPoints());
  poly->GetPointData()->ShallowCopy(grid->GetPointData());
  poly->GetCellData()->ShallowCopy(grid->GetCellData());
  poly->Allocate(grid->GetNumberOfCells());
  vtkNew<vtkGenericCell> cell;
  std::vector<vtkIdType> stream;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    grid->GetCell(c, cell);
    stream.clear();
    for (int f = 0; f < cell->GetNumberOfFaces(); ++f)
    {
      vtkIdList* face = cell->GetFace(f)->GetPointIds();
      stream.push_back(face->GetNumberOfIds());
      for (vtkIdType i = 0; i < face->GetNumberOfIds(); ++i)
      {
        stream.push_back(face->GetId(i));
      }
    }
    poly->InsertNextCell(VTK_POLYHEDRON, cell->GetNumberOfPoints(),
      cell->GetPointIds()->GetPointer(0), cell->GetNumberOfFaces(), stream.data());
  }
  return poly;
}

// This rank's share of the flange: pieces [r*4/R, (r+1)*4/R) of its 4 files, appended.
vtkSmartPointer<vtkUnstructuredGrid> LocalFlange(int rank, int ranks)
{
  vtkNew<vtkAppendFilter> append;
  append->MergePointsOff();
  for (int p = 0; p < 4; ++p)
  {
    if (Owns(rank, ranks, p, 4))
    {
      append->AddInputData(ReadFlangePiece(p));
    }
  }
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  if (append->GetNumberOfInputConnections(0) > 0)
  {
    append->Update();
    grid->ShallowCopy(append->GetOutput());
  }
  return grid;
}

vtkSmartPointer<vtkDataObject> Run(
  vtkDataObject* input, int k, bool labelOnly, ErrorCounter* errors = nullptr)
{
  vtkNew<vtkAPCGraphPartition> partition;
  partition->SetInputData(input);
  partition->SetNumberOfPartitions(k);
  partition->SetLabelOnly(labelOnly);
  if (errors)
  {
    partition->AddObserver(vtkCommand::ErrorEvent, errors);
    partition->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, errors);
  }
  partition->Update();
  return partition->GetOutputDataObject(0);
}

void PolyhedraCase(vtkMPIController* controller)
{
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  auto flange = LocalFlange(rank, ranks);
  Tag(controller, flange);
  auto poly = AsPolyhedra(flange);
  Check(poly->GetNumberOfCells() == 0 || poly->GetCellType(0) == VTK_POLYHEDRON, rank,
    "the flange converted to polyhedra");

  // The same graph through polyhedron faces as through the hexahedra's and wedges' faces.
  const int k = 5;
  auto linear = GatherLabels(controller, vtkUnstructuredGrid::SafeDownCast(Run(flange, k, true)));
  auto polyLabels = GatherLabels(controller, vtkUnstructuredGrid::SafeDownCast(Run(poly, k, true)));
  if (rank == 0)
  {
    Check(linear.size() == 5712 && linear == polyLabels, 0,
      "polyhedra: the same pieces as the linear cells (same dual graph)");
  }

  // Polyhedra travel between ranks intact.
  vtkSmartPointer<vtkDataObject> movedObject = Run(poly, k, false);
  auto* moved = vtkUnstructuredGrid::SafeDownCast(movedObject);
  CheckMoved(controller, "flange polyhedra", poly, moved, k);
  bool allPolyhedra = true;
  vtkIdType faces = 0;
  for (vtkIdType c = 0; c < moved->GetNumberOfCells(); ++c)
  {
    allPolyhedra = allPolyhedra && moved->GetCellType(c) == VTK_POLYHEDRON;
    vtkIdType nfaces;
    const vtkIdType* stream;
    moved->GetFaceStream(c, nfaces, stream);
    faces += nfaces;
  }
  Check(allPolyhedra, rank, "polyhedra: still VTK_POLYHEDRON after moving");
  vtkIdType totalFaces = 0;
  controller->AllReduce(&faces, &totalFaces, 1, vtkCommunicator::SUM_OP);
  Check(totalFaces == 5340 * 6 + 372 * 5, rank, "polyhedra: every face arrived");
}

// --- composite inputs: each block on its own ----------------------------------------------------
void CompositeCase(vtkMPIController* controller)
{
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  auto flange = LocalFlange(rank, ranks);
  Tag(controller, flange);
  vtkNew<vtkMultiPieceDataSet> pieces; // what a multiblock holds as a partitioned block
  for (int p = 0; p < 4; ++p)
  {
    if (Owns(rank, ranks, p, 4))
    {
      pieces->SetPartition(pieces->GetNumberOfPartitions(), ReadFlangePiece(p));
    }
  }
  vtkNew<vtkMultiBlockDataSet> blocks;
  blocks->SetNumberOfBlocks(3);
  blocks->SetBlock(0, flange);
  blocks->SetBlock(1, nullptr); // a block no rank has
  blocks->SetBlock(2, pieces);
  const int k = 3;
  vtkSmartPointer<vtkDataObject> outObject = Run(blocks, k, false);
  auto* out = vtkMultiBlockDataSet::SafeDownCast(outObject);
  Check(out && out->GetNumberOfBlocks() == 3, rank, "multiblock: the structure is kept");
  if (!out || out->GetNumberOfBlocks() != 3)
  {
    return;
  }
  auto* block0 = vtkUnstructuredGrid::SafeDownCast(out->GetBlock(0));
  Check(block0 != nullptr, rank, "multiblock: block 0 is an unstructured grid");
  if (block0)
  {
    CheckMoved(controller, "multiblock block 0", flange, block0, k);
  }
  auto* block1 = vtkUnstructuredGrid::SafeDownCast(out->GetBlock(1));
  Check(
    !block1 || block1->GetNumberOfCells() == 0, rank, "multiblock: the empty block stays empty");
  auto* block2 = vtkPartitionedDataSet::SafeDownCast(out->GetBlock(2));
  Check(block2 != nullptr, rank, "multiblock: block 2 is still partitioned");
  vtkIdType cells = 0;
  int expectedPartitions = 0;
  for (int p = 0; p < k; ++p)
  {
    expectedPartitions += Owns(rank, ranks, p, k);
  }
  if (block2)
  {
    Check(static_cast<int>(block2->GetNumberOfPartitions()) == expectedPartitions, rank,
      "partitioned block: one partition per piece this rank owns");
    for (unsigned int i = 0; i < block2->GetNumberOfPartitions(); ++i)
    {
      auto* ug = vtkUnstructuredGrid::SafeDownCast(block2->GetPartition(i));
      auto* part =
        ug ? vtkIntArray::SafeDownCast(ug->GetCellData()->GetArray("PartitionId")) : nullptr;
      Check(part != nullptr, rank, "partitioned block: PartitionId present");
      if (part)
      {
        double range[2];
        part->GetRange(range);
        Check(range[0] == range[1] && Owns(rank, ranks, static_cast<int>(range[0]), k), rank,
          "partitioned block: each partition is one piece of this rank");
        cells += ug->GetNumberOfCells();
      }
    }
  }
  vtkIdType total = 0;
  controller->AllReduce(&cells, &total, 1, vtkCommunicator::SUM_OP);
  Check(total == 5712, rank, "partitioned block: every cell once");
}

// --- empty face arrays on a grid without polyhedra (what ParaView's parallel XML reader gives
// some ranks) must not be taken for polyhedra ---------------------------------------------------
void EmptyFaceArraysCase(vtkMPIController* controller)
{
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  auto flange = LocalFlange(rank, ranks);
  Tag(controller, flange);
  vtkNew<vtkIdTypeArray> locations, faces;
  flange->SetCells(flange->GetCellTypesArray(), flange->GetCells(), locations, faces);
  vtkNew<vtkMultiPieceDataSet> pieces;
  pieces->SetPartition(0, flange);
  vtkNew<vtkMultiBlockDataSet> blocks;
  blocks->SetBlock(0, flange);
  blocks->SetBlock(1, pieces);
  const int k = ranks + 2;
  vtkSmartPointer<vtkDataObject> outObject = Run(blocks, k, false);
  auto* out = vtkMultiBlockDataSet::SafeDownCast(outObject);
  auto* grid = out ? vtkUnstructuredGrid::SafeDownCast(out->GetBlock(0)) : nullptr;
  Check(grid != nullptr, rank, "empty face arrays: partitioned");
  if (grid)
  {
    CheckMoved(controller, "flange with empty face arrays", flange, grid, k);
  }
  auto* split = out ? vtkPartitionedDataSet::SafeDownCast(out->GetBlock(1)) : nullptr;
  vtkIdType n = 0, total = 0;
  for (unsigned int i = 0; split && i < split->GetNumberOfPartitions(); ++i)
  {
    n += split->GetPartition(i)->GetNumberOfCells();
  }
  controller->AllReduce(&n, &total, 1, vtkCommunicator::SUM_OP);
  Check(total == 5712, rank, "empty face arrays: the partitioned block split into its pieces");
}

// --- bad inputs: an error on every rank, nobody left waiting ------------------------------------
void ExpectError(
  vtkMPIController* controller, vtkDataObject* input, int k, const char* what, const char* message)
{
  const int rank = controller->GetLocalProcessId();
  vtkNew<ErrorCounter> errors;
  Run(input, k, false, errors);
  Check(errors->Count > 0, rank, std::string(what) + ": an error");
  if (message)
  {
    Check(errors->Last.find(message) != std::string::npos ||
        errors->Last.find("another rank") != std::string::npos,
      rank, std::string(what) + ": the error says '" + message + "' (got: " + errors->Last + ")");
  }
  controller->Barrier(); // reached by every rank: nobody hangs in the filter
}

void BadInputCases(vtkMPIController* controller)
{
  const int rank = controller->GetLocalProcessId();
  const int ranks = controller->GetNumberOfProcesses();
  vtkNew<vtkUnstructuredGrid> empty;
  empty->SetPoints(vtkNew<vtkPoints>());
  ExpectError(controller, empty, 0, "no cells", "no cells");

  auto flange = LocalFlange(rank, ranks);
  ExpectError(controller, flange, -1, "negative K", "NumberOfPartitions is -1");

  vtkNew<vtkImageData> image;
  image->SetDimensions(4, 4, 4);
  ExpectError(controller, image, 0, "image data", "needs a vtkUnstructuredGrid");

  if (ranks > 1)
  {
    // Only rank 1 is wrong: every rank must still fail together.
    vtkSmartPointer<vtkDataObject> input = flange;
    if (rank == 1)
    {
      input = image;
    }
    ExpectError(controller, input, 0, "image data on one rank", "needs a vtkUnstructuredGrid");

    vtkNew<vtkMultiBlockDataSet> blocks;
    blocks->SetNumberOfBlocks(rank == 0 ? 2 : 1);
    blocks->SetBlock(0, flange);
    ExpectError(controller, blocks, 0, "different structure per rank", "structure");
  }

  // Cells on one rank only is fine: the pieces go to every rank.
  vtkSmartPointer<vtkUnstructuredGrid> one = empty.Get();
  if (rank == 0)
  {
    one = ReadFlangePiece(0);
  }
  vtkNew<ErrorCounter> errors;
  vtkSmartPointer<vtkDataObject> outObject = Run(one, 0, false, errors);
  auto* out = vtkUnstructuredGrid::SafeDownCast(outObject);
  Check(errors->Count == 0, rank, "cells on one rank only: no error");
  vtkIdType n = out ? out->GetNumberOfCells() : 0, total = 0;
  controller->AllReduce(&n, &total, 1, vtkCommunicator::SUM_OP);
  Check(total == 1438 && n > 0, rank, "cells on one rank only: every rank gets a piece");

  // Fewer pieces than ranks: the ranks without a piece get an empty grid that still has the
  // arrays (APC Volume skips the frame on every rank if one lacks the coloured array).
  vtkSmartPointer<vtkDataObject> singleObject = Run(flange, 1, false);
  auto* single = vtkUnstructuredGrid::SafeDownCast(singleObject);
  Check(single && single->GetNumberOfCells() == (Owns(rank, ranks, 0, 1) ? 5712 : 0), rank,
    "K = 1: the owner of piece 0 (the last rank) gets every cell, the others none");
  Check(single && single->GetPointData()->GetArray("T") &&
      single->GetCellData()->GetArray("PartitionId"),
    rank, "K = 1: the arrays are there on every rank, even without cells");
}

// --- jagged pieces (one rank, whole mesh): graph partition vs kd-tree
// -----------------------------
using Box = std::array<double, 6>;

Box Empty()
{
  return { 1e300, -1e300, 1e300, -1e300, 1e300, -1e300 };
}

void Grow(Box& b, const double* cell)
{
  for (int d = 0; d < 3; ++d)
  {
    b[2 * d] = std::min(b[2 * d], cell[2 * d]);
    b[2 * d + 1] = std::max(b[2 * d + 1], cell[2 * d + 1]);
  }
}

double Volume(const Box& b)
{
  double v = 1;
  for (int d = 0; d < 3; ++d)
  {
    v *= std::max(0.0, b[2 * d + 1] - b[2 * d]);
  }
  return v;
}

// Pairs of pieces whose boxes overlap by more than `fraction` of the smaller box's volume.
int OverlappingPairs(const std::vector<Box>& boxes, double fraction)
{
  int pairs = 0;
  for (std::size_t a = 0; a < boxes.size(); ++a)
  {
    for (std::size_t b = a + 1; b < boxes.size(); ++b)
    {
      Box i;
      for (int d = 0; d < 3; ++d)
      {
        i[2 * d] = std::max(boxes[a][2 * d], boxes[b][2 * d]);
        i[2 * d + 1] = std::min(boxes[a][2 * d + 1], boxes[b][2 * d + 1]);
      }
      pairs += Volume(i) > fraction * std::min(Volume(boxes[a]), Volume(boxes[b]));
    }
  }
  return pairs;
}

// Recursive median split of the cell centroids along the widest axis, into `parts` parts of
// proportional sizes: ParaView's kind of convex blocks.
void KdSplit(std::vector<vtkIdType>& cells, std::size_t begin, std::size_t end, int parts,
  int first, const std::vector<std::array<double, 3>>& centre, std::vector<int>& part)
{
  if (parts == 1)
  {
    for (std::size_t i = begin; i < end; ++i)
    {
      part[cells[i]] = first;
    }
    return;
  }
  Box b = Empty();
  for (std::size_t i = begin; i < end; ++i)
  {
    const auto& x = centre[cells[i]];
    const double pt[6] = { x[0], x[0], x[1], x[1], x[2], x[2] };
    Grow(b, pt);
  }
  int axis = 0;
  for (int d = 1; d < 3; ++d)
  {
    axis = b[2 * d + 1] - b[2 * d] > b[2 * axis + 1] - b[2 * axis] ? d : axis;
  }
  const int left = parts / 2;
  const std::size_t mid = begin + (end - begin) * left / parts;
  std::nth_element(cells.begin() + begin, cells.begin() + mid, cells.begin() + end,
    [&](vtkIdType a, vtkIdType c) { return centre[a][axis] < centre[c][axis]; });
  KdSplit(cells, begin, mid, left, first, centre, part);
  KdSplit(cells, mid, end, parts - left, first + left, centre, part);
}

void JaggedCase(vtkMPIController* controller)
{
  auto wind = ReadWindPiece(0, 1);
  const int k = 8;
  vtkNew<vtkAPCGraphPartition> partition;
  partition->SetInputData(wind);
  partition->SetNumberOfPartitions(k);
  partition->LabelOnlyOn();
  partition->SetController(nullptr);
  partition->Update();
  auto* out = vtkUnstructuredGrid::SafeDownCast(partition->GetOutput());
  auto* graphPart = vtkIntArray::SafeDownCast(out->GetCellData()->GetArray("PartitionId"));
  Check(graphPart != nullptr, 0, "jagged: PartitionId");
  if (!graphPart)
  {
    return;
  }
  const vtkIdType n = wind->GetNumberOfCells();
  std::vector<std::array<double, 3>> centre(static_cast<std::size_t>(n));
  std::vector<Box> cellBox(static_cast<std::size_t>(n));
  for (vtkIdType c = 0; c < n; ++c)
  {
    centre[c] = Centroid(wind, c);
    wind->GetCellBounds(c, cellBox[c].data());
  }
  std::vector<vtkIdType> cells(static_cast<std::size_t>(n));
  std::iota(cells.begin(), cells.end(), 0);
  std::vector<int> kdPart(static_cast<std::size_t>(n), 0);
  KdSplit(cells, 0, cells.size(), k, 0, centre, kdPart);

  std::vector<Box> graphBoxes(k, Empty()), kdBoxes(k, Empty());
  for (vtkIdType c = 0; c < n; ++c)
  {
    Grow(graphBoxes[graphPart->GetValue(c)], cellBox[c].data());
    Grow(kdBoxes[kdPart[c]], cellBox[c].data());
  }
  const int graphAny = OverlappingPairs(graphBoxes, 0), kdAny = OverlappingPairs(kdBoxes, 0);
  const int graphDeep = OverlappingPairs(graphBoxes, 0.1), kdDeep = OverlappingPairs(kdBoxes, 0.1);
  std::printf("jagged: wind K=%d, %d piece pairs: bounding boxes overlapping at all: graph %d, "
              "kd-tree %d; by more than 10%% of the smaller box: graph %d, kd-tree %d\n",
    k, k * (k - 1) / 2, graphAny, kdAny, graphDeep, kdDeep);
  Check(graphDeep > kdDeep, 0, "jagged: graph pieces overlap more than kd-tree pieces");
  Check(graphDeep >= k / 2, 0, "jagged: graph pieces overlap like puzzle pieces");
  (void)controller;
}
} // namespace

int main(int argc, char* argv[])
{
  vtkSmartPointer<vtkMPIController> controller = apctest::StartMPI(&argc, &argv);
  WindCases(controller);
  PolyhedraCase(controller);
  CompositeCase(controller);
  EmptyFaceArraysCase(controller);
  BadInputCases(controller);
  if (controller->GetNumberOfProcesses() == 1)
  {
    JaggedCase(controller);
  }
  return apctest::FinishMPITest(controller);
}
