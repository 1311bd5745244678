// SPDX-License-Identifier: BSD-3-Clause
#include "apcWindTracer.h"

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkCellType.h"
#include "vtkFloatArray.h"
#include "vtkHexahedron.h"
#include "vtkIntArray.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkPyramid.h"
#include "vtkTetra.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"
#include "vtkWedge.h"
#include "vtkXMLPUnstructuredGridReader.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <unordered_map>

namespace apc
{
namespace
{
// Where the tracer starts and enters (metres, the case's coordinates): a slab in front of the
// first buildings, a band of y, up to a height.
constexpr double SlabEndX = 0.0;
constexpr double BandY0 = 50.0;
constexpr double BandY1 = 130.0;
constexpr double BandTopZ = 40.0;
constexpr double PlaneTolerance = 0.1; // m: snapping left the box's sides a few mm uneven

bool InBand(double y, double z)
{
  return y >= BandY0 && y <= BandY1 && z <= BandTopZ;
}

// The faces of the linear cells the data hold, as VTK numbers their corners.
int FaceCorners(int type, int face, vtkIdType corners[4])
{
  const vtkIdType* ids = nullptr;
  int count = 0;
  switch (type)
  {
    case VTK_TETRA:
      ids = face < 4 ? vtkTetra::GetFaceArray(face) : nullptr;
      count = 3;
      break;
    case VTK_PYRAMID:
      ids = face < 5 ? vtkPyramid::GetFaceArray(face) : nullptr;
      count = face == 0 ? 4 : 3;
      break;
    case VTK_WEDGE:
      ids = face < 5 ? vtkWedge::GetFaceArray(face) : nullptr;
      count = face < 2 ? 3 : 4;
      break;
    case VTK_HEXAHEDRON:
      ids = face < 6 ? vtkHexahedron::GetFaceArray(face) : nullptr;
      count = 4;
      break;
    default:
      return -1; // an unsupported type
  }
  if (!ids)
  {
    return 0; // past the last face
  }
  std::copy(ids, ids + count, corners);
  return count;
}

struct FaceKeyHash
{
  std::size_t operator()(const std::array<float, 12>& key) const
  {
    std::size_t h = 1469598103934665603ull;
    for (float v : key)
    {
      std::uint32_t bits;
      std::memcpy(&bits, &v, sizeof bits);
      h = (h ^ bits) * 1099511628211ull;
    }
    return h;
  }
};

bool AllRanksOk(bool ok, MPI_Comm comm)
{
  int mine = ok ? 1 : 0, all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, comm);
  return all == 1;
}
}

bool WindTracer::Initialize(
  const std::string& pvtu, MPI_Comm comm, int dataRanks, double timeStep, std::string& error)
{
  this->Dt = timeStep;
  this->Comm = comm;
  MPI_Comm_rank(comm, &this->Rank);
  MPI_Comm_size(comm, &this->Size);
  this->DataRanks = dataRanks > 0 ? std::min(dataRanks, this->Size) : this->Size;
  std::string mine;
  bool ok = this->ReadPieces(pvtu, mine);
  if (!AllRanksOk(ok, comm))
  {
    error = "cannot read the mesh " + pvtu + (mine.empty() ? " (on another rank)" : ": " + mine);
    return false;
  }
  this->ShareLayout();
  if (!AllRanksOk(this->BuildFaces(), comm))
  {
    error = "the mesh " + pvtu + " has cells of a type other than tetra, pyramid, wedge, hex";
    return false;
  }
  this->MatchInPieces();
  this->MatchAcrossPieces();
  this->BuildHalo();
  this->BuildFluxes();
  this->BuildWalls();
  this->BuildMesh();
  return true;
}

bool WindTracer::ReadPieces(const std::string& pvtu, std::string& error)
{
  if (!std::ifstream(pvtu).good())
  {
    error = "no such file";
    return false;
  }
  vtkNew<vtkXMLPUnstructuredGridReader> reader;
  reader->SetFileName(pvtu.c_str());
  reader->UpdateInformation();
  const int pieces = reader->GetNumberOfPieces();
  std::vector<std::int64_t> counts(pieces, 0);
  this->LocalStart.assign(1, 0);
  for (int p = this->Rank; p < pieces && this->Rank < this->DataRanks; p += this->DataRanks)
  {
    reader->UpdatePiece(p, pieces, 0);
    vtkNew<vtkUnstructuredGrid> grid;
    grid->ShallowCopy(reader->GetOutput());
    if (grid->GetNumberOfCells() == 0 || !grid->GetCellData()->GetArray("U_mag"))
    {
      error = "piece " + std::to_string(p) + " has no cells or no cell array U_mag";
      return false;
    }
    counts[p] = grid->GetNumberOfCells();
    this->Pieces.push_back(p);
    this->Grids.emplace_back(grid);
    this->LocalStart.push_back(this->LocalStart.back() + counts[p]);
  }
  this->PieceOffsets.assign(counts.begin(), counts.end()); // this rank's counts, for now
  return pieces > 0;
}

// Every rank's piece sizes (global cell ids) and the domain's bounds.
void WindTracer::ShareLayout()
{
  std::vector<std::int64_t> counts = this->PieceOffsets;
  const int pieces = static_cast<int>(counts.size());
  MPI_Allreduce(MPI_IN_PLACE, counts.data(), pieces, MPI_INT64_T, MPI_SUM, this->Comm);
  double low[3] = { 1e300, 1e300, 1e300 }, high[3] = { -1e300, -1e300, -1e300 };
  for (const auto& grid : this->Grids)
  {
    const double* b = grid->GetBounds();
    for (int d = 0; d < 3; ++d)
    {
      low[d] = std::min(low[d], b[2 * d]);
      high[d] = std::max(high[d], b[2 * d + 1]);
    }
  }
  MPI_Allreduce(MPI_IN_PLACE, low, 3, MPI_DOUBLE, MPI_MIN, this->Comm);
  MPI_Allreduce(MPI_IN_PLACE, high, 3, MPI_DOUBLE, MPI_MAX, this->Comm);
  for (int d = 0; d < 3; ++d)
  {
    this->Bounds[2 * d] = low[d];
    this->Bounds[2 * d + 1] = high[d];
  }
  this->PieceOffsets.assign(1, 0);
  for (auto n : counts)
  {
    this->PieceOffsets.push_back(this->PieceOffsets.back() + n);
  }
  this->C.assign(this->LocalStart.back(), 0.0);
}

std::int64_t WindTracer::GlobalOf(std::int64_t local) const
{
  const auto it = std::upper_bound(this->LocalStart.begin(), this->LocalStart.end(), local);
  const std::size_t k = static_cast<std::size_t>(it - this->LocalStart.begin()) - 1;
  return this->PieceOffsets[this->Pieces[k]] + local - this->LocalStart[k];
}

int WindTracer::OwnerOf(std::int64_t global) const
{
  const auto it = std::upper_bound(this->PieceOffsets.begin(), this->PieceOffsets.end(), global);
  return static_cast<int>(it - this->PieceOffsets.begin() - 1) % this->DataRanks;
}

std::int64_t WindTracer::LocalOf(std::int64_t global) const
{
  const auto it = std::upper_bound(this->PieceOffsets.begin(), this->PieceOffsets.end(), global);
  const int piece = static_cast<int>(it - this->PieceOffsets.begin()) - 1;
  if (this->OwnerOf(global) != this->Rank)
  {
    return -1;
  }
  return this->LocalStart[piece / this->DataRanks] + global - this->PieceOffsets[piece];
}

std::int64_t WindTracer::SlotOf(std::int64_t global) const
{
  const std::int64_t local = this->LocalOf(global);
  if (local >= 0)
  {
    return local;
  }
  const int rank = this->OwnerOf(global);
  const auto begin = this->RecvGlobal.begin() + this->RecvDispls[rank];
  const auto end = begin + this->RecvCounts[rank];
  return this->LocalStart.back() +
    (std::lower_bound(begin, end, global) - this->RecvGlobal.begin());
}

// One cell's faces: area vector oriented away from the cell's centre, centre, corners; and the
// cell's volume (divergence theorem over those faces) and speed.
bool WindTracer::AddCellFaces(vtkUnstructuredGrid* grid, vtkIdType cell, std::int64_t local)
{
  vtkIdType npts;
  const vtkIdType* pts;
  grid->GetCellPoints(cell, npts, pts);
  double centre[3] = { 0, 0, 0 };
  for (vtkIdType i = 0; i < npts; ++i)
  {
    const double* x = grid->GetPoint(pts[i]);
    for (int d = 0; d < 3; ++d)
    {
      centre[d] += x[d] / npts;
    }
  }
  double volume = 0;
  vtkIdType corners[4];
  int count;
  for (int f = 0; (count = FaceCorners(grid->GetCellType(cell), f, corners)) > 0; ++f)
  {
    std::array<double, 3> area{ 0, 0, 0 }, mid{ 0, 0, 0 };
    std::array<std::array<double, 3>, 4> x{};
    std::array<vtkIdType, 4> ids{ -1, -1, -1, -1 };
    for (int i = 0; i < count; ++i)
    {
      ids[i] = pts[corners[i]];
      grid->GetPoint(ids[i], x[i].data());
    }
    for (int i = 0; i < count; ++i)
    {
      const auto& a = x[i];
      const auto& b = x[(i + 1) % count];
      area[0] += 0.5 * (a[1] * b[2] - a[2] * b[1]);
      area[1] += 0.5 * (a[2] * b[0] - a[0] * b[2]);
      area[2] += 0.5 * (a[0] * b[1] - a[1] * b[0]);
      for (int d = 0; d < 3; ++d)
      {
        mid[d] += a[d] / count;
      }
    }
    double outward = 0;
    for (int d = 0; d < 3; ++d)
    {
      outward += area[d] * (mid[d] - centre[d]);
    }
    if (outward < 0)
    {
      area = { -area[0], -area[1], -area[2] };
    }
    volume += std::abs(outward) / 3.0; // the pyramid from the centre over the face
    this->FaceArea.push_back(area);
    this->FaceCentre.push_back(mid);
    this->FacePoints.push_back(ids);
    this->FaceCell.push_back(local);
  }
  this->Volume.push_back(volume);
  this->Speed.push_back(grid->GetCellData()->GetArray("U_mag")->GetComponent(cell, 0));
  this->FaceStart.push_back(static_cast<std::int64_t>(this->FaceArea.size()));
  return count == 0;
}

bool WindTracer::BuildFaces()
{
  this->FaceStart.assign(1, 0);
  for (std::size_t k = 0; k < this->Grids.size(); ++k)
  {
    for (vtkIdType c = 0; c < this->Grids[k]->GetNumberOfCells(); ++c)
    {
      if (!this->AddCellFaces(this->Grids[k], c, this->LocalStart[k] + c))
      {
        return false;
      }
    }
  }
  this->Neighbour.assign(this->FaceArea.size(), -1);
  return true;
}

// Two faces of one piece with the same corners (point ids) are one face between two cells.
void WindTracer::MatchInPieces()
{
  for (std::size_t k = 0; k < this->Grids.size(); ++k)
  {
    std::unordered_map<std::array<float, 12>, std::int64_t, FaceKeyHash> open;
    for (std::int64_t f = this->FaceStart[this->LocalStart[k]];
         f < this->FaceStart[this->LocalStart[k + 1]]; ++f)
    {
      auto ids = this->FacePoints[f];
      std::sort(ids.begin(), ids.end());
      std::array<float, 12> key{};
      for (int i = 0; i < 4; ++i)
      {
        key[i] = static_cast<float>(ids[i]); // exact below 2^24 points per piece
      }
      auto found = open.emplace(key, f);
      if (!found.second)
      {
        const std::int64_t g = found.first->second;
        this->Neighbour[f] = this->GlobalOf(this->FaceCell[g]);
        this->Neighbour[g] = this->GlobalOf(this->FaceCell[f]);
        open.erase(found.first);
      }
    }
  }
}

// The faces no cell of their piece shares: every rank gets all ranks' (their corners'
// coordinates; the pieces were cut from one mesh, so shared corners are the same floats) and
// looks its own up among the other pieces'.
void WindTracer::MatchAcrossPieces()
{
  std::vector<Face> mine;
  std::vector<std::int64_t> faces;
  for (std::int64_t f = 0; f < static_cast<std::int64_t>(this->Neighbour.size()); ++f)
  {
    if (this->Neighbour[f] >= 0)
    {
      continue;
    }
    vtkUnstructuredGrid* grid = this->GridOfFace(f);
    std::array<std::array<float, 3>, 4> corners{};
    int count = 0;
    for (; count < 4 && this->FacePoints[f][count] >= 0; ++count)
    {
      double x[3];
      grid->GetPoint(this->FacePoints[f][count], x);
      corners[count] = { static_cast<float>(x[0]), static_cast<float>(x[1]),
        static_cast<float>(x[2]) };
    }
    std::sort(corners.begin(), corners.begin() + count);
    Face face{ {}, this->GlobalOf(this->FaceCell[f]) };
    for (int i = 0; i < count; ++i)
    {
      std::copy(corners[i].begin(), corners[i].end(), face.Key.begin() + 3 * i);
    }
    mine.push_back(face);
    faces.push_back(f);
  }
  int bytes = static_cast<int>(mine.size() * sizeof(Face));
  std::vector<int> counts(this->Size), displs(this->Size, 0);
  MPI_Allgather(&bytes, 1, MPI_INT, counts.data(), 1, MPI_INT, this->Comm);
  for (int r = 1; r < this->Size; ++r)
  {
    displs[r] = displs[r - 1] + counts[r - 1];
  }
  std::vector<Face> all((displs.back() + counts.back()) / sizeof(Face));
  MPI_Allgatherv(
    mine.data(), bytes, MPI_BYTE, all.data(), counts.data(), displs.data(), MPI_BYTE, this->Comm);
  std::unordered_multimap<std::array<float, 12>, std::int64_t, FaceKeyHash> byKey;
  for (const Face& face : all)
  {
    byKey.emplace(face.Key, face.Cell);
  }
  for (std::size_t i = 0; i < mine.size(); ++i)
  {
    auto range = byKey.equal_range(mine[i].Key);
    for (auto it = range.first; it != range.second; ++it)
    {
      if (it->second != mine[i].Cell)
      {
        this->Neighbour[faces[i]] = it->second;
      }
    }
  }
}

// Which other ranks' cells this rank's faces need (sorted, per rank), and which of its own
// cells the other ranks need: the Alltoallv layout of every step's halo exchange.
void WindTracer::BuildHalo()
{
  std::vector<std::vector<std::int64_t>> need(this->Size);
  for (std::int64_t g : this->Neighbour)
  {
    if (g >= 0 && this->LocalOf(g) < 0)
    {
      need[this->OwnerOf(g)].push_back(g);
    }
  }
  this->RecvCounts.assign(this->Size, 0);
  this->RecvDispls.assign(this->Size, 0);
  this->RecvGlobal.clear();
  for (int r = 0; r < this->Size; ++r)
  {
    std::sort(need[r].begin(), need[r].end());
    need[r].erase(std::unique(need[r].begin(), need[r].end()), need[r].end());
    this->RecvDispls[r] = static_cast<int>(this->RecvGlobal.size());
    this->RecvCounts[r] = static_cast<int>(need[r].size());
    this->RecvGlobal.insert(this->RecvGlobal.end(), need[r].begin(), need[r].end());
  }
  this->SendCounts.assign(this->Size, 0);
  this->SendDispls.assign(this->Size, 0);
  MPI_Alltoall(
    this->RecvCounts.data(), 1, MPI_INT, this->SendCounts.data(), 1, MPI_INT, this->Comm);
  for (int r = 1; r < this->Size; ++r)
  {
    this->SendDispls[r] = this->SendDispls[r - 1] + this->SendCounts[r - 1];
  }
  this->SendCells.resize(this->SendDispls.back() + this->SendCounts.back());
  MPI_Alltoallv(this->RecvGlobal.data(), this->RecvCounts.data(), this->RecvDispls.data(),
    MPI_INT64_T, this->SendCells.data(), this->SendCounts.data(), this->SendDispls.data(),
    MPI_INT64_T, this->Comm);
  for (auto& cell : this->SendCells)
  {
    cell = this->LocalOf(cell);
  }
  this->SendBuffer.resize(this->SendCells.size());
  this->C.resize(this->LocalStart.back() + this->RecvGlobal.size(), 0.0);
}

// values holds the local cells, then the halo's slots: the slots get their owners' values.
void WindTracer::Exchange(std::vector<double>& values)
{
  for (std::size_t i = 0; i < this->SendCells.size(); ++i)
  {
    this->SendBuffer[i] = values[this->SendCells[i]];
  }
  MPI_Alltoallv(this->SendBuffer.data(), this->SendCounts.data(), this->SendDispls.data(),
    MPI_DOUBLE, values.data() + this->LocalStart.back(), this->RecvCounts.data(),
    this->RecvDispls.data(), MPI_DOUBLE, this->Comm);
}

vtkUnstructuredGrid* WindTracer::GridOfFace(std::int64_t face) const
{
  const std::int64_t local = this->FaceCell[face];
  const auto it = std::upper_bound(this->LocalStart.begin(), this->LocalStart.end(), local);
  return this->Grids[it - this->LocalStart.begin() - 1];
}

bool WindTracer::OnInlet(std::int64_t face) const
{
  const auto& ids = this->FacePoints[face];
  vtkUnstructuredGrid* grid = this->GridOfFace(face);
  for (int i = 0; i < 4 && ids[i] >= 0; ++i)
  {
    if (std::abs(grid->GetPoint(ids[i])[0] - this->Bounds[0]) > PlaneTolerance)
    {
      return false;
    }
  }
  return true;
}

// The inflow terms of every cell (weights dt |F| / V) and the initial field.
void WindTracer::BuildFluxes()
{
  const std::int64_t cells = this->LocalStart.back();
  std::vector<double> speed(this->C.size(), 0.0);
  std::copy(this->Speed.begin(), this->Speed.end(), speed.begin());
  this->Exchange(speed);
  std::vector<double> flux(this->Neighbour.size(), 0.0); // > 0 in, 0 for no inflow
  std::vector<bool> inlet(this->Neighbour.size(), false);
  for (std::int64_t c = 0; c < cells; ++c)
  {
    for (std::int64_t f = this->FaceStart[c]; f < this->FaceStart[c + 1]; ++f)
    {
      const double ax = this->FaceArea[f][0];
      if (this->Neighbour[f] >= 0)
      {
        flux[f] = -ax * 0.5 * (this->Speed[c] + speed[this->SlotOf(this->Neighbour[f])]);
      }
      else if (this->OnInlet(f))
      {
        inlet[f] = true;
        flux[f] = -ax * this->Speed[c];
      }
      flux[f] = std::max(flux[f], 0.0);
    }
  }
  this->InStart.assign(1, 0);
  this->InletWeight.assign(cells, 0.0);
  this->InletValue.assign(cells, 0.0);
  for (std::int64_t c = 0; c < cells; ++c)
  {
    for (std::int64_t f = this->FaceStart[c]; f < this->FaceStart[c + 1]; ++f)
    {
      const double w = this->Dt * flux[f] / this->Volume[c];
      if (w > 0 && inlet[f])
      {
        const auto& x = this->FaceCentre[f];
        this->InletWeight[c] += w;
        this->InletValue[c] += InBand(x[1], x[2]) ? w : 0.0;
      }
      else if (w > 0)
      {
        this->InWeight.push_back(w);
        this->InSlot.push_back(this->SlotOf(this->Neighbour[f]));
      }
    }
    this->InStart.push_back(static_cast<std::int64_t>(this->InWeight.size()));
    std::array<double, 3> centre{ 0, 0, 0 };
    const double n = static_cast<double>(this->FaceStart[c + 1] - this->FaceStart[c]);
    for (std::int64_t f = this->FaceStart[c]; f < this->FaceStart[c + 1]; ++f)
    {
      for (int d = 0; d < 3; ++d)
      {
        centre[d] += this->FaceCentre[f][d] / n;
      }
    }
    this->C[c] = centre[0] <= SlabEndX && InBand(centre[1], centre[2]) ? 1.0 : 0.0;
  }
  this->Next.assign(this->C.size(), 0.0);
}

void WindTracer::Advance()
{
  this->Exchange(this->C);
  const std::int64_t cells = this->LocalStart.back();
  for (std::int64_t c = 0; c < cells; ++c)
  {
    double sum = this->C[c] + this->InletValue[c];
    double weight = 1.0 + this->InletWeight[c];
    for (std::int64_t i = this->InStart[c]; i < this->InStart[c + 1]; ++i)
    {
      sum += this->InWeight[i] * this->C[this->InSlot[i]];
      weight += this->InWeight[i];
    }
    this->Next[c] = sum / weight;
  }
  std::swap_ranges(this->Next.begin(), this->Next.begin() + cells, this->C.begin());
}

double WindTracer::GetTracerVolume() const
{
  double mine = 0, all = 0;
  for (std::size_t c = 0; c < this->Volume.size(); ++c)
  {
    mine += this->C[c] * this->Volume[c];
  }
  MPI_Allreduce(&mine, &all, 1, MPI_DOUBLE, MPI_SUM, this->Comm);
  return all;
}
}
