// SPDX-License-Identifier: BSD-3-Clause
// The simulation of the Catalyst example: a passive tracer carried by the wind of the bundled
// windAroundBuildings case, on the mesh pieces each MPI rank owns. The solver is written the way
// a small finite-volume code is (cells, faces matched across pieces, a halo exchange per step),
// so that the adaptor next to it shows what a real code hands to Catalyst.
#ifndef apcWindTracer_h
#define apcWindTracer_h

#include <mpi.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "vtkSmartPointer.h"
#include "vtkType.h"

class vtkMultiBlockDataSet;
class vtkPolyData;
class vtkUnstructuredGrid;
class vtkFloatArray;

namespace apc
{
/**
 * Solves the advection equation dc/dt + u . grad(c) = 0 for a tracer concentration c in
 * [0, 1], in advective form, with first-order upwind finite volumes, explicit in the upwind
 * neighbours and implicit in the cell's own value (point-implicit Euler):
 *
 *   c_P' = (c_P + sum_f w_f c_N(f)) / (1 + sum_f w_f),   w_f = dt |F_f| / V_P,
 *
 * summed over the inflow faces f of cell P, where F_f = u_f . A_f is the volume flux through f
 * (A_f its outward area vector) and c_N the upwind neighbour's value (a cell of the same piece,
 * of another piece on this rank, of a piece on another rank through the halo, or the inlet's
 * value). For small w this is the explicit upwind step; the new value is always a weighted mean
 * of old values, so c stays in [0, 1] for any dt. That matters here: snappyHexMesh's
 * decomposed polyhedra leave a few tiny cells whose explicit limit is microseconds (the median
 * cell allows 0.27 s). Faces without a neighbour that are not the inlet (ground, buildings,
 * top and sides) let nothing in.
 *
 * The velocity: the bundled data keep the wind's speed U_mag (cell data) but not its
 * direction, so u = U_mag x, the tutorial's inflow direction (+x), at the local speed (u_f is
 * the mean of the two cells' u). The tracer thus streams along x, fast above the roofs, slowly
 * in the street canyons, and the buildings leave shadows behind them.
 *
 * Initial and boundary values: c = 1 in a slab at the inlet (x below the first buildings, a
 * band of y, below a height) and on the inlet faces of that band, 0 elsewhere.
 *
 * Every cell's update reads only its own values and its upwind neighbours' previous values, in
 * the cell's own face order: any number of ranks computes bit-identical fields.
 */
class WindTracer
{
public:
  // Reads this rank's pieces of a .pvtu (piece p goes to rank p % dataRanks: the ranks from
  // dataRanks on own nothing; 0 means all ranks), matches faces across pieces and ranks, sets up
  // the halo and the fluxes. Collective. Returns false on every rank if any rank failed.
  bool Initialize(
    const std::string& pvtu, MPI_Comm comm, int dataRanks, double timeStep, std::string& error);

  // One explicit step of length GetTimeStep(). Collective (halo exchange).
  void Advance();

  double GetTimeStep() const { return this->Dt; }
  int GetNumberOfPieces() const { return static_cast<int>(this->PieceOffsets.size()) - 1; }
  std::int64_t GetNumberOfLocalCells() const { return static_cast<std::int64_t>(this->C.size()); }

  // The rank's mesh as Catalyst gets it: one block per piece of the whole data set, this rank's
  // pieces filled, the others null (the same structure on every rank, as ParaView expects).
  // The cell array "tracer" (float) is refreshed from the field at every call; the blocks'
  // points and cells are made once and shared, as a simulation's mesh usually is.
  vtkMultiBlockDataSet* GetMesh();

  // The rank's share of the ground and the buildings' walls (faces with no neighbour that are
  // not on the domain's bounding box), with a cell array "patch": 0 ground, 1 building.
  vtkPolyData* GetWalls() { return this->Walls; }

  // Sum over ranks of the tracer's integral (c V), for a log line. Collective.
  double GetTracerVolume() const;

private:
  struct Face
  {
    std::array<float, 12> Key; // corner coordinates, sorted (unused corners 0)
    std::int64_t Cell;         // global id of the cell it belongs to
  };
  bool ReadPieces(const std::string& pvtu, std::string& error);
  void ShareLayout();
  bool AddCellFaces(vtkUnstructuredGrid* grid, vtkIdType cell, std::int64_t local);
  bool BuildFaces();
  void MatchInPieces();
  void MatchAcrossPieces();
  void BuildHalo();
  void Exchange(std::vector<double>& values);
  void BuildFluxes();
  void BuildWalls();
  void BuildMesh();
  std::int64_t GlobalOf(std::int64_t local) const;
  int OwnerOf(std::int64_t global) const;          // the rank owning a cell
  std::int64_t LocalOf(std::int64_t global) const; // -1 if another rank owns it
  std::int64_t SlotOf(std::int64_t global) const;  // local cell, or C's halo slot
  bool OnInlet(std::int64_t face) const;
  // The owned piece's grid that holds a boundary face's corners (FacePoints index into it).
  vtkUnstructuredGrid* GridOfFace(std::int64_t face) const;

  MPI_Comm Comm = MPI_COMM_NULL;
  int Rank = 0;
  int Size = 1;
  int DataRanks = 1;
  std::vector<std::int64_t> PieceOffsets; // global cell id of each piece's first cell (+ total)
  std::vector<int> Pieces;                // pieces this rank owns
  std::vector<std::int64_t> LocalStart;   // first local cell of each owned piece (+ total)
  std::vector<vtkSmartPointer<vtkUnstructuredGrid>> Grids;
  std::array<double, 6> Bounds{};

  // Per local cell: its faces (CSR), per face the outward area vector, centre, corners (the
  // piece's point ids), cell (local) and neighbour (global id, or -1); per cell its volume
  // (divergence theorem) and speed.
  std::vector<std::int64_t> FaceStart;
  std::vector<std::array<double, 3>> FaceArea;
  std::vector<std::array<double, 3>> FaceCentre;
  std::vector<std::array<vtkIdType, 4>> FacePoints; // -1 after the last corner
  std::vector<std::int64_t> FaceCell;
  std::vector<std::int64_t> Neighbour;
  std::vector<double> Volume;
  std::vector<double> Speed;

  // The update: per cell its inflow terms (weight dt|F|/V and neighbour slot: a local cell, or
  // LocalCells + halo slot), and the inlet's constant part.
  std::vector<std::int64_t> InStart;
  std::vector<double> InWeight;
  std::vector<std::int64_t> InSlot;
  std::vector<double> InletWeight; // dt |F| / V summed over inlet faces
  std::vector<double> InletValue;  // dt |F| c_in / V summed over inlet faces

  // Halo: what goes to / comes from each rank (Alltoallv layout), local cells sent.
  std::vector<int> SendCounts, SendDispls, RecvCounts, RecvDispls;
  std::vector<std::int64_t> SendCells;
  std::vector<std::int64_t> RecvGlobal; // global id of each halo slot, sorted per rank
  std::vector<double> SendBuffer;

  std::vector<double> C;    // the field, plus the halo's slots after it
  std::vector<double> Next; // the next step's field
  double Dt = 0;

  vtkSmartPointer<vtkMultiBlockDataSet> Mesh;
  std::vector<vtkSmartPointer<vtkFloatArray>> Tracer;
  vtkSmartPointer<vtkPolyData> Walls;
};
}

#endif
